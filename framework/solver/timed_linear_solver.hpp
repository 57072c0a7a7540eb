// Where a run's time goes: counts and times of the sparse LU (KLU) that IDA
// drives through the SUNLinearSolver interface. The wrapper forwards every
// operation to the KLU solver it wraps and adds two clock readings around
// each setup and solve (tens of nanoseconds against microseconds of work).
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
// outliving the wrapper) that counts into `counts`. Free it with
// SUNLinSolFree; that leaves `klu` alone.
SUNLinearSolver timed_klu(SUNLinearSolver klu, LinearSolverCounts* counts, SUNContext ctx);

// Seconds since `start`, on the steady clock.
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace pneumo
