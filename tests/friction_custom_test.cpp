// Custom eq. 8 friction coefficients in the cylinder (`friction: custom`,
// `friction_cushion: custom`, components/friction.hpp), in the form that
// `pneumo fit friction -o` writes:
//   * the YAML the fit writes (fit::friction_preset_yaml, the function behind
//     the CLI's -o) for the Annex C coefficient sets, pasted into a cylinder,
//     gives the same friction force along a cushioned stroke as the named
//     presets annexC_pAB+ / annexC_pEC (within 1e-9 of the peak force; the
//     only difference is the N/bar -> N/Pa -> per-bar round trip of the
//     slopes), while a copy with b0 changed by 1 N differs by 1 N - so the
//     custom coefficients are really read;
//   * the file the pneumo binary writes from noise-free synthetic data drives
//     a cylinder to the preset's friction within the 6 significant digits the
//     file carries;
//   * misuse is an error naming the parameter: a custom coefficient beside a
//     named preset, cushion coefficients without friction_cushion: custom,
//     custom with a non-preset friction model.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "components/friction.hpp"
#include "framework/core/error.hpp"
#include "components/fit/friction_fit.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

// Every line indented, so that a snippet becomes part of a component's mapping
// (what a user does when pasting the fit's output into the cylinder).
std::string indent(const std::string& text, int n) {
  std::istringstream in(text);
  std::string line, out;
  while (std::getline(in, line)) out += std::string(n, ' ') + line + "\n";
  return out;
}

// One pull-in rig (supply -> throttle -> A; B -> meter-out -> atmosphere) with
// the suffix s on every name and the given friction lines in the cylinder,
// 5 bar, z_EC 1.5 rev. Free: 3.7 kg, through the cushioning zone onto the
// stop. Driven: the rod moved at 0.25 m/s from x = 1 mm (the motion, and
// with it every pressure, is then independent of the friction).
enum class Motion { free, driven };

std::string rig(const std::string& s, const std::string& friction, Motion motion) {
  std::string y;
  y += "  supply_" + s + ": {type: pressure_source, p: 5 bar}\n";
  y += "  in_" + s + ": {type: iso6358_throttle, C: 1.0 dm3/(s*bar), b: 0.3}\n";
  y += "  out_" + s + ": {type: iso6358_throttle, C: 0.35 dm3/(s*bar), b: 0.45}\n";
  y += "  atm_" + s + ": {type: atmosphere}\n";
  if (motion == Motion::free)
    y += "  load_" + s + ": {type: translational_mass, m: 3.7 kg}\n";
  else
    y += "  load_" + s + ": {type: velocity_source, v: 0.25 m/s, s0: 1 mm}\n";
  y += "  cyl_" + s + ":\n";
  if (motion == Motion::driven) y += "    x0: 1 mm\n";
  y += indent(R"(type: cushioned_cylinder
bore: 32 mm
rod: 12 mm
stroke: 100 mm
plug_diameter: 16 mm
cushion_length: 20 mm
dead_volume_rod_side: 3.0e-6 m3
dead_volume_cushion: 2.0e-6 m3
dead_volume_channel: 1.0e-6 m3
bore_opening_C: 5.0 dm3/(s*bar)
cushion_C_of_z: [[0, 0], [1.5, 0.12 dm3/(s*bar)], [6, 0.4 dm3/(s*bar)]]
cushion_b0: 0.3
z_EC: 1.5 rev
p0_cap: 5 bar
)",
              4);
  y += indent(friction, 4);
  return y;
}

std::string connections(const std::string& s) {
  return "  - [supply_" + s + ".port, in_" + s + ".a]\n  - [in_" + s + ".b, cyl_" + s + ".A]\n  - [cyl_" + s +
         ".B, out_" + s + ".a]\n  - [out_" + s + ".b, atm_" + s + ".port]\n  - [cyl_" + s + ".flange, load_" + s +
         ".flange]\n";
}

std::string outputs(const std::string& s) {
  return "  F_" + s + ": cyl_" + s + ".F_friction\n  x_" + s + ": cyl_" + s + ".x\n  v_" + s + ": cyl_" + s +
         ".v\n  open_" + s + ": cyl_" + s + ".bore_open\n";
}

// Several independent rigs in one netlist: they share the integrator's steps,
// so equal coefficients give equal trajectories to rounding.
std::string netlist(const std::vector<std::pair<std::string, std::string>>& rigs, Motion motion) {
  std::string y = "ambient: {p: 101325 Pa, T: 293.15 K}\ncomponents:\n";
  for (const auto& [s, f] : rigs) y += rig(s, f, motion);
  y += "connections:\n";
  for (const auto& [s, f] : rigs) y += connections(s);
  y += "outputs:\n";
  for (const auto& [s, f] : rigs) y += outputs(s);
  y += motion == Motion::free ? "simulation: {t_end: 0.45 s, rtol: 1e-7, atol: 1e-7, output_interval: 1 ms}\n"
                              : "simulation: {t_end: 0.36 s, rtol: 1e-7, atol: 1e-7, output_interval: 1 ms}\n";
  return y;
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k) m = std::max(m, std::abs(a[k] - b[k]));
  return m;
}

const std::string kPresets = "friction: annexC_pAB+\nfriction_cushion: annexC_pEC\n";

std::string fit_yaml(const components::FrictionCoefficients& c, bool cushion) {
  fit::FitReport report;  // only its RSS and R2 reach the (comment) header
  return fit::friction_preset_yaml(c, report, fit::FrictionModel::eq8, cushion, "copy of an Annex C set");
}

// Driven stroke: the same state at every output for all rigs, so the
// friction forces are compared at equal (x, v, p_A, p_EC) - 1e-9 of the peak
// force leaves room only for the rounding of the N/bar -> N/Pa -> per-bar
// round trip of the slopes.
TEST(CustomFriction, FitPresetReproducesTheNamedPresetsAlongACushionedStroke) {
  const auto& presets = components::friction_presets();
  const components::FrictionCoefficients main = presets.at("annexC_pAB+"), cushion = presets.at("annexC_pEC");
  const std::string custom = fit_yaml(main, false) + fit_yaml(cushion, true);
  components::FrictionCoefficients shifted = main;
  shifted.b0 += 1.0;  // 1 N more on the main stroke
  const std::string custom_shifted = fit_yaml(shifted, false) + fit_yaml(cushion, true);
  const std::string yaml =
      netlist({{"preset", kPresets}, {"custom", custom}, {"shifted", custom_shifted}}, Motion::driven);
  const RunResult r = run_simulation(parse_netlist(yaml, "custom_friction.yaml"), builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;

  const auto F_p = column(r.table, "F_preset"), F_c = column(r.table, "F_custom"), F_s = column(r.table, "F_shifted");
  const auto x_p = column(r.table, "x_preset");
  const auto open = column(r.table, "open_preset");
  // The stroke uses both sets: the main stroke (bore open) and the
  // cushioning zone (bore closed, p_EC above supply), with friction at both.
  double F_main = 0, F_zone = 0;
  for (std::size_t k = 0; k < F_p.size(); ++k) {
    if (open[k] > 0.999) F_main = std::max(F_main, std::abs(F_p[k]));
    if (open[k] < 0.001) F_zone = std::max(F_zone, std::abs(F_p[k]));
  }
  ASSERT_GT(F_main, 10.0);
  ASSERT_GT(F_zone, 10.0);
  ASSERT_GT(x_p.back(), 0.085) << "the stroke does not reach into the cushioning zone";

  const double F_peak = max_abs(F_p);
  const double dF = max_abs_diff(F_p, F_c);
  // b0 + 1 N on the main stroke: exactly 1 N more friction, weighted by the
  // bore opening that blends the main and the cushioning-zone set.
  double d_shift = 0;
  for (std::size_t k = 1; k < F_p.size(); ++k) d_shift = std::max(d_shift, std::abs(F_s[k] - F_p[k] + open[k]));
  std::cout << "[custom-friction] driven stroke: peak |F| " << F_peak << " N (main stroke " << F_main
            << " N, zone " << F_zone << " N); max |F_custom - F_preset| = " << dF
            << " N; b0 + 1 N: max |F_shifted - F_preset + open| = " << d_shift << " N\n";
  EXPECT_LE(dF, 1e-9 * F_peak);
  EXPECT_LE(d_shift, 1e-9 * F_peak) << "the custom coefficients are not what drives the cylinder";
}

// Free stroke (the piston moved by the gas, onto the stop): the custom copy
// follows the same trajectory. Near rest the regularised sign makes the
// force a steep function of v (F/v_reg = 8e5 N s/m), so rounding-level
// differences of the state show up amplified there: compared while sliding
// (|v| > 1 cm/s) at 1e-7 (measured 1.0e-8 - the two copies leave the
// rod-end stop a rounding apart and IDA is no longer re-initialised there),
// everywhere at 1e-6 of the peak force. The two copies share no
// connection: run as one System, so that one IDA takes the same steps for
// both (run_simulation would integrate them apart, each with steps of its
// own, and they would agree only to the solver's tolerance).
TEST(CustomFriction, FitPresetFollowsTheSameFreeStroke) {
  const auto& presets = components::friction_presets();
  const std::string custom =
      fit_yaml(presets.at("annexC_pAB+"), false) + fit_yaml(presets.at("annexC_pEC"), true);
  const Netlist nl = parse_netlist(netlist({{"preset", kPresets}, {"custom", custom}}, Motion::free), "free.yaml");
  System system(elaborate(nl, builtin_registry()));
  const RunResult r = run_system(system, solver_options(nl.simulation));
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const auto F_p = column(r.table, "F_preset"), F_c = column(r.table, "F_custom");
  const auto x_p = column(r.table, "x_preset"), x_c = column(r.table, "x_custom"), v_p = column(r.table, "v_preset");
  ASSERT_GT(x_p.back(), 0.099) << "the piston does not reach the cap";
  double d_sliding = 0;
  for (std::size_t k = 0; k < F_p.size(); ++k)
    if (std::abs(v_p[k]) > 0.01) d_sliding = std::max(d_sliding, std::abs(F_c[k] - F_p[k]));
  const double F_peak = max_abs(F_p), dF = max_abs_diff(F_p, F_c), dx = max_abs_diff(x_p, x_c);
  std::cout << "[custom-friction] free stroke: max |dF| sliding " << d_sliding << " N, overall " << dF
            << " N of peak " << F_peak << " N; max |dx| = " << dx << " m\n";
  EXPECT_LE(d_sliding, 1e-7 * F_peak);
  EXPECT_LE(dF, 1e-6 * F_peak);
  EXPECT_LE(dx, 1e-9 * 0.1);
}

// The CLI end to end: noise-free eq. 8 data of annexC_pAB+ (p = p_A + p_B
// gauge), `pneumo fit friction --model eq8 --pressure pAB+ --fix FC=5.4 -o`,
// the written file pasted into a cylinder. The file carries 6 significant
// digits; 1e-4 of the peak force is far above that rounding and far below
// any real difference between friction laws.
TEST(CustomFriction, FileWrittenByPneumoFitDrivesTheCylinder) {
  const fs::path dir = fs::temp_directory_path() / ("pneumo_custom_friction_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto c = components::friction_presets().at("annexC_pAB+");
  std::ostringstream csv;
  csv.precision(12);
  csv << "v [m/s],p_A [bar_rel],p_B [bar_rel],F [N]\n";
  for (int i = 0; i < 25; ++i) {
    const double v = 0.002 * std::pow(0.7 / 0.002, i / 24.0);
    for (double pB : {0.5, 2.0, 3.5, 5.0, 6.5}) {
      const double pA = 0.8 * pB + 0.5;
      csv << v << "," << pA << "," << pB << "," << components::friction_magnitude(c, v, pA + pB) << "\n";
    }
  }
  {
    std::ofstream(dir / "points.csv") << csv.str();
  }
  const auto [rc, out] = run_cli("fit friction '" + (dir / "points.csv").string() +
                                 "' --model eq8 --pressure pAB+ --fix FC=5.4 -o '" + (dir / "main.yaml").string() + "'");
  ASSERT_EQ(rc, 0) << out;
  const std::string main = read_file(dir / "main.yaml");
  fs::remove_all(dir);
  ASSERT_NE(main.find("friction: custom"), std::string::npos) << main;

  const std::string custom = main + "friction_cushion: annexC_pEC\n";
  const RunResult r = run_simulation(
      parse_netlist(netlist({{"preset", kPresets}, {"fitted", custom}}, Motion::free), "fitted.yaml"),
      builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const auto F_p = column(r.table, "F_preset"), F_f = column(r.table, "F_fitted");
  const double dF = max_abs_diff(F_p, F_f), F_peak = max_abs(F_p);
  std::cout << "[custom-friction] fitted file: max |F_fitted - F_preset| = " << dF << " N of peak " << F_peak
            << " N\n";
  EXPECT_LE(dF, 1e-4 * F_peak);
}

// Misuse is an error at the netlist line of the parameter.
std::string error_of(const std::string& friction) {
  try {
    run_simulation(parse_netlist(netlist({{"a", friction}}, Motion::free), "misuse.yaml"), builtin_registry());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(CustomFriction, CoefficientsBesideANamedPresetAreAnError) {
  const std::string e1 = error_of("friction: annexC_pAB+\nfriction_b0: 3 N\n");
  EXPECT_NE(e1.find("friction_b0"), std::string::npos) << e1;
  EXPECT_NE(e1.find("friction: custom"), std::string::npos) << e1;
  EXPECT_NE(e1.find("misuse.yaml:"), std::string::npos) << e1;

  const std::string e2 = error_of("friction: annexB_5.14\nfriction_pressure: pAB+\n");
  EXPECT_NE(e2.find("friction_pressure"), std::string::npos) << e2;

  const std::string e3 = error_of("friction: custom\nfriction_b0: 3 N\nfriction_cushion_kv0: 100 N\n");
  EXPECT_NE(e3.find("friction_cushion_kv0 needs friction_cushion: custom"), std::string::npos) << e3;

  const std::string e4 = error_of("friction_model: lugre\nfriction_FC: 5 N\nfriction: custom\n");
  EXPECT_NE(e4.find("needs friction_model: preset"), std::string::npos) << e4;

  const std::string e5 = error_of("friction: custom\nfriction_pressure: p_AB\n");
  EXPECT_NE(e5.find("'p_AB' is not allowed"), std::string::npos) << e5;

  // The slopes are pressures' reciprocals: a plain force is rejected.
  const std::string e6 = error_of("friction: custom\nfriction_b1: 3 N\n");
  EXPECT_NE(e6.find("friction_b1"), std::string::npos) << e6;
}

// A friction_element with a custom set: its `pressure` is the set's p.
TEST(CustomFriction, FrictionElementUsesTheCustomSetAtItsPressure) {
  const auto c = components::friction_presets().at("annexC_pAB+");
  const std::string yaml = R"(
components:
  drive: {type: velocity_source, v: 0.2 m/s}
  f: {type: friction_element, pressure: 4 bar, )" +
                           std::string("friction: custom, friction_pressure: pAB+, friction_b0: 5.63 N, "
                                       "friction_b1: -0.1 N/bar, friction_FS0: 17.06 N, friction_FS1: 0.714 N/bar, "
                                       "friction_FC: 5.4 N, friction_vS: 3.98e-3 m/s, friction_kv0: 87.46 N, "
                                       "friction_kv1: 6.1 N/bar, friction_a: 0.746}\n") +
                           R"(connections:
  - [drive.flange, f.flange]
outputs:
  F: f.F
simulation: {t_end: 0.1 s, output_interval: 10 ms}
)";
  const RunResult r = run_simulation(parse_netlist(yaml, "element.yaml"), builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  // eq. 8 by hand: p = 4 bar, |v| = 0.2 m/s.
  const double v = 0.2, p = 4.0;
  const double expected = 5.63 - 0.1 * p + (17.06 + 0.714 * p - 5.4) * std::exp(-v / 3.98e-3) +
                          (87.46 + 6.1 * p) * std::pow(v, 0.746);
  EXPECT_NEAR(-column(r.table, "F").back(), expected, 1e-6 * expected);
  EXPECT_NEAR(expected, components::friction_magnitude(c, v, p), 1e-9 * expected);
}

}  // namespace
}  // namespace pneumo
