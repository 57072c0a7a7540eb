// The commands of `pneumo`. Each lives in its own file and is added the same
// way, add_<name>_command(app): it declares its options on a subcommand of
// `app` and returns what main runs when that subcommand was chosen.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace pneumo::cli {

struct Command {
  CLI::App* app = nullptr;  // the subcommand
  // Exit status: 0 success, 1 the run (simulation, fit, sweep) failed. Bad
  // input throws InputError or StructureError (main: message, status 2).
  std::function<int()> run{};
  // The file a StructureError is about (the command's netlist), if any.
  std::function<std::string()> input{};
  // Called after bad input was reported, before exiting with status 2.
  std::function<void()> on_error{};
};

// --set NAME=VALUE ..., with one meaning in every command that runs a
// netlist (apply_override in framework/netlist/netlist.hpp).
inline CLI::Option* add_set_option(CLI::App* cmd, std::vector<std::string>& sets) {
  return cmd
      ->add_option("--set", sets,
                   "override a value of the netlist: a top-level parameter NAME=VALUE, a component's "
                   "COMPONENT.PARAMETER=VALUE ('cylinder.bore=40 mm') or a simulation: key, "
                   "simulation.KEY=VALUE ('simulation.t_end=0.5 s'); VALUE an SI number or a quantity ('7 bar')")
      ->take_all();
}

Command add_simulate_command(CLI::App& app);
Command add_plot_command(CLI::App& app);
Command add_sweep_command(CLI::App& app);
Command add_sensitivity_command(CLI::App& app);
Command add_components_command(CLI::App& app);
Command add_fit_command(CLI::App& app);
Command add_diagnose_command(CLI::App& app);
Command add_calibrate_command(CLI::App& app);
Command add_optimize_command(CLI::App& app);
Command add_draw_command(CLI::App& app);
Command add_export_fmu_command(CLI::App& app);

}  // namespace pneumo::cli
