#include "framework/io/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace pneumo {

namespace fs = std::filesystem;

namespace {

std::string errno_text() { return std::strerror(errno); }

// What an existing, non-regular target is, for the message ("" if absent or regular).
std::string what_else(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return "";
  if (S_ISLNK(st.st_mode)) return "a symbolic link (name the file it points to, if that is what you mean)";
  if (S_ISDIR(st.st_mode)) return "a directory (give a file name in it)";
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return "a device";
  if (S_ISFIFO(st.st_mode)) return "a FIFO";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  return "";
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  return fs::equivalent(a, b, ec) && !ec;
}

void refuse_inputs(const std::string& path, const std::string& option, const std::vector<std::string>& inputs) {
  for (const auto& in : inputs)
    if (!in.empty() && same_file(path, in))
      throw std::invalid_argument(option + " " + path + ": this is an input of the run (" + in +
                                  "); pneumo never writes over its inputs: choose another output name");
}

// A temporary beside `target`, created exclusively (O_EXCL: a planted file or
// symlink of that name makes it fail rather than be followed).
std::string create_temporary(const fs::path& target, int& fd) {
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::string name = (dir / ("." + target.filename().string() + ".XXXXXX")).string();
  fd = ::mkostemp(name.data(), O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("cannot write '" + target.string() + "': " + errno_text());
  // mkostemp makes 0600; a results file gets the usual permissions.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  return name;
}

bool write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

void check_output_file(const std::string& path, const std::string& option, const std::vector<std::string>& inputs) {
  if (path.empty()) throw std::invalid_argument(option + " \"\": give a file name");
  if (const std::string other = what_else(path); !other.empty())
    throw std::invalid_argument(option + " " + path + ": this is " + other +
                                "; pneumo writes its output only to a regular file or a new name");
  refuse_inputs(path, option, inputs);
}

void check_chosen_output_file(const std::string& path, const std::string& how, const std::vector<std::string>& inputs,
                              bool (*written_by_pneumo)(const std::string&)) {
  check_output_file(path, "output", inputs);
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(path, ec))) return;
  if (written_by_pneumo && written_by_pneumo(first_line_of(path))) return;
  throw std::invalid_argument(path + " exists and was not named as this run's output; pneumo does not replace it: " +
                              how);
}

void write_text_atomic(const std::string& path, const std::string& text) {
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  if (const std::string other = what_else(path); !other.empty())
    throw std::runtime_error("cannot write '" + path + "': it is " + other);
  int fd = -1;
  const std::string tmp = create_temporary(target, fd);
  const bool written = write_all(fd, text);
  const bool closed = ::close(fd) == 0;
  if (!written || !closed) {
    const std::string why = errno_text();
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write '" + path + "': " + why);
  }
  // Checked again just before the rename: a device or link planted meanwhile is not replaced.
  if (const std::string other = what_else(path); !other.empty() || ::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = other.empty() ? errno_text() : "it is " + other;
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write '" + path + "': " + why);
  }
}

std::string first_line_of(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(fs::symlink_status(path, ec))) return "";
  std::ifstream in(path, std::ios::binary);
  std::string line;
  char c;
  while (line.size() < 4096 && in.get(c) && c != '\n') line += c;
  return line;
}

void check_input_file(const std::string& path, const std::string& what) {
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (!fs::exists(st)) throw std::invalid_argument(what + " " + path + ": no such file");
  if (!fs::is_regular_file(st)) {
    const std::string kind = fs::is_directory(st) ? "a directory" : "not a regular file (a device, FIFO or socket)";
    throw std::invalid_argument(what + " " + path + ": this is " + kind + "; name a file");
  }
}

std::string read_input_file(const std::string& path, const std::string& what) {
  check_input_file(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(what + " " + path + ": cannot be read");
  std::string text;
  char chunk[65536];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxInputBytes)
      throw std::invalid_argument(what + " " + path + ": larger than " + std::to_string(kMaxInputBytes >> 20) +
                                  " MB, more than pneumo reads");
  }
  return text;
}

std::FILE* open_journal(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK, 0666);
  if (fd < 0) {
    const std::string other = what_else(path);
    throw std::runtime_error("cannot write the journal '" + path + "': " + (other.empty() ? errno_text() : "it is " + other));
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw std::runtime_error("cannot write the journal '" + path + "': it is not a regular file");
  }
  std::FILE* f = ::fdopen(fd, "ab");
  if (!f) ::close(fd);
  return f;
}

bool remove_if_ours(const std::string& path, bool (*is_ours)(const std::string&)) {
  std::error_code ec;
  if (!fs::is_regular_file(fs::symlink_status(path, ec)) || !is_ours(first_line_of(path))) return false;
  return fs::remove(path, ec);
}

}  // namespace pneumo
