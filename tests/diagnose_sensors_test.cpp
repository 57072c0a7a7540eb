// Which sensor would decide (issue #19): two hypotheses that differ only in a
// part of the circuit no measured signal sees. A circuit of two independent
// tank fillings; only tank 1's pressure is measured; hypothesis b raises the
// second supply's pressure by 0.1 bar. The measured signal cannot separate
// them at all (the parts are integrated apart, so tank 1's trace is the same
// bit for bit), and the best sensor is one on the second supply's node, whose
// pressure differs by exactly 1e4 Pa all the time: 1e4 / sigma noise sd with
// sigma the measured pressure noise.
#include <gtest/gtest.h>

#include "components/builtin.hpp"
#include "framework/diagnose/sensors.hpp"

namespace pneumo {
namespace {

std::string model(const std::string& p_supply2) {
  return R"(
components:
  supply1: {type: pressure_source, p: 6 bar, T: 293.15 K}
  thr1: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  tank1: {type: volume, V: 0.5 L, p0: 1 atm, T0: 293.15 K}
  supply2: {type: pressure_source, p: )" + p_supply2 + R"(, T: 293.15 K}
  thr2: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  tank2: {type: volume, V: 0.5 L, p0: 1 atm, T0: 293.15 K}
connections:
  - [supply1.port, thr1.a]
  - [thr1.b, tank1.port]
  - [supply2.port, thr2.a]
  - [thr2.b, tank2.port]
outputs: {p1: tank1.p}
simulation: {t_end: 0.5 s, output_interval: 5 ms}
)";
}

TEST(DiagnoseSensors, TheUnmeasuredNodeThatDiffersIsChosenWithItsExactSeparation) {
  const auto& reg = builtin_registry();
  const std::vector<Netlist> a = {parse_netlist(model("5 bar"), "a.yaml")};
  const std::vector<Netlist> b = {parse_netlist(model("5.1 bar"), "b.yaml")};
  const double sigma_p = 500.0;  // the measured pressure signal's noise, Pa
  const auto noise = diagnose::sensor_noise({{"Pa", sigma_p}});
  const auto c = diagnose::choose_sensor("low_supply", "high_supply", a, b, reg, noise, {{"tank1.p", "p1"}}, 2);

  EXPECT_EQ(c.measured_signal, "p1");
  EXPECT_EQ(c.measured_separation, 0.0);
  ASSERT_FALSE(c.best.empty());
  const auto& s = c.best.front();
  EXPECT_EQ(s.unit, "Pa");
  EXPECT_TRUE(s.quantity.rfind("supply2.", 0) == 0 || s.quantity.rfind("thr2.a", 0) == 0) << s.quantity;
  EXPECT_NEAR(s.separation, 1e4 / sigma_p, 1e-6);
  // Tank 2 starts at the same pressure in both hypotheses, so it separates
  // them less than the supply node does, but it separates them.
  for (const auto& other : c.best)
    if (other.quantity == "tank2.p") {
      EXPECT_GT(other.separation, 1.0);
      EXPECT_LT(other.separation, s.separation);
    }
  EXPECT_NE(diagnose::sensor_sentence(c).find("a pressure sensor at"), std::string::npos);
}

}  // namespace
}  // namespace pneumo
