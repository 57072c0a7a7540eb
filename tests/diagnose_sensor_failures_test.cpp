// A run the sensor advice cannot use says why (issue #31: run failures kept
// with their reason, never swallowed). Two tank fillings, hypothesis b with
// the second supply 0.1 bar higher; at the second operating point b's model
// has a throttle of negative conductance and does not run. That run is
// skipped with its reason, and the separation comes from the first alone:
// the second supply's node differs by exactly 1e4 Pa there.
#include <gtest/gtest.h>

#include "components/builtin.hpp"
#include "framework/diagnose/sensors.hpp"

namespace pneumo {
namespace {

std::string model(const std::string& p_supply2, const std::string& C2) {
  return "components:\n"
         "  supply1: {type: pressure_source, p: 6 bar, T: 293.15 K}\n"
         "  thr1: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}\n"
         "  tank1: {type: volume, V: 0.5 L, p0: 1 atm, T0: 293.15 K}\n"
         "  supply2: {type: pressure_source, p: " + p_supply2 + ", T: 293.15 K}\n"
         "  thr2: {type: iso6358_throttle, C: " + C2 + ", b: 0.3}\n"
         "  tank2: {type: volume, V: 0.5 L, p0: 1 atm, T0: 293.15 K}\n"
         "connections:\n  - [supply1.port, thr1.a]\n  - [thr1.b, tank1.port]\n"
         "  - [supply2.port, thr2.a]\n  - [thr2.b, tank2.port]\n"
         "outputs: {p1: tank1.p}\n"
         "simulation: {t_end: 0.5 s, output_interval: 5 ms}\n";
}

TEST(DiagnoseSensorFailures, ARunThatFailsIsSkippedWithItsReason) {
  const auto& reg = builtin_registry();
  const std::string ok = "0.2 dm3/(s*bar)";
  const std::vector<Netlist> a = {parse_netlist(model("5 bar", ok), "a.yaml"), parse_netlist(model("5 bar", ok), "a.yaml")};
  const std::vector<Netlist> b = {parse_netlist(model("5.1 bar", ok), "b.yaml"),
                                  parse_netlist(model("5.1 bar", "-0.2 dm3/(s*bar)"), "b.yaml")};
  const double sigma_p = 500.0;
  const auto c = diagnose::choose_sensor("low_supply", "high_supply", a, b, reg, diagnose::sensor_noise({{"Pa", sigma_p}}),
                                         {{"tank1.p", "p1"}}, 2);
  ASSERT_EQ(c.run_failures.size(), 1u);
  EXPECT_EQ(c.run_failures[0].rfind("run 2 of high_supply: ", 0), 0u) << c.run_failures[0];
  EXPECT_NE(c.run_failures[0].find("thr2"), std::string::npos) << c.run_failures[0];
  ASSERT_FALSE(c.best.empty());
  EXPECT_NEAR(c.best.front().separation, 1e4 / sigma_p, 1e-6);
}

}  // namespace
}  // namespace pneumo
