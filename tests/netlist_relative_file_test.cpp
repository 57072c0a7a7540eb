// A data file a netlist names by a relative path is read from the netlist's
// folder, not from the working directory: the same netlist runs from
// anywhere (the tests run in the build tree, far from the netlist).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using test_support::run_cli;
using test_support::TempDir;
namespace fs = std::filesystem;

const std::string kNetlist = R"(
components:
  pos: {type: data_signal, file: DATA, separator: whitespace, header: no,
        time_column: "1", time_unit: ms, column: "5", unit: mm}
  servo: {type: position_source, s0: 0.004 mm, tau: 1 ms}
  sensor: {type: position_sensor}
connections:
  - [pos.y, servo.s_in]
  - [pos.dy, servo.v_in]
  - [servo.flange, sensor.flange]
outputs:
  s: sensor.s
simulation: {t_end: 0.5 s, output_interval: 10 ms}
)";

std::string netlist_naming(const std::string& data) {
  std::string y = kNetlist;
  y.replace(y.find("DATA"), 4, data);
  return y;
}

TEST(NetlistRelativeFile, ADataSignalFileIsReadFromTheNetlistsFolder) {
  TempDir dir;
  fs::create_directories(dir.path() / "rig" / "runs");
  fs::copy_file(std::string(PNEUMO_SOURCE_DIR) + "/tests/data/tudelft/O-ring_3bar_head.csv",
                dir.path() / "rig" / "runs" / "position.csv");
  ASSERT_FALSE(fs::exists(fs::current_path() / "runs" / "position.csv"));  // not beside the working directory
  for (const std::string name : {"runs/position.csv", "./runs/../runs/position.csv"}) {
    SCOPED_TRACE(name);
    const auto net = (dir.path() / "rig" / "replay.yaml").string();
    std::ofstream(net) << netlist_naming(name);
    const auto out = (dir.path() / "out.csv").string();
    const auto [rc, text] = run_cli("simulate '" + net + "' -o '" + out + "'");
    EXPECT_EQ(rc, 0) << text;
    EXPECT_TRUE(fs::exists(out)) << text;
  }
}

TEST(NetlistRelativeFile, AMissingRelativeFileIsNamedWhereItWasLookedFor) {
  TempDir dir;
  fs::create_directories(dir.path() / "rig");
  const auto net = (dir.path() / "rig" / "replay.yaml").string();
  std::ofstream(net) << netlist_naming("absent.csv");
  const auto [rc, text] = run_cli("simulate '" + net + "' -o '" + (dir.path() / "out.csv").string() + "'");
  EXPECT_EQ(rc, 2) << text;
  EXPECT_NE(text.find((dir.path() / "rig" / "absent.csv").string()), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(dir.path() / "out.csv"));
}

}  // namespace
}  // namespace pneumo
