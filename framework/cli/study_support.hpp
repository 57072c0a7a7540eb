// What the study commands (sweep, sensitivity) share: their error
// handling under MPI, their summary line and default output names.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "framework/cli/command.hpp"
#include "framework/study/sweep.hpp"

namespace pneumo::cli {

// What every study command takes.
struct StudyArgs {
  std::string netlist, output, metrics;
  std::vector<std::string> sets;  // --set
  int threads = 1;
  bool quiet = false, eliminate = true;  // alias elimination is the default
};

// The netlist, --set, -j, --metrics and --keep-aliases of a study command.
void add_study_options(CLI::App* cmd, StudyArgs& a);

// NETLIST_STEM + suffix, in the working directory.
std::string default_output(const std::string& netlist, const char* suffix);

// The command's output file, checked before any work: the one named with -o
// (not an input, directory, device or link), or NETLIST_STEM + suffix, which
// replaces only a file whose first line `ours` accepts (one pneumo wrote).
// Bad names are InputErrors (exit 2).
std::string study_output(const StudyArgs& a, const char* suffix, bool (*ours)(const std::string& first_line),
                         const std::vector<std::string>& inputs);

// After bad input: under mpirun an error on one rank must stop the others,
// which would otherwise wait for it in a collective call.
void stop_ranks();

// A study command's Command: bad input stops the other MPI ranks.
template <class Args>
Command study_command(CLI::App* cmd, std::shared_ptr<Args> a, int (*run)(const Args&)) {
  return {.app = cmd, .run = [a, run] { return run(*a); }, .input = [a] { return a->netlist; }, .on_error = stop_ranks};
}

// The sweep's summary line on stdout (nothing when quiet).
void report(const study::SweepSummary& s, const std::string& output, bool quiet);

// The exit status of a study whose every run failed, after saying why on
// stderr (`headline`, then): 2 when the model as written is bad input (its
// circuit cannot be built: an unknown component type, a parameter out of
// its range, a structural error), with that one error; otherwise 1, with
// `why` (the runs' reasons).
int every_run_failed(const Model& model, const std::string& headline, const std::string& why);

}  // namespace pneumo::cli
