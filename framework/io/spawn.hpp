// Running a helper program (gnuplot) without a shell: the program and its
// arguments are an argument vector, so no name a user gave is ever parsed as
// a command. Its private files live in a folder of their own.
#pragma once

#include <string>
#include <vector>

namespace pneumo {

// A folder only this process uses (mkdtemp under TMPDIR), removed with
// everything in it when the object goes.
class PrivateFolder {
 public:
  PrivateFolder();
  ~PrivateFolder();
  PrivateFolder(const PrivateFolder&) = delete;
  PrivateFolder& operator=(const PrivateFolder&) = delete;
  // The path of `name` inside the folder.
  std::string path(const std::string& name) const;

 private:
  std::string dir_;
};

// Runs argv[0] (looked up on PATH) with `argv`, its standard output and error
// to `log_path`, and waits. Throws std::runtime_error when it cannot be
// started (naming `package`, the Debian package that installs it) or exits
// non-zero (quoting the first lines it printed). With `folder`, the program
// runs in that folder (zip stores paths relative to it); log_path is opened
// before it changes there.
void run_program(const std::vector<std::string>& argv, const std::string& log_path, const std::string& package,
                 const std::string& folder = "");

}  // namespace pneumo
