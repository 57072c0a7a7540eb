// pneumo calibrate MODEL.yaml --runs DIR --free NAME[=LOW:HIGH] ... --out DIR
// Fits netlist parameters to measured runs (framework/diagnose/calibrate.hpp)
// and writes, in the report folder: report.json, calibrated.yaml (the values
// as a netlist snippet), and per run RUN.csv with RUN.png / RUN.svg
// (measured, the netlist's and the calibrated model's signals).
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>

#include "components/builtin.hpp"
#include "framework/cli/command.hpp"
#include "framework/diagnose/calibrate.hpp"
#include "framework/io/files.hpp"
#include "framework/io/plot.hpp"
#include "framework/io/results.hpp"

namespace pneumo::cli {

namespace {

namespace fs = std::filesystem;

struct CalibrateArgs {
  std::string model, runs, out;
  std::vector<std::string> free, sets;
  int threads = 2, max_iterations = 30;
  bool quiet = false;
};

bool is_report_json(const std::string& first_line) { return first_line == "{"; }
bool is_snippet(const std::string& first_line) { return first_line.rfind("# pneumo calibrate:", 0) == 0; }

// The report folder: not the runs folder, and the files pneumo writes there
// replaced only when pneumo wrote them.
void check_report_folder(const CalibrateArgs& a) {
  std::error_code ec;
  try {
    if (fs::equivalent(a.out, a.runs, ec))
      throw std::invalid_argument("--out " + a.out + ": this is the runs folder; write the report to a folder of its own");
    const std::string again = "choose another --out";
    check_chosen_output_file((fs::path(a.out) / "report.json").string(), again, {a.model}, is_report_json);
    check_chosen_output_file((fs::path(a.out) / "calibrated.yaml").string(), again, {a.model}, is_snippet);
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{"--out", 0, 0}, "", "", e.what());
  }
}

// One run's measured and simulated signals, in the units its outputs show.
ResultsTable run_table(const diagnose::CalibrationReport& rep, const std::string& run, std::vector<std::string>& panels) {
  ResultsTable table;
  table.names = {"t"};
  table.units = {"s"};
  table.display = {units::DisplayUnit{}};
  std::vector<const diagnose::CalibrationTrace*> traces;
  for (const auto& tr : rep.traces)
    if (tr.run == run) traces.push_back(&tr);
  for (const auto* tr : traces) {
    std::string panel;
    for (const char* what : {"_measured", "_netlist", "_calibrated"}) {
      table.names.push_back(tr->signal + what);
      table.units.push_back(tr->unit);
      table.display.push_back(tr->display);
      panel += (panel.empty() ? "" : "+") + tr->signal + what;
    }
    panels.push_back(panel);
  }
  for (std::size_t i = 0; i < traces.front()->t.size(); ++i) {
    std::vector<double> row{traces.front()->t[i]};
    for (const auto* tr : traces) row.insert(row.end(), {tr->measured[i], tr->before[i], tr->after[i]});
    table.add_row(std::move(row));
  }
  return table;
}

int calibrate_command(const CalibrateArgs& a) {
  check_report_folder(a);
  diagnose::CalibrateOptions opt;
  opt.free = a.free;
  opt.sets = a.sets;
  opt.threads = std::max(1, a.threads);
  opt.max_iterations = std::max(1, a.max_iterations);
  opt.progress = !a.quiet;
  const auto rep = diagnose::calibrate(a.model, a.runs, builtin_registry(), opt);
  fs::create_directories(a.out);
  diagnose::write_calibration_json(rep, (fs::path(a.out) / "report.json").string());
  write_text_atomic((fs::path(a.out) / "calibrated.yaml").string(), diagnose::calibration_snippet(rep));
  std::vector<std::string> runs;
  for (const auto& g : rep.gaps)
    if (std::find(runs.begin(), runs.end(), g.run) == runs.end()) runs.push_back(g.run);
  std::cout << diagnose::calibration_summary(rep);
  for (const auto& run : runs) {
    std::vector<std::string> panels;
    const std::string csv = (fs::path(a.out) / (run + ".csv")).string();
    write_csv_atomic(csv, run_table(rep, run, panels));
    try {
      plot_results(csv, (fs::path(a.out) / run).string(), panels, "run " + run + ": measured, netlist, calibrated");
    } catch (const std::runtime_error& e) {
      std::cerr << "pneumo: warning: no plot of run " << run << ": " << e.what() << "\n";
    }
  }
  std::cout << "wrote " << a.out << "/report.json, calibrated.yaml and, per run, RUN.csv and RUN.png/.svg\n";
  return 0;
}

}  // namespace

Command add_calibrate_command(CLI::App& app) {
  auto a = std::make_shared<CalibrateArgs>();
  auto* cmd = app.add_subcommand("calibrate", "fit netlist parameters to measured runs (weighted least squares)");
  cmd->add_option("model", a->model, "model netlist (YAML)")->required();
  add_set_option(cmd, a->sets);
  cmd->add_option("--runs", a->runs, "directory of measured runs (NAME.yaml naming its data, as for diagnose)")
      ->required();
  cmd->add_option("--free", a->free,
                  "NAME or COMPONENT.PARAMETER to fit, optionally =LOW:HIGH (SI numbers, quantities such as "
                  "'1 N:20 N', or factors of the netlist's value such as 0.5x:2x; default 0.25x:4x); repeatable")
      ->required();
  cmd->add_option("--out", a->out, "report directory (report.json, calibrated.yaml, RUN.csv/.png/.svg)")->required();
  cmd->add_option("--threads", a->threads, "parallel simulations (default 2)");
  cmd->add_option("--max-iterations", a->max_iterations, "Levenberg-Marquardt iterations (default 30)");
  cmd->add_flag("-q,--quiet", a->quiet, "no progress display");
  return {.app = cmd, .run = [a] { return calibrate_command(*a); }, .input = [a] { return a->model; }};
}

}  // namespace pneumo::cli
