// pneumo simulate NETLIST [--set NAME=VALUE ...] [-o results.csv] [--stats] [--plot PREFIX]
//                 [--energy-audit audit.yaml] [--metrics-out metrics.csv]
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "components/builtin.hpp"
#include "framework/analysis/energy_audit.hpp"
#include "framework/analysis/run_metrics.hpp"
#include "framework/cli/command.hpp"
#include "framework/cli/split_list.hpp"
#include "framework/io/plot.hpp"
#include "framework/io/results.hpp"
#include "framework/model/simulation_options.hpp"
#include "framework/run/model.hpp"
#include "framework/run/run.hpp"

namespace pneumo::cli {

namespace {

struct SimulateArgs {
  std::string netlist, output;
  std::vector<std::string> sets;
  bool stats = false, quiet = false, output_given = false;
  std::string plot_prefix, plot_columns, audit_path, metrics_path;
};

void print_stats(const SolverResult& r, double seconds, std::ostream& out) {
  const auto& s = r.stats;
  out << "solver: IDA + KLU, " << s.variables << " variables, " << s.nonzeros << " Jacobian nonzeros\n"
      << "  (the netlist's " << s.netlist_variables << " unknowns: " << s.explicit_variables
      << " solved inside the residual, " << s.netlist_variables - s.explicit_variables - s.variables
      << " substituted as aliases or constants)\n"
      << "  steps " << s.steps << ", residual evaluations " << s.residual_evals << ", Jacobian evaluations "
      << s.jacobian_evals;
  if (s.jacobian_recombinations > 0)
    out << " (and " << s.jacobian_recombinations << " recombined from the last one's parts; " << s.recombined_retries
        << " failed a Newton iteration and were evaluated afresh at the same step)";
  out << "\n"
      << "  nonlinear iterations " << s.nonlinear_iterations << ", convergence failures " << s.nonlinear_failures
      << ", error test failures " << s.error_test_failures << "\n"
      << "  root function evaluations " << s.root_evals << ", re-initialisations " << s.reinitialisations
      << ", events " << r.events.size() << "\n";
  if (s.parts > 1)
    out << "  " << s.parts << " independent parts, each its own IDA (steps of the largest " << s.part_steps_max
        << ")\n";
  out << "  wall time " << seconds * 1e3 << " ms\n";
  if (s.pattern_misses > 0)
    out << "  WARNING: " << s.pattern_misses << " Jacobian entries fell outside the structural pattern\n";
}

void write_energy_audit(const std::vector<EnergyAudit>& audits, const std::string& audit_path, bool quiet) {
  std::ostringstream yaml;
  write_audit_yaml(audits, yaml);
  write_text_atomic(audit_path, yaml.str());
  if (!quiet) {
    for (const auto& a : audits) print_audit(a, std::cout);
    std::cout << "wrote the energy audit to " << audit_path << "\n";
  }
}

void print_metrics(const Netlist& nl, const std::vector<double>& values, const std::vector<units::DisplayUnit>& units,
                   const std::vector<std::string>& why) {
  for (std::size_t i = 0; i < nl.metrics.size(); ++i)
    std::cout << "metric " << nl.metrics[i].name << " = " << std::setprecision(6) << units[i].shown(values[i])
              << (units[i].unit == "1" ? "" : " " + units[i].unit)
              << (why[i].empty() ? "" : " (undefined: " + why[i] + ")") << "\n";
}

void write_metrics_csv(const std::string& path, const Netlist& nl, const std::vector<double>& values,
                       const std::vector<units::DisplayUnit>& units) {
  std::ostringstream csv;
  csv << "metric,value,unit\n" << std::setprecision(17);
  for (std::size_t i = 0; i < nl.metrics.size(); ++i)
    csv << nl.metrics[i].name << "," << units[i].shown(values[i]) << "," << units[i].unit << "\n";
  write_text_atomic(path, csv.str());
}

// Bad output names are bad input, found before the run. A default name
// (no -o) never replaces a file that is there.
void check_outputs(const SimulateArgs& a, const std::string& output) {
  const std::vector<std::string> inputs{a.netlist};
  try {
    if (a.output_given)
      check_output_file(output, "-o", inputs);
    else
      check_chosen_output_file(output, "give -o " + output + " to replace it, or another name", inputs);
    if (!a.audit_path.empty()) check_output_file(a.audit_path, "--energy-audit", inputs);
    if (!a.metrics_path.empty()) check_output_file(a.metrics_path, "--metrics-out", inputs);
    if (!a.plot_prefix.empty()) {
      check_output_file(a.plot_prefix + ".png", "--plot", inputs);
      check_output_file(a.plot_prefix + ".svg", "--plot", inputs);
    }
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{a.netlist, 0, 0}, "", "", e.what());
  }
}

void print_written(const ResultsTable& table, const std::string& output) {
  std::cout << "wrote " << table.rows.size() << " rows x " << table.names.size() << " columns to " << output << "\n";
  // Final values: quick sanity for the user.
  if (!table.rows.empty()) {
    const auto& last = table.rows.back();
    std::cout << "final:";
    for (std::size_t i = 0; i < last.size(); ++i) {
      const units::DisplayUnit d = table.shown_as(i);
      std::cout << " " << table.names[i] << "=" << d.shown(last[i]) << (d.unit.empty() || d.unit == "1" ? "" : " " + d.unit);
    }
    std::cout << "\n";
  }
}

int simulate_command(const SimulateArgs& a) {
  const std::string& netlist_path = a.netlist;
  std::string output = a.output;
  const bool stats = a.stats, quiet = a.quiet;
  const std::string &plot_prefix = a.plot_prefix, &plot_columns = a.plot_columns, &audit_path = a.audit_path;
  const Model model = load_model(netlist_path, builtin_registry(), a.sets);  // with the netlist's `plugins:`
  Netlist nl = model.netlist;
  const bool user_outputs = !nl.outputs.empty();
  if (output.empty() && !a.output_given) output = std::filesystem::path(netlist_path).stem().string() + ".csv";
  check_outputs(a, output);
  if (const auto parent = std::filesystem::path(output).parent_path(); !parent.empty())
    std::filesystem::create_directories(parent);

  const auto t0 = std::chrono::steady_clock::now();
  const Registry& registry = model.registry;
  // Every metric of the netlist is evaluated; integrals and audits are extra outputs.
  const std::vector<bool> all_metrics(nl.metrics.size(), true);
  add_metric_outputs(nl, all_metrics);
  Circuit circuit = elaborate(nl, registry);  // the parameters' errors surface here, assembly's in run_circuit
  std::vector<AuditPlan> audit_plans;
  if (!audit_path.empty() || metrics_read_audit(nl, all_metrics)) audit_plans = prepare_energy_audit(nl, circuit);
  if (!audit_path.empty() && audit_plans.empty())
    throw InputError(SourceLocation{nl.file, 1, 1}, "", "",
                     "--energy-audit: no component of this netlist declares an energy audit");
  if (!user_outputs)
    throw InputError(SourceLocation{nl.file, 1, 1}, "", "",
                     "the netlist has no 'outputs:' (name: component.variable); nothing would be written");
  const std::vector<units::DisplayUnit> metric_unit = metric_units(nl, circuit);
  RunResult run = run_circuit(std::move(circuit), solver_options(nl.simulation));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<EnergyAudit> audits;
  std::vector<double> metric_values;
  if (run.solver.ok) {
    audits = energy_audit(audit_plans, run);
    metric_values = evaluate_metrics(nl, all_metrics, run, audits);
  }
  drop_audit_columns(run.table);
  drop_metric_columns(run.table);

  if (!quiet)
    for (const auto& ev : run.solver.events)
      std::cout << "event t = " << ev.t << " s  " << ev.component << ": " << ev.message << "\n";
  if (!run.solver.ok) {
    const std::string partial = write_partial_csv(output, run.table, run.solver.message);
    std::cerr << "pneumo: simulation of " << netlist_path << " failed: " << run.solver.message << "\n";
    std::cerr << "pneumo: no results written to " << output << " (a file of that name is left as it was)";
    if (!partial.empty()) std::cerr << "; the rows computed so far are in " << partial;
    std::cerr << "\n";
    if (stats) print_stats(run.solver, seconds, std::cerr);
    return 1;
  }
  write_csv_atomic(output, run.table);
  if (!quiet)
    for (const auto& w : run.solver.warnings) std::cerr << "pneumo: warning: " << w << "\n";
  if (!a.metrics_path.empty()) write_metrics_csv(a.metrics_path, nl, metric_values, metric_unit);
  if (!audit_path.empty()) write_energy_audit(audits, audit_path, quiet);
  if (!quiet) print_written(run.table, output);
  if (!quiet) print_metrics(nl, metric_values, metric_unit, undefined_metric_reasons(nl, metric_values, run));
  if (stats) print_stats(run.solver, seconds, std::cout);
  if (!plot_prefix.empty()) {
    plot_results(output, plot_prefix, split_list(plot_columns), nl.file);
    if (!quiet) std::cout << "plotted " << plot_prefix << ".png and " << plot_prefix << ".svg\n";
  }
  return 0;
}

}  // namespace

Command add_simulate_command(CLI::App& app) {
  auto a = std::make_shared<SimulateArgs>();
  auto* sim = app.add_subcommand("simulate", "simulate a netlist and write the outputs to CSV");
  sim->footer("The netlist's simulation: keys (unit, default, valid range):\n" + simulation_options_help());
  sim->add_option("netlist", a->netlist, "netlist file (YAML)")->required();
  add_set_option(sim, a->sets);
  sim->add_option("-o,--output", a->output, "results CSV (default: NETLIST_STEM.csv)")
      ->each([a](const std::string&) { a->output_given = true; });
  sim->add_flag("--stats", a->stats, "print solver statistics");
  sim->add_flag("-q,--quiet", a->quiet, "print nothing but errors");
  sim->add_option("--plot", a->plot_prefix, "also plot the results to PREFIX.png and PREFIX.svg (gnuplot)");
  sim->add_option("--columns", a->plot_columns, "columns to plot, comma separated (default: all)");
  sim->add_option("--energy-audit", a->audit_path,
                  "energy audit of every component that declares one: print it and write it (YAML) to FILE");
  sim->add_option("--metrics-out", a->metrics_path, "write the netlist's metrics to FILE (CSV: metric,value,unit)");
  return {.app = sim, .run = [a] { return simulate_command(*a); }, .input = [a] { return a->netlist; }};
}

}  // namespace pneumo::cli
