// The missing term's form (docs/how-to/diagnose.md): when the best balance
// needs a correction, which function of the model's own states it is - "an
// extra force of 2.5 N/mm against the stroke", "a force proportional to the
// acceleration", "friction concentrated around x = 45 mm" - rather than a
// shape over time that holds only for the runs it was fitted on.
//
// A dictionary of candidate terms is built from the model's unknowns near
// the balance (of the components whose equations read its state and those
// joined to them: a missing term reads its own part of the circuit, and the
// dictionary does not grow with the square of a line's pressures) by
// their units (constant; positions, and Gaussian bumps on a grid of centres
// and widths over the stroke the runs cover; velocities, |v|, a smoothed
// sign and the acceleration; pressures and their differences;
// temperatures; sign(v) and v times each of those), each term's output
// sensitivity from one simulation per run with it added to the balance
// (SolverOptions::disturbances' terms, which read the state as it is
// simulated) - after the first round only for the terms the first round's
// sensitivities rank best. Terms are chosen by forward selection, each kept only when it
// lowers the leave-one-run-out prediction error: a form must carry from the
// runs it was fitted on to a run it was not. The chosen coefficients are
// refined by Gauss-Newton steps on simulations with the form in the model,
// and the last of those is the form's confirmation (the gap it leaves).
// Components are never named: variables are the System's, units theirs.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "framework/diagnose/diagnose.hpp"
#include "framework/solver/ida_solver.hpp"

namespace pneumo {
class System;
}

namespace pneumo::diagnose {

// The unit of a System unknown: a component's internal variable
// ("component.variable") from its ComponentInfo, a node's from the
// quantity the assembly names it by ("" when unknown).
std::string unknown_unit(const System& sys, const std::string& name);

struct FormInput {
  const std::vector<MeasuredRun>* runs = nullptr;
  std::vector<int> used;                          // runs the verdict model finishes
  std::vector<Eigen::VectorXd> r0;                // per used run: (measured - simulated) / sigma
  std::function<Netlist(int run)> netlist_of;     // the verdict model at a run's operating point
  const Registry* registry = nullptr;
  // Signals of a run with disturbances (empty when the solver failed, the reason in why).
  std::function<std::vector<std::vector<double>>(int run, const std::vector<Disturbance>&, std::string* why)> simulate;
  std::function<Eigen::VectorXd(int run, const std::vector<std::vector<double>>& signals)> residual;
  std::function<void(const std::string&)> log;
  int threads = 2;
};

// The form found for `balance` (a differential unknown whose rate is in
// `rate_unit`); nullopt when the runs are too few to judge one (fewer than
// two). `gap_shape` is the time-shaped correction's gap, for comparison.
std::optional<FormFinding> discover_form(const FormInput& in, const std::string& balance, const std::string& rate_unit,
                                         double gap_shape);

// The form a measured signal's reading gains beyond the model: which
// function of the model's variables near the component the output `signal`
// comes from (a force a position-driven flange feels, a transducer's
// error). The terms add to the reading and do not act on the model, so the
// residual is linear in them: chosen by the same leave-one-run-out forward
// selection, fitted exactly, no simulation beyond one a run that records
// the variables. nullopt when the runs are too few (fewer than two) or
// `signal` is no output of a component.
std::optional<FormFinding> discover_reading_form(const FormInput& in, const std::string& signal, double gap_shape);

// report.json's "form" and its HTML paragraph.
std::string form_json(const FormFinding& f, const std::function<std::string(double)>& num,
                      const std::function<std::string(const std::string&)>& str);
std::string form_html(const FormFinding& f, const std::function<std::string(const std::string&)>& html);

}  // namespace pneumo::diagnose
