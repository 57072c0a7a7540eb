#include "framework/io/spawn.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <fcntl.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

extern char** environ;

namespace pneumo {

namespace fs = std::filesystem;

PrivateFolder::PrivateFolder() {
  std::error_code ec;
  std::string pattern = (fs::temp_directory_path(ec) / "pneumo.XXXXXX").string();
  if (ec) pattern = "/tmp/pneumo.XXXXXX";
  if (!::mkdtemp(pattern.data()))
    throw std::runtime_error("cannot make a private folder for helper files in " + pattern + ": " +
                             std::strerror(errno));
  dir_ = pattern;
}

PrivateFolder::~PrivateFolder() {
  std::error_code ec;
  fs::remove_all(dir_, ec);
}

std::string PrivateFolder::path(const std::string& name) const { return (fs::path(dir_) / name).string(); }

namespace {

std::string first_lines(const std::string& path, int n) {
  std::ifstream in(path);
  std::string out, line;
  while (n-- > 0 && std::getline(in, line)) out += (out.empty() ? "" : " | ") + line;
  return out;
}

}  // namespace

void run_program(const std::vector<std::string>& argv, const std::string& log_path, const std::string& package,
                 const std::string& folder) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  if (!folder.empty()) posix_spawn_file_actions_addchdir_np(&actions, folder.c_str());
  pid_t pid = 0;
  const int rc = ::posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  const std::string name = argv[0];
  if (rc == ENOENT)
    throw std::runtime_error(name + " is not installed (Debian package " + package + ")");
  if (rc != 0) throw std::runtime_error("cannot start " + name + ": " + std::strerror(rc));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw std::runtime_error("lost " + name + ": " + std::strerror(errno));
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
    throw std::runtime_error(name + " is not installed or cannot run (Debian package " + package + ")");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    const std::string said = first_lines(log_path, 3);
    throw std::runtime_error(name + " failed" + (said.empty() ? std::string() : ": " + said));
  }
}

}  // namespace pneumo
