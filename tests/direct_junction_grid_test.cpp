// The meter-out cylinder drawn as in FluidSIM (benchmarks/meter_out_direct_grid.yaml:
// the valve's ports straight into the one-way flow controls, junctions
// without volume) runs to t_end at operating points of its grid that used to
// end in IDA_CONV_FAIL after a stop contact (issue 36: the exhaust
// junctions' pressures, algebraic unknowns out of IDA's error test, drifted
// off their flow balances while the flows died away), and its strokes take
// the time of the same circuit with 1 mm3 lines at those junctions.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

struct Point {
  double p_s, m, C_cap, C_rod;  // Pa absolute, kg, m3/(s*Pa)
};

// The grid's netlist at one point; with `line` non-empty, a volume of that
// size at each junction (line_A at the ambient, line_B at the supply
// pressure, as the valve at rest connects them).
std::string direct_netlist(const Point& pt, const std::string& line) {
  std::string s = read_file(std::string(PNEUMO_SOURCE_DIR) + "/benchmarks/meter_out_direct_grid.yaml");
  s = replace_once(s, "p_s: 6 bar g", "p_s: " + num(pt.p_s) + " Pa");
  s = replace_once(s, "m_load: 2 kg", "m_load: " + num(pt.m) + " kg");
  s = replace_once(s, "C_cap: 0.1 dm3/(s*bar)", "C_cap: " + num(pt.C_cap) + " m3/(s*Pa)");
  s = replace_once(s, "C_rod: 0.1 dm3/(s*bar)", "C_rod: " + num(pt.C_rod) + " m3/(s*Pa)");
  if (line.empty()) return s;
  s = replace_once(s, "  air:      {type: atmosphere}\n",
                   "  air:      {type: atmosphere}\n"
                   "  line_A:   {type: volume, V: " + line + ", p0: 0 bar g}\n"
                   "  line_B:   {type: volume, V: " + line + ", p0: p_s}\n");
  s = replace_once(s, "  - [valve.A, flow_cap.b]", "  - [valve.A, line_A.port]\n  - [line_A.port_b, flow_cap.b]");
  return replace_once(s, "  - [valve.B, flow_rod.b]", "  - [valve.B, line_B.port]\n  - [line_B.port_b, flow_rod.b]");
}

TEST(DirectJunctionGrid, FailedPointsRunToTheEndLikeTinyLines) {
  // Before: the first failed 6 ms after the rod-end contact (t = 0.4159 s),
  // the second 2 s after the retraction's cap-end contact (t = 3.9284 s),
  // the third 29 ms after the rod-end contact (t = 1.4419 s).
  for (const Point& pt : {Point{501325, 2.8, 1e-9, 2.5e-9}, Point{501325, 2.8, 0.5e-9, 1e-9},
                          Point{701325, 6.4, 2e-9, 0.5e-9}}) {
    SCOPED_TRACE("p_s = " + num(pt.p_s) + " Pa, m = " + num(pt.m) + " kg, C_cap = " + num(pt.C_cap) +
                 ", C_rod = " + num(pt.C_rod));
    const RunResult direct = run_simulation(parse_netlist(direct_netlist(pt, ""), "direct"), builtin_registry());
    ASSERT_TRUE(direct.solver.ok) << direct.solver.message;
    EXPECT_NEAR(direct.solver.t_reached, 4.0, 1e-9);
    const RunResult tube = run_simulation(parse_netlist(direct_netlist(pt, "1 mm3"), "tube"), builtin_registry());
    ASSERT_TRUE(tube.solver.ok) << tube.solver.message;
    // Extension from the command at 0.1 s to the rod-end contact, retraction
    // from the command at 2 s to the cap-end contact.
    expect_strokes_like(direct.solver, tube.solver, 0.1, 2.0, 0.01);
    // It ends retracted, against the cap-end stop.
    EXPECT_LT(std::abs(at(direct.table, "x", 4.0)), 1e-4);
  }
}

}  // namespace
}  // namespace pneumo
