#include "framework/solver/ida_solver.hpp"

#include "framework/solver/serial_vector_ops.hpp"

// IDAS (not IDA): the same integrator plus quadratures, which integrate
// requested outputs (energy accounts) to the solver's accuracy.
#include <idas/idas.h>
#include <idas/idas_ls.h>
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

// IDA's Newton matrix dF/dy + cj dF/dy' kept in its two parts, so that a
// request for a new matrix that only follows a change of cj is answered by
// recombining them (CVODE does this for its own Newton matrix; IDA does
// not). cj = alpha / h changes with every change of step size or order, and
// IDA asks for a new matrix once cj is more than 25 % off the one the
// factorisation used; most of its requests are these, while the state has
// hardly moved. Recombining is exact in cj, since F is linear in y' and the
// explicitly solved unknowns have no y' (System::newton_matrix_parts). The parts
// are evaluated afresh when they may be too old for the Newton iteration:
// after a nonlinear convergence failure, after kMaxAgeSteps steps (CVODE's
// limit), after an event or a re-initialisation, after KLU rejected a
// pivot, and throughout IDACalcIC, which starts from far-off values. Used
// only when IDA integrates no algebraic unknown (see simulate).
struct NewtonMatrixParts {
  static constexpr long kMaxAgeSteps = 50;
  bool enabled = true;
  bool valid = false;
  bool in_calc_ic = false;
  std::vector<double> dFdy, dFdyp;  // in IDA's scaled variables, in the matrix's order
  long steps_at = 0, convergence_failures_at = 0;
  long recombined = 0;  // requests answered without an evaluation
};

struct UserData {
  System* system = nullptr;
  std::exception_ptr error;  // exceptions never cross the C callbacks
  std::string last_message;
  std::vector<sunindextype> col_ptr, row_idx;
  SUNLinearSolver klu = nullptr;
  void* ida = nullptr;
  NewtonMatrixParts parts;
  const ProbeSet* integrands = nullptr;
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
};

int residual_cb(realtype t, N_Vector y, N_Vector yp, N_Vector rr, void* user) {
  auto* u = static_cast<UserData*>(user);
  try {
    return u->system->residual(t, u->physical_y(y), u->physical_yp(yp), N_VGetArrayPointer(rr));
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
    // SUNLinSol_KLU refactors with the pivot order of its first factorisation
    // and gives up (recoverably) when one of those pivots is now exactly zero
    // - e.g. a throttle that went choked has dm/dp_down == 0. After such a
    // failure, ask for a fresh factorisation with new pivots.
    long last = 0;
    const bool klu_rejected =
        u->klu && u->ida && IDAGetLastLinFlag(u->ida, &last) == IDA_SUCCESS && last == SUNLS_PACKAGE_FAIL_REC;
    if (klu_rejected) SUNLinSol_KLUReInit(u->klu, J, SUNSparseMatrix_NNZ(J), SUNKLU_REINIT_PARTIAL);
    double* values = SUNSparseMatrix_Data(J);
    auto& parts = u->parts;
    const std::size_t nz = u->row_idx.size();
    long steps = 0, convergence_failures = 0;
    if (u->ida) {
      IDAGetNumSteps(u->ida, &steps);
      IDAGetNumNonlinSolvConvFails(u->ida, &convergence_failures);
    }
    if (parts.valid && !parts.in_calc_ic && !klu_rejected && convergence_failures == parts.convergence_failures_at &&
        steps >= parts.steps_at && steps - parts.steps_at < NewtonMatrixParts::kMaxAgeSteps) {
      for (std::size_t k = 0; k < nz; ++k) values[k] = parts.dFdy[k] + cj * parts.dFdyp[k];
      ++parts.recombined;
      return 0;
    }
    const double* py = u->physical_y(y);
    const double* pyp = u->physical_yp(yp);
    // Chain rule for the scaling: column c is multiplied by nominal[c].
    auto scale_columns = [&](double* v) {
      for (std::size_t c = 0; c + 1 < u->col_ptr.size(); ++c)
        for (auto k = u->col_ptr[c]; k < u->col_ptr[c + 1]; ++k) v[k] *= u->nominal[c];
    };
    parts.valid = false;
    if (!parts.enabled || parts.in_calc_ic) {
      const int flag = u->system->jacobian(t, py, pyp, cj, values);
      scale_columns(values);
      return flag;
    }
    parts.dFdy.resize(nz);
    parts.dFdyp.resize(nz);
    const int flag = u->system->newton_matrix_parts(t, py, pyp, parts.dFdy.data(), parts.dFdyp.data());
    scale_columns(parts.dFdy.data());
    scale_columns(parts.dFdyp.data());
    for (std::size_t k = 0; k < nz; ++k) values[k] = parts.dFdy[k] + cj * parts.dFdyp[k];
    parts.valid = flag == 0;
    parts.steps_at = steps;
    parts.convergence_failures_at = convergence_failures;
    return flag;
  } catch (...) {
    u->error = std::current_exception();
    return -1;
  }
}

// Integrands of the quadratures (outputs declared as integrals).
int quadrature_cb(realtype t, N_Vector y, N_Vector yp, N_Vector q, void* user) {
  auto* u = static_cast<UserData*>(user);
  try {
    const double* py = u->physical_y(y);
    const double* pyp = u->physical_yp(yp);
    u->system->probe_all(*u->integrands, t, py, pyp, N_VGetArrayPointer(q));
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

SolverResult simulate(System& system, const SolverOptions& opt, const OutputFn& output, const Quadratures* quad) {
  SolverResult result;
  const int n = system.size();
  ContextOwner context;
  UserData user;
  user.system = &system;
  user.col_ptr.assign(system.col_ptr().begin(), system.col_ptr().end());
  user.row_idx.assign(system.row_idx().begin(), system.row_idx().end());

  VectorPtr y(N_VNew_Serial(n, context.ctx)), yp(N_VNew_Serial(n, context.ctx));
  VectorPtr atol(N_VNew_Serial(n, context.ctx)), id(N_VNew_Serial(n, context.ctx));
  // Compiled vector kernels (serial_vector_ops.hpp: Debian's serial N_Vector
  // is built unoptimised) with the fused operations: IDA's predictor,
  // interpolation and error norms combine k vectors in one pass. IDA clones
  // y for its own vectors, which inherit the kernels.
  use_compiled_serial_ops(y.get());
  use_compiled_serial_ops(yp.get());
  std::vector<double> y0, yp0;
  system.reset_modes();
  system.start_values(y0, yp0);
  user.nominal = system.nominal();
  user.y_phys.assign(n, 0.0);
  user.yp_phys.assign(n, 0.0);
  for (int i = 0; i < n; ++i) {
    N_VGetArrayPointer(y.get())[i] = y0[i] / user.nominal[i];
    N_VGetArrayPointer(yp.get())[i] = yp0[i] / user.nominal[i];
    N_VGetArrayPointer(atol.get())[i] = opt.atol;
    N_VGetArrayPointer(id.get())[i] = system.differential()[i];
  }

  MatrixPtr A(SUNSparseMatrix(n, n, std::max<long>(1, system.nnz()), CSC_MAT, context.ctx));
  SolverPtr LS(SUNLinSol_KLU(y.get(), A.get(), context.ctx));
  IdaPtr mem(IDACreate(context.ctx));
  user.klu = LS.get();
  user.ida = mem.get();
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
  // Algebraic unknowns (if any are left after explicit elimination) stay
  // out of the error test; without any, IDA's plain norms are used.
  const bool any_algebraic = std::any_of(system.differential().begin(), system.differential().end(),
                                         [](double d) { return d == 0.0; });
  check(IDASetSuppressAlg(ida, any_algebraic ? SUNTRUE : SUNFALSE), "IDASetSuppressAlg");
  // An algebraic row of the Newton matrix has no cj dF/dy' part to dominate
  // it at short steps: it is dF/dy alone, and an old one slows the Newton
  // iteration on the flows and forces more than reuse saves (measured: the
  // cushion rig without alias elimination, 41 algebraic unknowns, 19 %
  // slower with reuse; 9 algebraic unknowns of the full rig, no gain).
  user.parts.enabled = opt.reuse_jacobian && !any_algebraic;
  check(IDASetMaxNumSteps(ida, opt.max_steps), "IDASetMaxNumSteps");
  if (opt.max_step > 0) check(IDASetMaxStep(ida, opt.max_step), "IDASetMaxStep");
  const int n_quad = quad ? static_cast<int>(quad->integrands.size()) : 0;
  VectorPtr q;
  ProbeSet integrands;
  if (n_quad > 0) {
    integrands = system.probe_set(quad->integrands);
    user.integrands = &integrands;
    q.reset(N_VNew_Serial(n_quad, context.ctx));
    N_VConst(0.0, q.get());
    check(IDAQuadInit(ida, quadrature_cb, q.get()), "IDAQuadInit");
    // Error-controlled like the states: an integral is as accurate as the
    // trajectory it integrates (absolute tolerance in the integral's unit).
    VectorPtr atol_q(N_VNew_Serial(n_quad, context.ctx));
    std::copy(quad->atol.begin(), quad->atol.end(), N_VGetArrayPointer(atol_q.get()));
    check(IDAQuadSVtolerances(ida, opt.rtol, atol_q.get()), "IDAQuadSVtolerances");
    check(IDASetQuadErrCon(ida, SUNFALSE), "IDASetQuadErrCon");
    quad->values->assign(n_quad, 0.0);
  }

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
    // IDACalcIC corrects the states' y' with the iteration matrix
    // dF/dy + cj dF/dy', cj = 1 / (1e-3 (t_next - t)): the dF/dy part is an
    // error of that Newton which shrinks with cj. With the algebraic unknowns
    // solved explicitly (System) the states couple directly (a hose's flow
    // and its segments' energy), so a short scale keeps it converging in a
    // few iterations: 10 us gives cj = 1e8 1/s, far above any rate of a
    // pneumatic drive.
    const double t_next = t + std::min({opt.output_interval, 1e-5, std::max(opt.t_end - t, 1e-9)});
    user.parts.in_calc_ic = true;
    int flag = IDACalcIC(ida, IDA_YA_YDP_INIT, t_next);
    if (flag < 0) {
      // IDA's line search can stall on flow laws with flat (choked) pieces,
      // e.g. a junction without volume fed by choked throttles; a full
      // Newton without it converges from the same start (conservation_test).
      check(IDAReInit(ida, t, y.get(), yp.get()), "IDAReInit");
      check(IDASetLineSearchOffIC(ida, SUNTRUE), "IDASetLineSearchOffIC");
      flag = IDACalcIC(ida, IDA_YA_YDP_INIT, t_next);
      check(IDASetLineSearchOffIC(ida, SUNFALSE), "IDASetLineSearchOffIC");
    }
    user.parts.in_calc_ic = false;
    user.parts.valid = false;
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
  };
  auto emit = [&]() {
    if (n_quad > 0) {
      double tq = t;
      if (t > opt.t_start && IDAGetQuad(ida, &tq, q.get()) >= 0)
        std::copy_n(N_VGetArrayPointer(q.get()), n_quad, quad->values->begin());
    }
    output(t, user.physical_y(y.get()), user.physical_yp(yp.get()));
  };

  std::vector<double> events = system.time_events();
  events.erase(std::remove_if(events.begin(), events.end(), [&](double te) { return te > opt.t_end; }),
               events.end());
  std::size_t next_event = 0;
  // Events at (or before) t_start set the initial modes.
  while (next_event < events.size() && events[next_event] <= opt.t_start + eps_t) {
    system.handle_time_event(events[next_event], user.physical_y(y.get()), user.physical_yp(yp.get()),
                             result.events);
    ++next_event;
  }
  if (!consistent_ic()) return result;
  emit();

  // Output times: the grid t_start + k * output_interval, then t_end.
  long k = 1;
  const long n_out = static_cast<long>(std::ceil(span / opt.output_interval - 1e-9));
  auto grid_time = [&](long j) { return j >= n_out ? opt.t_end : opt.t_start + j * opt.output_interval; };
  // IDA takes one step per call (IDA_ONE_STEP) and the output times the step
  // passed are read off its interpolating polynomial: with IDA_NORMAL every
  // output time would also cost a root-function evaluation (IDA checks the
  // roots up to each tout), for outputs every ms about as many as the steps.
  VectorPtr y_out(N_VClone(y.get())), yp_out(N_VClone(y.get()));
  N_VConst(0.0, yp_out.get());  // stays 0 when the outputs read no y
  // y (and y') at tr in the last step, from IDA's interpolant.
  auto interpolate = [&](double tr, N_Vector yy, N_Vector yyp, bool with_yp) {
    check(IDAGetDky(ida, tr, 0, yy), "IDAGetDky");
    if (with_yp) check(IDAGetDky(ida, tr, 1, yyp), "IDAGetDky");
  };
  // An output row at t_out inside the last step, from the state yy, yyp there.
  auto emit_at = [&](double t_out, N_Vector yy, N_Vector yyp) {
    if (n_quad > 0 && IDAGetQuadDky(ida, t_out, 0, q.get()) >= 0)
      std::copy_n(N_VGetArrayPointer(q.get()), n_quad, quad->values->begin());
    output(t_out, user.physical_y(yy), user.physical_yp(yyp));
  };
  auto emit_interpolated = [&](double t_out) {
    interpolate(t_out, y_out.get(), yp_out.get(), opt.outputs_read_yp);
    emit_at(t_out, y_out.get(), yp_out.get());
  };
  // State events. The root functions are checked once per step at its end
  // t_n, on the y(t_n) IDA returns; a sign change since the last check is
  // located on IDA's interpolant (Illinois), and the event handled there. If
  // the event re-initialises, IDA restarts from the event (the rest of the
  // step is discarded); otherwise the search goes on to t_n. IDA's own
  // root finding does the same but interpolates y(t_n) once more per step.
  const int nr = system.n_roots();
  std::vector<int> root_info(std::max(1, nr));
  std::vector<double> g_lo(nr), g_hi(nr), g_c(nr), t_of(nr);
  double t_lo = t;
  VectorPtr y_ev(N_VClone(y.get())), yp_ev(N_VClone(y.get()));
  auto roots_at = [&](double tr, N_Vector yy, N_Vector yyp, std::vector<double>& g) {
    system.roots(tr, user.physical_y(yy), user.physical_yp(yyp), g.data());
    ++result.stats.root_evals;
  };
  // A root function exactly 0 at the start of an interval has no side yet:
  // its first nonzero value sets it, without an event (as IDA does).
  auto crosses = [](double a, double b) { return (a < 0 && b >= 0) || (a > 0 && b <= 0); };
  auto restart_roots = [&](const std::vector<int>* fired) {
    t_lo = t;
    if (nr == 0) return;
    roots_at(t, y.get(), yp.get(), g_lo);
    // A root just handled counts as crossed, whatever rounding left at t.
    if (fired)
      for (int i = 0; i < nr; ++i)
        if ((*fired)[i] != 0) g_lo[i] = (*fired)[i] > 0 ? std::max(g_lo[i], 1e-300) : std::min(g_lo[i], -1e-300);
  };
  restart_roots(nullptr);
  // Restart IDA from (t, y, yp) after an event that changed the modes: the
  // integrals so far, consistent values, the root functions' sides (`fired`:
  // the roots just handled, counted as crossed).
  auto restart = [&](const std::vector<int>* fired) -> bool {
    if (n_quad > 0) check(IDAGetQuadDky(ida, t, 0, q.get()), "IDAGetQuadDky");
    ++result.stats.reinitialisations;
    accumulate_stats();
    check(IDAReInit(ida, t, y.get(), yp.get()), "IDAReInit");
    if (n_quad > 0) check(IDAQuadReInit(ida, q.get()), "IDAQuadReInit");
    if (!consistent_ic()) return false;
    restart_roots(fired);
    return true;
  };
  // The earliest crossing in (t_lo, t_hi]; false if none.
  auto locate = [&](double t_hi, double& t_root) -> bool {
    double h_last = 0.0;
    IDAGetLastStep(ida, &h_last);
    const double ttol = 100.0 * std::numeric_limits<double>::epsilon() * (std::abs(t_hi) + std::abs(h_last));
    bool any = false;
    t_root = t_hi;
    std::fill(root_info.begin(), root_info.end(), 0);
    std::fill(t_of.begin(), t_of.end(), std::numeric_limits<double>::infinity());
    for (int i = 0; i < nr; ++i) {
      if (g_lo[i] == 0.0 || !crosses(g_lo[i], g_hi[i])) continue;
      double a = t_lo, fa = g_lo[i], b = t_hi, fb = g_hi[i];
      int side = 0;
      for (int it = 0; it < 60 && b - a > ttol && fb != 0.0; ++it) {
        double c = b - fb * (b - a) / (fb - fa);
        c = std::min(std::max(c, a + 0.5 * ttol), b - 0.5 * ttol);
        interpolate(c, y_ev.get(), yp_ev.get(), true);
        roots_at(c, y_ev.get(), yp_ev.get(), g_c);
        const double fc = g_c[i];
        if (crosses(fa, fc)) {  // the root lies in (a, c]
          b = c, fb = fc;
          if (side == -1) fa *= 0.5;
          side = -1;
        } else {
          a = c, fa = fc;
          if (side == 1) fb *= 0.5;
          side = 1;
        }
      }
      t_of[i] = b;  // the first point where g has crossed
      if (b < t_root || !any) t_root = b;
      any = true;
    }
    if (!any) return false;
    for (int i = 0; i < nr; ++i)
      if (t_of[i] <= t_root + ttol) root_info[i] = g_lo[i] < 0 ? 1 : -1;
    return true;
  };

  long steps_without_output = 0;
  while (t < opt.t_end - eps_t) {
    const double t_event = next_event < events.size() ? events[next_event] : std::numeric_limits<double>::infinity();
    const double t_stop = std::min(t_event, opt.t_end);
    check(IDASetStopTime(ida, t_stop), "IDASetStopTime");
    double t_ret = t;
    // tout matters only for the first step after a (re)initialisation (its
    // size), as it did with IDA_NORMAL.
    const int flag = IDASolve(ida, std::min(grid_time(k), t_stop), &t_ret, y.get(), yp.get(), IDA_ONE_STEP);
    if (flag < 0) {
      t = t_ret;
      emit();  // the last state IDA reached, for the partial results
      fail("integration failed at t = " + std::to_string(t_ret) + " s: " + flag_text(flag, user));
      break;
    }
    const long k_before = k;
    // State events in this step, in time order.
    bool restarted = false;
    if (nr > 0) {
      roots_at(t_ret, y.get(), yp.get(), g_hi);
      double t_root = t_ret;
      while (!restarted && locate(t_ret, t_root)) {
        while (k <= n_out && grid_time(k) < t_root - eps_t) emit_interpolated(grid_time(k++));
        interpolate(t_root, y_ev.get(), yp_ev.get(), true);
        const std::vector<int> fired = root_info;
        user.parts.valid = false;  // the modes may have changed
        const bool reinit = system.handle_roots(t_root, user.physical_y(y_ev.get()), user.physical_yp(yp_ev.get()),
                                                fired.data(), result.events);
        if (k <= n_out && std::abs(t_root - grid_time(k)) <= eps_t) ++k;
        if (reinit) {
          // Restart from the event; IDA's step beyond it is discarded.
          N_VScale(1.0, y_ev.get(), y.get());
          N_VScale(1.0, yp_ev.get(), yp.get());
          t = t_root;
          if (!restart(&fired)) break;
          emit();
          restarted = true;
        } else {
          emit_at(t_root, y_ev.get(), yp_ev.get());
          // Go on searching (t_root, t_n].
          t_lo = t_root;
          roots_at(t_root, y_ev.get(), yp_ev.get(), g_lo);
          for (int i = 0; i < nr; ++i)
            if (fired[i] != 0) g_lo[i] = g_hi[i];
        }
      }
      if (!result.message.empty()) break;
      if (restarted) {
        steps_without_output = 0;
        continue;
      }
      g_lo = g_hi;
      t_lo = t_ret;
    }
    // Stopped at a time event or t_end: an output time within eps_t of it is
    // that row (below), emitted after the event is handled.
    const bool stopped = flag == IDA_TSTOP_RETURN;
    while (k <= n_out && (stopped ? grid_time(k) < t_ret - eps_t : grid_time(k) <= t_ret))
      emit_interpolated(grid_time(k++));
    t = t_ret;
    // IDA's own limit (IDASetMaxNumSteps) counts the steps of one IDASolve
    // call, i.e. now one step: keep its meaning, at most max_steps steps
    // between one output (or event) and the next.
    steps_without_output = (stopped || k > k_before) ? 0 : steps_without_output + 1;
    if (steps_without_output >= opt.max_steps) {
      emit();  // the last state IDA reached, for the partial results
      fail("integration failed at t = " + std::to_string(t) + " s: IDA_TOO_MUCH_WORK (" +
           std::to_string(opt.max_steps) + " steps without reaching the next output time)");
      break;
    }
    if (!stopped) continue;
    bool reinit = false;
    if (next_event < events.size() && std::abs(t - t_event) <= eps_t) {
      user.parts.valid = false;
      reinit = system.handle_time_event(t, user.physical_y(y.get()), user.physical_yp(yp.get()), result.events);
      ++next_event;
    }
    if (reinit && !restart(nullptr)) break;
    const bool at_output = k <= n_out && std::abs(t - grid_time(k)) <= eps_t;
    if (at_output) ++k;
    if (at_output || reinit) emit();
  }
  if (user.error) std::rethrow_exception(user.error);
  if (result.message.empty()) {
    result.ok = true;
    result.t_reached = t;
  }

  accumulate_stats();
  auto& s = result.stats;
  // IDA counts its requests; those answered by recombining were no evaluation.
  s.jacobian_recombinations = user.parts.recombined;
  s.jacobian_evals -= user.parts.recombined;
  s.pattern_misses = system.pattern_misses();
  s.variables = n;
  s.netlist_variables = system.full_size();
  s.explicit_variables = system.explicit_size();
  s.nonzeros = system.nnz();
  return result;
}

}  // namespace pneumo
