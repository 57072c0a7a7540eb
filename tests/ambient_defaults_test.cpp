// Start values left out are the netlist's ambient, not a fixed 1.01325 bar
// and 20 degC (ParameterSpec::ambient_pressure_by_default and
// ambient_temperature_by_default, applied in elaboration).
//
// What is asserted: in a netlist at 0.95 bar and 30 degC, a volume and a
// cylinder written without p0, p0_cap, p0_rod or T0, vented to the
// atmosphere, start at that pressure and temperature and stay there (no
// flow: they are at rest with their surroundings); a pressure source
// without T delivers gas at 30 degC; the reference says what the default
// is.
#include <gtest/gtest.h>

#include <string>

#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using test_support::column;
using test_support::run_cli;

const char* kWarmThinAir = R"(
title: left-out start values at a non-standard ambient
ambient: {p: 0.95 bar, T: 30 degC}
components:
  air:    {type: atmosphere}
  vent:   {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 1 L}
  vent_c: {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.3}
  vent_r: {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.3}
  cyl:    {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm}
  load:   {type: translational_mass, m: 1 kg}
  supply: {type: pressure_source, p: 3 bar}
  feed:   {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.3}
  box:    {type: volume, V: 1 L, p0: 3 bar}
connections:
  - [tank.port, vent.a]
  - [vent.b, air.port]
  - [cyl.cap, vent_c.a]
  - [vent_c.b, air.port]
  - [cyl.rod, vent_r.a]
  - [vent_r.b, air.port]
  - [cyl.flange, load.flange]
  - [supply.port, feed.a]
  - [feed.b, box.port]
outputs:
  p_tank: tank.p
  T_tank: tank.T
  p_cap: cyl.p_cap
  p_rod: cyl.p_rod
  T_cap: cyl.T_cap
  x: cyl.x
  T_box: box.T
simulation: {t_end: 0.5 s, output_interval: 10 ms}
)";

TEST(AmbientDefaults, LeftOutStartValuesAreTheNetlistsAmbientAndStayThere) {
  const RunResult r = test_support::run_text(kWarmThinAir, "warm_thin_air.yaml");
  ASSERT_TRUE(r.solver.ok);
  for (const char* p : {"p_tank", "p_cap", "p_rod"})
    for (double v : column(r.table, p)) EXPECT_NEAR(v, 95000.0, 1e-6) << p;
  for (const char* T : {"T_tank", "T_cap"})
    for (double v : column(r.table, T)) EXPECT_NEAR(v, 303.15, 1e-6) << T;
  for (double v : column(r.table, "x")) EXPECT_NEAR(v, 0.0, 1e-12);
  // The box starts at 30 degC, is fed 30 degC gas at its own pressure: no flow, no heating.
  for (double v : column(r.table, "T_box")) EXPECT_NEAR(v, 303.15, 1e-6);
}

TEST(AmbientDefaults, TheReferenceSaysTheDefaultIsTheAmbient) {
  const auto [rc, out] = run_cli("components volume");
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("p0 [Pa, absolute] default ambient pressure"), std::string::npos) << out;
  EXPECT_NE(out.find("T0 [K] default ambient temperature"), std::string::npos) << out;
}

}  // namespace
}  // namespace pneumo
