#include "framework/solver/ida_solver.hpp"

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>

namespace pneumo {

namespace {

// RAII owners for the SUNDIALS handles.
struct ContextOwner {
  SUNContext ctx = nullptr;
  ContextOwner() {
    if (SUNContext_Create(nullptr, &ctx) != 0) throw std::runtime_error("SUNContext_Create failed");
  }
  ~ContextOwner() { SUNContext_Free(&ctx); }
  ContextOwner(const ContextOwner&) = delete;
  ContextOwner& operator=(const ContextOwner&) = delete;
};
struct VectorDeleter {
  void operator()(_generic_N_Vector* v) const { N_VDestroy(v); }
};
struct MatrixDeleter {
  void operator()(_generic_SUNMatrix* m) const { SUNMatDestroy(m); }
};
struct SolverDeleter {
  void operator()(_generic_SUNLinearSolver* s) const { SUNLinSolFree(s); }
};
struct IdaDeleter {
  void operator()(void* mem) const { IDAFree(&mem); }
};
using VectorPtr = std::unique_ptr<_generic_N_Vector, VectorDeleter>;
using MatrixPtr = std::unique_ptr<_generic_SUNMatrix, MatrixDeleter>;
using SolverPtr = std::unique_ptr<_generic_SUNLinearSolver, SolverDeleter>;
using IdaPtr = std::unique_ptr<void, IdaDeleter>;

struct UserData {
  System* system = nullptr;
  std::exception_ptr error;  // exceptions never cross the C callbacks
  std::string last_message;
  std::vector<sunindextype> col_ptr, row_idx;
};

int residual_cb(realtype t, N_Vector y, N_Vector yp, N_Vector rr, void* user) {
  auto* u = static_cast<UserData*>(user);
  try {
    return u->system->residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(rr));
  } catch (...) {
    u->error = std::current_exception();
    return -1;
  }
}

int jacobian_cb(realtype t, realtype cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* user, N_Vector,
                N_Vector, N_Vector) {
  auto* u = static_cast<UserData*>(user);
  try {
    // IDA zeroes the matrix (structure included) before each call.
    std::memcpy(SUNSparseMatrix_IndexPointers(J), u->col_ptr.data(), u->col_ptr.size() * sizeof(sunindextype));
    std::memcpy(SUNSparseMatrix_IndexValues(J), u->row_idx.data(), u->row_idx.size() * sizeof(sunindextype));
    return u->system->jacobian(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), cj, SUNSparseMatrix_Data(J));
  } catch (...) {
    u->error = std::current_exception();
    return -1;
  }
}

int root_cb(realtype t, N_Vector y, N_Vector yp, realtype* g, void* user) {
  auto* u = static_cast<UserData*>(user);
  try {
    u->system->roots(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), g);
    return 0;
  } catch (...) {
    u->error = std::current_exception();
    return -1;
  }
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

}  // namespace

SolverResult simulate(System& system, const SolverOptions& opt, const OutputFn& output) {
  SolverResult result;
  const int n = system.size();
  ContextOwner context;
  UserData user;
  user.system = &system;
  user.col_ptr.assign(system.col_ptr().begin(), system.col_ptr().end());
  user.row_idx.assign(system.row_idx().begin(), system.row_idx().end());

  VectorPtr y(N_VNew_Serial(n, context.ctx)), yp(N_VNew_Serial(n, context.ctx));
  VectorPtr atol(N_VNew_Serial(n, context.ctx)), id(N_VNew_Serial(n, context.ctx));
  std::vector<double> y0, yp0;
  system.reset_modes();
  system.start_values(y0, yp0);
  std::copy(y0.begin(), y0.end(), N_VGetArrayPointer(y.get()));
  std::copy(yp0.begin(), yp0.end(), N_VGetArrayPointer(yp.get()));
  for (int i = 0; i < n; ++i) {
    N_VGetArrayPointer(atol.get())[i] = opt.atol * system.nominal()[i];
    N_VGetArrayPointer(id.get())[i] = system.differential()[i];
  }

  MatrixPtr A(SUNSparseMatrix(n, n, std::max<long>(1, system.nnz()), CSC_MAT, context.ctx));
  SolverPtr LS(SUNLinSol_KLU(y.get(), A.get(), context.ctx));
  IdaPtr mem(IDACreate(context.ctx));
  if (!A || !LS || !mem) throw std::runtime_error("cannot create the SUNDIALS solver objects");
  void* ida = mem.get();

  auto check = [&](int flag, const char* what) {
    if (flag < 0) throw std::runtime_error(std::string(what) + " failed: " + flag_text(flag, user));
  };
  check(IDASetErrHandlerFn(ida, error_cb, &user), "IDASetErrHandlerFn");
  check(IDAInit(ida, residual_cb, opt.t_start, y.get(), yp.get()), "IDAInit");
  check(IDASVtolerances(ida, opt.rtol, atol.get()), "IDASVtolerances");
  check(IDASetUserData(ida, &user), "IDASetUserData");
  check(IDASetLinearSolver(ida, LS.get(), A.get()), "IDASetLinearSolver");
  check(IDASetJacFn(ida, jacobian_cb), "IDASetJacFn");
  check(IDASetId(ida, id.get()), "IDASetId");
  check(IDASetSuppressAlg(ida, SUNTRUE), "IDASetSuppressAlg");
  check(IDASetMaxNumSteps(ida, opt.max_steps), "IDASetMaxNumSteps");
  if (opt.max_step > 0) check(IDASetMaxStep(ida, opt.max_step), "IDASetMaxStep");
  if (system.n_roots() > 0) check(IDARootInit(ida, system.n_roots(), root_cb), "IDARootInit");

  double t = opt.t_start;
  const double span = opt.t_end - opt.t_start;
  const double eps_t = 1e-12 * std::max(1.0, std::abs(opt.t_end));
  auto fail = [&](const std::string& msg) {
    if (user.error) std::rethrow_exception(user.error);
    result.ok = false;
    result.message = msg;
    result.t_reached = t;
  };
  auto consistent_ic = [&]() -> bool {
    const double t_next = t + std::min(opt.output_interval, std::max(opt.t_end - t, 1e-9));
    const int flag = IDACalcIC(ida, IDA_YA_YDP_INIT, t_next);
    if (flag < 0) {
      fail("cannot find consistent initial values at t = " + std::to_string(t) + " s: " + flag_text(flag, user));
      return false;
    }
    IDAGetConsistentIC(ida, y.get(), yp.get());
    return true;
  };
  // IDAReInit resets IDA's counters: add them up before every re-initialisation.
  auto accumulate_stats = [&]() {
    long v = 0;
    auto& s = result.stats;
    IDAGetNumSteps(ida, &v), s.steps += v;
    IDAGetNumResEvals(ida, &v), s.residual_evals += v;
    IDAGetNumJacEvals(ida, &v), s.jacobian_evals += v;
    IDAGetNumNonlinSolvIters(ida, &v), s.nonlinear_iterations += v;
    IDAGetNumNonlinSolvConvFails(ida, &v), s.nonlinear_failures += v;
    IDAGetNumErrTestFails(ida, &v), s.error_test_failures += v;
    if (system.n_roots() > 0) IDAGetNumGEvals(ida, &v), s.root_evals += v;
  };
  auto emit = [&]() { output(t, N_VGetArrayPointer(y.get()), N_VGetArrayPointer(yp.get())); };

  std::vector<double> events = system.time_events();
  events.erase(std::remove_if(events.begin(), events.end(), [&](double te) { return te > opt.t_end; }),
               events.end());
  std::size_t next_event = 0;
  // Events at (or before) t_start set the initial modes.
  while (next_event < events.size() && events[next_event] <= opt.t_start + eps_t) {
    system.handle_time_event(events[next_event], N_VGetArrayPointer(y.get()), N_VGetArrayPointer(yp.get()),
                             result.events);
    ++next_event;
  }
  if (!consistent_ic()) return result;
  emit();

  long k = 1;
  const long n_out = static_cast<long>(std::ceil(span / opt.output_interval - 1e-9));
  std::vector<int> root_info(std::max(1, system.n_roots()));
  while (t < opt.t_end - eps_t) {
    const double t_out = k >= n_out ? opt.t_end : opt.t_start + k * opt.output_interval;
    const double t_event = next_event < events.size() ? events[next_event] : std::numeric_limits<double>::infinity();
    const double t_stop = std::min(t_event, opt.t_end);
    check(IDASetStopTime(ida, t_stop), "IDASetStopTime");
    double t_ret = t;
    const int flag = IDASolve(ida, std::min(t_out, t_stop), &t_ret, y.get(), yp.get(), IDA_NORMAL);
    if (flag < 0) {
      t = t_ret;
      fail("integration failed at t = " + std::to_string(t_ret) + " s: " + flag_text(flag, user));
      break;
    }
    t = t_ret;
    bool reinit = false;
    if (flag == IDA_ROOT_RETURN) {
      check(IDAGetRootInfo(ida, root_info.data()), "IDAGetRootInfo");
      reinit = system.handle_roots(t, N_VGetArrayPointer(y.get()), N_VGetArrayPointer(yp.get()), root_info.data(),
                                   result.events);
    } else if (next_event < events.size() && std::abs(t - t_event) <= eps_t) {
      reinit = system.handle_time_event(t, N_VGetArrayPointer(y.get()), N_VGetArrayPointer(yp.get()), result.events);
      ++next_event;
    }
    if (reinit) {
      ++result.stats.reinitialisations;
      accumulate_stats();
      check(IDAReInit(ida, t, y.get(), yp.get()), "IDAReInit");
      if (!consistent_ic()) break;
    }
    const bool at_output = std::abs(t - t_out) <= eps_t;
    if (at_output) ++k;
    if (at_output || flag == IDA_ROOT_RETURN || reinit) emit();
  }
  if (user.error) std::rethrow_exception(user.error);
  if (result.message.empty()) {
    result.ok = true;
    result.t_reached = t;
  }

  accumulate_stats();
  auto& s = result.stats;
  s.pattern_misses = system.pattern_misses();
  s.variables = n;
  s.nonzeros = system.nnz();
  return result;
}

}  // namespace pneumo
