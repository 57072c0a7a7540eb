// Measured inputs replayed: a data_signal plays the TU Delft position column
// (whitespace, no header, ms and mm) and a position_source makes a flange
// follow it; the simulated position reproduces the file's position.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "components/builtin.hpp"
#include "framework/io/data_file.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

const std::string kDir = std::string(PNEUMO_SOURCE_DIR) + "/tests/data/tudelft/";

const std::string kReplay = R"(
components:
  pos: {type: data_signal, file: DIR/O-ring_3bar_head.csv, separator: whitespace, header: no,
        time_column: "1", time_unit: ms, column: "5", unit: mm}
  servo: {type: position_source, s0: 0.004 mm, tau: 1 ms}
  sensor: {type: position_sensor}
connections:
  - [pos.y, servo.s_in]
  - [pos.dy, servo.v_in]
  - [servo.flange, sensor.flange]
outputs:
  s: sensor.s
  F: servo.F
simulation: {t_end: 6.69 s, output_interval: 1 ms}
)";

std::string replay_netlist() {
  std::string y = kReplay;
  y.replace(y.find("DIR/"), 4, kDir);
  return y;
}

TEST(Replay, AReplayedPositionReproducesTheFilesPositionWithinItsQuantisation) {
  const RunResult r = run_simulation(parse_netlist(replay_netlist(), "replay.yaml"), builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  DataFileSpec spec;
  spec.file = kDir + "O-ring_3bar_head.csv";
  spec.separator = DataSeparator::whitespace;
  spec.header = false;
  spec.columns = {DataColumnSpec{"t", 1, "", "ms"}, DataColumnSpec{"s", 5, "", "mm"}};
  const auto d = read_data_file(spec);
  // The laser's resolution: the smallest step between samples.
  double q = INFINITY;
  for (std::size_t i = 1; i < d.rows(); ++i)
    if (double step = std::abs(d.values[1][i] - d.values[1][i - 1]); step > 0) q = std::min(q, step);
  ASSERT_LT(q, 0.01e-3);
  const auto t = column(r.table, "t"), s = column(r.table, "s");
  int compared = 0;
  double worst = 0;
  for (std::size_t i = 0; i < d.rows(); ++i) {
    const double ti = d.values[0][i];
    if (ti > t.back()) break;
    // the output grid holds the sample times to the ms: nearest output row
    const std::size_t k = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), ti - 1e-6) - t.begin());
    if (k >= t.size() || std::abs(t[k] - ti) > 1e-6) continue;
    worst = std::max(worst, std::abs(s[k] - d.values[1][i]));
    ++compared;
  }
  EXPECT_GT(compared, 380);  // of the 400 samples (a few lie off the 1 ms grid)
  EXPECT_LT(worst, q / 2) << "quantisation step " << q << " m";
  std::printf("replayed position: %d samples, worst error %.3g m, quantisation %.3g m\n", compared, worst, q);
}

TEST(Replay, AMissingDataFileIsRefusedNamingIt) {
  std::string yaml = replay_netlist();
  yaml.replace(yaml.find("O-ring_3bar_head.csv"), 20, "no_such_run.csv");
  try {
    run_simulation(parse_netlist(yaml, "replay.yaml"), builtin_registry());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_run.csv"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pneumo
