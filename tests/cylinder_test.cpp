// The cylinder, its friction laws and its energy bookkeeping, each against a
// physical fact that does not come from the code under test:
//   * gas spring: small oscillations at sqrt(kappa p A^2 / (m V)) (adiabatic
//     closed chambers), period from the zero crossings of v;
//   * friction presets: a friction_element driven at constant speed gives
//     the force of paper [1] eq. 7 / eq. 8 with the Annex B / Annex C
//     coefficients, typed into this test from the paper (an independent
//     transcription); the cylinder feeds eq. 8 with its chamber pressures;
//   * LuGre (paper [3] eq. 8): stick-slip at a low drive speed, none at a
//     high one, the steady sliding force F_C + (F_S - F_C) e^-(v/vS)^2 + s2 v,
//     and a piston that sticks under a force below the break-away force;
//   * energy: over a full cushioned stroke, enthalpy in + heat = change of
//     the gas's internal energy + p dV work, and that work = change of
//     kinetic energy - friction and stop work (adiabatic and with heat);
//   * the cushion entry is an event at x = stroke - cushion_length;
//   * rod-end cushioning brakes an extending stroke.
// Figures are printed so that the margins are visible in the test log.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/assembly/system.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

constexpr double kPi = 3.14159265358979323846;

using namespace test_support;

std::string rig_text() { return read_file(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml"); }

// Replaces one exact occurrence (the test fails if the text is not there).
std::string replace_once(std::string s, const std::string& from, const std::string& to) {
  const auto pos = s.find(from);
  EXPECT_NE(pos, std::string::npos) << "netlist text not found: " << from;
  if (pos != std::string::npos) s.replace(pos, from.size(), to);
  return s;
}

struct SimRun {
  RunResult r;
  std::vector<double> col(const std::string& name) const { return test_support::column(r.table, name); }
};

SimRun run(const std::string& yaml, const std::string& name) {
  SimRun out;
  out.r = run_simulation(parse_netlist(yaml, name + ".yaml"), builtin_registry());
  EXPECT_TRUE(out.r.solver.ok) << name << ": " << out.r.solver.message;
  return out;
}

// Trapezoid integral of y over t. The solver writes a row after each event
// (post-event values) but none just before it, and flows or stop forces
// jump at some events (valve step, stop contact); over an interval ending at
// an event row the pre-event value is extrapolated linearly from the two
// rows before, so that the jump does not smear over an output interval.
double integral(const std::vector<double>& t, const std::vector<double>& y, const std::vector<double>& events = {}) {
  double s = 0;
  for (std::size_t k = 1; k < t.size(); ++k) {
    const double h = t[k] - t[k - 1];
    if (h <= 0) continue;
    double y_end = y[k];
    const bool at_event = std::find(events.begin(), events.end(), t[k]) != events.end();
    if (at_event && k >= 2 && t[k - 1] > t[k - 2])
      y_end = y[k - 1] + (y[k - 1] - y[k - 2]) / (t[k - 1] - t[k - 2]) * h;
    s += 0.5 * (y[k - 1] + y_end) * h;
  }
  return s;
}

// ---------------------------------------------------------------------------
// Gas spring. The rod-side chamber of a cylinder with both ports closed is
// an adiabatic gas spring, stiffness kappa p A_A^2 / V_A; the cap side (a
// 1 m3 dead volume: nearly constant pressure) adds kappa p A_B^2 / V_cap,
// which is included although it is 1e-5 of the total. A force holds the
// piston in equilibrium; an initial velocity starts a 0.14 mm oscillation.
TEST(GasSpring, OscillatesAtAdiabaticFrequency) {
  const double bore = 0.032, rod = 0.012, plug = 0.016, x0 = 0.05, stroke = 0.1;
  const double A_B = kPi * bore * bore / 4, A_R = kPi * rod * rod / 4, A_A = A_B - A_R, A_CP = kPi * plug * plug / 4;
  const double p_A = 3e5, p_cap = 1e5, p_amb = 101325, kappa = 1.4, m = 1.0;
  const double V0_A = 3e-6, V0_EC = 1.0, V0_ch = 1e-6;
  const double V_A = V0_A + A_A * x0;
  const double V_cap = V0_EC + (A_B - A_CP) * (stroke - x0) + V0_ch + A_CP * (stroke - x0);
  const double F_hold = -(p_A * A_A + p_amb * A_R - p_cap * A_B);
  std::ostringstream y;
  y.precision(17);
  y << R"(
ambient: {p: 101325 Pa, T: 293.15 K}
gas: {R: 287.05 J/(kg*K), kappa: 1.4}
components:
  load: {type: translational_mass, m: 1 kg, v0: 0.01 m/s}
  hold: {type: force_source, F: )" << F_hold << R"(}
  cyl:
    type: cushioned_cylinder
    bore: 32 mm
    rod: 12 mm
    stroke: 100 mm
    plug_diameter: 16 mm
    cushion_length: 20 mm
    dead_volume_rod_side: 3.0e-6 m3
    dead_volume_cushion: 1 m3
    dead_volume_channel: 1.0e-6 m3
    bore_opening_C: 5.0 dm3/(s*bar)
    cushion_C_of_z: [[0, 0], [6, 0.4 dm3/(s*bar)]]
    z_EC: 1
    x0: 50 mm
    p0_A: 3 bar
    p0_cap: 1 bar
connections:
  - [cyl.flange, load.flange, hold.flange]
outputs:
  v: cyl.v
  x: cyl.x
simulation: {t_end: 1 s, rtol: 1e-9, atol: 1e-9, output_interval: 0.5 ms}
)";
  const SimRun r = run(y.str(), "gas_spring");
  const auto t = r.col("t"), v = r.col("v"), x = r.col("x");
  std::vector<double> up;  // upward zero crossings of v, interpolated
  for (std::size_t k = 1; k < t.size(); ++k)
    if (v[k - 1] < 0 && v[k] >= 0) up.push_back(t[k - 1] + (t[k] - t[k - 1]) * (-v[k - 1]) / (v[k] - v[k - 1]));
  ASSERT_GE(up.size(), 8u);
  const double T_meas = (up.back() - up.front()) / static_cast<double>(up.size() - 1);
  const double k = kappa * p_A * A_A * A_A / V_A + kappa * p_cap * A_B * A_B / V_cap;
  const double T_closed = 2 * kPi / std::sqrt(k / m);
  const double amp = *std::max_element(x.begin(), x.end()) - x0;
  std::cout << "gas spring: period " << T_meas << " s, closed form " << T_closed << " s, deviation "
            << (T_meas / T_closed - 1) * 100 << " %, amplitude " << amp * 1e3 << " mm\n";
  EXPECT_NEAR(T_meas / T_closed, 1.0, 0.01);
  EXPECT_LT(amp, 2e-4);  // small amplitude indeed
}

// ---------------------------------------------------------------------------
// Friction presets at constant speed. Coefficients typed from paper [1],
// Annex B (eq. 7) and Annex C (eq. 8), independently of components/friction.cpp.
struct Eq8 {
  double b0, b1, FS0, FS1, FC, vS, kv0, kv1, a;
  double operator()(double v, double p_bar) const {
    return b0 + b1 * p_bar + (FS0 + FS1 * p_bar - FC) * std::exp(-v / vS) + (kv0 + kv1 * p_bar) * std::pow(v, a);
  }
};

// One friction_element per (preset, pressure, speed), each dragged by its own
// velocity source; the forces are read after 1 ms.
void check_presets(const std::vector<std::pair<std::string, Eq8>>& sets, const std::vector<double>& pressures_bar) {
  const std::vector<double> speeds = {0.002, 0.01, 0.05, 0.2, 0.5};
  std::ostringstream y;
  y.precision(17);
  y << "components:\n";
  std::vector<std::string> out_names;
  std::vector<double> expected;
  int n = 0;
  for (const auto& [name, eq] : sets)
    for (double p : pressures_bar)
      for (double v : speeds) {
        const std::string id = std::to_string(n++);
        y << "  d" << id << ": {type: velocity_source, v: " << v << "}\n";
        y << "  f" << id << ": {type: friction_element, friction: " << name << ", pressure: " << p << " bar}\n";
        out_names.push_back("F" + id);
        expected.push_back(-eq(v, p));
      }
  y << "connections:\n";
  for (int i = 0; i < n; ++i) y << "  - [d" << i << ".flange, f" << i << ".flange]\n";
  y << "outputs:\n";
  for (int i = 0; i < n; ++i) y << "  F" << i << ": f" << i << ".F\n";
  y << "simulation: {t_end: 1 ms, output_interval: 1 ms}\n";
  const SimRun r = run(y.str(), "presets");
  double worst = 0;
  for (int i = 0; i < n; ++i) {
    const double F = r.col(out_names[i]).back();
    worst = std::max(worst, std::abs(F - expected[i]) / std::abs(expected[i]));
    EXPECT_NEAR(F, expected[i], 1e-6 * std::abs(expected[i])) << out_names[i];
  }
  std::cout << n << " preset points, worst relative deviation from the paper's formula " << worst << "\n";
}

TEST(FrictionPresets, AnnexBEquation7AtConstantSpeed) {
  // p0 [bar_rel]: b, F_FS, F_FC, v_S, k_v, a (Annex B)
  auto eq7 = [](double b, double FS, double FC, double vS, double kv, double a) {
    return Eq8{b, 0, FS, 0, FC, vS, kv, 0, a};
  };
  check_presets({{"annexB_2.07", eq7(5.447, 20.46, 5.94, 0.00367, 102.5, 0.6796)},
                 {"annexB_3.127", eq7(2.824, 22.59, 5.273, 0.004483, 106.1, 0.7018)},
                 {"annexB_4.115", eq7(1.468, 25.78, 6.407, 0.004925, 123.7, 0.6513)},
                 {"annexB_5.14", eq7(2.776, 25.05, 4.31, 0.004033, 128.7, 0.6843)},
                 {"annexB_6.13", eq7(2.509, 25.51, 3.855, 0.003434, 140.8, 0.662)},
                 {"annexB_7.085", eq7(1.274, 32.95, 7.864, 0.005579, 147.6, 0.6468)},
                 {"annexB_8.075", eq7(-1.17, 31.08, 5.856, 0.005311, 158.8, 0.6317)}},
                {0.0});
}

TEST(FrictionPresets, AnnexCEquation8AtConstantSpeedAndPressure) {
  check_presets({{"annexC_pAB-", Eq8{-0.67, -4.4, 21.64, 11.78, 5.08, 4.16e-3, 49.9, 43.41, 0.429}},
                 {"annexC_pAB+", Eq8{5.63, -0.1, 17.06, 0.714, 5.4, 3.98e-3, 87.46, 6.1, 0.746}},
                 {"annexC_pEC", Eq8{9.66, 0.26, 8.8, 2.197, 8.8, 2.96e-3, 121, 19.61, 1.0}}},
                {0.5, 2.0, 4.0, 6.0});
}

// In the cylinder the eq. 8 pressure is the chamber pressure sum p_AB+ =
// (p_A - p_amb) + (p_EC - p_amb): the basic rig with annexC_pAB+, checked at
// every main-stroke sample (bore fully open, moving faster than 5 mm/s).
TEST(FrictionPresets, CylinderFeedsEquation8WithChamberPressures) {
  std::string y = replace_once(rig_text(), "friction: annexB_5.14", "friction: annexC_pAB+");
  y = replace_once(y, "  p_ch: cylinder.p_ch", "  p_ch: cylinder.p_ch\n  F_fr: cylinder.F_friction\n  open: cylinder.bore_open");
  y = replace_once(y, "t_end: 1.2 s", "t_end: 0.3 s");
  const SimRun r = run(y, "rig_annexC");
  const auto v = r.col("v"), pA = r.col("p_A"), pEC = r.col("p_EC"), F = r.col("F_fr"), open = r.col("open");
  const Eq8 eq{5.63, -0.1, 17.06, 0.714, 5.4, 3.98e-3, 87.46, 6.1, 0.746};
  int checked = 0;
  double worst = 0;
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (open[k] < 1.0 || std::abs(v[k]) < 5e-3) continue;
    const double p_bar = (pA[k] - 101325 + pEC[k] - 101325) / 1e5;
    const double expected = -(v[k] > 0 ? 1 : -1) * eq(std::abs(v[k]), p_bar);
    worst = std::max(worst, std::abs(F[k] - expected) / std::abs(expected));
    EXPECT_NEAR(F[k], expected, 1e-6 * std::abs(expected));
    ++checked;
  }
  std::cout << "cylinder eq. 8 (pAB+): " << checked << " samples, worst relative deviation " << worst << "\n";
  EXPECT_GT(checked, 100);
}

// ---------------------------------------------------------------------------
// LuGre: a 1 kg body on LuGre friction pulled through a 2 N/m spring whose
// far end moves at v_d (the classic example of Canudas de Wit et al. 1995,
// F_C = 1 N, F_S = 1.5 N, v_S = 1 mm/s, sigma0 = 1e5 N/m, sigma1 = 316 N s/m,
// sigma2 = 0.4 N s/m).
std::string lugre_rig(double v_drive, double t_end) {
  std::ostringstream y;
  y << R"(
components:
  drive:  {type: velocity_source, v: )" << v_drive << R"(}
  spring: {type: spring_damper, k: 2 N/m, d: 0, L0: 0}
  body:   {type: translational_mass, m: 1 kg, s0: 0, v0: 0}
  fric:   {type: friction_element, friction_model: lugre, friction_FC: 1 N, friction_FS: 1.5 N,
           friction_vS: 0.001 m/s, friction_sigma0: 1e5 N/m, friction_sigma1: 316 N*s/m,
           friction_viscous: 0.4 N*s/m}
connections:
  - [spring.a, body.flange, fric.flange]
  - [spring.b, drive.flange]
outputs:
  v: body.v
  F: spring.F
simulation: {t_end: )" << t_end << R"(, rtol: 1e-7, atol: 1e-7, output_interval: 5 ms}
)";
  return y.str();
}

TEST(LuGre, StickSlipAtLowDriveSpeed) {
  const double v_d = 0.1;
  const SimRun r = run(lugre_rig(v_d, 30.0), "lugre_slow");
  const auto t = r.col("t"), v = r.col("v"), F = r.col("F");
  // Count sticks: the velocity falls below 1 % of the drive speed after
  // having slipped faster than the drive.
  int sticks = 0;
  bool slipping = false;
  double F_peak = 0, F_trough = 1e9;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (v[k] > v_d) slipping = true;
    if (slipping && std::abs(v[k]) < 0.01 * v_d) {
      ++sticks;
      slipping = false;
    }
    if (t[k] > 5) {
      F_peak = std::max(F_peak, F[k]);
      F_trough = std::min(F_trough, F[k]);
    }
  }
  std::cout << "LuGre v_d = 0.1 m/s: " << sticks << " sticks in 30 s, spring force saw-tooth " << F_trough << " .. "
            << F_peak << " N\n";
  EXPECT_GE(sticks, 3);
  // Saw-tooth: it breaks away near F_S (the drive loads the spring slowly)
  // and drops well below F_C.
  EXPECT_NEAR(F_peak, 1.5, 0.05);
  EXPECT_LT(F_trough, 0.9);
}

TEST(LuGre, NoStickSlipAtHighDriveSpeed) {
  const double v_d = 1.0;
  const SimRun r = run(lugre_rig(v_d, 30.0), "lugre_fast");
  const auto t = r.col("t"), v = r.col("v"), F = r.col("F");
  double v_min_after_breakaway = 1e9, dev_late = 0;
  bool moving = false;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (v[k] > 0.5 * v_d) moving = true;
    if (moving) v_min_after_breakaway = std::min(v_min_after_breakaway, v[k]);
    if (t[k] > 20) dev_late = std::max(dev_late, std::abs(v[k] - v_d));
  }
  // Steady sliding: the spring carries the LuGre steady-state force
  // g(v_d) + sigma2 v_d (z settles at g(v)/sigma0 sign v).
  const double F_ss = 1.0 + 0.5 * std::exp(-(v_d / 0.001) * (v_d / 0.001)) + 0.4 * v_d;
  std::cout << "LuGre v_d = 1 m/s: min v after break-away " << v_min_after_breakaway << " m/s, |v - v_d| <= " << dev_late
            << " after 20 s, final spring force " << F.back() << " N (steady state " << F_ss << ")\n";
  EXPECT_GT(v_min_after_breakaway, 0.3 * v_d);  // never sticks again
  EXPECT_LT(dev_late, 0.05 * v_d);
  EXPECT_NEAR(F.back(), F_ss, 0.01 * F_ss);
}

// ---------------------------------------------------------------------------
// The rig's cylinder as a horizontal drive: a piston with LuGre friction
// (F_S = 60 N) under a net pressure force of 40 N must stay put; 80 N moves it.
std::string lugre_piston(double p_cap_bar) {
  std::ostringstream y;
  y << R"(
ambient: {p: 101325 Pa, T: 293.15 K}
components:
  load: {type: translational_mass, m: 2 kg}
  cyl:
    type: cushioned_cylinder
    bore: 32 mm
    rod: 12 mm
    stroke: 100 mm
    plug_diameter: 16 mm
    cushion_length: 20 mm
    dead_volume_rod_side: 3.0e-6 m3
    dead_volume_cushion: 2.0e-6 m3
    dead_volume_channel: 1.0e-6 m3
    bore_opening_C: 5.0 dm3/(s*bar)
    cushion_C_of_z: [[0, 0], [6, 0.4 dm3/(s*bar)]]
    z_EC: 1
    x0: 50 mm
    p0_A: 101325 Pa
    p0_cap: )" << p_cap_bar << R"( bar
    friction_model: lugre
    friction_FC: 40 N
    friction_FS: 60 N
    friction_vS: 0.005 m/s
    friction_sigma0: 1e6 N/m
    friction_sigma1: 2000 N*s/m
    friction_viscous: 50 N*s/m
connections:
  - [cyl.flange, load.flange]
outputs:
  x: cyl.x
  v: cyl.v
  F_fr: cyl.F_friction
  F_p: cyl.F_pressure
simulation: {t_end: 0.5 s, rtol: 1e-7, atol: 1e-7, output_interval: 1 ms}
)";
  return y.str();
}

TEST(LuGre, PistonSticksBelowBreakAwayForce) {
  // Net pressure force towards x = 0: (p_cap - p_amb) A_B (ports closed:
  // the chambers hardly change pressure over micrometres).
  const double A_B = kPi * 0.032 * 0.032 / 4;
  const double p_stick = 101325 + 40.0 / A_B, p_slip = 101325 + 80.0 / A_B;
  const SimRun stuck = run(lugre_piston(p_stick / 1e5), "lugre_stuck");
  const auto t = stuck.col("t"), x = stuck.col("x"), v = stuck.col("v"), Ff = stuck.col("F_fr"),
             Fp = stuck.col("F_p");
  // The load is applied at once: the body gives way until the bristles
  // carry it (a transient of ~25 ms, 0.27 mm), then stays. What is left is a
  // creep of ~1e-6 m/s, the friction_v_eps rounding of |v| in dz/dt.
  std::size_t k0 = 0;
  while (t[k0] < 0.1) ++k0;
  double v_max = 0;
  for (std::size_t k = k0; k < t.size(); ++k) v_max = std::max(v_max, std::abs(v[k]));
  const double drift = std::abs(x.back() - x[k0]);
  std::cout << "LuGre piston under " << -Fp.back() << " N (F_C 40 N, F_S 60 N): settles "
            << (0.05 - x[k0]) * 1e3 << " mm from x0, then moves " << drift * 1e6 << " um in 0.4 s (|v| <= " << v_max
            << " m/s); friction holds " << Ff.back() << " N\n";
  EXPECT_LT(drift, 1e-6);
  EXPECT_LT(v_max, 1e-5);
  EXPECT_NEAR(Ff.back(), -Fp.back(), 1e-3 * 40.0);  // friction balances the load
  const SimRun slips = run(lugre_piston(p_slip / 1e5), "lugre_slips");
  const double travel = std::abs(slips.col("x").back() - 0.05);
  std::cout << "LuGre piston under 80 N: travels " << travel * 1e3 << " mm in 0.5 s\n";
  EXPECT_GT(travel, 5e-3);
}

// ---------------------------------------------------------------------------
// Energy over a full cushioned stroke (the basic rig, 0.5 s: stroke, cushion,
// impact, settling). Gas: sum of enthalpy in + heat in = dU_gas + sum p dV.
// Piston + load: the work of pressure, friction and stops = d(kinetic
// energy). The integrals asserted are the solver's (integral outputs, IDAS
// quadratures at rtol 1e-8): the balance holds to the solver's tolerance
// since U is a state. Trapezoid integrals on the 0.02 ms output grid are
// printed for comparison (their error is the grid's, ~1e-4 of the throughput).
struct Balance {
  double gas_residual, gas_scale, mech_residual, mech_scale, heat;
};

Balance energy_balance(const std::string& yaml, const std::string& name, SimRun* keep = nullptr) {
  std::string y = replace_once(yaml, "  p_ch: cylinder.p_ch",
                               "  p_ch: cylinder.p_ch\n  H_A: cylinder.H_A\n  H_B: cylinder.H_B\n  Q_A: cylinder.Q_A\n"
                               "  Q_cap: cylinder.Q_cap\n  P_pdV: cylinder.P_pdV\n  U_gas: cylinder.U_gas\n"
                               "  F_p: cylinder.F_pressure\n  P_fric: cylinder.P_friction\n  P_stop: cylinder.P_stop\n"
                               "  H_cush: cylinder.H_cushion\n"
                               // The same powers integrated by the solver (IDAS quadratures).
                               "  I_H_A: {integral: cylinder.H_A}\n  I_H_B: {integral: cylinder.H_B}\n"
                               "  I_Q_A: {integral: cylinder.Q_A}\n  I_Q_cap: {integral: cylinder.Q_cap}\n"
                               "  I_P_pdV: {integral: cylinder.P_pdV}\n  I_P_fric: {integral: cylinder.P_friction}\n"
                               "  I_P_stop: {integral: cylinder.P_stop}\n  I_v: {integral: cylinder.v}");
  // The valves open over 2 ms instead of a step: right after a step the
  // flows decay within microseconds, which no output grid resolves.
  y = replace_once(y, "kind: step, value: 0, height: 1, t_start: t_switch}",
                   "kind: ramp, value: 0, height: 1, t_start: t_switch, duration: 2 ms}");
  y = replace_once(y, "t_end: 1.2 s", "t_end: 0.5 s");
  y = replace_once(y, "rtol: 1e-6", "rtol: 1e-8");
  y = replace_once(y, "atol: 1e-6", "atol: 1e-8");
  y = replace_once(y, "output_interval: 1 ms", "output_interval: 0.02 ms");
  const SimRun r = run(y, name);
  std::vector<double> ev;
  for (const auto& e : r.r.solver.events) ev.push_back(e.t);
  auto integral = [&](const std::vector<double>& tt, const std::vector<double>& yy) {
    return ::pneumo::integral(tt, yy, ev);
  };
  const auto t = r.col("t"), v = r.col("v"), H_A = r.col("H_A"), H_B = r.col("H_B"), Q_A = r.col("Q_A"),
             Q_cap = r.col("Q_cap"), P_pdV = r.col("P_pdV"), U = r.col("U_gas"), F_p = r.col("F_p"),
             P_fric = r.col("P_fric"), P_stop = r.col("P_stop"), x = r.col("x");
  std::vector<double> gas_in(t.size()), abs_terms(t.size()), P_mech(t.size()), P_amb(t.size()), abs_mech(t.size());
  const double A_R = kPi * 0.012 * 0.012 / 4, m_load = 3.7;
  for (std::size_t k = 0; k < t.size(); ++k) {
    gas_in[k] = H_A[k] + H_B[k] + Q_A[k] + Q_cap[k];
    abs_terms[k] = std::abs(H_A[k]) + std::abs(H_B[k]) + std::abs(Q_A[k]) + std::abs(Q_cap[k]) + std::abs(P_pdV[k]);
    P_mech[k] = F_p[k] * v[k] + P_fric[k] + P_stop[k];
    abs_mech[k] = std::abs(F_p[k] * v[k]) + std::abs(P_fric[k]) + std::abs(P_stop[k]);
    P_amb[k] = 101325 * A_R * v[k];
  }
  Balance b;
  const double dU = U.back() - U.front();
  const double W_gas = integral(t, P_pdV);
  const double E_in = integral(t, gas_in);
  // Trapezoid on the output grid: quadrature error of the test itself.
  const double trapezoid_gas_residual = E_in - (dU + W_gas);
  b.gas_scale = integral(t, abs_terms);
  const double dKE = 0.5 * m_load * (v.back() * v.back() - v.front() * v.front());
  const double trapezoid_mech_residual = integral(t, P_mech) - dKE;
  b.mech_scale = integral(t, abs_mech);
  // The residuals asserted: the solver's integrals (to its tolerance).
  auto end = [&](const char* name) { return r.col(name).back(); };
  b.gas_residual = end("I_H_A") + end("I_H_B") + end("I_Q_A") + end("I_Q_cap") - (dU + end("I_P_pdV"));
  b.mech_residual = end("I_P_pdV") + 101325 * A_R * end("I_v") + end("I_P_fric") + end("I_P_stop") - dKE;
  std::cout << name << ": trapezoid residuals gas " << trapezoid_gas_residual << " J, piston "
            << trapezoid_mech_residual << " J; solver integrals gas " << b.gas_residual << " J, piston "
            << b.mech_residual << " J\n";
  b.heat = integral(t, Q_A) + integral(t, Q_cap);
  // The p dV work of the gas is the pressure force's work minus the ambient's on the rod.
  const double W_force = integral(t, [&] {
    std::vector<double> p(t.size());
    for (std::size_t k = 0; k < t.size(); ++k) p[k] = F_p[k] * v[k] - P_amb[k];
    return p;
  }());
  std::cout << name << ": x " << x.front() << " -> " << x.back() << " m; gas: in (H + Q) " << E_in << " J = dU "
            << dU << " J + p dV work " << W_gas << " J, residual " << b.gas_residual << " J ("
            << b.gas_residual / b.gas_scale << " of " << b.gas_scale << " J throughput); heat "
            << integral(t, Q_A) + integral(t, Q_cap) << " J; cushion throttle enthalpy "
            << integral(t, r.col("H_cush")) << " J\n"
            << "  piston: pressure work " << integral(t, [&] {
                 std::vector<double> p(t.size());
                 for (std::size_t k = 0; k < t.size(); ++k) p[k] = F_p[k] * v[k];
                 return p;
               }())
            << " J, friction " << integral(t, P_fric) << " J, stops " << integral(t, P_stop) << " J, dKE " << dKE
            << " J, residual " << b.mech_residual << " J (" << b.mech_residual / b.mech_scale << ")\n";
  EXPECT_NEAR(W_force, W_gas, 1e-9 * b.gas_scale + 1e-12);
  EXPECT_GT(x.back(), 0.0999);  // a full stroke to the cap
  if (keep) *keep = r;
  return b;
}

TEST(CylinderEnergy, BalanceOverCushionedStrokeAdiabatic) {
  const Balance b = energy_balance(rig_text(), "rig_adiabatic");
  EXPECT_EQ(b.heat, 0.0);
  // The integrals are error-controlled at the run's rtol (1e-6) and IDA
  // steps over the kinks where the bore opening starts and stops closing:
  // measured 1.9e-8 of the throughput (1.6e-10 when IDA was re-initialised
  // at those kinks). A missing term would be ~1e-1 (the cushion throttle
  // alone carries 99 J of 261 J).
  EXPECT_LT(std::abs(b.gas_residual), 1e-7 * b.gas_scale);
  EXPECT_LT(std::abs(b.mech_residual), 1e-6 * b.mech_scale);
}

// With wall heat: gas-to-wall convection inside (wall_alpha over the moving
// wall area), walls as thermal masses, convection from the walls to a fixed
// ambient temperature.
TEST(CylinderEnergy, BalanceOverCushionedStrokeWithWallHeat) {
  std::string y = replace_once(rig_text(), "    T0: 293.15 K\n\nconnections:",
                               "    T0: 293.15 K\n    wall_alpha: 200 W/(m2*K)\n"
                               "  wall_A:   {type: thermal_mass, C: 30 J/K, T0: 293.15 K}\n"
                               "  wall_cap: {type: thermal_mass, C: 30 J/K, T0: 293.15 K}\n"
                               "  film_A:   {type: heat_convection, alpha: 10 W/(m2*K), A: 0.02 m2}\n"
                               "  film_cap: {type: heat_convection, alpha: 10 W/(m2*K), A: 0.02 m2}\n"
                               "  room:     {type: fixed_temperature, T: 293.15 K}\n\nconnections:");
  y = replace_once(y, "  - [cylinder.flange, load.flange]",
                   "  - [cylinder.flange, load.flange]\n  - [cylinder.heat_A, wall_A.port, film_A.a]\n"
                   "  - [cylinder.heat_cap, wall_cap.port, film_cap.a]\n  - [film_A.b, film_cap.b, room.port]");
  y = replace_once(y, "  T_EC: cylinder.T_EC",
                   "  T_EC: cylinder.T_EC\n  T_A: cylinder.T_A\n  Tw_A: cylinder.heat_A.T\n  Tw_cap: cylinder.heat_cap.T");
  SimRun r;
  const Balance b = energy_balance(y, "rig_wall_heat", &r);
  EXPECT_GT(b.heat, 1.0);  // the walls do exchange heat with the gas (J)
  // The film follows the piston: Q = alpha A(x) (T_wall - T_gas) with
  // A(x) = end faces + lateral surface over the chamber length (stroke
  // travel + dead volume / area), rod side with the rod's surface.
  const double bore = 0.032, rod = 0.012, A_B = kPi * bore * bore / 4, A_A = A_B - kPi * rod * rod / 4;
  const auto x = r.col("x"), Q_A = r.col("Q_A"), Q_cap = r.col("Q_cap"), T_A = r.col("T_A"), T_EC = r.col("T_EC"),
             Tw_A = r.col("Tw_A"), Tw_cap = r.col("Tw_cap");
  double worst = 0;
  for (std::size_t k = 0; k < x.size(); k += 97) {
    const double area_A = 2 * A_A + kPi * (bore + rod) * (x[k] + 3.0e-6 / A_A);
    const double area_cap = 2 * A_B + kPi * bore * (0.1 - x[k] + 3.0e-6 / A_B);
    const double qa = 200 * area_A * (Tw_A[k] - T_A[k]), qc = 200 * area_cap * (Tw_cap[k] - T_EC[k]);
    worst = std::max({worst, std::abs(Q_A[k] - qa) / (std::abs(qa) + 1e-3), std::abs(Q_cap[k] - qc) / (std::abs(qc) + 1e-3)});
    // (T_wall - T_gas) is a small difference of temperatures that are
    // solved to ~1e-6 K; the area itself changes tenfold over the stroke.
    EXPECT_NEAR(Q_A[k], qa, 1e-4 * std::abs(qa) + 200 * area_A * 1e-5);
    EXPECT_NEAR(Q_cap[k], qc, 1e-4 * std::abs(qc) + 200 * area_cap * 1e-5);
  }
  std::cout << "wall film law: worst relative deviation " << worst << "; rod-side area " << 2 * A_A + kPi * (bore + rod) * (x.front() + 3.0e-6 / A_A)
            << " -> " << 2 * A_A + kPi * (bore + rod) * (x.back() + 3.0e-6 / A_A) << " m2\n";
  // As in the adiabatic case (rtol 1e-6, kinks stepped over): measured 1.0e-8.
  EXPECT_LT(std::abs(b.gas_residual), 1e-7 * b.gas_scale);
  EXPECT_LT(std::abs(b.mech_residual), 1e-6 * b.mech_scale);
}

// ---------------------------------------------------------------------------
// The cushion entry is a located event: the event log has it, and the row
// written at the event time has x = stroke - cushion_length.
TEST(CushionEntry, IsAnEventAtTheEntryPosition) {
  std::string y = replace_once(rig_text(), "t_end: 1.2 s", "t_end: 0.4 s");
  const SimRun r = run(y, "rig_entry");
  const auto t = r.col("t"), x = r.col("x");
  double t_entry = -1;
  for (const auto& ev : r.r.solver.events)
    if (ev.component == "cylinder" && ev.message.find("enters the cushioning zone") != std::string::npos) {
      t_entry = ev.t;
      break;
    }
  ASSERT_GT(t_entry, 0) << "no cushion entry event";
  double x_at = std::nan(""), best = 1e9;
  for (std::size_t k = 0; k < t.size(); ++k)
    if (std::abs(t[k] - t_entry) < best) {
      best = std::abs(t[k] - t_entry);
      x_at = x[k];
    }
  std::cout << "cushion entry event at t = " << t_entry << " s, x = " << x_at << " m (row at |dt| = " << best
            << " s), x - 0.08 m = " << x_at - 0.08 << " m\n";
  EXPECT_EQ(best, 0.0);  // a row at the event time itself
  EXPECT_NEAR(x_at, 0.08, 1e-6);
}

// ---------------------------------------------------------------------------
// Rod-end cushioning: the rig mirrored (supply to the cap side, meter-out
// from the rod side), the piston starting at the cap and extending to x = 0.
std::string extending_rig(bool rod_cushion) {
  std::string y = replace_once(rig_text(), "  - [valve_PA.b, cylinder.A]\n  - [cylinder.B, meter_out.a]",
                               "  - [valve_PA.b, cylinder.B]\n  - [cylinder.A, meter_out.a]");
  std::string init = "    p0_A: p_supply\n    p0_cap: 101325 Pa\n    x0: 100 mm\n";
  if (rod_cushion)
    init += "    rod_plug_diameter: 18 mm\n    rod_cushion_length: 20 mm\n    rod_dead_volume_cushion: 2.0e-6 m3\n";
  y = replace_once(y, "    p0_A: 101325 Pa\n    p0_cap: p_supply\n", init);
  if (rod_cushion) y = replace_once(y, "  p_ch: cylinder.p_ch", "  p_ch: cylinder.p_ch\n  p_ECr: cylinder.p_EC_rod");
  y = replace_once(y, "t_end: 1.2 s", "t_end: 0.5 s");
  y = replace_once(y, "output_interval: 1 ms", "output_interval: 0.1 ms");
  return y;
}

// Speed at the first contact with the rod-end stop (x crossing 0).
double rod_impact_speed(const SimRun& r) {
  const auto x = r.col("x"), v = r.col("v");
  for (std::size_t k = 1; k < x.size(); ++k)
    if (x[k - 1] > 0 && x[k] <= 0) {
      const double w = x[k - 1] / (x[k - 1] - x[k]);
      return std::abs(v[k - 1] + w * (v[k] - v[k - 1]));
    }
  ADD_FAILURE() << "the piston never reached the rod-end stop";
  return std::nan("");
}

TEST(RodCushion, BrakesTheExtendingStroke) {
  const SimRun plain = run(extending_rig(false), "extend_plain");
  const SimRun cushioned = run(extending_rig(true), "extend_rod_cushion");
  const double v_plain = rod_impact_speed(plain), v_cush = rod_impact_speed(cushioned);
  const auto p_ECr = cushioned.col("p_ECr");
  const double p_max = *std::max_element(p_ECr.begin(), p_ECr.end());
  bool entered = false;
  for (const auto& ev : cushioned.r.solver.events)
    entered |= ev.message.find("enters the rod-end cushioning zone") != std::string::npos;
  std::cout << "extending stroke: impact " << v_plain << " m/s without, " << v_cush
            << " m/s with rod-end cushioning; peak p_EC_rod " << p_max / 1e5 << " bar (supply 5 bar)\n";
  EXPECT_TRUE(entered);
  EXPECT_LT(v_cush, 0.7 * v_plain);
  EXPECT_GT(p_max, 5e5);
}

// ---------------------------------------------------------------------------
// Per-instance info: the rod-end chamber, its port and the LuGre state exist
// only when their parameters ask for them; half-given rod cushioning is an
// error naming the missing parameter.
InputError elaboration_error(const std::string& yaml) {
  try {
    System s(elaborate(parse_netlist(yaml, "bad.yaml"), builtin_registry()));
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError";
  return InputError({}, "", "", "");
}

TEST(CylinderInstance, RodCushionPortsAndParametersPerInstance) {
  // No rod cushioning: no EC_rod port.
  std::string y = replace_once(rig_text(), "  - [cylinder.flange, load.flange]",
                               "  - [cylinder.flange, load.flange]\n  - [cylinder.EC_rod, exhaust.port]");
  InputError e = elaboration_error(y);
  EXPECT_EQ(e.component(), "cylinder");
  EXPECT_NE(std::string(e.what()).find("no port 'EC_rod'"), std::string::npos) << e.what();
  // Rod cushioning without its length.
  y = replace_once(rig_text(), "    p0_A: 101325 Pa\n", "    p0_A: 101325 Pa\n    rod_plug_diameter: 18 mm\n");
  e = elaboration_error(y);
  EXPECT_EQ(e.parameter(), "rod_cushion_length") << e.what();
  // Overlapping cushioning zones.
  y = replace_once(rig_text(), "    p0_A: 101325 Pa\n",
                   "    p0_A: 101325 Pa\n    rod_plug_diameter: 18 mm\n    rod_cushion_length: 80 mm\n"
                   "    rod_dead_volume_cushion: 2.0e-6 m3\n");
  e = elaboration_error(y);
  EXPECT_EQ(e.parameter(), "rod_cushion_length") << e.what();
  // With rod cushioning and taps the instance has the extra chamber, port and state.
  y = replace_once(rig_text(), "    p0_A: 101325 Pa\n",
                   "    p0_A: 101325 Pa\n    rod_plug_diameter: 18 mm\n    rod_cushion_length: 20 mm\n"
                   "    rod_dead_volume_cushion: 2.0e-6 m3\n    cushion_taps: yes\n    friction_model: lugre\n"
                   "    friction_FC: 10 N\n");
  y = replace_once(y, "friction: annexB_5.14", "friction: none");
  const Circuit c = elaborate(parse_netlist(y, "rod.yaml"), builtin_registry());
  const auto& info = c.components[c.find("cylinder")]->info();
  EXPECT_GE(info.port_index("EC"), 0);
  EXPECT_GE(info.port_index("EC_rod"), 0);
  EXPECT_EQ(info.roots, 6);
  EXPECT_EQ(info.variables.back().name, "z");
  // The type's info (what 'pneumo components' lists) has everything.
  EXPECT_GE(builtin_registry().find("cushioned_cylinder")->info->port_index("EC_rod"), 0);
}

}  // namespace
}  // namespace pneumo
