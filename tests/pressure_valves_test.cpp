// Pressure valves against what their data sheet states:
//   * relief valve: a tank filled through a throttle levels off between the
//     set pressure and the set pressure plus the valve's band, where the
//     relieved flow equals the feed (mass conservation at steady state);
//   * relieving pressure regulator: at three load flows the outlet stays
//     within the stated droop below the set pressure and falls as the flow
//     grows; a back-driven outlet is relieved to the exhaust, with the supply
//     path shut, between the relief's opening and full-open pressures.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

constexpr double kAmb = 101325;

TEST(ReliefValve, TankLevelsOffAtTheSetPressureWithinTheBand) {
  const RunResult r = run_text(R"(
ambient: {p: 101325 Pa, T: 293.15 K}
components:
  source: {type: pressure_source, p: 8 bar, T: 293.15 K}
  feed:   {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 0.5 L, p0: 1 bar}
  relief: {type: relief_valve, p_set: 5 bar g, band: 0.5 bar, C: 1 dm3/(s*bar)}
  air:    {type: atmosphere}
connections:
  - [source.port, feed.a]
  - [feed.b, tank.port, relief.in]
  - [relief.out, air.port]
outputs:
  p: tank.p
  m_feed: feed.m_flow
  m_relief: relief.m_flow
simulation: {t_end: 5 s}
)",
                               "relief.yaml");
  const double p_set = 5e5 + kAmb, band = 0.5e5;
  const double p = column(r.table, "p").back();
  const double m_feed = column(r.table, "m_feed").back(), m_relief = column(r.table, "m_relief").back();
  std::printf("relief: tank at %.6g Pa (set %.6g, band %.3g); feed %.5g kg/s, relieved %.5g kg/s\n", p, p_set, band,
              m_feed, m_relief);
  EXPECT_GT(p, p_set);
  EXPECT_LT(p, p_set + band);
  EXPECT_GT(m_feed, 1e-4);  // the feed is still flowing: the valve holds the pressure
  EXPECT_NEAR(m_relief, m_feed, 1e-4 * m_feed);
}

// Regulator (set 4 barg, droop 0.3 bar) from an 8 bar supply into a small
// volume; `load` is what the outlet volume feeds.
std::string regulator_circuit(const std::string& load) {
  return R"(
ambient: {p: 101325 Pa, T: 293.15 K}
components:
  supply: {type: pressure_source, p: 8 bar, T: 293.15 K}
  reg:    {type: pressure_regulator, p_set: 4 barg, droop: 0.3 bar, C: 1 dm3/(s*bar), relief_offset: 0.1 bar,
           relief_band: 0.3 bar}
  line:   {type: volume, V: 0.05 L, p0: 4 bar}
  vent:   {type: atmosphere}
)" + load + R"(
connections:
  - [supply.port, reg.in]
  - [reg.out, line.port]
  - [reg.exhaust, vent.port]
  - [line.port_b, load.a]
  - [load.b, sink.port]
outputs:
  p_out: reg.p_out
  m: reg.m_flow
  m_relief: reg.m_flow_relief
simulation: {t_end: 2 s}
)";
}

TEST(PressureRegulator, HoldsItsOutletWithinTheDroopAtThreeFlows) {
  const double p_set = 4e5 + kAmb, droop = 0.3e5;
  double p_previous = p_set, m_previous = 0;
  for (const char* C : {"0.05", "0.2", "0.5"}) {
    const RunResult r =
        run_text(regulator_circuit(std::string("  load: {type: iso6358_throttle, C: ") + C +
                                   " dm3/(s*bar), b: 0.3}\n  sink: {type: atmosphere}"),
                 std::string("regulator_") + C + ".yaml");
    const double p = column(r.table, "p_out").back(), m = column(r.table, "m").back();
    std::printf("regulator: load C %s dm3/(s*bar): flow %.5g kg/s, outlet %.6g Pa (%.4g Pa below set)\n", C, m, p,
                p_set - p);
    EXPECT_LT(p, p_set);
    EXPECT_GT(p, p_set - droop);
    EXPECT_GT(m, m_previous);  // more flow ...
    EXPECT_LT(p, p_previous);  // ... more droop
    EXPECT_NEAR(column(r.table, "m_relief").back(), 0.0, 1e-12);
    p_previous = p;
    m_previous = m;
  }
}

TEST(PressureRegulator, RelievesABackDrivenOutlet) {
  // A 7 bar source pushes into the outlet through a throttle.
  const RunResult r = run_text(regulator_circuit("  load: {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.3}\n"
                                                 "  sink: {type: pressure_source, p: 7 bar, T: 293.15 K}"),
                               "regulator_backdriven.yaml");
  const double p_relief = 4e5 + kAmb + 0.1e5, band = 0.3e5;
  const double p = column(r.table, "p_out").back();
  const double m_relief = column(r.table, "m_relief").back(), m = column(r.table, "m").back();
  std::printf("regulator back-driven: outlet %.6g Pa (relief opens at %.6g), relieved %.5g kg/s, supply %.3g kg/s\n",
              p, p_relief, m_relief, m);
  EXPECT_GT(p, p_relief);
  EXPECT_LT(p, p_relief + band);
  EXPECT_GT(m_relief, 1e-4);
  EXPECT_EQ(m, 0.0);  // the supply path is shut (its opening is exactly 0 above p_set)
}

}  // namespace
}  // namespace pneumo
