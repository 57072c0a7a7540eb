// Design optimisation over netlist parameters (`pneumo optimize`), robust
// against uncertain operating conditions (paper [1]'s stated next step: the
// cushioning readjusted by trial and error whenever load or pressure change).
//
// A design point x (continuous design variables within bounds) is judged on
// the same set of uncertainty samples for every x - common random numbers,
// drawn once by Latin hypercube from the given distributions - so that two
// designs are compared on equal terms and the optimiser sees a smooth
// function, not noise. The objective and each constraint are a robust
// statistic of a netlist metric over those samples (the mean, mean + k sd or
// a quantile); without uncertain parameters, the single nominal run. A run
// that fails or whose metric is undefined (its event never happened) makes
// the point infeasible, with the reason kept.
//
// The optimiser is NLopt's: DIRECT-L (global, bounds and inequality
// constraints) for a first look, then COBYLA (local, derivative-free) from the
// best point found. Runs go through the sweep engine's SweepRunner on threads;
// every finished run is appended to a journal (OUTPUT.journal), so a resumed
// optimisation reads what was done instead of running it again.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "framework/run/model.hpp"
#include "framework/study/metrics.hpp"
#include "framework/study/parameters.hpp"

namespace pneumo::study {

struct Uncertain {
  enum class Kind { normal, uniform, lognormal };
  StudyParameter parameter;
  Kind kind = Kind::uniform;
  double a = 0.0, b = 0.0;  // normal/lognormal: mean, sd; uniform: low, high (SI)
  std::string text;         // as written
  double quantile(double u) const;  // inverse CDF, u in (0, 1)
};

struct Robust {
  enum class Kind { mean, mean_ksd, quantile };
  Kind kind = Kind::mean;
  double k = 0.0;  // mean + k sd, or the quantile's probability
  std::string text;
};

struct Constraint {
  std::string metric;
  double limit = 0.0;  // metric <= limit (SI), or >= when `at_least`
  bool at_least = false;
  std::string text;
  // The statistic over the samples: STAT(METRIC)<=VALUE, else --robust's.
  std::optional<Robust> statistic;
};

struct OptimizeProblem {
  std::vector<Range> design;  // bounds (SI)
  std::vector<std::string> objectives;  // one, or two with pareto
  std::vector<Constraint> constraints;
  std::vector<Uncertain> uncertain;
  Robust robust;
  int samples = 32;  // uncertainty samples (ignored without uncertain parameters)
  unsigned long seed = 1;
};

struct OptimizeOptions {
  int threads = 1;
  int max_evaluations = 60;  // design points per optimisation
  std::string algorithm = "direct+cobyla";  // or cobyla, bobyqa, direct
  bool pareto = false;
  int pareto_points = 8;
  bool auto_adjust = false;
  bool progress = true;
  std::string journal;  // "" = none
};

// One design point evaluated over the samples.
struct PointResult {
  std::vector<double> x;                       // design values (SI)
  std::vector<std::vector<double>> metric;     // per objective/constraint metric, per sample
  std::vector<double> robust;                  // robust statistic of each of those metrics
  std::vector<double> constrained;             // each constraint's statistic of its metric
  bool feasible_runs = true;                   // every run ok and every metric defined
  std::string reason;                          // why not
  bool feasible() const;                       // runs ok and constraints met
  double violation = 0.0;                      // largest constraint excess (0 = met)
};

struct ParetoPoint {
  std::vector<double> x;
  double f1 = 0.0, f2 = 0.0;
};

struct OptimizeResult {
  PointResult best;
  bool found = false;        // a feasible point was found
  long runs = 0;             // simulations run (the journal's not counted)
  long runs_resumed = 0;     // taken from the journal
  long failed_runs = 0;      // of runs and runs_resumed, those that failed
  long evaluations = 0;      // design points evaluated
  std::vector<std::string> metric_names;  // objectives then constraint metrics
  std::vector<std::string> metric_units;
  std::vector<ParetoPoint> front;  // with pareto: the non-dominated feasible points, by f1
  std::vector<PointResult> history;  // every point evaluated, in order
  // auto-adjust: the interval of the (single) design variable around the
  // optimum where every constraint holds.
  double feasible_lo = 0.0, feasible_hi = 0.0;
};

// Parses `normal:MEAN:SD`, `uniform:LOW:HIGH`, `lognormal:MEAN:SD` (values may
// carry units). Throws InputError naming the argument.
Uncertain parse_uncertain(const Netlist& netlist, const Registry& registry, const std::string& spec);
// mean | mean+ksd:K | quantile:Q
Robust parse_robust(const std::string& text);
// METRIC<=VALUE or METRIC>=VALUE (VALUE may carry the metric's unit), or
// STAT(METRIC)<=VALUE with STAT as for --robust (mean(t_cushion)<=0.1s).
Constraint parse_constraint(const std::vector<Metric>& available, const std::string& text);
// NAME=LOW:HIGH, checked against the component parameter's valid range.
std::vector<Range> parse_design(const Netlist& netlist, const Registry& registry, const std::vector<std::string>& specs);

// Runs `model` (its components from the model's registry).
OptimizeResult optimize(const Model& model, const OptimizeProblem& problem, const OptimizeOptions& options);
// One design point over the problem's samples (no optimisation), as an
// OptimizeResult whose best is that point.
OptimizeResult evaluate_design(const Model& model, const OptimizeProblem& problem,
                               const OptimizeOptions& options, const std::vector<double>& x);

void write_result_yaml(const OptimizeProblem& problem, const OptimizeOptions& options, const OptimizeResult& result,
                       const std::string& path);

}  // namespace pneumo::study
