// Withheld-effect benchmark for `pneumo diagnose` (issue #6).
//
// Generates synthetic measured runs from netlists/cushion_rig.yaml with one
// or two effects switched on in forms and values that differ from the
// candidates (benchmarks/withheld_effects.yaml, second-order sensor lags
// here), sampled at 500 Hz with noise (x 0.02 mm, p 2 kPa, T 0.3 K) and
// quantisation, plus cases with nothing withheld; diagnoses each case against
// catalogues/cushion_rig.yaml and prints the confusion matrix, the share of
// single-effect cases with the right effect first, false claims on clean
// data and the validation gap shrink.
//
//   diagnose_benchmark [--source DIR] [--work DIR] [--quick] [--threads N] [--noise-scale F]
//                      [--case NAME] [--screen-keep N]
#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <sstream>

#include "components/builtin.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "framework/run/run.hpp"

using namespace pneumo;
using namespace pneumo::diagnose;
namespace fs = std::filesystem;

namespace {

struct Case {
  std::string name;
  std::vector<std::string> withheld;  // names in withheld_effects.yaml or sensor_lag_T / sensor_lag_p
  unsigned seed;
};

struct OperatingPoint {
  double p_supply, m_load, z_EC;
};

std::vector<double> lag(const std::vector<double>& t, const std::vector<double>& u, double tau) {
  std::vector<double> y(u.size());
  y[0] = u[0];
  for (std::size_t i = 1; i < u.size(); ++i) {
    const double a = std::exp(-(t[i] - t[i - 1]) / tau);
    y[i] = a * y[i - 1] + (1 - a) * u[i];
  }
  return y;
}

double interp(const std::vector<double>& t, const std::vector<double>& y, double tq) {
  if (tq <= t.front()) return y.front();
  if (tq >= t.back()) return y.back();
  const std::size_t i = std::upper_bound(t.begin(), t.end(), tq) - t.begin();
  const double w = (tq - t[i - 1]) / (t[i] - t[i - 1]);
  return y[i - 1] + w * (y[i] - y[i - 1]);
}

void generate(const Case& c, const fs::path& dir, const std::string& source, double noise_scale) {
  const std::string model_file = source + "/netlists/cushion_rig.yaml";
  const YAML::Node model = YAML::LoadFile(model_file);
  const Catalogue truth =
      load_catalogue(source + "/benchmarks/withheld_effects.yaml", model, model_file, builtin_registry());
  std::vector<EffectInstance> inst;
  bool lag_T = false, lag_p = false;
  for (const auto& w : c.withheld) {
    if (w == "sensor_lag_T") lag_T = true;
    else if (w == "sensor_lag_p") lag_p = true;
    else inst.push_back({truth.find(w), {}});
  }
  const std::string text = YAML::Dump(apply_effects(model, inst, nullptr));
  const std::vector<OperatingPoint> ops = {{5e5, 3.7, 1.5}, {6e5, 2.5, 1.0}, {4e5, 5.0, 2.5},
                                           {5.5e5, 4.5, 2.0}, {4.5e5, 3.0, 1.2}, {6.5e5, 4.0, 3.0}};
  const std::vector<std::string> signals = {"x", "p_A", "p_EC", "T_EC"};
  const std::map<std::string, std::pair<double, double>> noise = {  // sigma, quantum
      {"x", {2e-5, 5e-6}}, {"p_A", {2e3, 100}}, {"p_EC", {2e3, 100}}, {"T_EC", {0.3, 0.1}}};
  std::mt19937 rng(c.seed);
  fs::create_directories(dir);
  for (std::size_t k = 0; k < ops.size(); ++k) {
    Netlist nl = parse_netlist(text, model_file);
    apply_override(nl, "p_supply=" + std::to_string(ops[k].p_supply));
    apply_override(nl, "m_load=" + std::to_string(ops[k].m_load));
    apply_override(nl, "z_EC=" + std::to_string(ops[k].z_EC));
    nl.simulation.t_end = 0.6;
    nl.simulation.output_interval = 2e-4;
    nl.simulation.rtol = 1e-7;
    const RunResult res = run_simulation(nl, builtin_registry());
    if (!res.solver.ok) throw std::runtime_error("truth simulation failed: " + res.solver.message);
    std::vector<double> ts;
    for (const auto& row : res.table.rows) ts.push_back(row[0]);
    const std::string name = "run" + std::to_string(k + 1);
    std::ofstream csv(dir / (name + ".csv"));
    csv << "t";
    for (const auto& s : signals) csv << "," << s;
    csv << "\n";
    std::vector<std::vector<double>> ys;
    for (const auto& s : signals) {
      const int col = res.table.column(s);
      std::vector<double> y;
      for (const auto& row : res.table.rows) y.push_back(row[col]);
      if (lag_T && s == "T_EC") y = lag(ts, lag(ts, y, 0.12), 0.04);          // second-order thermocouple
      if (lag_p && s[0] == 'p') y = lag(ts, lag(ts, y, 0.004), 0.0015);       // second-order transducer
      ys.push_back(std::move(y));
    }
    csv.precision(10);
    for (double t = 0.0; t <= 0.6 + 1e-12; t += 0.002) {
      csv << t;
      for (std::size_t s = 0; s < signals.size(); ++s) {
        const auto [sigma, q] = noise.at(signals[s]);
        std::normal_distribution<double> n(0.0, sigma * noise_scale);
        const double v = interp(ts, ys[s], t) + n(rng);
        csv << "," << std::round(v / q) * q;
      }
      csv << "\n";
    }
    std::ofstream yml(dir / (name + ".yaml"));
    yml << "data: " << name << ".csv\nrole: " << (k < 4 ? "calibration" : "validation") << "\noperating_point:\n"
        << "  p_supply: " << ops[k].p_supply << "\n  m_load: " << ops[k].m_load << "\n  z_EC: " << ops[k].z_EC << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string source = PNEUMO_SOURCE_DIR, work = "/tmp/pneumo_diagnose_benchmark";
  bool quick = false;
  int threads = 2;
  double noise_scale = 1.0;
  std::string only_case;
  int screen_keep = -1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--source" && i + 1 < argc) source = argv[++i];
    else if (a == "--work" && i + 1 < argc) work = argv[++i];
    else if (a == "--quick") quick = true;
    else if (a == "--threads" && i + 1 < argc) threads = std::stoi(argv[++i]);
    else if (a == "--noise-scale" && i + 1 < argc) noise_scale = std::stod(argv[++i]);
    else if (a == "--case" && i + 1 < argc) only_case = argv[++i];
    else if (a == "--screen-keep" && i + 1 < argc) screen_keep = std::stoi(argv[++i]);
    else {
      std::cerr << "usage: diagnose_benchmark [--source DIR] [--work DIR] [--quick] [--threads N] [--noise-scale F] "
                   "[--case NAME] [--screen-keep N]\n";
      return 2;
    }
  }
  std::vector<Case> cases = {
      {"none_1", {}, 11},
      {"heat_transfer", {"heat_transfer"}, 1},
      {"leakage_piston_seal", {"leakage_piston_seal"}, 2},
      {"valve_timing", {"valve_timing"}, 3},
      {"sensor_lag_T", {"sensor_lag_T"}, 4},
      {"end_stop_elasticity", {"end_stop_elasticity"}, 5},
      {"friction_pressure", {"friction_pressure"}, 6},
      {"supply_droop", {"supply_droop"}, 7},
      {"line_volume", {"line_volume"}, 8},
      {"sensor_lag_p", {"sensor_lag_p"}, 9},
      {"friction_cushion_zone", {"friction_cushion_zone"}, 10},
      {"none_2", {}, 12},
      {"heat_transfer+leakage_piston_seal", {"heat_transfer", "leakage_piston_seal"}, 13},
      {"valve_timing+sensor_lag_T", {"valve_timing", "sensor_lag_T"}, 14},
      {"none_3", {}, 15},
  };
  if (quick) cases = {cases[0], cases[1], cases[2], cases[3]};
  if (!only_case.empty()) {
    std::erase_if(cases, [&](const Case& c) { return c.name != only_case; });
    // Any other withheld effect on its own (those in no catalogue).
    if (cases.empty() && YAML::LoadFile(source + "/benchmarks/withheld_effects.yaml")["effects"][only_case])
      cases.push_back({only_case, {only_case}, 21});
    if (cases.empty()) {
      std::cerr << "diagnose_benchmark: no case '" << only_case << "'\n";
      return 2;
    }
  }

  struct Outcome {
    Case c;
    std::vector<std::string> verdict;
    std::vector<std::vector<std::string>> groups;
    double before, after, seconds;
  };
  std::vector<Outcome> outcomes;
  DiagnoseOptions opt;
  opt.threads = threads;
  if (screen_keep > 0) opt.screen_keep = screen_keep;
  opt.progress = std::getenv("PNEUMO_BENCH_VERBOSE") != nullptr;
  for (const auto& c : cases) {
    const fs::path dir = fs::path(work) / c.name;
    fs::remove_all(dir);
    try {
      generate(c, dir / "runs", source, noise_scale);
    } catch (const std::exception& ex) {
      std::printf("%-36s    SKIPPED: generating the data failed: %s\n", c.name.c_str(), ex.what());
      continue;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const auto rep = pneumo::diagnose::diagnose(source + "/netlists/cushion_rig.yaml", (dir / "runs").string(),
                              source + "/catalogues/cushion_rig.yaml", builtin_registry(), opt);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    write_report_json(rep, (dir / "report.json").string());
    write_report_html(rep, (dir / "report.html").string());
    outcomes.push_back({c, rep.verdict, rep.verdict_groups, rep.validation_before.total.rms,
                        rep.validation_after.total.rms, secs});
    std::string v;
    for (const auto& n : rep.verdict) v += (v.empty() ? "" : "+") + n;
    std::printf("%-36s -> %-40s gap %8.3g -> %6.3g  (%.0f s, %ld simulations)\n", c.name.c_str(),
                v.empty() ? "(none)" : v.c_str(), rep.validation_before.total.rms, rep.validation_after.total.rms,
                secs, rep.simulations);
    if (rep.unexplained)
      std::printf("    unexplained (%ld simulations, %.1f s): %s\n", rep.unexplained->simulations,
                  rep.unexplained->seconds, rep.unexplained->sentence.c_str());
    std::fflush(stdout);
  }

  // Confusion matrix of the single-effect and clean cases: withheld -> first verdict.
  std::vector<std::string> labels = {"none"};
  for (const auto& o : outcomes)
    if (o.c.withheld.size() == 1) labels.push_back(o.c.withheld[0]);
  auto first = [](const Outcome& o) { return o.verdict.empty() ? std::string("none") : o.verdict[0]; };
  std::vector<std::string> cols = labels;
  for (const auto& o : outcomes)
    if (std::find(cols.begin(), cols.end(), first(o)) == cols.end()) cols.push_back(first(o));
  std::printf("\nconfusion matrix (rows: withheld, columns: first effect in the verdict)\n%-24s", "");
  for (std::size_t j = 0; j < cols.size(); ++j) std::printf(" %3zu", j);
  std::printf("\n");
  for (const auto& row : labels) {
    std::printf("%-24s", row.c_str());
    for (const auto& col : cols) {
      int n = 0;
      for (const auto& o : outcomes) {
        const std::string w = o.c.withheld.empty() ? "none" : o.c.withheld.size() == 1 ? o.c.withheld[0] : "";
        if (w == row && first(o) == col) ++n;
      }
      std::printf(" %3s", n ? std::to_string(n).c_str() : ".");
    }
    std::printf("\n");
  }
  for (std::size_t j = 0; j < cols.size(); ++j) std::printf("  column %zu = %s\n", j, cols[j].c_str());

  int single = 0, right = 0, right_group = 0, clean = 0, claimed = 0, pairs = 0, pair_both = 0, extra = 0;
  std::vector<double> shrink;
  for (const auto& o : outcomes) {
    if (o.c.withheld.empty()) {
      ++clean;
      claimed += !o.verdict.empty();
      continue;
    }
    shrink.push_back(1 - o.after / o.before);
    if (o.c.withheld.size() == 1) {
      ++single;
      right += first(o) == o.c.withheld[0];
      extra += o.verdict.size() > 1;
      bool in = false;
      if (!o.groups.empty())
        for (const auto& g : o.groups[0]) in = in || g == o.c.withheld[0];
      right_group += in;
    } else {
      ++pairs;
      int found = 0;
      for (const auto& w : o.c.withheld) found += std::find(o.verdict.begin(), o.verdict.end(), w) != o.verdict.end();
      pair_both += found == static_cast<int>(o.c.withheld.size());
    }
  }
  std::sort(shrink.begin(), shrink.end());
  const double med = shrink.empty() ? NAN
                     : shrink.size() % 2 ? shrink[shrink.size() / 2]
                                         : 0.5 * (shrink[shrink.size() / 2 - 1] + shrink[shrink.size() / 2]);
  double total_s = 0;
  for (const auto& o : outcomes) total_s += o.seconds;
  std::printf("\nsingle-effect cases: right effect first in %d / %d (%.0f %%; target >= 90 %%), within the reported group %d / %d\n",
              right, single, single ? 100.0 * right / single : 0.0, right_group, single);
  std::printf("single-effect cases with a second effect claimed as well: %d / %d\n", extra, single);
  std::printf("clean cases: an effect claimed in %d / %d (target 0)\n", claimed, clean);
  std::printf("two-effect cases: both found in %d / %d\n", pair_both, pairs);
  std::printf("median validation gap shrink (cases with an effect): %.0f %% (target >= 70 %%)\n", 100 * med);
  std::printf("diagnosis time: %.0f s for %zu cases (%.0f s each, 6 runs x 12 candidates, %d threads)\n", total_s,
              outcomes.size(), total_s / outcomes.size(), threads);
  return 0;
}
