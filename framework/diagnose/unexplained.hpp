// Which balance of the model needs a correction (docs/how-to/diagnose.md):
// when no candidate effect brings the gap down
// to the noise, every state's balance gets a smooth additive disturbance
// d(t) on its derivative (SolverOptions::disturbances), and every measured
// signal a smooth offset plus a gain. Each d is a sum of hat functions over
// each run's span (Disturbance's piecewise-linear knots); its output
// sensitivities come from one simulation per hat and run (finite
// differences, on threads); the coefficients minimise the residual sum of
// squares plus a second-difference penalty whose weight generalised
// cross-validation chooses, all runs together. A balance scores by the
// share of the excess gap (gap - 1) it removes; the best few are confirmed
// by simulating the fitted disturbance. Components are never named: the
// balances are the System's variable names, their kind the state's unit.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "framework/diagnose/diagnose.hpp"
#include "framework/solver/ida_solver.hpp"

namespace pneumo::diagnose {

// A run of the verdict model kept at some times (Engine::keep): its signals
// (empty: it failed) and the same run with disturbances that are zero up to
// times[j], resumed there - what comes before is not integrated again.
struct KeptRun {
  std::vector<std::vector<double>> signals;
  std::function<std::vector<std::vector<double>>(std::size_t j, const std::vector<Disturbance>& disturbances,
                                                 std::string* why)>
      from;
};

struct UnexplainedInput {
  const std::vector<MeasuredRun>* runs = nullptr;
  const std::vector<std::string>* phase_names = nullptr;
  const std::vector<std::vector<int>>* phases = nullptr;  // per run, per sample
  const Netlist* model = nullptr;                          // the verdict's model (its states and their units)
  const Registry* registry = nullptr;
  std::function<void(const std::string&)> log;
  std::function<Netlist(int run)> netlist_of;  // the verdict model at a run's operating point (the form's variables)
  // Run `run` kept at `times`: every disturbed run of the search goes on
  // from one of its checkpoints (a hat from the knot before it).
  std::function<KeptRun(int run, const std::vector<double>& times)> keep;
};

// Fills `u`'s balances, shape and sentence (its gap, signal, phase and
// windows are the caller's, who knows the verdict).
void explain_by_balances(const UnexplainedInput& in, const DiagnoseOptions& opt, Unexplained& u);

// The hat functions are this many knots over each run's span.
inline constexpr int kDisturbanceKnots = 10;

// report.json's "unexplained" (null when empty) and the HTML section, with
// the report's number and text formatting.
std::string unexplained_json(const std::optional<Unexplained>& u, const std::function<std::string(double)>& num,
                             const std::function<std::string(const std::string&)>& str);
std::string unexplained_html(const std::optional<Unexplained>& u,
                             const std::function<std::string(const std::string&)>& html);

}  // namespace pneumo::diagnose
