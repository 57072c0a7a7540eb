// The plain double-acting cylinder (`cylinder`) and the single-acting
// cylinder, each against a fact that does not come from the code under test:
//   * meter-out speed control: at steady speed the rod-side pressure holds
//     the force balance p_cap A = p_rod (A - A_rod) + p_amb A_rod + d v, and the
//     piston moves at the throttle's volume flow (ISO 6358 at that pressure)
//     over the annulus area, within 5 %;
//   * conventions: x = 0 retracted, x = stroke extended, events tagged
//     "extended" at the stroke's end; the flange position equals x; the
//     example circuit (5/2 valve, meter-out, silencer) extends, waits and
//     retracts in that order;
//   * end cushioning: with the needle closed further the piston arrives at
//     the end slower; the cushioned end's energy audit balances (energy in
//     = where it went, to 1e-4 of the input) at either end, with the
//     kinetic energy at entry 1/2 m v^2 of the load;
//   * single-acting: the spring alone returns the piston (without it, the
//     piston stays); at rest the spring and pressure forces balance (closed
//     form for a vented spring chamber, the observed pressures for a closed
//     one).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "framework/analysis/energy_audit.hpp"
#include "framework/assembly/system.hpp"
#include "framework/core/error.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

constexpr double kPi = 3.14159265358979323846;

// Supply through a large valve on the cap port, the rod side exhausted
// through a meter-out throttle (`retract`: the other way round); both
// chambers start at supply pressure (the valve has just switched), the
// piston at rest retracted unless `cylinder_extra` sets x0. Viscous friction
// damps the gas spring's oscillation, so the speed settles. `more` adds
// components, `more_connections` connections.
std::string meter_out_circuit(const std::string& cylinder_extra, bool retract = false, const std::string& more = "",
                              const std::string& more_connections = "") {
  const std::string driven = retract ? "rod" : "cap", metered = retract ? "cap" : "rod";
  return R"(
ambient: {p: 101325 Pa, T: 293.15 K}
components:
  supply:    {type: pressure_source, p: 6 bar, T: 293.15 K}
  valve:     {type: iso6358_throttle, C: 2 dm3/(s*bar), b: 0.3}
  meter_out: {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.3}
  exhaust:   {type: atmosphere}
  load:      {type: translational_mass, m: 2 kg}
  cyl:       {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 200 mm, p0_cap: 6 bar, p0_rod: 6 bar,
              friction_model: coulomb_viscous, friction_viscous: 200 N*s/m)" +
         cylinder_extra + "}\n" + more + R"(
connections:
  - [supply.port, valve.a]
  - [valve.b, cyl.)" + driven + R"(]
  - [cyl.)" + metered + R"(, meter_out.a]
  - [meter_out.b, exhaust.port]
  - [cyl.flange, load.flange]
)" + more_connections + R"(
outputs:
  x: cyl.x
  v: cyl.v
  s: load.s
  p_rod: cyl.p_rod
  p_cap: cyl.p_cap
  T_rod: cyl.T_rod
simulation: {t_end: 2.5 s, output_interval: 1 ms}
)";
}

// First time at which column `name` reaches `level` (linear between rows).
double crossing(const ResultsTable& t, const std::string& name, double level) {
  const auto time = column(t, "t");
  const auto y = column(t, name);
  for (std::size_t k = 1; k < y.size(); ++k)
    if (y[k - 1] < level && y[k] >= level) return time[k - 1] + (level - y[k - 1]) / (y[k] - y[k - 1]) * (time[k] - time[k - 1]);
  return std::nan("");
}

TEST(PlainCylinder, MeterOutSpeedFollowsTheThrottleFlowLaw) {
  const RunResult r = run_text(meter_out_circuit(""), "meter_out.yaml");
  const double A = kPi * 0.032 * 0.032 / 4, A_rod = kPi * 0.012 * 0.012 / 4, A_ann = A - A_rod;
  // Mean speed over the middle of the stroke, from the crossing times.
  const double t1 = crossing(r.table, "x", 0.10), t2 = crossing(r.table, "x", 0.16);
  ASSERT_TRUE(std::isfinite(t1) && std::isfinite(t2));
  const double v_mean = 0.06 / (t2 - t1);
  const double t_mid = 0.5 * (t1 + t2);
  double p_rod = 0, T_rod = 0, p_cap = 0;
  {
    const auto time = column(r.table, "t");
    const auto k = std::lower_bound(time.begin(), time.end(), t_mid) - time.begin();
    p_rod = column(r.table, "p_rod")[k];
    T_rod = column(r.table, "T_rod")[k];
    p_cap = column(r.table, "p_cap")[k];
    EXPECT_NEAR(column(r.table, "s")[k], column(r.table, "x")[k], 1e-12);  // flange position = x
  }
  // Force balance at constant speed: viscous friction, no load force.
  const double p_amb = 101325;
  EXPECT_GT(p_cap, 0.99 * 6e5);  // the supply valve is large
  const double p_rod_balance = (p_cap * A - p_amb * A_rod - 200 * v_mean) / A_ann;
  EXPECT_NEAR(p_rod, p_rod_balance, 0.005 * p_rod_balance);
  // ISO 6358 at the balance pressure: choked (p_amb / p_rod < b).
  ASSERT_LT(p_amb / p_rod_balance, 0.3);
  const double C = 0.1e-3 / 1e5, rho_ref = 1.185, T_ref = 293.15, R = 287.05;
  const double m_flow = C * rho_ref * p_rod_balance * std::sqrt(T_ref / T_rod);
  const double v_law = m_flow * R * T_rod / p_rod_balance / A_ann;
  std::printf("meter-out: v_mean %.5f m/s, flow law %.5f m/s (%.2f %%); p_rod %.4g Pa, balance %.4g Pa\n", v_mean,
              v_law, 100 * (v_mean / v_law - 1), p_rod, p_rod_balance);
  EXPECT_NEAR(v_mean, v_law, 0.05 * v_law);
  // It reaches the end of the stroke: an "extended" event near x = stroke.
  bool extended = false;
  for (const auto& ev : r.solver.events) extended = extended || (ev.component == "cyl" && ev.tag == "extended");
  EXPECT_TRUE(extended);
  EXPECT_NEAR(column(r.table, "x").back(), 0.2, 1e-4);
}

TEST(PlainCylinder, CushioningBrakesTheEndOfTheStroke) {
  // The same stroke into a cushioned rod end, needle nearly closed versus
  // wide open: the closed needle arrives later and slower at the stop.
  const std::string cushion =
      ", rod_cushion_length: 20 mm, rod_plug_diameter: 18 mm, rod_cushion_C: ";
  const RunResult open = run_text(meter_out_circuit(cushion + "1 dm3/(s*bar)"), "cushion_open.yaml");
  const RunResult shut = run_text(meter_out_circuit(cushion + "0.02 dm3/(s*bar)"), "cushion_shut.yaml");
  auto impact = [](const RunResult& r) {
    for (const auto& ev : r.solver.events)
      if (ev.component == "cyl" && ev.tag == "extended") return ev.t;
    return std::nan("");
  };
  auto entry = [](const RunResult& r) {
    for (const auto& ev : r.solver.events)
      if (ev.component == "cyl" && ev.tag == "rod_cushion_entry") return ev.t;
    return std::nan("");
  };
  ASSERT_TRUE(std::isfinite(entry(open)) && std::isfinite(entry(shut)));
  EXPECT_NEAR(entry(open), entry(shut), 1e-3);  // same main stroke
  const double dt_open = impact(open) - entry(open), dt_shut = impact(shut) - entry(shut);
  std::printf("cushion zone crossed in %.4f s (needle open) and %.4f s (nearly shut)\n", dt_open, dt_shut);
  EXPECT_GT(dt_shut, 1.5 * dt_open);
}

TEST(PlainCylinder, MeterOutCircuitExtendsWaitsAndRetracts) {
  // netlists/meter_out_cylinder.yaml: the valve switches at 0.1 s and back
  // at 2 s; the cylinder reaches each end in between, in that order.
  const RunResult r =
      run_text(read_file(std::string(PNEUMO_SOURCE_DIR) + "/netlists/meter_out_cylinder.yaml"), "meter_out_cylinder");
  std::vector<std::string> order;
  for (const auto& ev : r.solver.events)
    if (ev.tag == "switched_on" || ev.tag == "switched_off" || ev.tag == "extended" || ev.tag == "retracted")
      order.push_back(ev.component + "." + ev.tag);
  const std::vector<std::string> expected = {"valve.switched_on", "cyl.extended", "valve.switched_off",
                                             "cyl.retracted"};
  EXPECT_EQ(order, expected);
  EXPECT_NEAR(at(r.table, "x", 1.9), 0.1, 1e-4);
  EXPECT_NEAR(column(r.table, "x").back(), 0.0, 1e-4);
}

TEST(PlainCylinder, IncompleteCushioningIsAnInputErrorAtItsLine) {
  // A cushioning length without the plug's diameter: the error names the
  // file and line, the component and the missing parameter.
  const std::string text = meter_out_circuit(", cap_cushion_length: 20 mm, cap_cushion_C: 0.05 dm3/(s*bar)");
  try {
    System system(elaborate(parse_netlist(text, "incomplete.yaml"), builtin_registry()));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.component(), "cyl");
    EXPECT_EQ(e.parameter(), "cap_plug_diameter");
    EXPECT_NE(std::string(e.what()).find("incomplete.yaml:9"), std::string::npos) << e.what();
  }
}

// The audit of the cushioned end of `text` (one audit), printed.
EnergyAudit audit_of(const std::string& text, const std::string& name) {
  Netlist nl = parse_netlist(text, name);
  Circuit circuit = elaborate(nl, builtin_registry());
  const auto plans = prepare_energy_audit(nl, circuit);
  const RunResult r = run_circuit(std::move(circuit), solver_options(nl.simulation));
  EXPECT_TRUE(r.solver.ok) << r.solver.message;
  const auto audits = energy_audit(plans, r);
  EXPECT_EQ(audits.size(), 1u);
  if (audits.empty()) return {};
  std::ostringstream s;
  print_audit(audits[0], s);
  std::printf("%s", s.str().c_str());
  return audits[0];
}

double audit_term(const std::vector<AuditTerm>& terms, const std::string& name) {
  for (const auto& t : terms)
    if (t.name == name) return t.joules;
  ADD_FAILURE() << "no audit term " << name;
  return NAN;
}

TEST(PlainCylinder, CushionEnergyAuditBalancesAtEitherEnd) {
  // Extending into the rod-end cushion.
  const EnergyAudit rod = audit_of(
      meter_out_circuit(", rod_cushion_length: 20 mm, rod_plug_diameter: 18 mm, rod_cushion_C: 0.05 dm3/(s*bar)"),
      "audit_rod.yaml");
  ASSERT_TRUE(rod.opened);
  EXPECT_EQ(rod.title, "rod-end cushioning");
  EXPECT_LT(std::abs(rod.residual()), 1e-4 * rod.total_in);
  EXPECT_NEAR(audit_term(rod.in, "kinetic_energy_at_entry"), 0.5 * 2 * rod.speed_at_open * rod.speed_at_open, 1e-12);
  // Retracting into the cap-end cushion, with wall heat.
  const EnergyAudit cap = audit_of(
      meter_out_circuit(", x0: 200 mm, cap_cushion_length: 20 mm, cap_plug_diameter: 16 mm, "
                        "cap_cushion_C: 0.05 dm3/(s*bar), wall_alpha: 100 W/(m2*K), friction_FC: 10 N",
                        true, "  wall: {type: thermal_mass, C: 50 J/K, T0: 293.15 K}", "  - [cyl.heat_cap, wall.port]"),
      "audit_cap.yaml");
  ASSERT_TRUE(cap.opened);
  EXPECT_EQ(cap.title, "cap-end cushioning");
  EXPECT_LT(std::abs(cap.residual()), 1e-4 * cap.total_in);
  EXPECT_GT(audit_term(cap.out, "heat_to_walls"), 0.0);  // compression-heated cushion gas
  EXPECT_GT(audit_term(cap.out, "cushion_gas_compression"), 0.0);
}

// A single-acting cylinder, bore 20 mm, rod 8 mm, stroke 50 mm; `cap` is
// the component on its cap port through a throttle.
std::string single_acting(const std::string& cylinder_extra, const std::string& cap_source, double t_end) {
  return R"(
ambient: {p: 101325 Pa, T: 293.15 K}
components:
  source:   )" + cap_source + R"(
  throttle: {type: iso6358_throttle, C: 0.5 dm3/(s*bar), b: 0.3}
  load:     {type: translational_mass, m: 0.3 kg}
  cyl:      {type: single_acting_cylinder, bore: 20 mm, rod: 8 mm, stroke: 50 mm, friction_model: coulomb_viscous,
             friction_viscous: 20 N*s/m)" + cylinder_extra + R"(}
connections:
  - [source.port, throttle.a]
  - [throttle.b, cyl.cap]
  - [cyl.flange, load.flange]
outputs:
  x: cyl.x
  p_cap: cyl.p_cap
  p_rod: cyl.p_rod
  F_spring: cyl.F_spring
simulation: {t_end: )" + num(t_end) + R"( s}
)";
}

TEST(SingleActingCylinder, ReturnsUnderItsSpringAlone) {
  // Extended at the start, cap side vented: the spring brings it home; the
  // same cylinder without a spring stays where it is.
  const std::string vent = "{type: atmosphere}";
  const RunResult sprung = run_text(
      single_acting(", spring_preload: 10 N, spring_rate: 200 N/m, x0: 45 mm", vent, 1.0), "sprung.yaml");
  const RunResult loose =
      run_text(single_acting(", spring_preload: 0 N, spring_rate: 0 N/m, x0: 45 mm", vent, 1.0), "loose.yaml");
  bool retracted = false;
  for (const auto& ev : sprung.solver.events) retracted = retracted || ev.tag == "retracted";
  EXPECT_TRUE(retracted);
  EXPECT_NEAR(column(sprung.table, "x").back(), 0.0, 1e-5);
  EXPECT_NEAR(column(loose.table, "x").back(), 0.045, 1e-9);
}

TEST(SingleActingCylinder, AtRestSpringAndPressureForcesBalance) {
  const double A = kPi * 0.02 * 0.02 / 4, A_rod = kPi * 0.008 * 0.008 / 4, p_amb = 101325, p_s = 3e5;
  const double F0 = 20, k = 2000;
  const std::string supply = "{type: pressure_source, p: 3 bar, T: 293.15 K}";
  // Vented: the closed form x = ((p_s - p_amb) A - F0) / k.
  const RunResult vented = run_text(single_acting(", spring_preload: 20 N, spring_rate: 2000 N/m", supply, 3.0),
                                    "vented.yaml");
  const double x_eq = ((p_s - p_amb) * A - F0) / k;
  std::printf("single-acting at rest: x %.9f m, closed form %.9f m\n", column(vented.table, "x").back(), x_eq);
  EXPECT_NEAR(column(vented.table, "x").back(), x_eq, 1e-6 * x_eq);
  // Closed spring chamber: its gas spring joins the balance.
  const RunResult closed = run_text(
      single_acting(", spring_preload: 20 N, spring_rate: 2000 N/m, spring_chamber: closed", supply, 3.0),
      "closed.yaml");
  const double x = column(closed.table, "x").back(), p_cap = column(closed.table, "p_cap").back();
  const double p_rod = column(closed.table, "p_rod").back();
  const double imbalance = p_cap * A - p_rod * (A - A_rod) - p_amb * A_rod - (F0 + k * x);
  std::printf("closed spring chamber at rest: x %.6f m, p_rod %.6g Pa, force imbalance %.3g N\n", x, p_rod, imbalance);
  EXPECT_LT(x, x_eq - 1e-3);    // the trapped air pushes back
  EXPECT_GT(p_rod, 1.05 * p_amb);
  EXPECT_NEAR(imbalance, 0.0, 1e-6 * p_cap * A);
}

}  // namespace
}  // namespace pneumo
