// Where a run's time goes: counts and times of the sparse LU (KLU) that IDA
// drives through the SUNLinearSolver interface. The wrapper forwards every
// operation to the KLU solver it wraps and counts; asked to, it adds two
// clock readings around each setup and solve (some 30 ns each here, against
// a few microseconds of work: with the residual's and Newton matrix's, about
// 5 % of a small circuit's run, so only benchmarks ask).
#pragma once

#include <sundials/sundials_linearsolver.h>

#include <chrono>

namespace pneumo {

struct LinearSolverCounts {
  long factorisations = 0;    // with new pivots (the first, after IDA re-initialises, or on a bad condition)
  long analyses = 0;          // of those, with a fresh fill-reducing ordering (KLU's analysis)
  long refactorisations = 0;  // the last pivots kept, new values
  long solves = 0;
  double setup_seconds = 0.0, solve_seconds = 0.0;

  LinearSolverCounts& operator+=(const LinearSolverCounts& o) {
    factorisations += o.factorisations;
    analyses += o.analyses;
    refactorisations += o.refactorisations;
    solves += o.solves;
    setup_seconds += o.setup_seconds;
    solve_seconds += o.solve_seconds;
    return *this;
  }
};

// A SUNLinearSolver over `klu` (a SUNLinSol_KLU, owned by the caller and
// outliving the wrapper) that counts into `counts`, and times if `clock`.
// Free it with SUNLinSolFree; that leaves `klu` alone.
SUNLinearSolver timed_klu(SUNLinearSolver klu, LinearSolverCounts* counts, bool clock, SUNContext ctx);

// Seconds since `start`, on the steady clock.
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A phase's time added to `into` when `on` (SolverOptions::time_phases);
// without, no clock is read.
class PhaseTimer {
 public:
  PhaseTimer(bool on, double& into) : into_(on ? &into : nullptr) {
    if (into_) start_ = std::chrono::steady_clock::now();
  }
  ~PhaseTimer() {
    if (into_) *into_ += seconds_since(start_);
  }
  PhaseTimer(const PhaseTimer&) = delete;
  PhaseTimer& operator=(const PhaseTimer&) = delete;

 private:
  double* into_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace pneumo
