// The cylinders' declared fault friction_pressure (fault_friction_per_pressure,
// N/Pa): a running friction k |dp| against the motion, dp the pressure across
// the piston seal. A single-acting cylinder held at 5 bar gauge (a large
// supply port) and driven at a constant 20 mm/s: with k = 1e-5 N/Pa the drive
// needs k * 5e5 Pa = 5 N more against the motion, in either direction, and
// nothing at all with k = 0 beyond the law (here none). The cushioned
// cylinder's faults are the same part (components/cylinder_parts.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

std::string rig(double v, double k) {
  return R"(parameters: {k: )" + test_support::num(k) + R"(, v: )" + test_support::num(v) + R"(}
components:
  supply: {type: pressure_source, p: 5 barg}
  port: {type: iso6358_throttle, C: 5 dm3/(s*bar), b: 0.3}
  cyl: {type: single_acting_cylinder, bore: 25 mm, rod: 8 mm, stroke: 50 mm, spring_rate: 0 N/m,
        x0: 20 mm, p0_cap: 5 barg, fault_friction_per_pressure: k}
  drive: {type: velocity_source, v: v, s0: 20 mm}
connections:
  - [supply.port, port.a]
  - [port.b, cyl.cap]
  - [drive.flange, cyl.flange]
outputs:
  F: drive.F
  p: cyl.p_cap
simulation: {t_end: 0.5 s, output_interval: 10 ms}
)";
}

double force_at_end(double v, double k) {
  const RunResult r = test_support::run_text(rig(v, k), "pressure_friction.yaml");
  EXPECT_TRUE(r.solver.ok) << r.solver.message;
  return test_support::at(r.table, "F", 0.5);
}

double dp_at_end(double v) {
  const RunResult r = test_support::run_text(rig(v, 0), "pressure_friction.yaml");
  return test_support::at(r.table, "p", 0.5) - 101325.0;
}

TEST(PressureFrictionFault, AddsKTimesThePressureAcrossTheSealAgainstTheMotion) {
  for (double v : {0.02, -0.02}) {
    const double extra = force_at_end(v, 1e-5) - force_at_end(v, 0.0);
    const double expected = 1e-5 * dp_at_end(v) * (v > 0 ? 1.0 : -1.0);  // the drive pushes through the friction
    EXPECT_NEAR(extra, expected, 0.01 * std::abs(expected)) << "v = " << v;
    EXPECT_NEAR(std::abs(expected), 5.0, 0.2);  // 5 bar across the seal, 1 N/bar
  }
}

// A double-acting cylinder's seal of two lips (friction_chamber_pressure,
// 1/Pa): the whole law's force grows with the chambers' summed gauge
// pressure, not their difference. Coulomb 20 N + viscous 100 N*s/m, cap side
// 5 bar g, rod side 2 bar g, driven at 20 mm/s either way: m = 1e-6 1/Pa
// (10 % per bar) makes the friction 1 + m (5 + 2) bar = 1.7 times the law's.
std::string two_chambers(double v, const std::string& fault) {
  return R"(components:
  supply_cap: {type: pressure_source, p: 5 barg}
  supply_rod: {type: pressure_source, p: 2 barg}
  port_cap: {type: iso6358_throttle, C: 5 dm3/(s*bar), b: 0.3}
  port_rod: {type: iso6358_throttle, C: 5 dm3/(s*bar), b: 0.3}
  cyl: {type: cylinder, bore: 25 mm, rod: 8 mm, stroke: 50 mm, x0: 20 mm, p0_cap: 5 barg, p0_rod: 2 barg,
        friction_model: coulomb_viscous, friction_FC: 20 N, friction_viscous: 100 N*s/m)" +
         fault + R"(}
  drive: {type: velocity_source, v: )" + test_support::num(v) + R"(, s0: 20 mm}
connections:
  - [supply_cap.port, port_cap.a]
  - [port_cap.b, cyl.cap]
  - [supply_rod.port, port_rod.a]
  - [port_rod.b, cyl.rod]
  - [drive.flange, cyl.flange]
outputs: {F: cyl.F_friction, p_cap: cyl.p_cap, p_rod: cyl.p_rod}
simulation: {t_end: 0.5 s, output_interval: 10 ms}
)";
}

TEST(PressureFrictionFault, LipSealsScaleTheLawWithTheChambersSummedGaugePressure) {
  for (double v : {0.02, -0.02}) {
    const RunResult sound = test_support::run_text(two_chambers(v, ""), "lips.yaml");
    const RunResult lips =
        test_support::run_text(two_chambers(v, ", fault_friction_per_chamber_pressure: 1e-6"), "lips.yaml");
    ASSERT_TRUE(sound.solver.ok && lips.solver.ok);
    const double sum = test_support::at(sound.table, "p_cap", 0.5) + test_support::at(sound.table, "p_rod", 0.5) -
                       2 * 101325.0;
    const double F0 = test_support::at(sound.table, "F", 0.5);
    EXPECT_NEAR(std::abs(F0), 22.0, 0.01) << v;  // 20 N + 100 N*s/m x 20 mm/s
    EXPECT_NEAR(test_support::at(lips.table, "F", 0.5) / F0, 1 + 1e-6 * sum, 1e-6) << v;
    EXPECT_NEAR(1e-6 * sum, 0.7, 0.02);
  }
}

// The cushioned cylinder declares the same friction faults. On the cushion
// rig, 1 N/bar of pressure friction slows the stroke, dissipates more in the
// cushioning phase's friction, and the energy audit - which counts friction
// through the component's own force - still closes (to 1e-4 of its input).
double metric(const std::string& out, const std::string& name) {
  const auto at = out.find("metric " + name + " = ");
  EXPECT_NE(at, std::string::npos) << name << "\n" << out;
  return at == std::string::npos ? NAN : std::stod(out.substr(at + name.size() + 10));
}

TEST(PressureFrictionFault, OnTheCushionedCylinderItDissipatesAndTheAuditCloses) {
  test_support::TempDir dir;
  const std::string rig = std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml";
  const auto csv = (dir.path() / "rig.csv").string();
  const auto [rc0, sound] = test_support::run_cli("simulate '" + rig + "' -o '" + csv + "'");
  const auto [rc1, faulty] =
      test_support::run_cli("simulate '" + rig + "' -o '" + csv + "' --set cylinder.fault_friction_per_pressure=1e-5");
  ASSERT_EQ(rc0, 0) << sound;
  ASSERT_EQ(rc1, 0) << faulty;
  EXPECT_GT(metric(faulty, "t_move"), metric(sound, "t_move"));
  EXPECT_GT(metric(faulty, "E_friction_cushion"), metric(sound, "E_friction_cushion") + 0.005);  // J
  EXPECT_LT(std::abs(metric(faulty, "audit_residual")), 1e-4);
}

}  // namespace
}  // namespace pneumo
