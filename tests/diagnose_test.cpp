// Sim-to-real gap diagnosis (issue #6): a withheld piston-seal leak is found
// among three candidates and the gap shrinks to the noise level; clean data
// gets an empty verdict; bad measured data and bad catalogues get errors
// that name the file, line and parameter; the HTML report renders in a
// real headless Chromium.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "components/builtin.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "framework/run/run.hpp"

namespace fs = std::filesystem;
using namespace pneumo;
using namespace pneumo::diagnose;

namespace {

const std::string kSource = PNEUMO_SOURCE_DIR;
const std::string kModel = kSource + "/netlists/cushion_rig.yaml";

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("pneumo_diagnose_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The shipped catalogue cut down to a few effects (keeps the test fast).
std::string small_catalogue(const fs::path& dir, const std::vector<std::string>& keep) {
  YAML::Node full = YAML::LoadFile(kSource + "/catalogues/cushion_rig.yaml");
  YAML::Node out;
  out["phases"] = full["phases"];
  for (const auto& k : keep) out["effects"][k] = full["effects"][k];
  const auto path = (dir / "catalogue.yaml").string();
  std::ofstream(path) << YAML::Dump(out);
  return path;
}

// Two runs (calibration, validation) of the rig with `extra` YAML appended
// to the netlist's components/connections (the withheld truth), sampled at
// 500 Hz over 0.45 s with Gaussian noise (x 0.02 mm, p 2 kPa, T 0.3 K).
// `late_valve_lagging_T`: instead of the leak, an S-shaped valve opening from
// 16 to 28 ms and a second-order thermometer (time constants 0.12 s, 0.04 s).
void make_runs(const fs::path& dir, const std::string& leak_C, unsigned seed, bool late_valve_lagging_T = false) {
  YAML::Node model = YAML::LoadFile(kModel);
  if (late_valve_lagging_T)
    model["components"]["valve_cmd"] = YAML::Load(
        "{type: signal_source, kind: table, table: [[0, 0], [0.016, 0], [0.019, 0.1], [0.022, 0.5], [0.025, 0.9], "
        "[0.028, 1.0], [10, 1.0]]}");
  if (!leak_C.empty()) {
    // Near-laminar leak (b = 0.1): another form than the candidate's b = 0.3.
    model["components"]["true_leak"] = YAML::Load("{type: iso6358_throttle, C: " + leak_C + ", b: 0.1}");
    model["connections"].push_back(YAML::Load("[true_leak.a, cylinder.A]"));
    model["connections"].push_back(YAML::Load("[true_leak.b, cylinder.B]"));
  }
  const std::string text = YAML::Dump(model);
  fs::create_directories(dir);
  std::mt19937 rng(seed);
  const struct {
    const char* name;
    const char* role;
    double p, m;
  } runs[] = {{"cal", "calibration", 5e5, 3.7}, {"val", "validation", 6e5, 2.5}};
  const std::vector<std::pair<std::string, double>> sig = {{"x", 2e-5}, {"p_A", 2e3}, {"p_EC", 2e3}, {"T_EC", 0.3}};
  for (const auto& r : runs) {
    Netlist nl = parse_netlist(text, kModel);
    apply_override(nl, "p_supply=" + std::to_string(r.p));
    apply_override(nl, "m_load=" + std::to_string(r.m));
    nl.simulation.t_end = 0.45;
    nl.simulation.output_interval = 2e-3;
    const RunResult res = run_simulation(nl, builtin_registry());
    ASSERT_TRUE(res.solver.ok);
    std::ofstream csv(dir / (std::string(r.name) + ".csv"));
    csv << "t";
    for (const auto& s : sig) csv << "," << s.first;
    csv << "\n";
    csv.precision(10);
    std::vector<double> T_sensor(2, res.table.rows.front()[res.table.column("T_EC")]);  // two lag stages
    double t_prev = res.table.rows.front()[0];
    for (const auto& row : res.table.rows) {
      if (late_valve_lagging_T) {
        const double h = row[0] - t_prev;
        T_sensor[0] += (1 - std::exp(-h / 0.12)) * (row[res.table.column("T_EC")] - T_sensor[0]);
        T_sensor[1] += (1 - std::exp(-h / 0.04)) * (T_sensor[0] - T_sensor[1]);
        t_prev = row[0];
      }
      csv << row[0];
      for (const auto& s : sig) {
        std::normal_distribution<double> n(0, s.second);
        const double y = late_valve_lagging_T && s.first == "T_EC" ? T_sensor[1] : row[res.table.column(s.first)];
        csv << "," << y + n(rng);
      }
      csv << "\n";
    }
    std::ofstream(dir / (std::string(r.name) + ".yaml"))
        << "data: " << r.name << ".csv\nrole: " << r.role << "\noperating_point:\n  p_supply: " << r.p
        << "\n  m_load: " << r.m << "\n";
  }
}

DiagnoseOptions quiet() {
  DiagnoseOptions o;
  o.progress = false;
  return o;
}

struct LeakCase {
  fs::path dir;
  DiagnosisReport report;
};

// Measured runs with the withheld leak (no diagnosis: for the bad-input tests).
const fs::path& leak_runs() {
  static const fs::path dir = [] {
    const fs::path d = temp_dir("leak_runs");
    make_runs(d, "3e-10", 7);
    return d;
  }();
  return dir;
}

const LeakCase& leak_case() {
  static const LeakCase c = [] {
    LeakCase l;
    l.dir = temp_dir("leak");
    make_runs(l.dir / "runs", "3e-10", 7);
    const auto cat = small_catalogue(l.dir, {"heat_transfer", "leakage_piston_seal", "end_stop_elasticity"});
    l.report = pneumo::diagnose::diagnose(kModel, (l.dir / "runs").string(), cat, builtin_registry(), quiet());
    write_report_json(l.report, (l.dir / "report.json").string());
    write_report_html(l.report, (l.dir / "report.html").string());
    return l;
  }();
  return c;
}

}  // namespace

TEST(Diagnose, NoiseEstimateFromThirdDifferences) {
  // A smooth stroke-like signal plus white noise: the estimate recovers sigma.
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 2e-5);
  std::vector<double> y;
  for (int i = 0; i < 2000; ++i) y.push_back(0.05 * (1 - std::cos(i * 2e-3 * 3)) + n(rng));
  EXPECT_NEAR(estimate_noise(y), 2e-5, 0.1 * 2e-5);
}

TEST(Diagnose, FindsWithheldLeakAndShrinksTheGap) {
  const auto& r = leak_case().report;
  ASSERT_FALSE(r.verdict.empty());
  EXPECT_EQ(r.verdict[0], "leakage_piston_seal");
  // The leak makes a gap far above the noise, and the fitted leak removes it
  // down to the noise level (normalised RMS ~ 1).
  EXPECT_GT(r.validation_before.total.rms, 5.0);
  EXPECT_LT(r.validation_after.total.rms, 1.5);
  for (const auto& e : r.effects)
    if (e.name == "leakage_piston_seal") {
      EXPECT_EQ(e.rank, 1);
      EXPECT_TRUE(e.significant);
      // Other b (0.3 vs 0.1): the conductance is recovered only roughly.
      EXPECT_GT(e.values[0], 3e-10 / 3);
      EXPECT_LT(e.values[0], 3e-10 * 3);
    }
  // The noise estimated from the data is the noise put in (a MAD estimate
  // from 225 samples has a standard error near 8 %; 25 % is three of them).
  for (const auto& [name, sigma] : r.noise)
    if (name == "p_A") {
      EXPECT_NEAR(sigma, 2e3, 500);
    }
}

TEST(Diagnose, ReportJsonHasVerdictEffectsAndWhere) {
  const std::string j = slurp(leak_case().dir / "report.json");
  EXPECT_NE(j.find("\"verdict\": [\"leakage_piston_seal\""), std::string::npos);
  for (const char* key : {"\"effects\"", "\"where\"", "\"validation_gap_before\"", "\"validation_gap_after\"",
                          "\"significance\"", "\"cushioning\"", "\"stroke\"", "\"significant_windows\""})
    EXPECT_NE(j.find(key), std::string::npos) << key;
  // Phase shares of the gap add up to the whole.
  const auto& g = leak_case().report.validation_before;
  double share = 0;
  for (const auto& p : g.phase_total) share += p.ssr / g.total.ssr;
  EXPECT_NEAR(share, 1.0, 1e-9);
}

TEST(Diagnose, LaggingThermometerDoesNotHideALateValve) {
  // Two effects at once: the lagging temperature dominates the total gap, the
  // late valve shifts x and the pressures. Judged per signal, the first
  // effect found does not hide the second; forward selection finds both.
  const fs::path dir = temp_dir("two_effects");
  make_runs(dir / "runs", "", 9, true);
  const auto cat = small_catalogue(dir, {"valve_timing", "sensor_lag_T", "leakage_piston_seal"});
  const auto r = pneumo::diagnose::diagnose(kModel, (dir / "runs").string(), cat, builtin_registry(), quiet());
  ASSERT_EQ(r.verdict.size(), 2u);
  EXPECT_NE(std::find(r.verdict.begin(), r.verdict.end(), "valve_timing"), r.verdict.end());
  EXPECT_NE(std::find(r.verdict.begin(), r.verdict.end(), "sensor_lag_T"), r.verdict.end());
  EXPECT_GT(r.validation_before.total.rms, 5.0);
  EXPECT_LT(r.validation_after.total.rms, 0.2 * r.validation_before.total.rms);
  // The fitted opening lies within the true 16-28 ms opening.
  for (const auto& [name, v] : r.final_values)
    if (name == "valve_timing") {
      EXPECT_GT(v[0], 0.014);
      EXPECT_LT(v[0], 0.028);
    }
}

TEST(Diagnose, CleanDataClaimsNothing) {
  const fs::path dir = temp_dir("clean");
  make_runs(dir / "runs", "", 8);
  const auto cat = small_catalogue(dir, {"heat_transfer", "leakage_piston_seal", "end_stop_elasticity"});
  const auto r = pneumo::diagnose::diagnose(kModel, (dir / "runs").string(), cat, builtin_registry(), quiet());
  EXPECT_TRUE(r.verdict.empty());
  EXPECT_LT(r.validation_before.total.rms, 1.2);  // the model is the truth: within noise
  for (const auto& e : r.effects) EXPECT_FALSE(e.significant) << e.name;
}

TEST(Diagnose, CommandLineWritesAReportThatRendersInHeadlessChromium) {
  // The whole command: pneumo diagnose on the leak runs, then report.html in a real browser.
  const fs::path dir = temp_dir("cli_ok");
  const auto cat = small_catalogue(dir, {"heat_transfer", "leakage_piston_seal", "end_stop_elasticity"});
  const std::string cmd = std::string(PNEUMO_BINARY) + " diagnose " + kModel + " --runs " + leak_runs().string() +
                          " --effects " + cat + " --effects-only --out " + (dir / "out").string() + " > " + (dir / "log").string() +
                          " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir / "log");
  EXPECT_NE(slurp(dir / "log").find("fit 1 /"), std::string::npos);  // the progress display
  EXPECT_NE(slurp(dir / "out" / "report.json").find("\"verdict\": [\"leakage_piston_seal\""), std::string::npos);
  const fs::path dom = dir / "dom.html";
  // Debian's chromium is required: a missing browser fails the test.
  const std::string chromium = "chromium --headless --no-sandbox --disable-gpu --dump-dom 'file://" +
                               (dir / "out" / "report.html").string() + "' > '" + dom.string() + "' 2>/dev/null";
  ASSERT_EQ(std::system(chromium.c_str()), 0) << "chromium (Debian package) must be installed: " << chromium;
  const std::string d = slurp(dom);
  EXPECT_NE(d.find("id=\"ranking\""), std::string::npos);
  EXPECT_NE(d.find("<td class=\"l\">leakage_piston_seal</td>"), std::string::npos);
  std::size_t traces = 0;
  for (std::size_t p = 0; (p = d.find("class=\"trace\"", p)) != std::string::npos; ++p) ++traces;
  EXPECT_EQ(traces, 4u);  // one validation run, four measured signals
  EXPECT_NE(d.find("class=\"before\""), std::string::npos);
  EXPECT_NE(d.find("class=\"after\""), std::string::npos);
  EXPECT_NE(d.find("id=\"phase-bars\""), std::string::npos);
}

namespace {

// Copies the leak runs and breaks one file; returns the error message.
std::string error_for(const std::string& name, const std::function<void(const fs::path&)>& breakit) {
  const fs::path dir = temp_dir("bad_" + name);
  fs::copy(leak_runs(), dir);
  breakit(dir);
  const fs::path cat_dir = temp_dir("bad_" + name + "_catalogue");
  const auto cat = small_catalogue(cat_dir, {"leakage_piston_seal"});
  try {
    pneumo::diagnose::diagnose(kModel, dir.string(), cat, builtin_registry(), quiet());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void replace_in(const fs::path& p, const std::string& from, const std::string& to) {
  std::string s = slurp(p);
  const auto pos = s.find(from);
  ASSERT_NE(pos, std::string::npos);
  s.replace(pos, from.size(), to);
  std::ofstream(p) << s;
}

}  // namespace

TEST(Diagnose, BadMeasuredDataGetsClearErrors) {
  std::string e = error_for("missing_column", [](const fs::path& d) {
    std::string s = slurp(d / "cal.csv");
    const auto l2 = s.find('\n', s.find('\n') + 1) + 1;  // third line
    const auto end = s.find('\n', l2);
    s.replace(s.rfind(',', end), end - s.rfind(',', end), "");
    std::ofstream(d / "cal.csv") << s;
  });
  EXPECT_NE(e.find("cal.csv:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("missing column"), std::string::npos) << e;

  e = error_for("unknown_output", [](const fs::path& d) { replace_in(d / "val.csv", "t,x,", "t,x_piston,"); });
  EXPECT_NE(e.find("val.csv:1:"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown output name 'x_piston'"), std::string::npos) << e;

  e = error_for("unknown_parameter", [](const fs::path& d) { replace_in(d / "cal.yaml", "m_load:", "m_mass:"); });
  EXPECT_NE(e.find("cal.yaml:5:"), std::string::npos) << e;
  EXPECT_NE(e.find("parameter 'm_mass'"), std::string::npos) << e;
  EXPECT_NE(e.find("no top-level parameter"), std::string::npos) << e;

  e = error_for("nan", [](const fs::path& d) {
    std::string s = slurp(d / "val.csv");
    const auto l = s.find('\n', s.find('\n') + 1) + 1;  // first data line after one row
    s.replace(s.find(',', s.find(',', l) + 1) + 1, 0, "nan");
    std::ofstream(d / "val.csv") << s;
  });
  EXPECT_NE(e.find("val.csv:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("not a finite number"), std::string::npos) << e;

  e = error_for("time", [](const fs::path& d) {
    std::string s = slurp(d / "cal.csv");
    const auto l = s.find('\n', s.find('\n', s.find('\n') + 1) + 1) + 1;  // line 4
    s.replace(l, s.find(',', l) - l, "0");
    std::ofstream(d / "cal.csv") << s;
  });
  EXPECT_NE(e.find("cal.csv:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("time must increase"), std::string::npos) << e;

  // A list where a name is expected: an input error at its line, not yaml-cpp's exception.
  e = error_for("role_list", [](const fs::path& d) { replace_in(d / "val.yaml", "role: validation", "role: [validation]"); });
  EXPECT_NE(e.find("val.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("'role' must be plain text"), std::string::npos) << e;
}

TEST(Diagnose, BadCatalogueNamesFileLineEffectAndParameter) {
  const fs::path dir = temp_dir("bad_catalogue");
  const Netlist model = load_netlist(kModel);
  auto load = [&](const std::string& text) -> std::string {
    std::ofstream(dir / "c.yaml") << text;
    try {
      load_catalogue((dir / "c.yaml").string(), model, builtin_registry());
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  std::string e = load(
      "effects:\n  leak:\n    parameters:\n      C: {initial: 1, lower: 2, upper: 3, null: 0}\n"
      "    set: {meter_out.C: \"${C}\"}\n");
  EXPECT_NE(e.find("c.yaml:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("effect 'leak'"), std::string::npos) << e;
  EXPECT_NE(e.find("parameter 'C'"), std::string::npos) << e;
  EXPECT_NE(e.find("initial lies outside"), std::string::npos) << e;

  e = load("effects:\n  leak:\n    parameters:\n      C: {initial: 1e-9, lower: 0, upper: 3e-9}\n"
           "    set: {meter_out.C: \"${D}\"}\n");
  EXPECT_NE(e.find("c.yaml:5:"), std::string::npos) << e;
  EXPECT_NE(e.find("'${D}': 'D' is not one of the effect's parameters"), std::string::npos) << e;

  e = load("effects:\n  leak:\n    parameters:\n      C: {initial: 1e-9, lower: 0, upper: 3e-9}\n"
           "    set: {meter_out.C: \"${2 * (C + }\"}\n");
  EXPECT_NE(e.find("c.yaml:5:"), std::string::npos) << e;
  EXPECT_NE(e.find("expression ends early"), std::string::npos) << e;

  e = load("effects:\n  leak:\n    set: {meter_out.Cx: 1e-9}\n");
  EXPECT_NE(e.find("c.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("effect 'leak' does not apply"), std::string::npos) << e;

  // A component to add that is not a map (found by fuzz/catalogue_fuzzer): an InputError at its line.
  e = load("effects:\n  leak:\n    add_components:\n      h: \"just text\"\n");
  EXPECT_NE(e.find("c.yaml:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("component 'h' in add_components must be a map"), std::string::npos) << e;

  // A patch needing a component type that is not registered is unavailable, not an error.
  std::ofstream(dir / "c.yaml") << "effects:\n  hose:\n    add_components: {h: {type: hose_not_yet, L: 1}}\n";
  const Catalogue cat = load_catalogue((dir / "c.yaml").string(), model, builtin_registry());
  ASSERT_EQ(cat.effects.size(), 1u);
  EXPECT_EQ(cat.effects[0].unavailable, "unavailable: type hose_not_yet not registered");

  // Model parameters as candidates (recalibrate:): unknown names at their line.
  e = load("recalibrate:\n  m_load: {}\n  cylinder.dead_volume: {}\n");
  EXPECT_NE(e.find("c.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("has no parameter 'dead_volume'"), std::string::npos) << e;
  e = load("recalibrate:\n  piston.mass: {}\n");
  EXPECT_NE(e.find("c.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("no component 'piston'"), std::string::npos) << e;
  e = load("recalibrate:\n  m_lod: {}\n");
  EXPECT_NE(e.find("no top-level parameter 'm_lod'"), std::string::npos) << e;
  e = load("recalibrate:\n  load.m: {}\n");  // the netlist writes m: m_load
  EXPECT_NE(e.find("re-calibrate that parameter"), std::string::npos) << e;
  e = load("recalibrate:\n  m_load: {lower: 2x, upper: 3x}\n");
  EXPECT_NE(e.find("lies outside [lower, upper]"), std::string::npos) << e;
}

// A map or list where the catalogue expects a plain name or text (a key, a
// type, a description, a phase, a scale): an InputError at that node's line,
// never yaml-cpp's own exception (the first found by fuzz/catalogue_fuzzer
// in CI: a top-level key that is a map).
TEST(Diagnose, CatalogueNamesThatAreMapsOrListsGetLocatedErrors) {
  const fs::path dir = temp_dir("catalogue_shapes");
  const Netlist model = load_netlist(kModel);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"effects: {}\n? {a: 1}\n: 2\n", "c.yaml:2:"},
      {"effects:\n  ? [a, b]\n  : {set: {meter_out.C: 1e-9}}\n", "c.yaml:2:"},
      {"effects:\n  leak:\n    ? {x: 1}\n    : 2\n", "c.yaml:3:"},
      {"effects:\n  leak:\n    description: {x: 1}\n", "c.yaml:3:"},
      {"effects:\n  leak:\n    parameters:\n      C: {initial: 1, lower: 0, upper: 2, unit: [m]}\n", "c.yaml:4:"},
      {"effects:\n  leak:\n    parameters:\n      C: {initial: 1, lower: 0, upper: 2, scale: {a: 1}}\n",
       "c.yaml:4:"},
      {"effects:\n  leak:\n    parameters:\n      ? [C]\n      : {initial: 1, lower: 0, upper: 2}\n", "c.yaml:4:"},
      {"effects:\n  leak:\n    requires: {types: [[orifice]]}\n", "c.yaml:3:"},
      {"effects:\n  leak:\n    requires: {ports: [{a: 1}]}\n", "c.yaml:3:"},
      {"effects:\n  leak:\n    measure:\n      ? [x]\n      : {lag: 0.01}\n", "c.yaml:4:"},
      {"phases:\n  - {name: [a], from: start}\neffects: {}\n", "c.yaml:2:"},
      {"phases:\n  - {name: a, from: {b: 1}}\neffects: {}\n", "c.yaml:2:"},
      {"recalibrate:\n  ? [m_load]\n  : {}\n", "c.yaml:2:"},
      {"recalibrate:\n  m_load: {scale: [log]}\n", "c.yaml:2:"},
      {"recalibrate:\n  m_load: {description: {a: 1}}\n", "c.yaml:2:"},
  };
  for (const auto& [text, where] : cases) {
    std::ofstream(dir / "c.yaml") << text;
    std::string e;
    try {
      load_catalogue((dir / "c.yaml").string(), model, builtin_registry());
    } catch (const InputError& ex) {
      e = ex.what();
    }
    EXPECT_NE(e.find(where), std::string::npos) << text << " -> " << e;
    EXPECT_EQ(e.find("unexpected YAML shape"), std::string::npos) << "not checked before reading: " << text;
  }
}

TEST(Diagnose, ShippedCatalogueLoadsAgainstTheRig) {
  const Netlist model = load_netlist(kModel);
  const Catalogue cat = load_catalogue(kSource + "/catalogues/cushion_rig.yaml", model, builtin_registry());
  for (const char* name : {"heat_transfer", "friction_pressure", "friction_cushion_zone", "leakage_cushion_seal",
                           "leakage_piston_seal", "sensor_lag_T", "sensor_lag_p", "valve_timing", "line_volume",
                           "supply_droop", "end_stop_elasticity", "lugre"})
    EXPECT_NE(cat.find(name), nullptr) << name;
  // Re-calibration candidates: the null is the netlist's value (0.35 dm3/(s*bar), 2 cm3).
  ASSERT_NE(cat.find("meter_out.C"), nullptr);
  EXPECT_NEAR(*cat.find("meter_out.C")->parameters[0].null_value, 0.35e-8, 1e-20);
  ASSERT_NE(cat.find("cylinder.dead_volume_cushion"), nullptr);
  EXPECT_NEAR(*cat.find("cylinder.dead_volume_cushion")->parameters[0].null_value, 2e-6, 1e-18);
  // At its null value an effect reproduces the unpatched model.
  const Effect* leak = cat.find("leakage_piston_seal");
  ASSERT_NE(leak, nullptr);
  MeasurementModel mm;
  Netlist patched = apply_effects(model, {{leak, {0.0}}}, &mm);
  Netlist base = load_netlist(kModel);
  patched.simulation.t_end = base.simulation.t_end = 0.4;
  const auto a = run_simulation(patched, builtin_registry()), b = run_simulation(base, builtin_registry());
  ASSERT_TRUE(a.solver.ok && b.solver.ok);
  const int cx = a.table.column("x");
  EXPECT_NEAR(a.table.rows.back()[cx], b.table.rows.back()[cx], 1e-7);
}

// The largest difference in piston position between two netlists over the
// first 0.6 s (a stroke into the cushion), NaN when one fails.
double max_x_difference(Netlist a, Netlist b) {
  a.simulation.t_end = b.simulation.t_end = 0.6;
  const auto ra = run_simulation(a, builtin_registry()), rb = run_simulation(b, builtin_registry());
  if (!ra.solver.ok || !rb.solver.ok) {
    ADD_FAILURE() << ra.solver.message << " / " << rb.solver.message;
    return NAN;
  }
  const int xa = ra.table.column("x"), xb = rb.table.column("x");
  double m = 0;
  for (std::size_t i = 0; i < std::min(ra.table.rows.size(), rb.table.rows.size()); ++i)
    m = std::max(m, std::abs(ra.table.rows[i][xa] - rb.table.rows[i][xb]));
  return m;
}

// Every parameter's null value (the effect vanishes), or a failure.
std::vector<double> null_values(const Effect& e) {
  std::vector<double> v;
  for (const auto& p : e.parameters) {
    EXPECT_TRUE(p.null_value.has_value()) << e.name << "." << p.name;
    v.push_back(p.null_value.value_or(NAN));
  }
  return v;
}

TEST(Diagnose, FrictionCandidateHoldsTheNetlistsLawAtItsNull) {
  // The main-stroke law (Annex B 5.14) at level s growing at m per bar of
  // p_A + p_B: its null (s = 1, m = 0) is the unpatched stroke.
  const Netlist model = load_netlist(kModel);
  const Catalogue cat = load_catalogue(kSource + "/catalogues/cushion_rig.yaml", model, builtin_registry());
  const Effect* e = cat.find("friction_pressure");
  ASSERT_TRUE(e && e->parameters.size() == 2u);  // s, m
  EXPECT_LT(max_x_difference(apply_effects(model, {{e, null_values(*e)}}, nullptr), model), 1e-7);
  // 10 % more friction per bar slows the stroke.
  EXPECT_GT(max_x_difference(apply_effects(model, {{e, {1.0, 0.1}}}, nullptr), model), 1e-4);
}

TEST(Diagnose, CushionZoneFrictionMovesFromTheMainLawToAnnexCpEC) {
  // The free weight w and level k are substituted into arithmetic
  // expressions: at w = 1, k = 1 the coefficients are Annex C pEC's (seed
  // 000), k scales the zone's whole law, and at the null (w = 0, k = 1) the
  // main-stroke law (Annex B 5.14) holds in the cushioning zone too, so the
  // stroke is the unpatched model's.
  const Netlist model = load_netlist(kModel);
  const Catalogue cat = load_catalogue(kSource + "/catalogues/cushion_rig.yaml", model, builtin_registry());
  const Effect* e = cat.find("friction_cushion_zone");
  ASSERT_NE(e, nullptr);
  ASSERT_EQ(e->parameters.size(), 2u);  // w, k
  const Netlist w1 = apply_effects(model, {{e, {1.0, 1.0}}}, nullptr);
  const auto cylinder = std::find_if(w1.components.begin(), w1.components.end(),
                                     [](const ComponentDecl& c) { return c.name == "cylinder"; });
  ASSERT_NE(cylinder, w1.components.end());
  auto at1 = [&](const std::string& name) {
    for (const auto& [n, v] : cylinder->parameters)
      if (n == name) return v;
    ADD_FAILURE() << name << " not set";
    return ValueDecl{};
  };
  // A value that is exactly ${...} is the SI number; one with a unit stays text, the number written in.
  EXPECT_NEAR(at1("friction_cushion_b0").si.value_or(NAN), 9.66, 1e-12);
  EXPECT_NEAR(at1("friction_cushion_FS0").si.value_or(NAN), 8.8, 1e-12);
  EXPECT_NEAR(at1("friction_cushion_vS").si.value_or(NAN), 2.96e-3, 1e-15);
  EXPECT_NEAR(at1("friction_cushion_a").si.value_or(NAN), 1.0, 1e-12);
  const std::string kv1 = at1("friction_cushion_kv1").text;
  EXPECT_NEAR(std::stod(kv1), 19.61, 1e-12);
  EXPECT_NE(kv1.find(" N/bar"), std::string::npos) << kv1;
  const Netlist k2 = apply_effects(model, {{e, {1.0, 2.0}}}, nullptr);
  for (const auto& c : k2.components)
    if (c.name == "cylinder")
      for (const auto& [n, v] : c.parameters)
        if (n == "friction_cushion_b0") EXPECT_NEAR(v.si.value_or(NAN), 2 * 9.66, 1e-12);

  EXPECT_LT(max_x_difference(apply_effects(model, {{e, null_values(*e)}}, nullptr), model), 1e-7);
  const double max_w1 = max_x_difference(w1, model);
  EXPECT_GT(max_w1, 1e-4);  // and the effect does act in the cushioning zone
}

TEST(Diagnose, CommandLineReportsBadInputWithExitStatus2) {
  const fs::path dir = temp_dir("cli");
  fs::copy(leak_runs(), dir / "runs");
  replace_in(dir / "runs" / "val.csv", "t,x,", "t,x_piston,");
  const std::string cmd = std::string(PNEUMO_BINARY) + " diagnose " + kModel + " --runs " + (dir / "runs").string() +
                          " --effects " + kSource + "/catalogues/cushion_rig.yaml --out " + (dir / "out").string() +
                          " > " + (dir / "log").string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_NE(slurp(dir / "log").find("unknown output name 'x_piston'"), std::string::npos) << slurp(dir / "log");
  EXPECT_FALSE(fs::exists(dir / "out" / "report.json"));
}
