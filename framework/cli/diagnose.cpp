// pneumo diagnose MODEL.yaml --runs DIR [--effects CATALOGUE.yaml] [--faults A,B] [--experiment NAME=LOW:HIGH]
//                 --out REPORT_DIR
// Candidates: the faults the circuit's components declare and the measured
// signals' measurement faults, plus (or, with --effects-only, instead) the
// catalogue's effects.
#include <filesystem>
#include <iostream>
#include <memory>

#include "components/builtin.hpp"
#include "framework/cli/command.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "framework/io/files.hpp"

namespace pneumo::cli {

namespace {

struct DiagnoseArgs {
  std::string model, runs, effects, out;
  std::vector<std::string> faults, sets, experiments;
  int threads = 2, max_effects = 2;
  bool quiet = false, effects_only = false;
};

bool is_report_json(const std::string& first_line) { return first_line == "{"; }
bool is_report_html(const std::string& first_line) { return first_line == "<!DOCTYPE html>"; }

// The report folder, checked before the diagnosis: not the runs folder (the
// measured data), and report.json / report.html in it are replaced only when
// they are reports pneumo wrote, never an input.
void check_report_folder(const DiagnoseArgs& a) {
  namespace fs = std::filesystem;
  std::error_code ec;
  std::vector<std::string> inputs{a.model};
  if (!a.effects.empty()) inputs.push_back(a.effects);
  try {
    if (fs::equivalent(a.out, a.runs, ec))
      throw std::invalid_argument("--out " + a.out + ": this is the runs folder; write the report to a folder of its own");
    const std::string again = "choose another --out";
    check_chosen_output_file((fs::path(a.out) / "report.json").string(), again, inputs, is_report_json);
    check_chosen_output_file((fs::path(a.out) / "report.html").string(), again, inputs, is_report_html);
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{"--out", 0, 0}, "", "", e.what());
  }
}

int diagnose_command(const DiagnoseArgs& a) {
  check_report_folder(a);
  diagnose::DiagnoseOptions opt;
  opt.threads = std::max(1, a.threads);
  opt.max_effects = std::max(1, a.max_effects);
  opt.progress = !a.quiet;
  if (a.effects_only && a.effects.empty())
    throw InputError(SourceLocation{"--effects-only", 0, 0}, "", "", "--effects-only needs --effects CATALOGUE.yaml");
  opt.declared_faults = !a.effects_only;
  opt.faults = a.faults;
  opt.sets = a.sets;
  opt.experiments = a.experiments;
  const auto rep = diagnose::diagnose(a.model, a.runs, a.effects, builtin_registry(), opt);
  std::filesystem::create_directories(a.out);
  diagnose::write_report_json(rep, (std::filesystem::path(a.out) / "report.json").string());
  diagnose::write_report_html(rep, (std::filesystem::path(a.out) / "report.html").string());
  std::cout << "verdict: " << diagnose::verdict_sentence(rep);
  std::cout << "\nvalidation gap " << rep.validation_before.total.rms << " -> " << rep.validation_after.total.rms
            << " (noise = 1)\nwrote " << a.out << "/report.json and report.html\n";
  return 0;
}

}  // namespace

Command add_diagnose_command(CLI::App& app) {
  auto a = std::make_shared<DiagnoseArgs>();
  auto* cmd = app.add_subcommand(
      "diagnose", "find which unmodelled effect explains the gap between a model and measured runs");
  cmd->add_option("model", a->model, "model netlist (YAML)")->required();
  add_set_option(cmd, a->sets);
  cmd->add_option("--runs", a->runs, "directory of measured runs (NAME.yaml + NAME.csv)")->required();
  cmd->add_option("--effects", a->effects,
                  "catalogue of candidate effects (YAML), added to the components' declared faults (one of the same "
                  "name replaces it)");
  cmd->add_flag("--effects-only", a->effects_only, "the catalogue's effects alone, without the declared faults");
  cmd->add_option("--faults", a->faults,
                  "only these candidates: COMPONENT.FAULT, a component, a measured output or a fault name "
                  "(comma-separated)")
      ->delimiter(',');
  cmd->add_option("--experiment", a->experiments,
                  "NAME=LOW:HIGH: a top-level parameter the proposed next run may set, and its range (values as "
                  "--set takes them; repeatable; default: what the runs vary, within their span)");
  cmd->add_option("--out", a->out, "report directory (report.json, report.html)")->required();
  cmd->add_option("--threads", a->threads, "parallel simulations (default 2)");
  cmd->add_option("--max-effects", a->max_effects, "forward selection depth (default 2)");
  cmd->add_flag("-q,--quiet", a->quiet, "no progress display");
  return {.app = cmd, .run = [a] { return diagnose_command(*a); }, .input = [a] { return a->model; }};
}

}  // namespace pneumo::cli
