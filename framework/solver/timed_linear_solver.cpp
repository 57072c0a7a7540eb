#include "framework/solver/timed_linear_solver.hpp"

#include <sunlinsol/sunlinsol_klu.h>

namespace pneumo {

namespace {

struct Timed {
  SUNLinearSolver klu;
  LinearSolverCounts* counts;
  bool clock;
};

Timed& timed(SUNLinearSolver s) { return *static_cast<Timed*>(s->content); }
SUNLinearSolverContent_KLU klu_content(SUNLinearSolver s) {
  return static_cast<SUNLinearSolverContent_KLU>(timed(s).klu->content);
}

SUNLinearSolver_Type get_type(SUNLinearSolver s) { return SUNLinSolGetType(timed(s).klu); }
SUNLinearSolver_ID get_id(SUNLinearSolver s) { return SUNLinSolGetID(timed(s).klu); }
int initialize(SUNLinearSolver s) { return SUNLinSolInitialize(timed(s).klu); }
sunindextype last_flag(SUNLinearSolver s) { return SUNLinSolLastFlag(timed(s).klu); }
int space(SUNLinearSolver s, long* real_words, long* int_words) {
  return SUNLinSolSpace(timed(s).klu, real_words, int_words);
}

// KLU analyses and factorises when it is told to start afresh (first use,
// IDA's re-initialisation, SUNLinSol_KLUReInit), else refactorises with
// the last pivots - and factorises anew when that leaves a bad condition
// estimate (a new numeric object).
int setup(SUNLinearSolver s, SUNMatrix a) {
  auto& t = timed(s);
  const SUNLinearSolverContent_KLU c = klu_content(s);
  const bool fresh = c->first_factorize != 0;
  const void* numeric = c->numeric;
  int flag = 0;
  {
    const PhaseTimer timer(t.clock, t.counts->setup_seconds);
    flag = SUNLinSolSetup(t.klu, a);
  }
  if (fresh) {
    ++t.counts->analyses;
    ++t.counts->factorisations;
  } else {
    ++t.counts->refactorisations;
    if (c->numeric != numeric) ++t.counts->factorisations;
  }
  return flag;
}

int solve(SUNLinearSolver s, SUNMatrix a, N_Vector x, N_Vector b, realtype tol) {
  auto& t = timed(s);
  int flag = 0;
  {
    const PhaseTimer timer(t.clock, t.counts->solve_seconds);
    flag = SUNLinSolSolve(t.klu, a, x, b, tol);
  }
  ++t.counts->solves;
  return flag;
}

int free_wrapper(SUNLinearSolver s) {
  if (!s) return 0;
  delete static_cast<Timed*>(s->content);
  s->content = nullptr;
  SUNLinSolFreeEmpty(s);
  return 0;
}

}  // namespace

SUNLinearSolver timed_klu(SUNLinearSolver klu, LinearSolverCounts* counts, bool clock, SUNContext ctx) {
  SUNLinearSolver s = SUNLinSolNewEmpty(ctx);
  if (!s) return nullptr;
  s->content = new Timed{klu, counts, clock};
  s->ops->gettype = get_type;
  s->ops->getid = get_id;
  s->ops->initialize = initialize;
  s->ops->setup = setup;
  s->ops->solve = solve;
  s->ops->lastflag = last_flag;
  s->ops->space = space;
  s->ops->free = free_wrapper;
  return s;
}

}  // namespace pneumo
