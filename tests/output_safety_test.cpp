// A user's file names are data, never code, and no file the user did not
// name as this run's output is written, replaced or deleted: names with shell
// and gnuplot syntax start nothing; device nodes, FIFOs, links and inputs
// named as outputs are refused with exit status 2 and left as they were.
#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.hpp"

extern char** environ;

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using test_support::TempDir;

struct Exit {
  int status = -1;  // -1: killed by a signal
  std::string err;
};

// Runs pneumo with `args` as an argument vector (no shell) in `dir`.
Exit pneumo(const std::vector<std::string>& args, const fs::path& dir) {
  std::vector<std::string> argv{PNEUMO_BINARY};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> c;
  for (auto& a : argv) c.push_back(a.data());
  c.push_back(nullptr);
  const std::string err_path = (dir / "stderr.txt").string();
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addchdir_np(&fa, dir.c_str());
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, c[0], &fa, nullptr, c.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  Exit e;
  if (rc != 0) return e;
  int st = 0;
  waitpid(pid, &st, 0);
  e.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  std::ifstream in(err_path);
  e.err.assign(std::istreambuf_iterator<char>(in), {});
  fs::remove(err_path);
  return e;
}

std::string contents(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

const std::string kTank = std::string(PNEUMO_SOURCE_DIR) + "/netlists/tank_filling.yaml";

// Every file in `dir` whose name starts with "INJECTED" (what the hostile
// names below would create if any of them reached a shell or gnuplot).
std::vector<std::string> injected(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().rfind("INJECTED", 0) == 0) found.push_back(e.path().string());
  return found;
}

TEST(NoShell, CommandSyntaxAndNewlinesInFileNamesStartNothing) {
  TempDir dir;
  // A netlist whose name holds a command substitution, a newline and a
  // gnuplot string break-out: its stem becomes the plot title.
  const std::string netlist = "tank$(touch INJECTED_1)\n' . system('touch INJECTED_2') . '.yaml";
  fs::copy_file(kTank, dir.path() / netlist);
  const Exit sim = pneumo({"simulate", netlist, "-o", "run`touch INJECTED_3`.csv", "--plot",
                           "plot$(touch INJECTED_4)", "--quiet"},
                          dir.path());
  EXPECT_EQ(sim.status, 0) << sim.err;
  EXPECT_TRUE(fs::exists(dir.path() / "run`touch INJECTED_3`.csv"));
  EXPECT_TRUE(fs::exists(dir.path() / "plot$(touch INJECTED_4).png")) << sim.err;
  // `pneumo plot` of a results file with such a name (its prefix is derived).
  const std::string csv = "r$(touch INJECTED_5);touch INJECTED_6\n.csv";
  fs::copy_file(dir.path() / "run`touch INJECTED_3`.csv", dir.path() / csv);
  const Exit plot = pneumo({"plot", csv}, dir.path());
  EXPECT_EQ(plot.status, 0) << plot.err;
  EXPECT_TRUE(fs::exists(dir.path() / "r$(touch INJECTED_5);touch INJECTED_6\n.png")) << plot.err;
  EXPECT_EQ(injected(dir.path()), std::vector<std::string>{}) << "a file name was run as a command";
}

// The rule behind the test above, for every source file pneumo is built
// from: no call that hands a command line to a shell.
TEST(NoShell, NoSourceFileStartsAShell) {
  const std::vector<std::string> calls{"std::system(", " ::system(", "popen(", "\"/bin/sh\"", "\"sh\"", "execl("};
  int files = 0;
  for (const std::string room : {"framework", "components", "python"}) {
    const fs::path root = fs::path(PNEUMO_SOURCE_DIR) / room;
    if (!fs::exists(root)) continue;
    for (const auto& e : fs::recursive_directory_iterator(root)) {
      const std::string ext = e.path().extension().string();
      if (ext != ".cpp" && ext != ".hpp" && ext != ".h" && ext != ".py") continue;
      ++files;
      const std::string text = contents(e.path());
      for (const auto& call : calls) EXPECT_EQ(text.find(call), std::string::npos) << e.path() << " uses " << call;
    }
  }
  EXPECT_GT(files, 50) << "the sources were not found";
}

// Each command's output options, pointed at `target`.
std::vector<std::vector<std::string>> outputs_onto(const std::string& target) {
  return {{"simulate", kTank, "-o", target, "--quiet"},
          {"simulate", kTank, "-o", "ok.csv", "--metrics-out", target, "--quiet"},
          {"simulate", kTank, "-o", "ok.csv", "--energy-audit", target, "--quiet"},
          {"sweep", kTank, "--grid", "p_source=2 bar:3 bar:2", "-o", target, "--quiet"}};
}

void expect_refused_and_kept(const fs::path& dir, const std::string& target, bool (*still_there)(const fs::path&)) {
  for (const auto& args : outputs_onto(target)) {
    const Exit e = pneumo(args, dir);
    EXPECT_EQ(e.status, 2) << args[0] << " " << args[args.size() - 3] << ": " << e.err;
    EXPECT_NE(e.err.find(target), std::string::npos) << "the message names the file: " << e.err;
    EXPECT_TRUE(still_there(dir / target)) << args[0] << " replaced " << target;
  }
  EXPECT_FALSE(fs::exists(dir / "ok.csv")) << "a refused run writes nothing";
}

bool is_char_device(const fs::path& p) {
  struct stat st {};
  return lstat(p.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}
bool is_fifo(const fs::path& p) {
  struct stat st {};
  return lstat(p.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

TEST(OutputFiles, ADeviceNodeNamedAsOutputStaysADevice) {
  TempDir dir;
  // The null device's numbers (1, 3); making one needs root, as CI runs.
  if (mknod((dir.path() / "null").c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0)
    GTEST_SKIP() << "mknod needs root here; the FIFO test covers non-regular targets";
  expect_refused_and_kept(dir.path(), "null", is_char_device);
}

TEST(OutputFiles, AFifoNamedAsOutputIsRefusedWithoutBlocking) {
  TempDir dir;
  ASSERT_EQ(mkfifo((dir.path() / "pipe").c_str(), 0600), 0);
  expect_refused_and_kept(dir.path(), "pipe", is_fifo);
}

TEST(OutputFiles, ALinkNamedAsOutputIsNotFollowed) {
  TempDir dir;
  const std::string victim = dir.write("victim.txt", "the user's own file\n");
  fs::create_symlink(victim, dir.path() / "link.csv");
  for (const auto& args : outputs_onto("link.csv")) {
    const Exit e = pneumo(args, dir.path());
    EXPECT_EQ(e.status, 2) << e.err;
  }
  EXPECT_TRUE(fs::is_symlink(dir.path() / "link.csv"));
  EXPECT_EQ(contents(victim), "the user's own file\n");
}

TEST(OutputFiles, AnOutputThatIsAnInputIsRefusedAndTheInputKept) {
  TempDir dir;
  fs::create_directories(dir.path() / "sub");
  fs::copy_file(kTank, dir.path() / "tank.yaml");
  const std::string before = contents(dir.path() / "tank.yaml");
  // The same file under three spellings: its name, a detour, a hard link.
  fs::create_hard_link(dir.path() / "tank.yaml", dir.path() / "hard.csv");
  for (const std::string target : {"tank.yaml", "sub/../tank.yaml", "hard.csv"}) {
    for (const auto& args : std::vector<std::vector<std::string>>{
             {"simulate", "tank.yaml", "-o", target, "--quiet"},
             {"simulate", "tank.yaml", "-o", "ok.csv", "--metrics-out", target, "--quiet"},
             {"sweep", "tank.yaml", "--grid", "p_source=2 bar:3 bar:2", "-o", target, "--quiet"}}) {
      const Exit e = pneumo(args, dir.path());
      EXPECT_EQ(e.status, 2) << target << ": " << e.err;
    }
  }
  // A samples file named as the sweep's output.
  dir.write("samples.csv", "p_source\n200000\n300000\n");
  const std::string samples = contents(dir.path() / "samples.csv");
  const Exit s = pneumo({"sweep", "tank.yaml", "--samples", "samples.csv", "-o", "samples.csv", "--quiet"}, dir.path());
  EXPECT_EQ(s.status, 2) << s.err;
  EXPECT_EQ(contents(dir.path() / "samples.csv"), samples);
  EXPECT_EQ(contents(dir.path() / "tank.yaml"), before);
  EXPECT_FALSE(fs::exists(dir.path() / "ok.csv"));
}

TEST(OutputFiles, ADefaultNameNeverReplacesAFileThatIsThere) {
  TempDir dir;
  fs::copy_file(kTank, dir.path() / "tank.yaml");
  dir.write("tank.csv", "my own notes\n");
  dir.write("tank.sweep.csv", "my own sweep\n");
  const Exit sim = pneumo({"simulate", "tank.yaml", "--quiet"}, dir.path());
  EXPECT_EQ(sim.status, 2) << sim.err;
  EXPECT_NE(sim.err.find("-o"), std::string::npos) << "says how to replace it: " << sim.err;
  EXPECT_EQ(contents(dir.path() / "tank.csv"), "my own notes\n");
  const Exit sweep = pneumo({"sweep", "tank.yaml", "--grid", "p_source=2 bar:3 bar:2", "--quiet"}, dir.path());
  EXPECT_EQ(sweep.status, 2) << sweep.err;
  EXPECT_EQ(contents(dir.path() / "tank.sweep.csv"), "my own sweep\n");
  // Without the file the default name is written; naming it replaces it.
  fs::remove(dir.path() / "tank.csv");
  ASSERT_EQ(pneumo({"simulate", "tank.yaml", "--quiet"}, dir.path()).status, 0);
  EXPECT_EQ(contents(dir.path() / "tank.csv").rfind("t [s],", 0), 0u);
  EXPECT_EQ(pneumo({"simulate", "tank.yaml", "-o", "tank.csv", "--quiet"}, dir.path()).status, 0);
}

TEST(OutputFiles, AJournalLinkPlantedBesideTheOutputIsNotFollowed) {
  TempDir dir;
  const std::string victim = dir.write("victim.txt", "keep me\n");
  fs::create_symlink(victim, dir.path() / "out.csv.journal");
  const Exit e = pneumo({"sweep", kTank, "--grid", "p_source=2 bar:3 bar:2", "-o", "out.csv", "--quiet"}, dir.path());
  EXPECT_EQ(e.status, 2) << "a sweep must not use a journal through a planted link";
  EXPECT_NE(e.err.find("symbolic link"), std::string::npos) << e.err;
  EXPECT_EQ(contents(victim), "keep me\n");
  EXPECT_FALSE(fs::exists(dir.path() / "out.csv")) << e.err;
}

}  // namespace
}  // namespace pneumo
