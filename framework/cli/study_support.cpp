#include "framework/cli/study_support.hpp"

#include "framework/cli/count_option.hpp"

#include <filesystem>
#include <iostream>

#include "framework/assembly/system.hpp"
#include "framework/io/files.hpp"
#include "framework/study/communicator.hpp"

namespace pneumo::cli {

namespace fs = std::filesystem;
using namespace pneumo::study;

void add_study_options(CLI::App* cmd, StudyArgs& a) {
  cmd->add_option("netlist", a.netlist, "netlist file (YAML)")->required();
  add_set_option(cmd, a.sets);
  cmd->add_option("-j,--threads", a.threads, "threads (per MPI rank)")->transform(whole_number(1, kMaxThreads));
  cmd->add_option("--metrics", a.metrics, "metrics, comma separated (default: all the netlist provides)");
  cmd->add_flag("--eliminate-aliases,!--keep-aliases", a.eliminate,
                "substitute alias equations before solving (the default; --keep-aliases: hand IDA every unknown)");
}

std::string default_output(const std::string& netlist, const char* suffix) {
  return fs::path(netlist).stem().string() + suffix;
}

std::string study_output(const StudyArgs& a, const char* suffix, bool (*ours)(const std::string&),
                         const std::vector<std::string>& inputs) {
  const std::string output = a.output.empty() ? default_output(a.netlist, suffix) : a.output;
  try {
    if (a.output.empty())
      check_chosen_output_file(output, "give -o " + output + " to replace it, or another name", inputs, ours);
    else
      check_output_file(output, "-o", inputs);
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{"-o", 0, 0}, "", "", e.what());
  }
  return output;
}

void stop_ranks() {
  try {
    if (launched_by_mpi() && process_communicator().size() > 1) process_communicator().abort(2);
  } catch (const std::exception&) {
  }
}

int every_run_failed(const Model& model, const std::string& headline, const std::string& why) {
  std::string refused;
  try {
    const System assembled(elaborate(model.netlist, model.registry));
  } catch (const InputError& e) {
    refused = e.what();
  } catch (const StructureError& e) {
    refused = model.path + ": " + e.what();
  }
  if (refused.empty()) {
    std::cerr << headline << "; why:\n" << why;
    return 1;
  }
  std::cerr << headline << ": the netlist itself is refused, so no run could start:\n" << refused << "\n";
  return 2;
}

void report(const SweepSummary& s, const std::string& output, bool quiet) {
  if (quiet) return;
  const double rate = s.seconds > 0 ? s.computed / s.seconds : 0.0;
  std::cout << "sweep: " << s.runs << " runs";
  if (s.ranks > 1) std::cout << " on " << s.ranks << " MPI ranks";
  if (s.done_before > 0) std::cout << " (" << s.done_before << " done before, resumed)";
  std::cout << ", " << s.computed << " run now in " << s.seconds << " s (" << rate << " runs/s on rank 0), "
            << s.failed << " failed\n";
  if (s.complete) std::cout << "wrote " << output << "\n";
}

}  // namespace pneumo::cli
