// The seal author's own tests, written with pneumo's test kit
// (framework/testkit/testkit.hpp): the AD Jacobian against finite
// differences, and conservation of mass and energy in a closed circuit.
#include <gtest/gtest.h>

#include <cmath>

#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "framework/testkit/testkit.hpp"
#include "seal_leakage.hpp"

namespace {

using namespace pneumo;

const Registry& registry() {
  static const Registry r = testkit::with_builtin(seal_example::register_seal_leakage);
  return r;
}

// Leakage in both directions at once: from a high-pressure tank into the
// middle one, and from the middle one back towards a source at 3 bar that
// starts above it; the gas arrives at different temperatures.
const char* kSnippet = R"(
components:
  high:   {type: volume, V: 0.2 L, p0: 8 bar, T0: 330 K}
  seal1:  {type: seal_leakage, d: 20 mm, h: 20 um, L: 4 mm}
  middle: {type: volume, V: 0.1 L, p0: 2 bar, T0: 290 K}
  seal2:  {type: seal_leakage, d: 30 mm, h: 15 um, L: 6 mm}
  supply: {type: pressure_source, p: 3 bar, T: 310 K}
connections:
  - [high.port, seal1.a]
  - [seal1.b, middle.port]
  - [middle.port, seal2.b]
  - [seal2.a, supply.port]
simulation: {rtol: 1e-8, atol: 1e-8}
)";

TEST(SealLeakage, JacobianMatchesFiniteDifferences) {
  for (const auto& check : testkit::check_jacobian(kSnippet, registry(), 0.2))
    EXPECT_TRUE(check.passed(1e-5)) << check.report();
}

// Two insulated tanks joined only by the seal: nothing crosses the
// boundary, so total mass and total internal energy stay constant (the
// volumes integrate m and U, and the seal's flows enter both balances with
// opposite signs: conserved to rounding, asserted 1e-12). The end pressure
// follows from energy conservation alone: p = (p1 V1 + p2 V2)/(V1 + V2).
TEST(SealLeakage, ConservesMassAndEnergyBetweenClosedTanks) {
  const char* text = R"(
components:
  a:    {type: volume, V: 0.1 L, p0: 6 bar, T0: 320 K}
  seal: {type: seal_leakage, d: 20 mm, h: 30 um, L: 4 mm}
  b:    {type: volume, V: 0.3 L, p0: 1 bar, T0: 280 K}
connections:
  - [a.port, seal.a]
  - [seal.b, b.port]
outputs: {p_a: a.p, p_b: b.p}
simulation: {t_end: 20 s, rtol: 1e-8, atol: 1e-8, output_interval: 0.1 s}
)";
  const auto checks = testkit::check_conservation(text, registry(), {testkit::mass_of({"a", "b"}),
                                                                     testkit::energy_of({"a", "b"})});
  for (const auto& c : checks) EXPECT_TRUE(c.passed(1e-12)) << c.report();

  const RunResult end = run_simulation(parse_netlist(text, "closed.yaml"), registry());
  ASSERT_TRUE(end.solver.ok) << end.solver.message;
  const auto& last = end.table.rows.back();
  const double p_f = (6e5 * 0.1 + 1e5 * 0.3) / 0.4;
  EXPECT_NEAR(last[end.table.column("p_a")], p_f, 1e-5 * p_f);
  EXPECT_NEAR(last[end.table.column("p_b")], p_f, 1e-5 * p_f);
}

}  // namespace
