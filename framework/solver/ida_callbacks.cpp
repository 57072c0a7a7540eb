#include "framework/solver/ida_callbacks.hpp"

#include <sunmatrix/sunmatrix_sparse.h>

#include <cstdlib>

namespace pneumo {

namespace {

// Runs f, keeping an exception for simulate() to rethrow: -1 (fatal) to IDA.
template <class F>
int guarded(UserData* u, F&& f) {
  try {
    return f();
  } catch (...) {
    u->error = std::current_exception();
    return -1;
  }
}

// SUNLinSol_KLU refactors with the pivot order of its first factorisation
// and gives up (recoverably) when one of those pivots is now exactly zero -
// e.g. a throttle that went choked has dm/dp_down == 0. After such a
// failure, ask for a fresh factorisation with new pivots.
bool refresh_rejected_pivots(const UserData& u, SUNMatrix J) {
  long last = 0;
  const bool rejected =
      u.klu && u.ida && IDAGetLastLinFlag(u.ida, &last) == IDA_SUCCESS && last == SUNLS_PACKAGE_FAIL_REC;
  if (rejected) SUNLinSol_KLUReInit(u.klu, J, SUNSparseMatrix_NNZ(J), SUNKLU_REINIT_PARTIAL);
  return rejected;
}

// Chain rule for the scaling: column c is multiplied by nominal[c].
void scale_columns(const UserData& u, double* v) {
  for (std::size_t c = 0; c + 1 < u.col_ptr.size(); ++c)
    for (auto k = u.col_ptr[c]; k < u.col_ptr[c + 1]; ++k) v[k] *= u.nominal[c];
}

// The Newton matrix's two parts at (t, y, y') into u.parts, in the
// matrix's pattern: the System's, or with the disturbances' share.
int evaluate_parts(UserData& u, double t, N_Vector y, N_Vector yp) {
  auto& parts = u.parts;
  const bool shifted = u.shifted.active();
  if (shifted) u.shift_slopes(t, y, yp);
  const double* py = u.physical_y(y);
  const double* pyp = u.disturbed_yp(t, y, yp);
  auto& dFdy = shifted ? u.system_dFdy : parts.dFdy;
  auto& dFdyp = shifted ? u.system_dFdyp : parts.dFdyp;
  dFdy.resize(u.row_idx.size());
  dFdyp.resize(u.row_idx.size());
  const int flag = u.eval->newton_matrix_parts(t, py, pyp, dFdy.data(), dFdyp.data());
  scale_columns(u, dFdy.data());
  scale_columns(u, dFdyp.data());
  if (shifted) {
    parts.dFdy.resize(u.shifted.nnz());
    parts.dFdyp.resize(u.shifted.nnz());
    u.shifted.assemble(dFdy.data(), dFdyp.data(), u.slopes, u.rate_slopes, u.nominal, parts.dFdy.data(),
                       parts.dFdyp.data());
  }
  return flag;
}

// A fresh Newton matrix: evaluated at once, or from freshly evaluated
// parts - kept for the requests that follow, or needed for the
// disturbances' share.
int fresh_matrix(UserData& u, double t, double cj, N_Vector y, N_Vector yp, double* values, long steps,
                 long convergence_failures) {
  auto& parts = u.parts;
  parts.valid = false;
  const bool keep = parts.enabled && !parts.in_calc_ic;
  if (!keep && !u.shifted.active()) {
    const int flag = u.eval->jacobian(t, u.physical_y(y), u.disturbed_yp(t, y, yp), cj, values);
    scale_columns(u, values);
    return flag;
  }
  const int flag = evaluate_parts(u, t, y, yp);
  parts.combine(cj, values);
  if (!keep) return flag;
  parts.valid = flag == 0;
  parts.steps_at = steps;
  parts.convergence_failures_at = convergence_failures;
  return flag;
}

}  // namespace

int residual_cb(realtype t_ida, N_Vector y, N_Vector yp, N_Vector rr, void* user) {
  auto* u = static_cast<UserData*>(user);
  const double t = u->model_t(t_ida);
  const PhaseTimer timer(u->time_phases, u->seconds_residual);
  return guarded(u, [&] {
    return u->eval->residual(t, u->physical_y(y), u->disturbed_yp(t, y, yp), N_VGetArrayPointer(rr));
  });
}

int jacobian_cb(realtype t_ida, realtype cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* user, N_Vector,
                N_Vector, N_Vector) {
  auto* u = static_cast<UserData*>(user);
  const double t = u->model_t(t_ida);
  const PhaseTimer timer(u->time_phases, u->seconds_jacobian);
  return guarded(u, [&] {
    // Every value, every call; the pattern was written once and IDA's
    // zeroing of the matrix is left out (keep_matrix in ida_solver.cpp).
    const bool klu_rejected = refresh_rejected_pivots(*u, J);
    double* values = SUNSparseMatrix_Data(J);
    long steps = 0, convergence_failures = 0;
    if (u->ida) {
      IDAGetNumSteps(u->ida, &steps);
      IDAGetNumNonlinSolvConvFails(u->ida, &convergence_failures);
    }
    if (u->parts.usable(steps, convergence_failures, klu_rejected)) {
      u->parts.combine(cj, values);
      ++u->parts.recombined;
      return 0;
    }
    return fresh_matrix(*u, t, cj, y, yp, values, steps, convergence_failures);
  });
}

int quadrature_cb(realtype t_ida, N_Vector y, N_Vector yp, N_Vector q, void* user) {
  auto* u = static_cast<UserData*>(user);
  const double t = u->model_t(t_ida);
  return guarded(u, [&] {
    u->eval->probe_all(*u->integrands, t, u->physical_y(y), u->physical_yp(yp), N_VGetArrayPointer(q));
    return 0;
  });
}

void error_cb(int, const char* module, const char* function, char* msg, void* user) {
  auto* u = static_cast<UserData*>(user);
  u->last_message = std::string(module) + "/" + function + ": " + msg;
}

std::string flag_text(long flag, const UserData& u) {
  char* name = IDAGetReturnFlagName(flag);
  std::string s = name ? name : "IDA error";
  free(name);
  if (!u.last_message.empty()) s += " (" + u.last_message + ")";
  return s;
}

}  // namespace pneumo
