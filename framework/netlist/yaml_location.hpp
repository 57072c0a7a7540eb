// Where a YAML node is written: for the readers of YAML files (netlist,
// metrics, effect catalogue), which are the only framework files that see
// yaml-cpp; everything past them works on typed values.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <string>

#include "framework/core/error.hpp"

namespace pneumo {

SourceLocation location_of(const std::string& file, const YAML::Node& node);

// The text of a node where a plain name or text is expected (a key, a type,
// a description). yaml-cpp's as<std::string>() throws its own exception on a
// map or list; this throws an InputError at the node's line, saying `what`
// was expected. A null node reads as "null", as yaml-cpp has it.
std::string plain_text(const std::string& file, const YAML::Node& node, const std::string& component,
                       const std::string& parameter, const std::string& what);

// An alias (*name) repeats the node its anchor (&name) marks, so a few
// kilobytes can stand for billions of values (a list of aliases to a list
// of aliases ...) and make every reader of the tree run out of memory.
// Throws an InputError at the file's start when `root` with its aliases
// expanded holds more than kMaxYamlValues nodes; counting stops there.
inline constexpr std::size_t kMaxYamlValues = 500000;

// A NUL byte makes yaml-cpp's LoadAll produce documents without end (the
// netlist fuzzer's out-of-memory); a file holding one is not text. Throws
// an InputError at the first one's line and column.
void check_no_nul(const std::string& file, const std::string& text);

// The first document of a YAML text, and the line of the first node of a
// second document that holds anything (0: none). yaml-cpp's LoadAll reports
// empty documents without end on some malformed texts (a tab before a key
// at the end, found by the netlist fuzzer), so the documents after the
// first are only looked for, up to the second. Throws yaml-cpp's
// ParserException and DeepRecursion as LoadAll does.
struct FirstDocument {
  YAML::Node root;
  int second_line = 0;
};
FirstDocument load_first_document(const std::string& text);
void check_expanded_size(const std::string& file, const YAML::Node& root);

}  // namespace pneumo
