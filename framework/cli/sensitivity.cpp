// pneumo sensitivity NETLIST --param NAME=LOW:HIGH ... [--method morris|sobol] [-j N] [-o indices.csv]
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "components/builtin.hpp"
#include "framework/io/results.hpp"
#include "framework/cli/command.hpp"
#include "framework/cli/count_option.hpp"
#include "framework/cli/split_list.hpp"
#include "framework/cli/study_support.hpp"
#include "framework/study/sensitivity.hpp"
#include "framework/study/sweep.hpp"

namespace pneumo::cli {

namespace {

bool is_sensitivity_header(const std::string& first_line) { return first_line.rfind("metric,parameter,", 0) == 0; }

namespace fs = std::filesystem;
using namespace pneumo::study;

struct SensitivityArgs : StudyArgs {
  std::string method = "morris";
  std::vector<std::string> params;
  int trajectories = 20, levels = 4, base = 256;
  long seed = 1;
};

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

int sensitivity_command(const SensitivityArgs& a) {
  Communicator& comm = process_communicator();
  const Model model = load_model(a.netlist, builtin_registry(), a.sets);
  const Netlist& nl = model.netlist;
  if (a.params.empty())
    throw InputError(SourceLocation{a.netlist, 1, 1}, "", "", "pneumo sensitivity: give the ranges with --param NAME=LOW:HIGH ...");
  const auto ranges = parse_ranges(nl, model.registry, a.params);
  const int k = static_cast<int>(ranges.size());
  const auto metrics = select_metrics(nl, model.registry, split_list(a.metrics));
  if (a.method != "morris" && a.method != "sobol")
    throw InputError(SourceLocation{a.netlist, 1, 1}, "", "", "--method must be morris or sobol, not '" + a.method + "'");

  std::vector<UnitPoint> unit;
  MorrisPlan morris;
  SobolPlan sobol;
  if (a.method == "morris") {
    morris = morris_plan(k, a.trajectories, a.levels, static_cast<std::uint64_t>(a.seed));
    unit = morris.points;
  } else {
    sobol = sobol_plan(k, a.base, static_cast<std::uint64_t>(a.seed));
    unit = sobol.points;
  }
  Design d;
  for (const auto& r : ranges) d.parameters.push_back(r.parameter);
  for (const auto& u : unit) {
    Sample s;
    for (int j = 0; j < k; ++j) s.push_back(ranges[j].lo + u[j] * (ranges[j].hi - ranges[j].lo));
    d.samples.push_back(std::move(s));
  }
  const std::string output = study_output(a, ".sensitivity.csv", is_sensitivity_header, {a.netlist});
  const std::string runs_path = (fs::path(output).parent_path() / fs::path(output).stem()).string() + ".runs.csv";
  try {
    check_chosen_output_file(runs_path, "choose another -o", {a.netlist}, is_sweep_results_header);
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{"-o", 0, 0}, "", "", e.what());
  }
  SweepOptions opt;
  opt.threads = a.threads;
  opt.progress = !a.quiet;
  opt.assembly.eliminate_aliases = a.eliminate;
  for (const auto& m : metrics) opt.metrics.push_back(m.name);
  if (comm.rank() == 0 && !a.quiet)
    std::cout << a.method << ": " << k << " parameters, " << d.samples.size() << " runs -> " << runs_path << "\n";
  const SweepSummary s = run_sweep(model, d, runs_path, opt, comm);
  if (comm.rank() != 0) return 0;
  report(s, runs_path, a.quiet);
  if (!s.complete) return 1;
  if (s.failed == s.runs)  // indices of no data would be NaN: say why instead
    return every_run_failed(model, "pneumo sensitivity: every run failed, there are no indices",
                            failure_summary(s.records));

  std::ostringstream csv;
  std::ostringstream table;
  if (a.method == "morris") {
    csv << "metric,parameter,mu_star,mu,sigma,effects\n";
    table << "Morris screening (" << a.trajectories << " trajectories, " << a.levels
          << " levels; effects per full parameter range)\n";
  } else {
    csv << "metric,parameter,S1,S1_lo,S1_hi,ST,ST_lo,ST_hi,rows\n";
    table << "Sobol indices (" << a.base << " base samples, 95 % bootstrap intervals)\n";
  }
  for (std::size_t m = 0; m < metrics.size(); ++m) {
    std::vector<double> f;
    for (const auto& r : s.records) f.push_back(r.ok ? metrics[m].display.shown(r.metrics[m]) : NAN);
    table << "  " << metrics[m].name << " [" << metrics[m].unit << "]\n";
    if (a.method == "morris") {
      const MorrisIndices ix = morris_indices(morris, f);
      for (int j = 0; j < k; ++j) {
        csv << metrics[m].name << "," << ranges[j].parameter.name << "," << num(ix.mu_star[j]) << ","
            << num(ix.mu[j]) << "," << num(ix.sigma[j]) << "," << ix.effects[j] << "\n";
        table << "    " << ranges[j].parameter.name << ": mu* " << num(ix.mu_star[j]) << ", mu " << num(ix.mu[j])
              << ", sigma " << num(ix.sigma[j]) << " (" << ix.effects[j] << " effects)\n";
      }
    } else {
      const SobolIndices ix = sobol_indices(sobol, f);
      for (int j = 0; j < k; ++j) {
        csv << metrics[m].name << "," << ranges[j].parameter.name << "," << num(ix.first[j]) << ","
            << num(ix.first_lo[j]) << "," << num(ix.first_hi[j]) << "," << num(ix.total[j]) << ","
            << num(ix.total_lo[j]) << "," << num(ix.total_hi[j]) << "," << ix.rows_used << "\n";
        table << "    " << ranges[j].parameter.name << ": S1 " << num(ix.first[j]) << " [" << num(ix.first_lo[j])
              << ", " << num(ix.first_hi[j]) << "], ST " << num(ix.total[j]) << " [" << num(ix.total_lo[j]) << ", "
              << num(ix.total_hi[j]) << "] (" << ix.rows_used << " rows)\n";
      }
    }
  }
  write_text_atomic(output, csv.str());
  if (!a.quiet) std::cout << table.str() << "wrote " << output << "\n";
  return 0;
}

}  // namespace

Command add_sensitivity_command(CLI::App& app) {
  auto sa = std::make_shared<SensitivityArgs>();
  auto* se = app.add_subcommand("sensitivity", "Morris screening or Sobol indices of the run metrics over parameter ranges");
  add_study_options(se, *sa);
  se->add_option("--param", sa->params, "NAME=LOW:HIGH (repeatable)")->take_all();
  se->add_option("--method", sa->method, "morris (screening) or sobol (variance-based indices)");
  se->add_option("--trajectories", sa->trajectories, "Morris: trajectories (runs = trajectories * (k + 1))")
      ->transform(whole_number(1, 100000));
  se->add_option("--levels", sa->levels, "Morris: grid levels (even)")->transform(whole_number(2, 1000));
  se->add_option("--base-samples", sa->base, "Sobol: base samples N (runs = N * (k + 2))")
      ->transform(whole_number(1, 1000000));
  se->add_option("--seed", sa->seed, "random seed of the design");
  se->add_option("-o,--output", sa->output,
                 "indices CSV (default: NETLIST_STEM.sensitivity.csv); the runs go to OUTPUT_STEM.runs.csv");
  se->add_flag("-q,--quiet", sa->quiet, "no progress bar or tables");
  return study_command(se, sa, sensitivity_command);
}

}  // namespace pneumo::cli
