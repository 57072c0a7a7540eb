// pneumo sweep NETLIST (--grid NAME=FROM:TO:COUNT ... | --samples FILE) [-j N] [-o results.csv]
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "components/builtin.hpp"
#include "framework/cli/command.hpp"
#include "framework/cli/split_list.hpp"
#include "framework/cli/study_support.hpp"
#include "framework/study/sweep.hpp"

namespace pneumo::cli {

namespace {

using namespace pneumo::study;

struct SweepArgs : StudyArgs {
  std::string samples;
  std::vector<std::string> grid;
};

int sweep_command(const SweepArgs& a) {
  Communicator& comm = process_communicator();
  const Model model = load_model(a.netlist, builtin_registry(), a.sets);
  if ((a.grid.empty()) == (a.samples.empty()))
    throw InputError(SourceLocation{a.netlist, 1, 1}, "", "", "pneumo sweep: give either --grid NAME=FROM:TO:COUNT ... or --samples FILE");
  const Design d = a.grid.empty() ? samples_design(model.netlist, model.registry, a.samples)
                                  : grid_design(model.netlist, model.registry, a.grid);
  const std::string output = study_output(a, ".sweep.csv", is_sweep_results_header, {a.netlist, a.samples});
  SweepOptions opt;
  opt.threads = a.threads;
  opt.progress = !a.quiet;
  opt.metrics = split_list(a.metrics);
  opt.assembly.eliminate_aliases = a.eliminate;
  const SweepSummary s = run_sweep(model, d, output, opt, comm);
  if (comm.rank() == 0) {
    report(s, output, a.quiet);
    if (s.failed > 0)
      std::cerr << "pneumo sweep: " << s.failed << " of " << s.runs << " runs failed (status 'failed' and the reason in "
                << output << ")\n";
  }
  if (comm.rank() == 0 && s.complete && s.runs > 0 && s.failed == s.runs)
    // Nothing was computed: a results file of failures is not a success.
    return every_run_failed(model, "pneumo sweep: every run failed", failure_summary(s.records));
  return s.complete || comm.rank() != 0 ? 0 : 1;
}

}  // namespace

Command add_sweep_command(CLI::App& app) {
  auto a = std::make_shared<SweepArgs>();
  auto* sw = app.add_subcommand("sweep", "run a netlist over a parameter grid or sample list; metrics per run to CSV");
  add_study_options(sw, *a);
  sw->add_option("--grid", a->grid,
                 "NAME=FROM:TO:COUNT (repeatable; full factorial). NAME: top-level parameter or COMPONENT.PARAMETER")
      ->take_all();
  sw->add_option("--samples", a->samples, "CSV of runs: header of parameter names, one row per run");
  sw->add_option("-o,--output", a->output, "results CSV (default: NETLIST_STEM.sweep.csv)");
  sw->add_flag("-q,--quiet", a->quiet, "no progress bar or summary");
  return study_command(sw, a, sweep_command);
}

}  // namespace pneumo::cli
