// End stops that hold the piston before the chamber they close is empty
// (components/cylinder_parts.hpp, StopHardening).
//
// What is asserted:
//  * the hardening's stored energy is the integral of its force (checked by
//    quadrature, on and past the tangent continuation), the force starts
//    with zero value and slope at half the reach and grows without bound
//    towards it;
//  * a hard impact of the movement-time rig of paper [2] (0.3 MPa gauge,
//    4.72 kg, 2.7 mm2 throttle: 2.87 m/s, 19.5 J into a 1e6 N/m bumper whose
//    linear spring would take 6.2 mm, past the cushion annulus' 2.76 mm)
//    runs to its end with the piston stopped inside the reach;
//  * the energy audit of that impact still balances, so the stop's stored
//    energy (E_stop) is the work its force did;
//  * a cylinder held against a soft stop (1e5 N/m) by 1.68 kN, whose linear
//    spring would take 16.8 mm past a cap dead volume 0.032 mm long, starts
//    at rest inside the reach, where the stop's force carries the load.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "components/builtin.hpp"
#include "components/cylinder_parts.hpp"
#include "framework/analysis/energy_audit.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using components::StopHardening;

// Midpoint quadrature of the hardening force from 0 to pen.
double work_of(double pen, double k, double reach) {
  const int n = 200000;
  const double h = pen / n;
  double w = 0;
  for (int i = 0; i < n; ++i) w += StopHardening::force((i + 0.5) * h, k, reach) * h;
  return w;
}

TEST(ProgressiveStop, ItsEnergyIsTheWorkOfItsForce) {
  const double k = 1e6, reach = 2.76e-3;
  for (double s : {0.4, 0.6, 0.9, 0.985, 0.9995}) {
    const double pen = s * reach;
    const double w = work_of(pen, k, reach);
    EXPECT_NEAR(StopHardening::energy(pen, k, reach), w, 1e-5 * std::max(w, 1e-9)) << "s = " << s;
  }
}

TEST(ProgressiveStop, StartsSmoothlyAtHalfTheReachAndHoldsBeforeIt) {
  const double k = 1e6, reach = 2e-3;
  EXPECT_EQ(StopHardening::force(0.5 * reach, k, reach), 0.0);
  // C1 at the start: force ~ k reach (ds)^2 / (1/4) just past it.
  const double ds = 1e-5;
  EXPECT_NEAR(StopHardening::force((0.5 + ds) * reach, k, reach), k * reach * 4 * ds * ds, 1e-3 * k * reach * 4 * ds * ds);
  // 13 k reach^2 of impact energy is absorbed before s = 0.985 ...
  EXPECT_GT(StopHardening::energy(0.985 * reach, k, reach), 13 * k * reach * reach);
  // ... and no finite energy reaches s = 1 on the curve's own branch.
  EXPECT_GT(StopHardening::energy(0.999 * reach, k, reach), 240 * k * reach * reach);
}

Netlist hard_impact_rig() {
  Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/movement_time_rig.yaml");
  apply_override(nl, "p_supply=0.3 MPag");
  apply_override(nl, "m_load=4.7222 kg");
  apply_override(nl, "A_throttle=2.7 mm2");
  return nl;
}

TEST(ProgressiveStop, AHardImpactStopsThePistonBeforeTheCushionVolumeIsEmpty) {
  const RunResult r = run_simulation(hard_impact_rig(), builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_NEAR(r.table.rows.back()[0], 8.0, 1e-9);  // ran to t_end
  const auto x = test_support::column(r.table, "x");
  const auto v = test_support::column(r.table, "v");
  const double stroke = 0.7, reach = 0.5e-6 / (components::kCylinderPi * (0.016 * 0.016 - 0.005 * 0.005) / 4);
  EXPECT_GT(*std::max_element(v.begin(), v.end()), 2.8);  // the impact is as hard as said
  const double pen = *std::max_element(x.begin(), x.end()) - stroke;
  EXPECT_GT(pen, 0.5 * reach);  // the hardening took part
  EXPECT_LT(pen, reach);
}

TEST(ProgressiveStop, TheAuditOfAHardImpactBalances) {
  const Netlist nl = hard_impact_rig();
  Circuit circuit = elaborate(nl, builtin_registry());
  const auto plans = prepare_energy_audit(nl, circuit);
  const RunResult r = run_circuit(std::move(circuit), solver_options(nl.simulation));
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const auto audits = energy_audit(plans, r);
  ASSERT_EQ(audits.size(), 1u);
  const EnergyAudit& a = audits[0];
  std::ostringstream s;
  print_audit(a, s);
  ASSERT_TRUE(a.opened) << s.str();
  EXPECT_GT(a.total_in, 19.0) << s.str();  // J: 1/2 4.72 kg (2.87 m/s)^2 and the driving work
  EXPECT_LT(std::abs(a.residual()), 1e-3 * a.total_in) << s.str();
}

TEST(ProgressiveStop, ACylinderHeldAgainstASoftStopStartsAtRestInsideTheReach) {
  const RunResult r = test_support::run_text(R"(
title: soft stop, small dead volume
ambient: {p: 101325 Pa, T: 293.15 K}
components:
  supply: {type: pressure_source, p: 6 bar g, T: 293.15 K}
  air:    {type: atmosphere}
  feed:   {type: iso6358_throttle, C: 1 dm3/(s*bar), b: 0.3}
  vent:   {type: iso6358_throttle, C: 1 dm3/(s*bar), b: 0.3}
  cyl:    {type: cylinder, bore: 63 mm, rod: 20 mm, stroke: 100 mm, stop_stiffness: 1e5 N/m,
           dead_volume_cap: 0.1 cm3, dead_volume_rod: 0.1 cm3, p0_rod: 6 bar g}
  load:   {type: translational_mass, m: 2 kg}
connections:
  - [supply.port, feed.a]
  - [feed.b, cyl.rod]
  - [cyl.cap, vent.a]
  - [vent.b, air.port]
  - [cyl.flange, load.flange]
outputs:
  x: cyl.x
  v: cyl.v
simulation: {t_end: 0.05 s, output_interval: 1 ms}
)",
                                             "soft_stop.yaml");
  ASSERT_TRUE(r.solver.ok);
  const double pi = components::kCylinderPi, A = pi * 0.063 * 0.063 / 4, A_rod = pi * 0.020 * 0.020 / 4;
  const double p_amb = 101325, F = 701325 * (A - A_rod) + p_amb * A_rod - p_amb * A;  // N, into the stop
  const double k = 1e5, reach = 0.1e-6 / A;
  const auto x = test_support::column(r.table, "x");
  const auto v = test_support::column(r.table, "v");
  const double pen = -x.front();
  EXPECT_GT(pen, 0.5 * reach);
  EXPECT_LT(pen, reach);
  EXPECT_NEAR(k * pen + StopHardening::force(pen, k, reach), F, 1e-6 * F);  // the stop carries the load
  for (std::size_t i = 0; i < x.size(); ++i) {
    EXPECT_NEAR(x[i], x.front(), 1e-12) << "t = " << r.table.rows[i][0];  // at rest
    EXPECT_LT(std::abs(v[i]), 1e-9);
  }
}

}  // namespace
}  // namespace pneumo
