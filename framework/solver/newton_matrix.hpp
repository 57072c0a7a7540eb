#pragma once

#include <cstddef>
#include <vector>

namespace pneumo {

// IDA's Newton matrix dF/dy + cj dF/dy' kept in its two parts, so that a
// request for a new matrix that only follows a change of cj is answered by
// recombining them (CVODE does this for its own Newton matrix; IDA does
// not). cj = alpha / h changes with every change of step size or order, and
// IDA asks for a new matrix once cj is more than 25 % off the one the
// factorisation used; most of its requests are these, while the state has
// hardly moved. Recombining is exact in cj, since F is linear in y' and the
// explicitly solved unknowns have no y' (Evaluator::newton_matrix_parts). The parts
// are evaluated afresh when they may be too old for the Newton iteration:
// after a nonlinear convergence failure, after kMaxAgeSteps steps (CVODE's
// limit), after an event or a re-initialisation, after KLU rejected a
// pivot, and throughout IDACalcIC, which starts from far-off values. Used
// only when IDA integrates no algebraic unknown (see simulate). IDA's
// Newton iteration is told a recombined matrix is not current
// (lsetup_knowing_recombination in ida_solver.cpp), so that one it fails on
// is evaluated afresh at the same step (failed_newton) instead of cutting
// the step.
struct NewtonMatrixParts {
  static constexpr long kMaxAgeSteps = 50;
  bool enabled = true;
  bool valid = false;
  bool in_calc_ic = false;
  std::vector<double> dFdy, dFdyp;  // in IDA's scaled variables, in the matrix's order
  long steps_at = 0, convergence_failures_at = 0;
  long recombined = 0;  // requests answered without an evaluation
  bool last_recombined = false;  // the matrix in use
  long retried = 0;  // Newton iterations failed on a recombined matrix, retried on a fresh one

  // Whether a request at IDA's counters now can be answered from the parts.
  bool usable(long steps, long convergence_failures, bool klu_rejected) const {
    return valid && !in_calc_ic && !klu_rejected && convergence_failures == convergence_failures_at &&
           steps >= steps_at && steps - steps_at < kMaxAgeSteps;
  }
  // The Newton iteration failed on the matrix in use: the next one is evaluated.
  void failed_newton() {
    if (last_recombined) ++retried;
    valid = false;
  }
  void combine(double cj, double* values) const {
    for (std::size_t k = 0; k < dFdy.size(); ++k) values[k] = dFdy[k] + cj * dFdyp[k];
  }
};

}  // namespace pneumo
