// A piston seal's presliding (friction_presliding, m; components/
// cylinder_parts.hpp SealPresliding): the seal deforms before it slides, so
// the friction's sign is replaced
// by an engagement w with dw/dx = sign(v) - w over the distance x0 (Dahl's
// model): from rest the law's force is reached as 1 - exp(-travel / x0),
// after a reversal it turns as -1 + (1 + w0) exp(-travel / x0) and crosses
// zero at a travel of x0 ln(1 + w0). Coulomb 20 N (no viscous part),
// x0 = 0.5 mm, the rod driven at 10 mm/s.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

constexpr double kFC = 20.0, kX0 = 0.5e-3, kV = 0.01, kReverseAt = 0.3;

// `type` a single-acting (vented) or a double-acting cylinder, both ports to
// the atmosphere; the drive reverses at kReverseAt.
std::string rig(const std::string& type, double x0, const std::string& more = "") {
  const bool single = type == "single_acting_cylinder";
  return std::string(R"(components:
  air: {type: pressure_source, p: 1 atm}
  port_cap: {type: iso6358_throttle, C: 5 dm3/(s*bar), b: 0.3}
)") + (single ? "" : "  port_rod: {type: iso6358_throttle, C: 5 dm3/(s*bar), b: 0.3}\n") + R"(  cyl: {type: )" + type + R"(, bore: 25 mm, rod: 8 mm, stroke: 50 mm, x0: 20 mm,)" +
         (single ? " spring_rate: 0 N/m," : "") + R"(
        friction_model: coulomb_viscous, friction_FC: 20 N, friction_v_reg: 0.1 mm/s,
        friction_presliding: )" + test_support::num(x0) + more + R"(}
  speed: {type: signal_source, kind: step, value: 0.01, height: -0.02, t_start: 0.3}
  drive: {type: velocity_source, s0: 20 mm}
connections:
  - [air.port, port_cap.a]
  - [port_cap.b, cyl.cap]
)" + (single ? "" : "  - [air.port, port_rod.a]\n  - [port_rod.b, cyl.rod]\n") +
         R"(  - [speed.y, drive.v_in]
  - [drive.flange, cyl.flange]
outputs: {F: cyl.F_friction}
simulation: {t_end: 0.45 s, output_interval: 1 ms}
)";
}

TEST(SealPresliding, TheFrictionBuildsOverTheDistanceAndTurnsOverItAtAReversal) {
  for (const std::string type : {"single_acting_cylinder", "cylinder"}) {
    const RunResult r = test_support::run_text(rig(type, kX0), "presliding.yaml");
    ASSERT_TRUE(r.solver.ok) << type << ": " << r.solver.message;
    // From rest: F = -F_C (1 - exp(-v t / x0)).
    for (double t : {0.01, 0.03, 0.05, 0.1, 0.2, 0.299})
      EXPECT_NEAR(test_support::at(r.table, "F", t), -kFC * (1 - std::exp(-kV * t / kX0)), 2e-3 * kFC)
          << type << " at t = " << t;
    // Reversed: w = -1 + (1 + w0) exp(-travel / x0), w0 = 1 - exp(-0.3 s v / x0),
    // zero at a travel of x0 ln(1 + w0).
    const double w0 = 1 - std::exp(-kV * kReverseAt / kX0), t_zero = kReverseAt + kX0 * std::log(1 + w0) / kV;
    const auto t = test_support::column(r.table, "t"), F = test_support::column(r.table, "F");
    double crossing = NAN;
    for (std::size_t i = 1; i < t.size(); ++i)
      if (t[i] > kReverseAt && F[i - 1] < 0 && F[i] >= 0) crossing = t[i - 1] + (t[i] - t[i - 1]) * -F[i - 1] / (F[i] - F[i - 1]);
    EXPECT_NEAR(crossing, t_zero, 0.5e-3) << type;  // 34.7 ms after the reversal
    EXPECT_NEAR(test_support::at(r.table, "F", 0.45), kFC * (1 - (1 + w0) * std::exp(-kV * 0.15 / kX0)), 2e-3 * kFC)
        << type;
  }
}

// Two elements (a generalised Maxwell-slip seal): 0.1 mm carrying 70 % of
// the force and 1 mm carrying 30 %, each engaging as 1 - exp(-travel / x_i).
TEST(SealPresliding, TwoElementsEngageEachOverItsOwnDistance) {
  const RunResult r = test_support::run_text(
      rig("cylinder", 0.1e-3, ", friction_presliding_slow: 1 mm, friction_presliding_slow_share: 0.3"),
      "presliding.yaml");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  for (double t : {0.01, 0.03, 0.1, 0.2, 0.299}) {
    const double x = kV * t;
    const double w = 0.7 * (1 - std::exp(-x / 0.1e-3)) + 0.3 * (1 - std::exp(-x / 1e-3));
    EXPECT_NEAR(test_support::at(r.table, "F", t), -kFC * w, 2e-3 * kFC) << "t = " << t;
  }
}

TEST(SealPresliding, WithoutItTheForceTurnsWithinTheLawsVelocityBand) {
  const RunResult r = test_support::run_text(rig("cylinder", 0.0), "presliding.yaml");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_NEAR(test_support::at(r.table, "F", 0.01), -kFC, 1e-6 * kFC);
  EXPECT_NEAR(test_support::at(r.table, "F", kReverseAt + 2e-3), kFC, 1e-6 * kFC);
}

}  // namespace
}  // namespace pneumo
