// The `pneumo` command line: one command a file (framework/cli/*.cpp), each
// added by add_<name>_command (command.hpp).
//   pneumo simulate NETLIST [--set NAME=VALUE ...] [-o results.csv] [--stats]
//   pneumo components [TYPE]
//   pneumo draw NETLIST -o circuit.svg|.png [--results run.csv -o view.html]
// Exit status: 0 success, 1 simulation failed, 2 bad input or usage.
#include <CLI/CLI.hpp>

#include <iostream>
#include <new>
#include <stdexcept>
#include <vector>

#include "framework/cli/command.hpp"
#include "framework/core/error.hpp"
#include "framework/core/version.hpp"

namespace {

using pneumo::cli::Command;

// Runs the chosen command; bad input is exit status 2.
int run(const Command& c) {
  try {
    return c.run();
  } catch (const pneumo::InputError& e) {
    std::cerr << e.what() << "\n";
  } catch (const pneumo::StructureError& e) {
    std::cerr << "pneumo: " << (c.input ? c.input() + ": " : "") << e.what() << "\n";
  } catch (const std::bad_alloc&) {
    std::cerr << "pneumo: error: not enough memory for this command; make the study smaller (fewer grid points, "
                 "samples or evaluations) or the results coarser (a longer output_interval)\n";
  } catch (const std::length_error& e) {
    std::cerr << "pneumo: error: the command asks for more elements than memory can hold (" << e.what()
              << "); make the study smaller\n";
  } catch (const std::exception& e) {
    std::cerr << "pneumo: error: " << e.what() << "\n";
  } catch (...) {
    // Only foreign code (a plugin) throws what is not a std::exception.
    std::cerr << "pneumo: error: an exception that is not a std::exception (thrown by a plugin's code?)\n";
  }
  if (c.on_error) c.on_error();
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pneumo::cli;
  CLI::App app{"pneumo - acausal simulation of pneumatic drives (YAML netlist -> DAE -> SUNDIALS IDA + KLU)"};
  app.set_version_flag("--version", PNEUMO_VERSION_STRING);
  app.require_subcommand(1);
  const std::vector<Command> commands{add_simulate_command(app),    add_plot_command(app),
                                      add_sweep_command(app),       add_sensitivity_command(app),
                                      add_components_command(app),  add_fit_command(app),
                                      add_diagnose_command(app),    add_optimize_command(app),
                                      add_draw_command(app),        add_calibrate_command(app),
                                      add_export_fmu_command(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  for (const auto& c : commands)
    if (c.app->parsed()) return run(c);
  return 0;
}
