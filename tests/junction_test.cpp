// Junctions without a volume are algebraic nodes that work (issue 36): a
// valve port drawn straight into a one-way flow control, and throttles in
// series, start from a consistent state and give the junction pressure the
// flow balance decides - no volume invented.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

RunResult run_text(const std::string& text, const std::string& name) {
  return run_simulation(parse_netlist(text, name), builtin_registry());
}

// The shipped meter-out cylinder with its valve ports joined to the flow
// controls: through lines of `line_volume`, or directly ("" = no line).
std::string meter_out(const std::string& line_volume) {
  std::string s = read_file(std::string(PNEUMO_SOURCE_DIR) + "/netlists/meter_out_cylinder.yaml");
  s = replace_once(s, "output_interval: 5 ms", "output_interval: 0.5 ms");
  if (!line_volume.empty()) {
    s = replace_once(s, "V: 5 cm3, p0: 0 bar g", "V: " + line_volume + ", p0: 0 bar g");
    return replace_once(s, "V: 5 cm3, p0: 6 bar g", "V: " + line_volume + ", p0: 6 bar g");
  }
  s = replace_once(s, "  line_A:   {type: volume, V: 5 cm3, p0: 0 bar g}\n", "");
  s = replace_once(s, "  line_B:   {type: volume, V: 5 cm3, p0: 6 bar g}\n", "");
  s = replace_once(s, "  - [valve.A, line_A.port]\n  - [line_A.port_b, flow_cap.b]", "  - [valve.A, flow_cap.b]");
  return replace_once(s, "  - [valve.B, line_B.port]\n  - [line_B.port_b, flow_rod.b]", "  - [valve.B, flow_rod.b]");
}

// The time at which column x first reaches `level` (linear between rows).
double time_at(const ResultsTable& t, const std::string& x, double level) {
  const int c = t.column(x);
  for (std::size_t i = 1; i < t.rows.size(); ++i) {
    const double a = t.rows[i - 1][c], b = t.rows[i][c];
    if (a < level && b >= level)
      return t.rows[i - 1][0] + (level - a) / (b - a) * (t.rows[i][0] - t.rows[i - 1][0]);
  }
  return NAN;
}

// Mean extension speed between 20 % and 80 % of the 100 mm stroke.
double extension_speed(const RunResult& r) {
  return 0.06 / (time_at(r.table, "x", 0.08) - time_at(r.table, "x", 0.02));
}

TEST(Junction, ValveStraightIntoFlowControlsRunsLikeATinyLine) {
  const RunResult direct = run_text(meter_out(""), "valve_into_flow_controls");
  ASSERT_TRUE(direct.solver.ok) << direct.solver.message;
  const RunResult tube = run_text(meter_out("1 mm3"), "one_mm3_lines");
  ASSERT_TRUE(tube.solver.ok) << tube.solver.message;
  const double v_direct = extension_speed(direct), v_tube = extension_speed(tube);
  ASSERT_TRUE(std::isfinite(v_direct)) << "the piston did not extend";
  EXPECT_NEAR(v_direct / v_tube, 1.0, 0.01) << v_direct << " m/s against " << v_tube << " m/s";
  // It extends, waits and retracts as the valve's schedule says.
  EXPECT_GT(at(direct.table, "x", 1.9), 0.0999);
  EXPECT_LT(at(direct.table, "x", 4.0), 1e-3);
}

// A 10 bar supply through throttles t1 (C 0.2, b 0.5) and t2 (C 0.5,
// b 0.3) in series to the atmosphere, the junction between them without a
// volume; with `step`, t2's opening a step from 0 to 1 at 10 ms.
RunResult choked_series(bool step, const std::string& simulation) {
  std::string text = R"(
components:
  supply: {type: pressure_source, p: 10 bar, T: 293.15 K}
  t1:     {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.5}
  t2:     {type: iso6358_throttle, C: 0.5 dm3/(s*bar), b: 0.3}
  air:    {type: atmosphere}
connections:
  - [supply.port, t1.a]
  - [t1.b, t2.a]
  - [t2.b, air.port]
outputs:
  p_j: t1.b.p
  m1: t1.m_flow
  m2: t2.m_flow
)";
  if (step) {
    text = replace_once(text, "  air:", "  cmd:    {type: signal_source, kind: step, value: 0, height: 1, t_start: 10 ms}\n  air:");
    text = replace_once(text, "outputs:", "  - [cmd.y, t2.opening]\noutputs:");
  }
  return run_text(text + "simulation: " + simulation + "\n", step ? "step_series" : "choked_series");
}

TEST(Junction, ChokedThrottlesInSeriesGiveTheClosedFormJunctionPressure) {
  // Both choked, equal mass flows: C1 rho_ref p_s sqrt(T_ref/T) =
  // C2 rho_ref p_j sqrt(T_ref/T) (throttling keeps an ideal gas's
  // temperature), so p_j = C1/C2 p_s = 4 bar; then p_j/p_s = 0.4 < b1 = 0.5
  // and p_amb/p_j = 0.25 < b2 = 0.3 - both choked indeed.
  const RunResult r = choked_series(false, "{t_end: 0.1 s, output_interval: 10 ms}");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  for (double t : {0.0, 0.05, 0.1}) {
    EXPECT_NEAR(at(r.table, "p_j", t) / 4e5, 1.0, 1e-3) << "t = " << t;
    EXPECT_NEAR(at(r.table, "m1", t) / at(r.table, "m2", t), 1.0, 1e-6);
  }
}

TEST(Junction, AJunctionWhosePathOpensAsAStepJumpsToItsNewBalance) {
  // The same series, t2 opened by a step at 10 ms (a valve path drawn as a
  // throttle): shut, no flow and the junction at the supply's 10 bar; open,
  // both choked and p_j = 4 bar at once, the flow C1 rho_ref p_s. The new
  // balance is 6 bar from the old one through the steep laminar piece of
  // the flow law, which the consistent-values Newton of IDA crosses only
  // with more iterations than its default.
  const RunResult r = choked_series(true, "{t_end: 0.05 s, output_interval: 1 ms}");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_NEAR(at(r.table, "p_j", 0.005) / 10e5, 1.0, 1e-9);
  EXPECT_EQ(at(r.table, "m1", 0.005), 0.0);
  const double m = 0.2e-8 * 1.185 * 10e5;  // C1 rho_ref p_s, T = T_ref
  for (double t : {0.011, 0.03, 0.05}) {
    EXPECT_NEAR(at(r.table, "p_j", t) / 4e5, 1.0, 1e-3) << "t = " << t;
    EXPECT_NEAR(at(r.table, "m1", t) / m, 1.0, 1e-3) << "t = " << t;
    EXPECT_NEAR(at(r.table, "m2", t) / at(r.table, "m1", t), 1.0, 1e-6) << "t = " << t;
  }
}

TEST(Junction, ThrottleIntoThrottleFollowsFlowReversal) {
  // A tank discharged through two throttles in series into a second tank
  // that starts higher: the flow runs from b to a first, then the pressures
  // meet. The junction pressure always lies between the two tanks' and the
  // gas is conserved.
  const RunResult r = run_text(R"(
components:
  left:  {type: volume, V: 0.5 L, p0: 2 bar, T0: 293.15 K}
  t1:    {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.4}
  t2:    {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.4}
  right: {type: volume, V: 0.5 L, p0: 6 bar, T0: 293.15 K}
connections:
  - [left.port, t1.a]
  - [t1.b, t2.a]
  - [t2.b, right.port]
outputs:
  p_l: left.p
  p_j: t1.b.p
  p_r: right.p
  m_l: left.m
  m_r: right.m
simulation: {t_end: 1 s, output_interval: 10 ms}
)",
                               "reversal");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const double m0 = at(r.table, "m_l", 0.0) + at(r.table, "m_r", 0.0);
  for (const auto& row : r.table.rows) {
    const double pl = row[r.table.column("p_l")], pj = row[r.table.column("p_j")], pr = row[r.table.column("p_r")];
    EXPECT_GE(pj, std::min(pl, pr) - 1.0) << "t = " << row[0];
    EXPECT_LE(pj, std::max(pl, pr) + 1.0) << "t = " << row[0];
    EXPECT_NEAR(row[r.table.column("m_l")] + row[r.table.column("m_r")], m0, 1e-9 * m0);
  }
  EXPECT_NEAR(at(r.table, "p_l", 1.0), at(r.table, "p_r", 1.0), 1e3) << "the tanks equalise";
}

}  // namespace
}  // namespace pneumo
