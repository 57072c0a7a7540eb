// Runs end, and say why when they cannot (issue 36; the timer of issue 29):
//   * the meter-out cylinder at operating points whose stop contact used to
//     end in IDA_CONV_FAIL (the valve exhaust's node without volume drifted
//     off its equation) runs to t_end, extending and retracting in order;
//   * a timer fed by its own inverted output (an oscillator) fires once per
//     delay, for a delay of 1 ms and of 1 us: no event is lost or doubled;
//   * an oscillator of 1 ns chatters: the run ends within its event budget
//     with a message naming the events;
//   * a node without volume between a choked check valve and a closed one
//     has no consistent start: the message names the node and the component.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

// netlists/meter_out_cylinder.yaml at supply pressure p_gauge (the rod side
// and line_B start at it), load m, the flow controls' C (m3/(s*Pa)).
std::string meter_out(double p_gauge, double m, double C_cap, double C_rod) {
  std::string s = read_file(std::string(PNEUMO_SOURCE_DIR) + "/netlists/meter_out_cylinder.yaml");
  const std::string p = num(p_gauge + 101325.0) + " Pa";
  for (int i = 0; i < 3; ++i) s = replace_once(s, "6 bar g", p);
  s = replace_once(s, "C: 0.1 dm3/(s*bar), check_C", "C: " + num(C_cap) + " m3/(s*Pa), check_C");
  s = replace_once(s, "C: 0.1 dm3/(s*bar), check_C", "C: " + num(C_rod) + " m3/(s*Pa), check_C");
  return replace_once(s, "m: 2 kg", "m: " + num(m) + " kg");
}

int count_tag(const SolverResult& r, const std::string& tag) {
  int n = 0;
  for (const auto& e : r.events) n += e.tag == tag;
  return n;
}

double first_time(const SolverResult& r, const std::string& tag) {
  for (const auto& e : r.events)
    if (e.tag == tag) return e.t;
  return NAN;
}

RunResult run_netlist(const std::string& text, const std::string& name) {
  return run_simulation(parse_netlist(text, name), builtin_registry());
}

TEST(SolverRobustness, MeterOutCylinderRunsThroughItsStopContacts) {
  // Points of the issue's grid (4 and 5 bar gauge) that failed a few ms
  // after a stop contact; the last one at the rod-end stop, the others at
  // the cap end.
  struct Point {
    double p_gauge, m, C_cap, C_rod;
  };
  for (const Point& pt : {Point{4e5, 1.0, 2e-9, 1.5000000000000002e-9}, Point{4e5, 2.8, 1e-9, 0.5e-9},
                          Point{4e5, 6.4, 1.5000000000000002e-9, 3e-9}}) {
    const RunResult r = run_netlist(meter_out(pt.p_gauge, pt.m, pt.C_cap, pt.C_rod), "meter_out");
    SCOPED_TRACE("m = " + num(pt.m) + " kg, C_cap = " + num(pt.C_cap) + ", C_rod = " + num(pt.C_rod));
    ASSERT_TRUE(r.solver.ok) << r.solver.message;
    EXPECT_NEAR(r.solver.t_reached, 4.0, 1e-9);
    // Extends after the valve switches at 0.1 s, retracts after 2 s, and
    // ends against the cap-end stop.
    const double extended = first_time(r.solver, "extended"), retracted = first_time(r.solver, "retracted");
    EXPECT_GT(extended, 0.1);
    EXPECT_LT(extended, 2.0);
    EXPECT_GT(retracted, 2.0);
    EXPECT_LT(std::abs(at(r.table, "x", 4.0)), 1e-4);
  }
}

// A timer on_delay whose input is its own output inverted: 0 -> started,
// `delay` later elapsed (output 1) -> input 0 -> reset -> started again.
std::string oscillator(const std::string& delay, const std::string& t_end, const std::string& interval) {
  return "components:\n"
         "  relay: {type: timer, kind: on_delay, delay: " + delay + "}\n"
         "  inv:   {type: not}\n"
         "connections:\n"
         "  - [relay.y, inv.in]\n"
         "  - [inv.y, relay.in]\n"
         "simulation: {t_end: " + t_end + ", output_interval: " + interval + "}\n";
}

TEST(SolverRobustness, TimerRearmedByItsOwnEventFiresOncePerDelay) {
  for (const double delay : {1e-3, 1e-6}) {
    SCOPED_TRACE("delay " + num(delay) + " s");
    const RunResult r = run_netlist(oscillator(num(delay) + " s", num(10.5 * delay) + " s", num(delay) + " s"), "osc");
    ASSERT_TRUE(r.solver.ok) << r.solver.message;
    ASSERT_EQ(count_tag(r.solver, "elapsed"), 10);
    int k = 0;
    for (const auto& e : r.solver.events)
      if (e.tag == "elapsed") EXPECT_NEAR(e.t, ++k * delay, 1e-6 * delay);
  }
}

TEST(SolverRobustness, ChatteringEventsEndTheRunNamingThem) {
  // 1 ns per cycle: a million events before the first output row.
  const RunResult r = run_netlist(oscillator("1 ns", "10 ms", "1 ms"), "chatter");
  ASSERT_FALSE(r.solver.ok);
  EXPECT_NE(r.solver.message.find("events chatter"), std::string::npos) << r.solver.message;
  EXPECT_NE(r.solver.message.find("relay 'elapsed'"), std::string::npos) << r.solver.message;
  EXPECT_NE(r.solver.message.find("relay 'reset'"), std::string::npos) << r.solver.message;
  // Within its budget: about a thousand restarts, a few microseconds.
  EXPECT_LT(r.solver.events.size(), 2000u);
  EXPECT_LT(r.solver.t_reached, 1e-5);
}

// At the start cv1 feeds the node choked from the tank (a flow that does
// not depend on the node's pressure) and cv2 is closed against it: the node
// has no volume to store the gas and no way out, and no equation determines
// its pressure.
const std::string kBlockedNode = R"(
components:
  tank: {type: volume, V: 1 L, p0: 3 bar}
  cv1:  {type: check_valve, C: 0.5 dm3/(s*bar)}
  cv2:  {type: check_valve, C: 0.5 dm3/(s*bar)}
  air:  {type: atmosphere}
connections:
  - [tank.port, cv1.in]
  - [cv1.out, cv2.out]
  - [cv2.in, air.port]
simulation: {t_end: 0.1 s}
)";

TEST(SolverRobustness, NodeWithoutConsistentStartIsNamed) {
  const RunResult r = run_netlist(kBlockedNode, "blocked_node");
  ASSERT_FALSE(r.solver.ok);
  const std::string& m = r.solver.message;
  EXPECT_NE(m.find("consistent initial values"), std::string::npos) << m;
  EXPECT_NE(m.find("p at {cv1.out, cv2.out}"), std::string::npos) << m;
  EXPECT_NE(m.find("cv2: check valve mass flow"), std::string::npos) << m;
  EXPECT_NE(m.find("add a volume"), std::string::npos) << m;
}

// `pneumo simulate --stats` after a run that could not start says what was
// being solved (issue #30: it printed "0 variables", as if the circuit were
// empty).
TEST(SolverRobustness, TheStatisticsOfARunThatCouldNotStartCountTheProblemSolved) {
  TempDir dir;
  const std::string path = dir.write("blocked.yaml", kBlockedNode + "outputs:\n  p: tank.p\n");
  const auto [status, out] = run_cli("simulate '" + path + "' --stats -o '" + (dir.path() / "r.csv").string() + "'");
  EXPECT_EQ(status, 1) << out;
  EXPECT_NE(out.find("consistent initial values"), std::string::npos) << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(solver: IDA \+ KLU, (\d+) variables, (\d+) Jacobian nonzeros)")))
      << out;
  EXPECT_GT(std::stoi(m[1]), 0) << out;
  EXPECT_GT(std::stoi(m[2]), 0) << out;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(the netlist's (\d+) unknowns)"))) << out;
  // The tank's state, the node's pressure and the valves' flows at least.
  EXPECT_GE(std::stoi(m[1]), 4) << out;
}

}  // namespace
}  // namespace pneumo
