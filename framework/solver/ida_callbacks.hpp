// The C callbacks IDA calls (residual, Newton matrix, quadratures, error
// messages) and the data they share. Exceptions never cross them: they are
// kept in UserData::error and rethrown by simulate().
#pragma once

#include <idas/idas.h>
#include <sunlinsol/sunlinsol_klu.h>

#include <cmath>
#include <exception>
#include <string>
#include <vector>

#include "framework/assembly/system.hpp"
#include "framework/solver/ida_solver.hpp"
#include "framework/solver/newton_matrix.hpp"
#include "framework/solver/timed_linear_solver.hpp"

namespace pneumo {

struct UserData {
  System* system = nullptr;
  std::exception_ptr error;  // exceptions never cross the C callbacks
  std::string last_message;
  std::vector<sunindextype> col_ptr, row_idx;
  SUNLinearSolver klu = nullptr;
  void* ida = nullptr;
  NewtonMatrixParts parts;
  const ProbeSet* integrands = nullptr;
  double seconds_residual = 0.0, seconds_jacobian = 0.0;  // in the callbacks
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
  // SolverOptions::disturbances by IDA unknown: the equations see
  // y' - d(t) (applied to yp_phys after physical_yp).
  std::vector<std::pair<int, const Disturbance*>> disturbed;
  // A steady start's settling integrates in a time of its own with the
  // model's time held at t_start: the equations see frozen_t (NaN: IDA's t).
  double frozen_t = NAN;
  double model_t(double t) const { return std::isnan(frozen_t) ? t : frozen_t; }
  const double* disturbed_yp(double t, N_Vector yp) {
    physical_yp(yp);
    for (const auto& [i, d] : disturbed) yp_phys[i] -= d->at(t);
    return yp_phys.data();
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
