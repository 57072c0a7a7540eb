// `--set NAME=VALUE` means the same in every command that runs a netlist:
// a top-level parameter, a component's COMPONENT.PARAMETER or a
// simulation.KEY, checked as a value written in the netlist is (issue #30:
// component parameters could be swept but not set, and `sweep`,
// `sensitivity`, `optimize` and `diagnose` had no --set at all).
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace pneumo {
namespace {

using test_support::read_file;
using test_support::replace_once;
using test_support::run_cli;
using test_support::TempDir;

const std::string kRig = std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml";

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// The file without its first line (a header or comment naming the input).
std::string body(const std::string& path) {
  const std::string text = read_file(path);
  return text.substr(text.find('\n') + 1);
}

// The rig as shipped and the rig with a 40 mm bore written in the file.
struct Rigs {
  TempDir dir;
  std::string shipped, edited;
  Rigs() {
    const std::string text = read_file(kRig);
    shipped = dir.write("rig.yaml", text);
    edited = dir.write("rig_40.yaml", replace_once(text, "bore: 32 mm", "bore: 40 mm"));
  }
  std::string out(const std::string& name) const { return (dir.path() / name).string(); }
};

TEST(SetEverywhere, ACylinderBoreSetInSimulateGivesTheRunOfTheEditedNetlist) {
  const Rigs r;
  const auto [s1, t1] = run_cli("simulate '" + r.shipped + "' --set 'cylinder.bore=40 mm' -q -o '" + r.out("set.csv") + "'");
  ASSERT_EQ(s1, 0) << t1;
  const auto [s2, t2] = run_cli("simulate '" + r.edited + "' -q -o '" + r.out("edited.csv") + "'");
  ASSERT_EQ(s2, 0) << t2;
  const auto [s3, t3] = run_cli("simulate '" + r.shipped + "' -q -o '" + r.out("shipped.csv") + "'");
  ASSERT_EQ(s3, 0) << t3;
  EXPECT_EQ(read_file(r.out("set.csv")), read_file(r.out("edited.csv")));
  EXPECT_NE(read_file(r.out("set.csv")), read_file(r.out("shipped.csv")));  // the bore matters
}

TEST(SetEverywhere, ASweepWithACylinderBoreSetRunsTheEditedNetlist) {
  const Rigs r;
  const std::string grid = " --grid 'm_load=2 kg:4 kg:2' --metrics t_move,v_impact -q -o '";
  const auto [s1, t1] = run_cli("sweep '" + r.shipped + "' --set 'cylinder.bore=40 mm'" + grid + r.out("set.csv") + "'");
  ASSERT_EQ(s1, 0) << t1;
  const auto [s2, t2] = run_cli("sweep '" + r.edited + "'" + grid + r.out("edited.csv") + "'");
  ASSERT_EQ(s2, 0) << t2;
  const auto [s3, t3] = run_cli("sweep '" + r.shipped + "'" + grid + r.out("shipped.csv") + "'");
  ASSERT_EQ(s3, 0) << t3;
  EXPECT_EQ(body(r.out("set.csv")), body(r.out("edited.csv")));
  EXPECT_NE(body(r.out("set.csv")), body(r.out("shipped.csv")));
}

// Every command reads --set, and a component parameter set there is checked
// as one written in the netlist: a misspelt name, a bare number that is not
// plausible in SI, and a unit of the wrong dimension are refused (status 2)
// with the option in the message.
TEST(SetEverywhere, EveryCommandRefusesABadComponentSettingNamingTheOption) {
  const Rigs r;
  const std::string runs = (r.dir.path() / "runs").string();
  std::filesystem::create_directories(runs);
  const std::vector<std::string> commands = {
      "simulate '" + r.shipped + "' -q -o '" + r.out("a.csv") + "'",
      "sweep '" + r.shipped + "' --grid 'm_load=2 kg:4 kg:2' -q -o '" + r.out("b.csv") + "'",
      "sensitivity '" + r.shipped + "' --param 'm_load=2 kg:4 kg' --trajectories 2 -q -o '" + r.out("c.csv") + "'",
      "optimize '" + r.shipped + "' --design 'z_EC=0.5:3' --minimize t_move --max-evaluations 4 -q -o '" +
          r.out("d.yaml") + "'",
      "diagnose '" + r.shipped + "' --runs '" + runs + "' --out '" + r.out("report") + "' -q",
      "draw '" + r.shipped + "' -o '" + r.out("e.svg") + "'",
  };
  const std::vector<std::pair<std::string, std::string>> settings = {
      {"cylinder.borr=40 mm", "unknown parameter"},
      {"cylinder.bore=40", "no unit"},
      {"cylinder.bore=40 bar", "cylinder"},
      {"cylindr.bore=40 mm", "no component 'cylindr'"},
  };
  for (const auto& command : commands)
    for (const auto& [setting, says] : settings) {
      const auto [status, text] = run_cli(command + " --set '" + setting + "'");
      EXPECT_EQ(status, 2) << command << " --set " << setting << "\n" << text;
      EXPECT_TRUE(has(text, "--set " + setting)) << command << "\n" << text;
      EXPECT_TRUE(has(text, says)) << command << " --set " << setting << "\n" << text;
    }
}

// simulation.KEY is a --set like any other, in a sweep as in simulate: a
// shorter t_end ends the runs before the piston reaches the cap, so the
// impact metric is undefined.
TEST(SetEverywhere, ASimulationKeySetInASweepShortensItsRuns) {
  const Rigs r;
  const std::string grid = " --grid 'm_load=2 kg:4 kg:2' --metrics t_move -q -o '";
  const auto [s1, t1] = run_cli("sweep '" + r.shipped + "' --set 'simulation.t_end=5 ms'" + grid + r.out("short.csv") + "'");
  ASSERT_EQ(s1, 0) << t1;
  const std::string text = body(r.out("short.csv"));
  std::stringstream lines(text);
  std::string line;
  int rows = 0;
  while (std::getline(lines, line))
    if (!line.empty() && line[0] != '#') {
      ++rows;
      EXPECT_TRUE(has(line, "nan")) << line;  // no impact within 5 ms
    }
  EXPECT_EQ(rows, 2) << text;
}

}  // namespace
}  // namespace pneumo
