// The one way pneumo reads and writes the files a user names.
//
// Writing: a target is checked before any work (not a directory, device,
// FIFO, socket or symbolic link, and not an input of the same run), and is
// written through a temporary file created exclusively beside it (no symlink
// followed) that replaces the target only once it is complete. A name the
// user did not give (a default or a derived name) never replaces a file that
// pneumo did not write. Reading: only regular files, so that a device or FIFO
// named as an input cannot make a run read forever.
//
// Every refusal is a std::invalid_argument whose message names the file and
// says what to change; the commands report it as bad input (exit status 2).
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

namespace pneumo {

// Refuses `path` as a target the user named with `option` ("-o") if it is
// empty, an existing directory, not a regular file, a symbolic link, or the
// same file as one of `inputs` (compared as files, not as spellings).
void check_output_file(const std::string& path, const std::string& option,
                       const std::vector<std::string>& inputs = {});

// As check_output_file, for a name pneumo chose (`how` says how the user
// names it instead, e.g. "give -o NAME"): the file may be replaced only if
// `written_by_pneumo` says its first line is one pneumo writes there.
void check_chosen_output_file(const std::string& path, const std::string& how, const std::vector<std::string>& inputs,
                              bool (*written_by_pneumo)(const std::string& first_line) = nullptr);

// Writes `text` to `path` (creating its directory) through an exclusive
// temporary beside it; `path` is replaced only when all is written. Throws
// std::runtime_error naming the path and the reason; leaves no temporary.
void write_text_atomic(const std::string& path, const std::string& text);

// The first line of a regular file, or "" (absent, unreadable, not regular).
std::string first_line_of(const std::string& path);

// Refuses (std::invalid_argument) an input that is not a regular file:
// absent, a directory, a device, FIFO or socket. `what` names it ("samples").
void check_input_file(const std::string& path, const std::string& what);

// The whole of a regular input file (check_input_file first), refused
// beyond kMaxInputBytes: a file of kernel or process state (/proc) counts
// as regular and may never end.
inline constexpr std::size_t kMaxInputBytes = std::size_t{1} << 30;
std::string read_input_file(const std::string& path, const std::string& what);

// Opens an append-only journal at `path` without following a symbolic link;
// refuses one that is not a regular file. The caller closes it.
std::FILE* open_journal(const std::string& path);

// Removes `path` only if it is a regular file whose first line `is_ours`
// accepts (a stale file pneumo wrote); returns whether it was removed.
bool remove_if_ours(const std::string& path, bool (*is_ours)(const std::string& first_line));

}  // namespace pneumo
