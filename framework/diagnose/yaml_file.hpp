// The diagnosis's YAML inputs (run files, the effect catalogue) read as one
// document with unique keys: yaml-cpp keeps the last of two equal keys and
// ignores every document after the first, so that a value the user wrote
// would silently not count.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace pneumo::diagnose {

// The file's single YAML document (a Null node if the file is empty).
// InputError at file:line:column for: a file that is not a regular file
// (a device or FIFO would be read forever), a syntax error, a second
// document, a key written twice in one map. `what` names the file's role
// in messages ("run file", "catalogue").
YAML::Node load_yaml_document(const std::string& path, const std::string& what);

// `text` cut to `max_chars` (with "..." after), for messages that quote a
// cell of a user's file: never more of the file than the offending cell.
std::string quoted_cell(const std::string& text, std::size_t max_chars = 40);

}  // namespace pneumo::diagnose
