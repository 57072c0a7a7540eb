// The `pneumo` command line.
//   pneumo simulate NETLIST [--set NAME=VALUE ...] [-o results.csv] [--stats]
//   pneumo components [TYPE]
// Exit status: 0 success, 1 simulation failed, 2 bad input or usage.
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "components/builtin.hpp"
#include "framework/cli/fit.hpp"
#include "framework/analysis/energy_audit.hpp"
#include "framework/cli/diagnose.hpp"
#include "framework/core/units.hpp"
#include "framework/core/version.hpp"
#include "framework/io/plot.hpp"
#include "framework/model/simulation_options.hpp"
#include "framework/plugin/plugin.hpp"
#include "framework/cli/study_commands.hpp"
#include "framework/cli/split_list.hpp"
#include "framework/run/run.hpp"

namespace {

using namespace pneumo;

const char* kVersion = PNEUMO_VERSION_STRING;

void print_component(const ComponentInfo& info, std::ostream& out) {
  out << info.type << "\n  " << info.description << "\n";
  out << "  ports:\n";
  for (const auto& p : info.ports) {
    out << "    " << p.name << " (" << domain_name(p.domain);
    if (p.causality == Causality::input) out << " input";
    if (p.causality == Causality::output) out << " output";
    if (p.optional) out << ", optional";
    out << ")  " << p.description << "\n";
  }
  if (!info.parameters.empty()) out << "  parameters:\n";
  for (const auto& p : info.parameters) {
    out << "    " << p.name;
    if (p.kind == ParameterKind::scalar) {
      out << " [" << p.unit << "]";
      if (p.default_value) out << " default " << *p.default_value;
      else out << (p.is_optional ? " optional" : " required");
      out << ", " << p.range_text();
    } else if (p.kind == ParameterKind::table) {
      out << " [table of rows (";
      for (std::size_t i = 0; i < p.columns.size(); ++i) out << (i ? ", " : "") << p.columns[i];
      out << ")]" << (p.required_table ? " required" : " optional");
    } else {
      out << " [text";
      if (!p.choices.empty()) {
        out << ": ";
        for (std::size_t i = 0; i < p.choices.size(); ++i) out << (i ? "|" : "") << p.choices[i];
      }
      out << "]";
      if (p.default_text) out << " default " << *p.default_text;
    }
    out << "  " << p.description << "\n";
  }
  if (!info.variables.empty() || !info.observables.empty()) out << "  outputs:\n";
  for (const auto& v : info.variables) out << "    " << v.name << " [" << v.unit << "]  " << v.description << "\n";
  for (const auto& v : info.observables) out << "    " << v.name << " [" << v.unit << "]  " << v.description << "\n";
}

void print_stats(const SolverResult& r, double seconds, std::ostream& out) {
  const auto& s = r.stats;
  out << "solver: IDA + KLU, " << s.variables << " variables, " << s.nonzeros << " Jacobian nonzeros\n"
      << "  (the netlist's " << s.netlist_variables << " unknowns: " << s.explicit_variables
      << " solved inside the residual, " << s.netlist_variables - s.explicit_variables - s.variables
      << " substituted as aliases or constants)\n"
      << "  steps " << s.steps << ", residual evaluations " << s.residual_evals << ", Jacobian evaluations "
      << s.jacobian_evals;
  if (s.jacobian_recombinations > 0) out << " (and " << s.jacobian_recombinations << " recombined from the last one's parts)";
  out << "\n"
      << "  nonlinear iterations " << s.nonlinear_iterations << ", convergence failures " << s.nonlinear_failures
      << ", error test failures " << s.error_test_failures << "\n"
      << "  root function evaluations " << s.root_evals << ", re-initialisations " << s.reinitialisations
      << ", events " << r.events.size() << "\n"
      << "  wall time " << seconds * 1e3 << " ms\n";
  if (s.pattern_misses > 0)
    out << "  WARNING: " << s.pattern_misses << " Jacobian entries fell outside the structural pattern\n";
}

using pneumo::cli::split_list;

int simulate_command(const std::string& netlist_path, const std::vector<std::string>& sets, std::string output,
                     bool stats, bool quiet, const std::string& plot_prefix, const std::string& plot_columns,
                     const std::string& audit_path) {
  Netlist nl = load_netlist(netlist_path);
  for (const auto& s : sets) apply_override(nl, s);
  const bool user_outputs = !nl.outputs.empty();
  if (!audit_path.empty() && prepare_energy_audit(nl).empty())
    throw InputError(SourceLocation{nl.file, 1, 1}, "", "",
                     "--energy-audit: the netlist has no cushioned_cylinder to audit");
  if (output.empty()) output = std::filesystem::path(netlist_path).stem().string() + ".csv";
  if (const auto parent = std::filesystem::path(output).parent_path(); !parent.empty())
    std::filesystem::create_directories(parent);

  const auto t0 = std::chrono::steady_clock::now();
  const Registry registry = registry_with_plugins(builtin_registry(), nl);  // the netlist's `plugins:`
  System system(elaborate(nl, registry));  // all input errors surface here
  if (!user_outputs)
    throw InputError(SourceLocation{nl.file, 1, 1}, "", "",
                     "the netlist has no 'outputs:' (name: component.variable); nothing would be written");
  RunResult run = run_system(system, solver_options(nl.simulation));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<CushionAudit> audits;
  if (!audit_path.empty()) {
    if (run.solver.ok) audits = energy_audit(nl, run);
    drop_audit_columns(run.table);
  }

  if (!quiet)
    for (const auto& ev : run.solver.events)
      std::cout << "event t = " << ev.t << " s  " << ev.component << ": " << ev.message << "\n";
  if (!run.solver.ok) {
    const std::string partial = write_partial_csv(output, run.table, run.solver.message);
    std::cerr << "pneumo: simulation of " << netlist_path << " failed: " << run.solver.message << "\n";
    if (!partial.empty())
      std::cerr << "pneumo: no results written to " << output << "; the rows computed so far are in " << partial
                << "\n";
    if (stats) print_stats(run.solver, seconds, std::cerr);
    return 1;
  }
  write_csv_atomic(output, run.table);
  if (!audit_path.empty()) {
    if (const auto parent = std::filesystem::path(audit_path).parent_path(); !parent.empty())
      std::filesystem::create_directories(parent);
    const std::string tmp = audit_path + ".writing";
    {
      std::ofstream f(tmp);
      write_audit_yaml(audits, f);
      if (!f) throw std::runtime_error("cannot write the energy audit to " + audit_path);
    }
    std::filesystem::rename(tmp, audit_path);
    if (!quiet) {
      for (const auto& a : audits) print_audit(a, std::cout);
      std::cout << "wrote the energy audit to " << audit_path << "\n";
    }
  }
  if (!quiet) {
    std::cout << "wrote " << run.table.rows.size() << " rows x " << run.table.names.size() << " columns to "
              << output << "\n";
    // Final values: quick sanity for the user.
    if (!run.table.rows.empty()) {
      const auto& last = run.table.rows.back();
      std::cout << "final:";
      for (std::size_t i = 0; i < last.size(); ++i)
        std::cout << " " << run.table.names[i] << "=" << last[i] << (run.table.units[i].empty() ? "" : " ")
                  << run.table.units[i];
      std::cout << "\n";
    }
  }
  if (stats) print_stats(run.solver, seconds, std::cout);
  if (!plot_prefix.empty()) {
    plot_results(output, plot_prefix, split_list(plot_columns), nl.file);
    if (!quiet) std::cout << "plotted " << plot_prefix << ".png and " << plot_prefix << ".svg\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pneumo - acausal simulation of pneumatic drives (YAML netlist -> DAE -> SUNDIALS IDA + KLU)"};
  app.set_version_flag("--version", kVersion);
  app.require_subcommand(1);

  auto* sim = app.add_subcommand("simulate", "simulate a netlist and write the outputs to CSV");
  sim->footer("The netlist's simulation: keys (unit, default, valid range):\n" + simulation_options_help());
  std::string netlist, output;
  std::vector<std::string> sets;
  bool stats = false, quiet = false;
  sim->add_option("netlist", netlist, "netlist file (YAML)")->required();
  sim->add_option("--set", sets,
                  "override a top-level parameter: NAME=VALUE, VALUE an SI number or a quantity ('7 bar')")
      ->take_all();
  sim->add_option("-o,--output", output, "results CSV (default: NETLIST_STEM.csv)");
  sim->add_flag("--stats", stats, "print solver statistics");
  sim->add_flag("-q,--quiet", quiet, "print nothing but errors");
  std::string plot_prefix, plot_columns;
  sim->add_option("--plot", plot_prefix, "also plot the results to PREFIX.png and PREFIX.svg (gnuplot)");
  sim->add_option("--columns", plot_columns, "columns to plot, comma separated (default: all)");
  std::string audit_path;
  sim->add_option("--energy-audit", audit_path,
                  "cushioning energy audit of every cushioned_cylinder: print it and write it (YAML) to FILE");

  auto* plot = app.add_subcommand("plot", "plot a results CSV to PNG and SVG through gnuplot");
  std::string plot_csv, plot_out;
  plot->add_option("results", plot_csv, "results CSV")->required();
  plot->add_option("-o,--output", plot_out, "output prefix (default: the CSV path without .csv)");
  plot->add_option("--columns", plot_columns, "columns to plot, comma separated (default: all)");

  int study_status = -1;  // set by `sweep` / `sensitivity` (framework/cli/study_commands.cpp)
  pneumo::cli::add_study_commands(app, study_status);

  auto* comps = app.add_subcommand("components", "list component types, or show one");
  std::string type;
  comps->add_option("type", type, "component type to describe");
  std::vector<std::string> comp_plugins;
  comps->add_option("--plugin", comp_plugins, "also list the types of this component plugin (shared library)")
      ->allow_extra_args(false);
  auto fit_cmd = pneumo::cli::add_fit_command(app);
  CLI::App* diagnose_cmd = add_diagnose_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (study_status >= 0) return study_status;

  try {
    if (fit_cmd->selected()) return fit_cmd->run();
    if (*sim) return simulate_command(netlist, sets, output, stats, quiet, plot_prefix, plot_columns, audit_path);
    if (*diagnose_cmd) return run_diagnose_command();
    if (*plot) {
      if (plot_out.empty()) plot_out = (std::filesystem::path(plot_csv).parent_path() /
                                        std::filesystem::path(plot_csv).stem()).string();
      plot_results(plot_csv, plot_out, split_list(plot_columns), plot_csv);
      std::cout << "plotted " << plot_out << ".png and " << plot_out << ".svg\n";
      return 0;
    }
    if (*comps) {
      Registry reg = builtin_registry();
      TypeOrigins origins;
      for (const auto& p : comp_plugins) load_plugin(p, SourceLocation{"--plugin", 0, 0}, reg, origins);
      if (!type.empty()) {
        const auto* entry = reg.find(type);
        if (!entry) {
          std::cerr << "pneumo: no component type '" << type << "' (run 'pneumo components' for the list)\n";
          return 2;
        }
        print_component(*entry->info, std::cout);
        return 0;
      }
      for (const auto& t : reg.types()) print_component(*reg.find(t)->info, std::cout);
      return 0;
    }
  } catch (const InputError& e) {
    std::cerr << e.what() << "\n";
    return 2;
  } catch (const StructureError& e) {
    std::cerr << "pneumo: " << netlist << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "pneumo: error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
