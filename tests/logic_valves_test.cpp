// Shuttle (OR), two-pressure (AND) and quick exhaust valves by their logic:
//   * the OR valve's outlet settles at the higher inlet pressure, the AND
//     valve's at the lower (only pressurised when both inlets are);
//   * the quick exhaust valve fills its working port from P with the
//     exhaust shut, and vents it through R (not back through P) once P is
//     vented.
#include <gtest/gtest.h>

#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

// Final outlet pressure of `type` with inlets at p1 and p2 (Pa), the outlet
// a volume starting at 3 bar.
double outlet(const std::string& type, double p1, double p2) {
  const RunResult r = run_text(R"(
components:
  s1:   {type: pressure_source, p: )" + num(p1) + R"( Pa}
  s2:   {type: pressure_source, p: )" + num(p2) + R"( Pa}
  gate: {type: )" + type + R"(, C: 0.2 dm3/(s*bar)}
  tank: {type: volume, V: 0.1 L, p0: 3 bar}
connections:
  - [s1.port, gate.in_1]
  - [s2.port, gate.in_2]
  - [gate.out, tank.port]
outputs:
  p: tank.p
simulation: {t_end: 1 s}
)",
                               type + ".yaml");
  return column(r.table, "p").back();
}

TEST(LogicValves, ShuttleValveIsAnOr) {
  EXPECT_NEAR(outlet("shuttle_valve", 5e5, 101325), 5e5, 1e-3 * 5e5);
  EXPECT_NEAR(outlet("shuttle_valve", 101325, 4e5), 4e5, 1e-3 * 4e5);
  EXPECT_NEAR(outlet("shuttle_valve", 101325, 101325), 101325, 1e-3 * 101325);
}

TEST(LogicValves, TwoPressureValveIsAnAnd) {
  EXPECT_NEAR(outlet("two_pressure_valve", 5e5, 101325), 101325, 1e-3 * 101325);
  EXPECT_NEAR(outlet("two_pressure_valve", 101325, 4e5), 101325, 1e-3 * 101325);
  EXPECT_NEAR(outlet("two_pressure_valve", 5e5, 4e5), 4e5, 1e-3 * 4e5);
}

// The working port a tank at p0; P fed from `p_line` through a line
// throttle and a hose volume; R to the atmosphere.
RunResult quick_exhaust(double p_line, double p0, const std::string& name) {
  return run_text(R"(
components:
  line_src: {type: pressure_source, p: )" + num(p_line) + R"( Pa}
  line:     {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.3}
  hose:     {type: volume, V: 0.01 L, p0: )" + num(p_line) + R"( Pa}
  qev:      {type: quick_exhaust_valve, C_PA: 0.5 dm3/(s*bar), C_AR: 2 dm3/(s*bar)}
  tank:     {type: volume, V: 0.1 L, p0: )" + num(p0) + R"( Pa}
  air:      {type: atmosphere}
connections:
  - [line_src.port, line.a]
  - [line.b, hose.port]
  - [hose.port_b, qev.P]
  - [qev.A, tank.port]
  - [qev.R, air.port]
outputs:
  p: tank.p
  m_PA: qev.m_flow_PA
  m_AR: qev.m_flow_AR
simulation: {t_end: 0.5 s, output_interval: 5 ms}
)",
                  name);
}

TEST(LogicValves, QuickExhaustValveFillsThroughPAndVentsThroughR) {
  const RunResult fill = quick_exhaust(6e5, 101325, "qev_fill.yaml");
  EXPECT_GT(at(fill.table, "p", 0.5), 4e5);
  EXPECT_GT(at(fill.table, "m_PA", 0.005), 1e-4);
  for (double m : column(fill.table, "m_AR")) EXPECT_EQ(m, 0.0);  // R stays sealed while filling
  const RunResult vent = quick_exhaust(101325, 6e5, "qev_vent.yaml");
  // It vents down to the disc's cracking pressure (0.1 bar) above P.
  EXPECT_LT(at(vent.table, "p", 0.5), 101325 + 0.12e5);
  // Early in the venting the flow leaves through R, none back through P.
  EXPECT_GT(at(vent.table, "m_AR", 0.005), 1e-4);
  EXPECT_EQ(at(vent.table, "m_PA", 0.005), 0.0);
}

}  // namespace
}  // namespace pneumo
