// pneumo optimize: design optimisation over netlist parameters, robust
// against uncertain operating conditions (framework/study/optimize.hpp).
#include <algorithm>
#include "framework/cli/command.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "components/builtin.hpp"
#include "framework/cli/command.hpp"
#include "framework/cli/count_option.hpp"
#include "framework/cli/split_list.hpp"
#include "framework/cli/study_support.hpp"
#include "framework/io/files.hpp"
#include "framework/io/plot.hpp"
#include "framework/study/communicator.hpp"
#include "framework/study/optimize.hpp"

namespace pneumo::cli {

namespace {

namespace fs = std::filesystem;
using namespace study;

struct OptimizeArgs {
  std::string netlist, output, robust = "mean", algorithm = "direct+cobyla";
  std::vector<std::string> sets, design, minimize, constraints, uncertain, at;
  int samples = 32, threads = 1, max_evaluations = 60, pareto_points = 8;
  unsigned long seed = 1;
  bool pareto = false, auto_adjust = false, quiet = false;
};

// The Pareto front over every feasible point evaluated.
void plot_front(const OptimizeProblem& p, const OptimizeResult& r, const std::string& prefix) {
  std::vector<std::vector<double>> designs, front;
  for (const auto& h : r.history)
    if (h.feasible()) designs.push_back({h.robust[0], h.robust[1]});
  for (const auto& f : r.front) front.push_back({f.f1, f.f2});
  auto label = [&](int i) { return p.objectives[i] + " [" + r.metric_units[i] + "]"; };
  try {
    plot_pareto_front(prefix, label(0), label(1), designs, front);
  } catch (const std::exception& e) {
    std::cerr << "pneumo optimize: no plot of the front: " << e.what() << "\n";
  }
}

// A value of a design variable in the unit it is shown in.
std::string text_of(const StudyParameter& parameter, double si) {
  std::ostringstream s;
  s << std::setprecision(4) << parameter.shown(si) << (parameter.display_unit == "1" ? "" : " " + parameter.display_unit);
  return s.str();
}

std::string unit_of(const OptimizeResult& r, const std::string& metric) {
  for (std::size_t m = 0; m < r.metric_names.size() && m < r.metric_units.size(); ++m)
    if (r.metric_names[m] == metric) return r.metric_units[m];
  return "";
}

// Why nothing was feasible: each constraint the least infeasible design
// evaluated violates, by how much.
void explain_infeasible(const OptimizeProblem& p, const OptimizeResult& r) {
  if (r.best.x.size() != p.design.size() || r.best.constrained.size() != p.constraints.size()) return;
  std::cout << "the least infeasible design evaluated:";
  for (std::size_t i = 0; i < p.design.size(); ++i)
    std::cout << " " << p.design[i].parameter.name << " = " << text_of(p.design[i].parameter, r.best.x[i]);
  std::cout << "\n";
  for (std::size_t i = 0; i < p.constraints.size(); ++i) {
    const Constraint& c = p.constraints[i];
    const double v = r.best.constrained[i];
    const double excess = c.at_least ? c.limit - v : v - c.limit;
    if (std::isnan(v))
      std::cout << "  constraint " << c.text << ": not evaluated (the runs failed)\n";
    else if (excess > 0)
      std::cout << "  constraint " << c.text << " violated: " << c.metric << " is " << v << " " << unit_of(r, c.metric)
                << ", " << excess << " " << unit_of(r, c.metric) << " beyond the limit\n";
  }
}

void print_result(const OptimizeProblem& p, const OptimizeOptions& o, const OptimizeResult& r, bool given) {
  std::cout << std::setprecision(4);
  if (!r.found) {
    std::cout << "no feasible design found" << (r.best.reason.empty() ? "" : ": " + r.best.reason) << "\n";
    explain_infeasible(p, r);
    return;
  }
  std::cout << (given ? "design:" : "optimum:");
  for (std::size_t i = 0; i < p.design.size(); ++i)
    std::cout << " " << p.design[i].parameter.name << " = " << p.design[i].parameter.shown(r.best.x[i])
              << (p.design[i].parameter.display_unit == "1" ? "" : " " + p.design[i].parameter.display_unit);
  std::cout << "\n";
  for (std::size_t m = 0; m < r.metric_names.size(); ++m)
    std::cout << "  " << r.metric_names[m] << " " << r.best.robust[m] << " " << r.metric_units[m]
              << (p.uncertain.empty() ? "" : " (" + p.robust.text + ")") << "\n";
  for (std::size_t i = 0; i < p.constraints.size(); ++i) {
    const Constraint& c = p.constraints[i];
    const double v = r.best.constrained[i];
    std::cout << "  constraint " << c.text << ": " << v << ", margin " << (c.at_least ? v - c.limit : c.limit - v)
              << "\n";
  }
  if (o.auto_adjust)
    std::cout << "  every constraint holds for " << p.design[0].parameter.name << " from "
              << p.design[0].parameter.shown(r.feasible_lo) << " to " << p.design[0].parameter.shown(r.feasible_hi)
              << (p.design[0].parameter.display_unit == "1" ? "" : " " + p.design[0].parameter.display_unit) << "\n";
  std::cout << r.evaluations << " design points, " << r.runs << " runs";
  if (r.runs_resumed) std::cout << " (+" << r.runs_resumed << " from the journal)";
  std::cout << "\n";
}

// The design --at gives: NAME=VALUE once for every design variable, within
// its --design range (outside, "found" would claim what was not searched).
std::vector<double> design_at(const Netlist& nl, const Registry& reg, const OptimizeProblem& p,
                              const std::vector<std::string>& at) {
  auto fail = [](const std::string& message) { throw InputError(SourceLocation{"--at", 0, 0}, "", "", message); };
  for (const auto& s : at) {
    const std::string name = s.substr(0, s.find('='));
    const auto same =
        std::count_if(at.begin(), at.end(), [&](const std::string& t) { return t.substr(0, t.find('=')) == name; });
    if (same > 1) fail("--at: " + name + " is given " + std::to_string(same) + " times; give it once");
    if (std::none_of(p.design.begin(), p.design.end(), [&](const Range& d) { return d.parameter.name == name; }))
      fail("--at " + s + ": '" + name + "' is not a design variable (give --design " + name + "=LOW:HIGH)");
  }
  std::vector<double> x;
  for (const auto& d : p.design) {
    const auto it = std::find_if(at.begin(), at.end(), [&](const std::string& s) {
      return s.substr(0, s.find('=')) == d.parameter.name;
    });
    if (it == at.end() || it->find('=') == std::string::npos) fail("--at: give NAME=VALUE for " + d.parameter.name);
    const double v = parse_value(nl, reg, d.parameter, it->substr(it->find('=') + 1), "--at " + *it);
    if (!(v >= d.lo && v <= d.hi))
      fail("--at " + *it + ": outside the --design range of " + d.parameter.name + " (" +
           text_of(d.parameter, d.lo) + " to " + text_of(d.parameter, d.hi) + "); widen the range or choose a value in it");
    x.push_back(v);
  }
  return x;
}

int optimize_command(const OptimizeArgs& a) {
  if (process_communicator().size() > 1)
    throw InputError(SourceLocation{a.netlist, 0, 0}, "", "", "pneumo optimize runs on threads (-j), not under mpirun");
  const Model model = load_model(a.netlist, builtin_registry(), a.sets);
  const Netlist& nl = model.netlist;
  const Registry& reg = model.registry;
  OptimizeProblem p;
  if (a.design.empty()) throw InputError(SourceLocation{a.netlist, 1, 1}, "", "", "give --design NAME=LOW:HIGH ...");
  p.design = parse_design(nl, reg, a.design);
  for (const auto& m : a.minimize)
    for (const auto& name : split_list(m)) p.objectives.push_back(name);
  if (p.objectives.empty() || p.objectives.size() > 2 || (p.objectives.size() == 2 && !a.pareto))
    throw InputError(SourceLocation{a.netlist, 1, 1}, "", "", "--minimize takes one metric (two with --pareto)");
  if (a.pareto && p.objectives.size() != 2)
    throw InputError(SourceLocation{"--pareto", 0, 0}, "", "",
                     "--pareto trades two objectives: give --minimize A,B (two metrics, comma separated)");
  const auto available = select_metrics(nl, reg, {});
  (void)select_metrics(nl, reg, p.objectives);  // unknown names are errors listing the available ones
  for (const auto& c : a.constraints) p.constraints.push_back(parse_constraint(available, c));
  for (const auto& u : a.uncertain) p.uncertain.push_back(parse_uncertain(nl, reg, u));
  {
    std::vector<StudyParameter> all;
    for (const auto& d : p.design) all.push_back(d.parameter);
    for (const auto& u : p.uncertain) all.push_back(u.parameter);
    refuse_repeated(nl, all, "--design and --uncertain");
  }
  p.robust = parse_robust(a.robust);
  if (a.samples < 2 && !p.uncertain.empty())
    throw InputError(SourceLocation{"--samples", 0, 0}, "", "", "--samples must be at least 2");
  p.samples = a.samples;
  p.seed = a.seed;
  if (a.auto_adjust && (p.design.size() != 1 || p.constraints.empty()))
    throw InputError(SourceLocation{"--auto-adjust", 0, 0}, "", "",
                     "--auto-adjust answers for one design variable and at least one --constraint");
  OptimizeOptions o;
  o.threads = a.threads;
  o.max_evaluations = a.max_evaluations;
  o.algorithm = a.algorithm;
  o.pareto = a.pareto;
  o.pareto_points = a.pareto_points;
  o.auto_adjust = a.auto_adjust;
  o.progress = !a.quiet;
  const std::string output = a.output.empty() ? fs::path(a.netlist).stem().string() + ".optimum.yaml" : a.output;
  try {
    if (a.output.empty())
      check_chosen_output_file(output, "give -o " + output + " to replace it, or another name", {a.netlist});
    else
      check_output_file(output, "-o", {a.netlist});
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{"-o", 0, 0}, "", "", e.what());
  }
  if (const auto parent = fs::path(output).parent_path(); !parent.empty()) fs::create_directories(parent);
  o.journal = output + ".journal";
  OptimizeResult r;
  if (a.at.empty()) {
    r = optimize(model, p, o);
  } else {  // evaluate one given design on the samples
    r = evaluate_design(model, p, o, design_at(nl, reg, p, a.at));
  }
  if (r.failed_runs > 0 && r.failed_runs == r.runs + r.runs_resumed &&
      every_run_failed(model, "pneumo optimize: every run failed",
                       "  " + r.best.reason + " (the best point's first failure)\n") == 2) {
    fs::remove(o.journal);  // bad input: nothing is written
    return 2;
  }
  write_result_yaml(p, o, r, output);
  if (!a.quiet) print_result(p, o, r, !a.at.empty());
  if (a.pareto) plot_front(p, r, (fs::path(output).parent_path() / fs::path(output).stem()).string() + ".pareto");
  fs::remove(o.journal);
  if (!a.quiet) std::cout << "wrote " << output << "\n";
  return r.found ? 0 : 1;
}

}  // namespace

Command add_optimize_command(CLI::App& app) {
  auto a = std::make_shared<OptimizeArgs>();
  auto* c = app.add_subcommand("optimize", "optimise design parameters for a metric, robust against uncertain conditions");
  c->add_option("netlist", a->netlist, "netlist file (YAML)")->required();
  add_set_option(c, a->sets);
  c->add_option("--design", a->design, "NAME=LOW:HIGH design variable (repeatable; units allowed)")->take_all();
  c->add_option("--minimize", a->minimize, "metric to minimise (two, comma separated, with --pareto)");
  c->add_option("--constraint", a->constraints, "METRIC<=VALUE or METRIC>=VALUE (repeatable; units allowed)")
      ->take_all();
  c->add_option("--uncertain", a->uncertain,
                "NAME=normal:MEAN:SD | uniform:LOW:HIGH | lognormal:MEAN:SD (repeatable; units allowed)")
      ->take_all();
  c->add_option("--robust", a->robust, "statistic over the samples: mean, mean+ksd:K or quantile:Q (default mean)");
  c->add_option("--samples", a->samples, "uncertainty samples (Latin hypercube, the same for every design)")
      ->transform(whole_number(1, 1000000));
  c->add_option("--seed", a->seed, "seed of the samples");
  c->add_option("--max-evaluations", a->max_evaluations, "design points per optimisation (default 60)")
      ->transform(whole_number(1, 2000000000));
  c->add_option("--algorithm", a->algorithm, "direct+cobyla (default), cobyla, bobyqa or direct")
      ->check(CLI::IsMember({"direct+cobyla", "cobyla", "bobyqa", "direct"}));
  c->add_option("--at", a->at, "NAME=VALUE for every design variable: evaluate that design, do not optimise")
      ->take_all();
  c->add_flag("--pareto", a->pareto, "two objectives: the Pareto front (epsilon-constraint), plotted");
  c->add_option("--pareto-points", a->pareto_points, "levels of the front (default 8)")
      ->transform(whole_number(1, 10000));
  c->add_flag("--auto-adjust", a->auto_adjust,
              "one design variable: the best setting that meets the constraints, and the range where they hold");
  c->add_option("-j,--threads", a->threads, "threads")->transform(whole_number(1, kMaxThreads));
  c->add_option("-o,--output", a->output, "result YAML (default: NETLIST_STEM.optimum.yaml)");
  c->add_flag("-q,--quiet", a->quiet, "no progress or summary");
  return {.app = c, .run = [a] { return optimize_command(*a); }, .input = [a] { return a->netlist; }};
}

}  // namespace pneumo::cli
