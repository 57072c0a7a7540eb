// The 5/3 valve holding a vertical load: a 20 kg mass hangs on the rod of a
// cylinder (gravity extends), both chambers at the pressures that carry it
// at mid-stroke, the valve in its centre.
//   * closed centre: both chambers are shut in; the load stays where it is;
//   * exhausted centre: both chambers vent; the load sinks to the stop;
//   * solenoid 12 from the schedule (P -> B, the rod side): the load is
//     lifted to the retracted end.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

constexpr double kPi = 3.14159265358979323846;

RunResult hang(const std::string& valve_extra, const std::string& name) {
  const double A = kPi * 0.032 * 0.032 / 4, A_rod = kPi * 0.012 * 0.012 / 4, p_amb = 101325;
  const double W = 20 * 9.81, p_cap = 3e5;
  const double p_rod = (p_cap * A - p_amb * A_rod + W) / (A - A_rod);  // force balance at rest
  return run_text(R"(
ambient: {p: 101325 Pa, T: 293.15 K}
components:
  supply:  {type: pressure_source, p: 6 bar, T: 293.15 K}
  valve:   {type: directional_valve_53, C: 0.5 dm3/(s*bar), t_switch_time: 10 ms)" +
                      valve_extra + R"(}
  air:     {type: atmosphere}
  cyl:     {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, x0: 50 mm, p0_cap: )" +
                      num(p_cap) + " Pa, p0_rod: " + num(p_rod) + R"( Pa,
            friction_model: coulomb_viscous, friction_viscous: 100 N*s/m}
  load:    {type: translational_mass, m: 20 kg}
  gravity: {type: force_source, F: )" + num(W) + R"( N}
connections:
  - [supply.port, valve.P]
  - [valve.A, cyl.cap]
  - [valve.B, cyl.rod]
  - [valve.R, air.port]
  - [cyl.flange, load.flange, gravity.flange]
outputs:
  x: cyl.x
simulation: {t_end: 2 s}
)",
                  name);
}

bool has_event(const RunResult& r, const std::string& tag) {
  for (const auto& ev : r.solver.events)
    if (ev.component == "cyl" && ev.tag == tag) return true;
  return false;
}

TEST(DirectionalValve53, ClosedCentreHoldsAVerticalLoad) {
  const RunResult r = hang(", centre: closed", "closed_centre.yaml");
  std::printf("closed centre: x from 50 mm to %.6f mm\n", 1e3 * column(r.table, "x").back());
  EXPECT_NEAR(column(r.table, "x").back(), 0.05, 1e-6);
}

TEST(DirectionalValve53, ExhaustedCentreLetsItSink) {
  const RunResult r = hang(", centre: exhausted", "exhausted_centre.yaml");
  EXPECT_TRUE(has_event(r, "extended"));
  EXPECT_NEAR(column(r.table, "x").back(), 0.1, 1e-4);
}

TEST(DirectionalValve53, Solenoid12LiftsIt) {
  const RunResult r = hang(", centre: closed, schedule: [[0.1, -1]]", "solenoid_12.yaml");
  bool switched = false;
  for (const auto& ev : r.solver.events) switched = switched || (ev.component == "valve" && ev.tag == "switched_12");
  EXPECT_TRUE(switched);
  EXPECT_TRUE(has_event(r, "retracted"));
  EXPECT_NEAR(column(r.table, "x").back(), 0.0, 1e-4);
}

}  // namespace
}  // namespace pneumo
