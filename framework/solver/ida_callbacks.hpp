// The C callbacks IDA calls (residual, Newton matrix, quadratures, error
// messages) and the data they share. Exceptions never cross them: they are
// kept in UserData::error and rethrown by simulate().
#pragma once

#include <idas/idas.h>
#include <sunlinsol/sunlinsol_klu.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <string>
#include <vector>

#include "framework/assembly/evaluator.hpp"
#include "framework/solver/disturbed_matrix.hpp"
#include "framework/solver/ida_solver.hpp"
#include "framework/solver/newton_matrix.hpp"
#include "framework/solver/timed_linear_solver.hpp"

namespace pneumo {

struct UserData {
  Evaluator* eval = nullptr;
  std::exception_ptr error;  // exceptions never cross the C callbacks
  std::string last_message;
  std::vector<sunindextype> col_ptr, row_idx;
  SUNLinearSolver klu = nullptr;
  void* ida = nullptr;
  NewtonMatrixParts parts;
  const ProbeSet* integrands = nullptr;
  bool time_phases = false;  // SolverOptions::time_phases
  double seconds_residual = 0.0, seconds_jacobian = 0.0;  // in the callbacks, if timed
  // IDA integrates scaled variables y / nominal: pressures (1e5 Pa) and
  // masses (1e-6 kg) in one Newton matrix would otherwise differ by 1e11 and
  // leave the sparse LU numerically singular.
  std::vector<double> nominal, y_phys, yp_phys;
  const double* physical_y(N_Vector y) {
    const double* s = N_VGetArrayPointer(y);
    for (std::size_t i = 0; i < nominal.size(); ++i) y_phys[i] = s[i] * nominal[i];
    return y_phys.data();
  }
  const double* physical_yp(N_Vector yp) {
    const double* s = N_VGetArrayPointer(yp);
    for (std::size_t i = 0; i < nominal.size(); ++i) yp_phys[i] = s[i] * nominal[i];
    return yp_phys.data();
  }
  // SolverOptions::disturbances by IDA unknown, their terms' factors by
  // what they read (an unknown, else a component's quantity): the equations
  // see y' - d(t, y, y') (applied to yp_phys after physical_yp).
  struct Reader {
    int unknown = -1;
    Probe probe;  // when unknown < 0 (index < 0: nothing, read as 0)
  };
  struct Disturbed {
    int i;
    const Disturbance* d;
    std::vector<std::vector<std::pair<Reader, Reader>>> factor_of;  // per term, per factor: variable, other
    int energy = -1;     // a gas mass's internal energy, which the gas's enthalpy kappa U / m enters
    double kappa = 0.0;
  };
  std::vector<Disturbed> disturbed;
  // The Newton matrix's share of the shifts (inactive without disturbances)
  // and its workspace: the System's parts in its own pattern, the slopes.
  DisturbedMatrix shifted;
  std::vector<double> shift, shift_moved, slopes, rate_slopes, system_dFdy, system_dFdyp;
  // A steady start's settling integrates in a time of its own with the
  // model's time held at t_start: the equations see frozen_t (NaN: IDA's t).
  double frozen_t = NAN;
  double model_t(double t) const { return std::isnan(frozen_t) ? t : frozen_t; }
  const double* disturbed_yp(double t, N_Vector y, N_Vector yp) {
    physical_yp(yp);
    if (disturbed.empty()) return yp_phys.data();
    physical_y(y);
    shifts(t, shift);  // every shift first: a term may read the rate of a disturbed unknown
    for (std::size_t k = 0; k < disturbed.size(); ++k) {
      yp_phys[disturbed[k].i] -= shift[2 * k];
      if (disturbed[k].energy >= 0) yp_phys[disturbed[k].energy] -= shift[2 * k + 1];
    }
    return yp_phys.data();
  }
  // What the disturbances take off y' at y_phys, yp_phys (undisturbed):
  // s[2k] off disturbance k's balance, s[2k + 1] off its gas's internal
  // energy - the gas's enthalpy, kappa U / m per unit of mass.
  void shifts(double t, std::vector<double>& s) const {
    s.resize(2 * disturbed.size());
    for (std::size_t k = 0; k < disturbed.size(); ++k) {
      const auto& r = disturbed[k];
      const double d = disturbance_at(r, t);
      s[2 * k] = d;
      s[2 * k + 1] = r.energy >= 0 && y_phys[r.i] > 0 ? d * r.kappa * y_phys[r.energy] / y_phys[r.i] : 0.0;
    }
  }
  // The shifts' slopes over shifted.columns() and over the rates of
  // shifted.rate_columns() at (t, y, y'), by forward differences
  // (DisturbedMatrix::assemble's order).
  void shift_slopes(double t, N_Vector y, N_Vector yp) {
    physical_y(y);
    physical_yp(yp);
    shifts(t, shift);
    slopes_over(t, shifted.columns(), y_phys, slopes);
    slopes_over(t, shifted.rate_columns(), yp_phys, rate_slopes);
  }
  // Each of `columns` of `x` (y_phys or yp_phys) moved in turn.
  void slopes_over(double t, const std::vector<int>& columns, std::vector<double>& x, std::vector<double>& out) {
    out.resize(columns.size() * shift.size());
    for (std::size_t q = 0; q < columns.size(); ++q) {
      const int c = columns[q];
      const double held = x[c];
      x[c] = held + 1e-7 * std::max(std::abs(held), nominal[c]);
      const double h = x[c] - held;
      shifts(t, shift_moved);
      x[c] = held;
      for (std::size_t k = 0; k < shift.size(); ++k) out[q * shift.size() + k] = (shift_moved[k] - shift[k]) / h;
    }
  }
  double read(const Reader& r, double t) const {
    if (r.unknown >= 0) return y_phys[r.unknown];
    return r.probe.index < 0 ? 0.0 : eval->probe(r.probe, t, y_phys.data(), yp_phys.data());
  }
  double disturbance_at(const Disturbed& r, double t) const {
    double d = r.d->t.empty() ? 0.0 : r.d->time_shaped(t);
    for (std::size_t j = 0; j < r.d->terms.size(); ++j) {
      const auto& term = r.d->terms[j];
      double v = term.coefficient;
      for (std::size_t f = 0; f < term.factors.size(); ++f) {
        const auto& [a, b] = r.factor_of[j][f];
        v *= term.factors[f](read(a, t), a.unknown >= 0 ? yp_phys[a.unknown] : 0.0, read(b, t));
      }
      d += v;
    }
    return d < 0 ? d * r.d->withdrawal_share(t, y_phys[r.i]) : d;
  }
};

int residual_cb(realtype t, N_Vector y, N_Vector yp, N_Vector rr, void* user);
int jacobian_cb(realtype t, realtype cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* user, N_Vector,
                N_Vector, N_Vector);
// Integrands of the quadratures (outputs declared as integrals).
int quadrature_cb(realtype t, N_Vector y, N_Vector yp, N_Vector q, void* user);
void error_cb(int, const char* module, const char* function, char* msg, void* user);
// IDA's name of a return flag, with its last error message.
std::string flag_text(long flag, const UserData& u);

}  // namespace pneumo
