#include "framework/solver/ida_solver.hpp"

#include "framework/solver/integration.hpp"

// IDAS (not IDA): the same integrator plus quadratures, which integrate
// requested outputs (energy accounts) to the solver's accuracy.
#include <idas/idas.h>
#include <idas/idas_ls.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_newton.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>

#include "framework/core/interrupt.hpp"
#include "framework/core/text.hpp"
#include "framework/solver/ida_callbacks.hpp"
#include "framework/solver/failure_report.hpp"
#include "framework/solver/ida_handles.hpp"
#include "framework/solver/output_grid.hpp"
#include "framework/solver/root_locator.hpp"
#include "framework/solver/serial_vector_ops.hpp"

namespace pneumo {

namespace {

struct NonlinearSolverDeleter {
  void operator()(_generic_SUNNonlinearSolver* s) const { SUNNonlinSolFree(s); }
};
using NonlinearSolverPtr = std::unique_ptr<_generic_SUNNonlinearSolver, NonlinearSolverDeleter>;

// IDA's Newton convergence test, stricter on the algebraic unknowns. IDA
// accepts a corrector after one iteration when the first correction times
// the convergence rate remembered from earlier steps is within tolerance;
// with a near-linear system that rate is tiny and a correction hundreds of
// times the tolerance passes. The states' error test catches what that
// leaves in them, but the algebraic unknowns are out of it
// (IDASetSuppressAlg): a node without volume is then held on its equation by
// nothing. Its error goes into the next prediction, which extrapolates the
// history (at order 5, an alternating error 31-fold), one iteration with
// an old matrix takes off only part of it, and the error grows step by step
// until no step converges (issue 36: the meter-out cylinder drawn without
// line volumes, after the end-stop contact, the exhaust junctions' flows
// dying away). So an algebraic unknown's first correction must be within
// tolerance at the rate IDA assumes after a new matrix (1/20); else the
// iteration goes on and IDA measures the rate of this step.
struct AlgebraicNewtonTest {
  static constexpr double kUnknownRate = 20.0;  // IDA's rate/(1 - rate) after a new matrix
  SUNNonlinSolConvTestFn ida_test = nullptr;
  void* ida_data = nullptr;
  std::vector<int> algebraic;

  static int test(SUNNonlinearSolver nls, N_Vector ycor, N_Vector del, realtype tol, N_Vector ewt, void* data) {
    const auto& self = *static_cast<AlgebraicNewtonTest*>(data);
    const int flag = self.ida_test(nls, ycor, del, tol, ewt, self.ida_data);
    int m = 0;
    if (flag != SUN_NLS_SUCCESS || SUNNonlinSolGetCurIter(nls, &m) != SUN_NLS_SUCCESS || m > 0) return flag;
    const double* d = N_VGetArrayPointer(del);
    const double* w = N_VGetArrayPointer(ewt);
    double worst = 0.0;
    for (int i : self.algebraic) worst = std::max(worst, std::abs(d[i] * w[i]));
    return kUnknownRate * worst <= tol ? SUN_NLS_SUCCESS : SUN_NLS_CONTINUE;
  }
};

// IDA's Newton matrix setup, wrapped so that the Newton iteration knows a
// recombined matrix (NewtonMatrixParts) for what it is: IDA reports every
// setup as a fresh matrix (jcur), and a Newton iteration that fails on a
// fresh matrix ends in a convergence failure that cuts the step to a
// quarter. Reported as old, the failure is retried at the same step with
// the matrix evaluated afresh (jbad), as CVODE does with a saved Jacobian.
// IDA installs its setup function (the same for every run) at each
// (re)initialisation, through the solver's setlsetupfn, which this
// replaces.
std::atomic<SUNNonlinSolLSetupFn> ida_lsetup{nullptr};

int lsetup_knowing_recombination(booleantype jbad, booleantype* jcur, void* ida_mem) {
  void* data = nullptr;
  IDAGetUserData(ida_mem, &data);
  auto& parts = static_cast<UserData*>(data)->parts;
  if (jbad) parts.failed_newton();
  const long recombined = parts.recombined;
  const int flag = ida_lsetup.load()(jbad, jcur, ida_mem);
  parts.last_recombined = parts.recombined != recombined;
  if (parts.last_recombined) *jcur = SUNFALSE;
  return flag;
}

int set_lsetup(SUNNonlinearSolver nls, SUNNonlinSolLSetupFn fn) {
  if (fn) ida_lsetup.store(fn);
  return SUNNonlinSolSetLSetupFn_Newton(nls, fn ? lsetup_knowing_recombination : nullptr);
}

// IDA zeroes the Newton matrix, pattern and values, before every
// evaluation; the pattern is written once (create_ida) and jacobian_cb
// writes every value, so that pass over the arrays (2-3 % of a run of the
// six-cylinder line) is left out.
int keep_matrix(SUNMatrix) { return SUNMAT_SUCCESS; }

}  // namespace

// One run of IDA over [t_start, t_end], in pieces (advance_to): IDA takes
// one step per call (IDA_ONE_STEP); after each step the state events in it
// are located and handled, the output times it passed are read off its
// interpolating polynomial, and a time event, the target or t_end it
// stopped at is handled.
class IdaRun {
 public:
  IdaRun(Evaluator& eval, const SolverOptions& opt, OutputFn output, const Quadratures* quad);
  bool start();
  bool resume(const Checkpoint& from);
  Checkpoint checkpoint();
  void keep_in_passing(std::vector<double> times) { passing_ = std::move(times), next_passing_ = 0; }
  std::vector<Checkpoint> passed() { return std::move(passed_); }
  bool advance_to(double target);
  bool inputs_changed();
  SolverResult finish_run();
  double time() const { return t_; }
  const double* y() { return user_.physical_y(y_.get()); }
  const double* yp() { return user_.physical_yp(yp_.get()); }
  const SolverResult& result() const { return result_; }

 private:
  void create_vectors();
  void create_ida();
  void prepare_run();
  void use_newton_solver(bool algebraic);
  void init_quadratures();
  void find_disturbed();
  void share_disturbances_in_matrix();
  // The unknowns a component's quantity reads, by (component, kind, index):
  // a quantity that several terms read is probed once.
  using ProbedReads = std::map<std::tuple<int, Probe::Kind, int>, std::vector<int>>;
  DisturbedMatrix::Shift shift_reads(const UserData::Disturbed& r, ProbedReads& probed) const;
  std::vector<int> probe_reads(const Probe& p) const;
  UserData::Reader reader(const Disturbance& d, const std::string& name, bool rate) const;
  int internal_energy_of(const std::string& unknown) const;
  void check(int flag, const char* what) const {
    if (flag < 0) throw std::runtime_error(std::string(what) + " failed: " + flag_text(flag, user_));
  }
  void fail(const std::string& msg);
  bool consistent_ic();
  bool consistent_ic_from_here();
  int calc_ic_without_line_search(double t_next);
  int calc_ic_with_more_iterations(double t_next);
  bool settle();
  bool rest_start();
  bool integrate_to_rest();
  bool at_rest(std::string* moving) const;
  double model_t(double t) const { return settling_ ? opt_.t_start : t; }
  void accumulate_stats();
  bool restart(const std::vector<int>* fired);
  void restart_roots(const std::vector<int>* fired);
  void roots_at(double tr, N_Vector yy, N_Vector yyp, std::vector<double>& g);
  void interpolate(double tr, N_Vector yy, N_Vector yyp, bool with_yp);
  void emit();
  void emit_at(double t_out, N_Vector yy, N_Vector yyp);
  void emit_interpolated(double t_out) {
    const bool keep = passing_due(t_out);
    interpolate(t_out, y_out_.get(), yp_out_.get(), opt_.outputs_read_yp || keep);
    emit_at(t_out, y_out_.get(), yp_out_.get());
    if (keep) keep_passing(t_out, y_out_.get(), yp_out_.get());
  }
  bool passing_due(double t) const { return next_passing_ < passing_.size() && t >= passing_[next_passing_] - eps_t_; }
  void keep_passing(double t, N_Vector yy, N_Vector yyp);
  enum class Next { step, restarted, stop };
  Next step();
  Next state_events(double t_ret);
  Next stopped_at(double t_event);
  Next too_much_work(const std::string& budget);
  bool within_event_budget();
  bool recover(double t_ret);
  std::string chatter_message() const;
  void finish();

  Evaluator& eval_;
  const System& system_;
  const SolverOptions opt_;  // copies: a resumable run outlives its caller's
  const OutputFn output_;
  const Quadratures* quad_;
  SolverResult result_;
  System::Junctions junctions_;  // System::junction_pressures
  const int n_;
  const int n_quad_;
  ContextOwner context_;
  UserData user_;
  VectorPtr y_, yp_, atol_, id_, q_, y_out_, yp_out_, y_ev_, yp_ev_;
  MatrixPtr A_;
  SolverPtr LS_;
  LinearSolverCounts lu_;
  SolverPtr timed_LS_;  // LS_, counted and timed into lu_
  NonlinearSolverPtr nls_;  // IDA's Newton (use_newton_solver)
  AlgebraicNewtonTest newton_test_;
  IdaPtr mem_;
  void* ida_ = nullptr;
  ProbeSet integrands_;
  double t_;
  double target_;  // where advance_to stops (<= t_end)
  const double eps_t_;
  std::vector<double> events_;  // time events up to t_end
  std::size_t next_event_ = 0;
  OutputGrid grid_;
  // Checkpoints taken at the first output row at or after each of these
  // times, from the interpolating polynomial (keep_in_passing): no stop.
  std::vector<double> passing_;
  std::size_t next_passing_ = 0;
  std::vector<Checkpoint> passed_;
  RootLocator roots_;
  long steps_without_output_ = 0;
  long steps_taken_ = 0;  // this integration's, against max_total_steps
  // The event budget between two output times (within_event_budget).
  long grid_k_at_budget_ = -1;
  std::size_t events_at_budget_ = 0;
  long restarts_at_budget_ = 0;
  double t_at_budget_ = 0.0;
  int recoveries_at_budget_ = 0, recoveries_ = 0;
  std::chrono::steady_clock::time_point start_clock_;
  // In a steady start's settling (rest_start): t_ is the settling time, the
  // model sees t_start, nothing is output.
  bool settling_ = false;
};

IdaRun::IdaRun(Evaluator& eval, const SolverOptions& opt, OutputFn output, const Quadratures* quad)
    : eval_(eval),
      system_(eval.system()),
      opt_(opt),
      output_(std::move(output)),
      quad_(quad),
      n_(system_.size()),
      n_quad_(quad ? static_cast<int>(quad->integrands.size()) : 0),
      t_(opt.t_start),
      target_(opt.t_start),
      eps_t_(1e-12 * std::max(1.0, std::abs(opt.t_end))),
      grid_(opt.t_start, opt.t_end, opt.output_interval),
      roots_(system_.n_roots()) {
  user_.eval = &eval;
  user_.time_phases = opt.time_phases;
  user_.col_ptr.assign(system_.col_ptr().begin(), system_.col_ptr().end());
  user_.row_idx.assign(system_.row_idx().begin(), system_.row_idx().end());
  create_vectors();
  find_disturbed();
  create_ida();
  if (n_quad_ > 0) init_quadratures();
}

// A factor reads a System unknown, else a component's quantity as outputs
// name it (COMPONENT.QUANTITY); only an unknown has a rate.
UserData::Reader IdaRun::reader(const Disturbance& d, const std::string& name, bool rate) const {
  UserData::Reader r;
  if (name.empty()) return r;
  const auto& names = system_.variable_names();
  if (const auto it = std::find(names.begin(), names.end(), name); it != names.end()) {
    r.unknown = static_cast<int>(it - names.begin());
    return r;
  }
  const auto dot = name.find('.');  // a quantity's name may hold a dot (port.p), a component's does not
  const int c = dot == std::string::npos ? -1 : system_.circuit().find(name.substr(0, dot));
  if (c >= 0 && !rate) r.probe = find_probe(system_.circuit(), c, name.substr(dot + 1));
  if (r.probe.index < 0)
    throw std::invalid_argument("disturbance on '" + d.variable + "': the system has no " +
                                (rate ? "unknown '" : "unknown or quantity '") + name + "'");
  return r;
}

// The unknown holding the internal energy of the gas whose mass `unknown`
// is, as its component declares it (VariableSpec::internal_energy); -1 for
// anything else.
int IdaRun::internal_energy_of(const std::string& unknown) const {
  const auto dot = unknown.rfind('.');
  const int c = dot == std::string::npos ? -1 : system_.circuit().find(unknown.substr(0, dot));
  if (c < 0) return -1;
  const auto& vars = system_.circuit().components[c]->info().variables;
  const auto spec = std::find_if(vars.begin(), vars.end(), [&](const VariableSpec& v) { return v.name == unknown.substr(dot + 1); });
  if (spec == vars.end() || spec->internal_energy.empty()) return -1;
  const auto& names = system_.variable_names();
  const auto it = std::find(names.begin(), names.end(), unknown.substr(0, dot + 1) + spec->internal_energy);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

void IdaRun::find_disturbed() {
  const auto& names = system_.variable_names();
  for (const auto& d : opt_.disturbances) {
    const auto it = std::find(names.begin(), names.end(), d.variable);
    if (it == names.end())
      throw std::invalid_argument("disturbance on '" + d.variable + "': the system has no such unknown");
    const int i = static_cast<int>(it - names.begin());
    if (system_.differential()[i] == 0.0)
      throw std::invalid_argument("disturbance on '" + d.variable + "': an algebraic unknown has no balance to disturb");
    if ((d.t.empty() && d.terms.empty()) || d.t.size() != d.rate.size() || !std::is_sorted(d.t.begin(), d.t.end()))
      throw std::invalid_argument("disturbance on '" + d.variable + "': needs ascending times, one rate each, or terms");
    if (d.held_t.size() != d.held.size() || !std::is_sorted(d.held_t.begin(), d.held_t.end()))
      throw std::invalid_argument("disturbance on '" + d.variable + "': needs ascending held times, one value each");
    UserData::Disturbed r{i, &d, {}, internal_energy_of(d.variable), system_.gas().kappa};
    for (const auto& term : d.terms) {
      auto& f = r.factor_of.emplace_back();
      for (const auto& factor : term.factors)
        f.emplace_back(reader(d, factor.variable, factor.of == DisturbanceFactor::Of::rate), reader(d, factor.other, false));
    }
    user_.disturbed.push_back(std::move(r));
  }
  share_disturbances_in_matrix();
}

// The Newton matrix holds what the disturbances' shifts do through the
// state (disturbed_matrix.hpp): each shift reads its balance, its gas's
// energy and whatever its terms read; its gas's energy reads the same.
void IdaRun::share_disturbances_in_matrix() {
  if (user_.disturbed.empty()) return;
  ProbedReads probed;
  std::vector<DisturbedMatrix::Shift> shifts;
  for (const auto& r : user_.disturbed) {
    auto balance = shift_reads(r, probed);
    auto energy = balance;
    energy.unknown = r.energy;
    shifts.push_back(std::move(balance));
    shifts.push_back(std::move(energy));
  }
  user_.shifted = DisturbedMatrix(user_.col_ptr, user_.row_idx, shifts);
}

DisturbedMatrix::Shift IdaRun::shift_reads(const UserData::Disturbed& r, ProbedReads& probed) const {
  std::set<int> reads{r.i}, rate_reads;
  if (r.energy >= 0) reads.insert(r.energy);
  for (std::size_t j = 0; j < r.factor_of.size(); ++j)
    for (std::size_t f = 0; f < r.factor_of[j].size(); ++f) {
      const auto& [a, b] = r.factor_of[j][f];
      if (r.d->terms[j].factors[f].of == DisturbanceFactor::Of::rate) rate_reads.insert(a.unknown);
      for (const auto* x : {&a, &b}) {
        if (x->unknown >= 0) reads.insert(x->unknown);
        if (x->unknown >= 0 || x->probe.index < 0) continue;
        const auto key = std::make_tuple(x->probe.component, x->probe.kind, x->probe.index);
        auto it = probed.find(key);
        if (it == probed.end()) it = probed.emplace(key, probe_reads(x->probe)).first;
        reads.insert(it->second.begin(), it->second.end());
      }
    }
  return {r.i, {reads.begin(), reads.end()}, {rate_reads.begin(), rate_reads.end()}};
}

// The unknowns a component's quantity reads: each moved in turn, at the
// start values and at two points off them, each unknown's way reversed
// between them (a quantity upwinded or switched reads the unknowns of one
// side of a flow at a time).
std::vector<int> IdaRun::probe_reads(const Probe& p) const {
  std::vector<double> y0, yp0;
  system_.start_values(y0, yp0);
  std::set<int> reads;
  for (const double off : {0.0, 0.05, -0.05}) {
    auto y = y0;
    for (int c = 0; c < n_; ++c) y[c] += (c % 2 ? off : -off) * std::max(std::abs(y[c]), user_.nominal[c]);
    const double base = eval_.probe(p, opt_.t_start, y.data(), yp0.data());
    if (!std::isfinite(base)) continue;
    for (int c = 0; c < n_; ++c) {
      const double held = y[c];
      y[c] += 1e-4 * std::max(std::abs(held), user_.nominal[c]);
      if (!(eval_.probe(p, opt_.t_start, y.data(), yp0.data()) == base)) reads.insert(c);
      y[c] = held;
    }
  }
  return {reads.begin(), reads.end()};
}

// y and y' scaled by each unknown's nominal magnitude (see UserData).
void IdaRun::create_vectors() {
  y_.reset(N_VNew_Serial(n_, context_.ctx));
  yp_.reset(N_VNew_Serial(n_, context_.ctx));
  atol_.reset(N_VNew_Serial(n_, context_.ctx));
  id_.reset(N_VNew_Serial(n_, context_.ctx));
  // Compiled vector kernels (serial_vector_ops.hpp: Debian's serial N_Vector
  // is built unoptimised) with the fused operations: IDA's predictor,
  // interpolation and error norms combine k vectors in one pass. IDA clones
  // y for its own vectors, which inherit the kernels.
  use_compiled_serial_ops(y_.get());
  use_compiled_serial_ops(yp_.get());
  std::vector<double> y0, yp0;
  eval_.reset_modes();
  system_.start_values(y0, yp0);
  user_.nominal = system_.nominal();
  junctions_ = system_.junction_pressures();
  user_.y_phys.assign(n_, 0.0);
  user_.yp_phys.assign(n_, 0.0);
  for (int i = 0; i < n_; ++i) {
    N_VGetArrayPointer(y_.get())[i] = y0[i] / user_.nominal[i];
    N_VGetArrayPointer(yp_.get())[i] = yp0[i] / user_.nominal[i];
    N_VGetArrayPointer(atol_.get())[i] = opt_.atol;
    N_VGetArrayPointer(id_.get())[i] = system_.differential()[i];
  }
}

void IdaRun::create_ida() {
  const bool shifted = user_.shifted.active();
  const auto& col_ptr = shifted ? user_.shifted.col_ptr() : user_.col_ptr;
  const auto& row_idx = shifted ? user_.shifted.row_idx() : user_.row_idx;
  A_.reset(SUNSparseMatrix(n_, n_, std::max<long>(1, static_cast<long>(row_idx.size())), CSC_MAT, context_.ctx));
  if (A_) {
    A_->ops->zero = keep_matrix;
    std::copy(col_ptr.begin(), col_ptr.end(), SUNSparseMatrix_IndexPointers(A_.get()));
    std::copy(row_idx.begin(), row_idx.end(), SUNSparseMatrix_IndexValues(A_.get()));
  }
  LS_.reset(SUNLinSol_KLU(y_.get(), A_.get(), context_.ctx));
  if (LS_) timed_LS_.reset(timed_klu(LS_.get(), &lu_, opt_.time_phases, context_.ctx));
  mem_.reset(IDACreate(context_.ctx));
  user_.klu = LS_.get();
  user_.ida = mem_.get();
  if (!A_ || !LS_ || !timed_LS_ || !mem_) throw std::runtime_error("cannot create the SUNDIALS solver objects");
  ida_ = mem_.get();
  check(IDASetErrHandlerFn(ida_, error_cb, &user_), "IDASetErrHandlerFn");
  check(IDAInit(ida_, residual_cb, opt_.t_start, y_.get(), yp_.get()), "IDAInit");
  check(IDASVtolerances(ida_, opt_.rtol, atol_.get()), "IDASVtolerances");
  check(IDASetUserData(ida_, &user_), "IDASetUserData");
  check(IDASetLinearSolver(ida_, timed_LS_.get(), A_.get()), "IDASetLinearSolver");
  check(IDASetJacFn(ida_, jacobian_cb), "IDASetJacFn");
  check(IDASetId(ida_, id_.get()), "IDASetId");
  // Algebraic unknowns (if any are left after explicit elimination) stay
  // out of the error test; without any, IDA's plain norms are used. (In
  // it, they cost 2-3 times the steps on circuits with nodes without
  // volume, and the rig without alias elimination fails; the Newton test
  // holds them on their equations instead: AlgebraicNewtonTest.)
  const bool any_algebraic = std::any_of(system_.differential().begin(), system_.differential().end(),
                                         [](double d) { return d == 0.0; });
  check(IDASetSuppressAlg(ida_, any_algebraic ? SUNTRUE : SUNFALSE), "IDASetSuppressAlg");
  use_newton_solver(any_algebraic);
  // An algebraic row of the Newton matrix has no cj dF/dy' part to dominate
  // it at short steps: it is dF/dy alone, and an old one slows the Newton
  // iteration on the flows and forces more than reuse saves (measured: the
  // cushion rig without alias elimination, 41 algebraic unknowns, 19 %
  // slower with reuse; 9 algebraic unknowns of the full rig, no gain).
  // Stream mixing rows are the exception: T_in = sum w T / sum w moves with
  // the weights of flows far from zero only slowly (measured: 16 cylinders
  // on one supply, 2114 -> 362 Newton matrices evaluated, CPU -20 %).
  const long algebraic = std::count(system_.differential().begin(), system_.differential().end(), 0.0);
  user_.parts.enabled = opt_.jacobian_reuse && algebraic <= system_.stream_mixing_rows();
  check(IDASetMaxNumSteps(ida_, opt_.max_steps), "IDASetMaxNumSteps");
  if (opt_.max_step > 0) check(IDASetMaxStep(ida_, opt_.max_step), "IDASetMaxStep");
}

// IDA's own Newton solver, its matrix setup wrapped
// (lsetup_knowing_recombination) and, with algebraic unknowns, its
// convergence test wrapped in AlgebraicNewtonTest (IDASetNonlinearSolver
// installs IDA's test, which the wrapper then calls first).
void IdaRun::use_newton_solver(bool algebraic) {
  nls_.reset(SUNNonlinSol_Newton(y_.get(), context_.ctx));
  if (!nls_) throw std::runtime_error("cannot create the SUNDIALS Newton solver");
  nls_->ops->setlsetupfn = set_lsetup;
  check(IDASetNonlinearSolver(ida_, nls_.get()), "IDASetNonlinearSolver");
  if (!algebraic) return;
  const auto* content = static_cast<SUNNonlinearSolverContent_Newton>(nls_->content);
  newton_test_.ida_test = content->CTest;
  newton_test_.ida_data = content->ctest_data;
  for (int i = 0; i < n_; ++i)
    if (system_.differential()[i] == 0.0) newton_test_.algebraic.push_back(i);
  check(SUNNonlinSolSetConvTestFn(nls_.get(), AlgebraicNewtonTest::test, &newton_test_), "SUNNonlinSolSetConvTestFn");
}

void IdaRun::init_quadratures() {
  integrands_ = system_.probe_set(quad_->integrands);
  user_.integrands = &integrands_;
  q_.reset(N_VNew_Serial(n_quad_, context_.ctx));
  // IDAS clones its quadrature history from q_: the same compiled kernels
  // as the states' vectors (serial_vector_ops.hpp).
  use_compiled_serial_ops(q_.get());
  N_VConst(0.0, q_.get());
  check(IDAQuadInit(ida_, quadrature_cb, q_.get()), "IDAQuadInit");
  // Error-controlled like the states: an integral is as accurate as the
  // trajectory it integrates (absolute tolerance in the integral's unit).
  VectorPtr atol_q(N_VNew_Serial(n_quad_, context_.ctx));
  std::copy(quad_->atol.begin(), quad_->atol.end(), N_VGetArrayPointer(atol_q.get()));
  check(IDAQuadSVtolerances(ida_, opt_.rtol, atol_q.get()), "IDAQuadSVtolerances");
  // Integrated on the trajectory's own steps, not steering them: auditing a
  // run never changes it (nor turns it into a failure at a stop's impact).
  check(IDASetQuadErrCon(ida_, SUNFALSE), "IDASetQuadErrCon");
  quad_->values->assign(n_quad_, 0.0);
}

void IdaRun::fail(const std::string& msg) {
  if (user_.error) std::rethrow_exception(user_.error);
  result_.ok = false;
  result_.message = msg;
  result_.t_reached = t_;
}

// Consistent values at t_. A junction without volume starts where
// System::guess_junction_pressures puts it (after an event, where the last
// step left it); from there the search can find every flow at the junction
// flat in its pressure (a regulator drawn straight onto a valve: at
// ambient its supply path and the valve's path from a charged chamber both
// choke). Then the junctions start at each of the start pressures the
// components give and halfway between them, lowest first - those the guess
// left at ambient alone, then all together - until one finds consistent
// values; the first failure's words stay when none does.
bool IdaRun::consistent_ic() {
  if (junctions_.unguessed.empty() && junctions_.guessed.empty()) return consistent_ic_from_here();
  const std::vector<double> y0(N_VGetArrayPointer(y_.get()), N_VGetArrayPointer(y_.get()) + n_);
  const std::vector<double> yp0(N_VGetArrayPointer(yp_.get()), N_VGetArrayPointer(yp_.get()) + n_);
  if (consistent_ic_from_here()) return true;
  const std::string failed = result_.message;
  const auto from = [&](double p, bool all) {
    double* y = N_VGetArrayPointer(y_.get());
    std::copy(y0.begin(), y0.end(), y);
    std::copy(yp0.begin(), yp0.end(), N_VGetArrayPointer(yp_.get()));
    for (int j : junctions_.unguessed) y[j] = p / user_.nominal[j];
    if (all)
      for (int j : junctions_.guessed) y[j] = p / user_.nominal[j];
    check(IDAReInit(ida_, t_, y_.get(), yp_.get()), "IDAReInit");
    result_.message.clear();
    return consistent_ic_from_here();
  };
  const auto& levels = system_.start_pressure_levels();
  for (std::size_t k = 0; k + 1 < 2 * levels.size(); ++k) {
    const double p = k % 2 == 0 ? levels[k / 2] : 0.5 * (levels[k / 2] + levels[k / 2 + 1]);
    if (!junctions_.unguessed.empty() && from(p, false)) return true;
    if (!junctions_.guessed.empty() && from(p, true)) return true;
  }
  fail(failed);
  return false;
}

bool IdaRun::consistent_ic_from_here() {
  // IDACalcIC corrects the states' y' with the iteration matrix
  // dF/dy + cj dF/dy', cj = 1 / (1e-3 (t_next - t)): the dF/dy part is an
  // error of that Newton which shrinks with cj. With the algebraic unknowns
  // solved explicitly (System) the states couple directly (a hose's flow
  // and its segments' energy), so a short scale keeps it converging in a
  // few iterations: 10 us gives cj = 1e8 1/s, far above any rate of a
  // pneumatic drive.
  const double t_next =
      t_ + (settling_ ? 1e-5 : std::min({opt_.output_interval, 1e-5, std::max(opt_.t_end - t_, 1e-9)}));
  user_.parts.in_calc_ic = true;
  int flag = IDACalcIC(ida_, IDA_YA_YDP_INIT, t_next);
  if (flag < 0) flag = calc_ic_without_line_search(t_next);
  if (flag < 0) flag = calc_ic_with_more_iterations(t_next);
  user_.parts.in_calc_ic = false;
  user_.parts.valid = false;
  IDAGetConsistentIC(ida_, y_.get(), yp_.get());  // on failure, IDA's last iterate, where the equations failed to hold
  if (flag < 0) {
    fail("cannot find consistent initial values at t = " + std::to_string(t_) + " s: " + flag_text(flag, user_) +
         "." + start_failure_report(user_, y_.get(), yp_.get(), t_));
    return false;
  }
  return true;
}

// IDA's line search can stall on flow laws with flat (choked) pieces, e.g.
// a junction without volume fed by choked throttles; a full Newton without
// it converges from the same start (conservation_test).
int IdaRun::calc_ic_without_line_search(double t_next) {
  check(IDAReInit(ida_, t_, y_.get(), yp_.get()), "IDAReInit");
  check(IDASetLineSearchOffIC(ida_, SUNTRUE), "IDASetLineSearchOffIC");
  const int flag = IDACalcIC(ida_, IDA_YA_YDP_INIT, t_next);
  check(IDASetLineSearchOffIC(ida_, SUNFALSE), "IDASetLineSearchOffIC");
  return flag;
}

// A junction without volume whose neighbour opens as a step (a valve path
// drawn as a throttle) must move bars away, through the steep laminar piece
// of the flow law, where each Newton step is short: more iterations than
// IDA's default 10 (junction_test), at the one step size only, so that a
// restart that cannot succeed stays cheap.
int IdaRun::calc_ic_with_more_iterations(double t_next) {
  check(IDAReInit(ida_, t_, y_.get(), yp_.get()), "IDAReInit");
  check(IDASetMaxNumItersIC(ida_, 60), "IDASetMaxNumItersIC");
  check(IDASetMaxNumJacsIC(ida_, 4), "IDASetMaxNumJacsIC");
  check(IDASetMaxNumStepsIC(ida_, 1), "IDASetMaxNumStepsIC");
  const int flag = IDACalcIC(ida_, IDA_YA_YDP_INIT, t_next);
  check(IDASetMaxNumItersIC(ida_, 10), "IDASetMaxNumItersIC");
  check(IDASetMaxNumJacsIC(ida_, 4), "IDASetMaxNumJacsIC");
  check(IDASetMaxNumStepsIC(ida_, 5), "IDASetMaxNumStepsIC");
  return flag;
}

// Event iteration: a mode change makes signals jump at the
// re-initialisation, where IDA cannot see a root; components that follow
// their inputs (logic with memory, step chains, timers) re-read them until
// none changes, each change followed by consistent values.
bool IdaRun::settle() {
  constexpr int kMaxPasses = 100;
  for (int pass = 0;; ++pass) {
    user_.parts.valid = false;
    std::vector<std::string> changed;
    if (!eval_.handle_input_changes(model_t(t_), user_.physical_y(y_.get()), user_.physical_yp(yp_.get()), result_.events,
                                      &changed))
      return true;
    if (pass == kMaxPasses) {
      std::string names;
      for (const auto& n : changed) names += (names.empty() ? "" : ", ") + n;
      fail("event iteration at t = " + std::to_string(t_) + " s does not settle: after " + std::to_string(kMaxPasses) +
           " passes the modes of " + names + " still change (a loop of signals that switch each other at one instant)");
      return false;
    }
    ++result_.stats.reinitialisations;
    accumulate_stats();
    check(IDAReInit(ida_, t_, y_.get(), yp_.get()), "IDAReInit");
    if (n_quad_ > 0) check(IDAQuadReInit(ida_, q_.get()), "IDAQuadReInit");
    if (!consistent_ic()) return false;
  }
}

// A steady start (SimulationSettings::steady_start): the same equations
// integrated in a settling time of their own, from 0, with the model's time
// held at t_start - valves in their initial positions, sources at their
// t_start values, no time event - until every state is at rest; the run
// then starts at t_start from there. State events are handled as in the
// run, so a piston comes to rest against its stop, and a switch or a
// sequencer its state triggers acts (a circuit whose logic keeps cycling
// never rests: an error, as the event budget's); their log entries are
// dropped, they happened before the run. Unconnected heat ports exchange
// heat with the ambient meanwhile (Evaluator::set_resting): at rest the gas
// is at the ambient temperature.
constexpr double kMaxSettleTime = 1e6;  // s of settling time
constexpr long kMaxSettleSteps = 100000;

bool IdaRun::rest_start() {
  if (!eval_.set_resting(true))
    throw std::invalid_argument("a steady start needs the System assembled with AssemblyOptions::rest_heat");
  settling_ = true;
  user_.frozen_t = opt_.t_start;
  const std::size_t logged = result_.events.size();
  // IDA's own limit on the step would keep it from striding over the long
  // settling; the error test alone decides.
  if (opt_.max_step > 0) check(IDASetMaxStep(ida_, kMaxSettleTime), "IDASetMaxStep");
  auto reinit_at = [&](double t) {
    t_ = t;
    if (n_quad_ > 0) N_VConst(0.0, q_.get());
    ++result_.stats.reinitialisations;
    accumulate_stats();
    check(IDAReInit(ida_, t_, y_.get(), yp_.get()), "IDAReInit");
    if (n_quad_ > 0) check(IDAQuadReInit(ida_, q_.get()), "IDAQuadReInit");
    return consistent_ic() && settle();
  };
  const bool ok = reinit_at(0.0) && integrate_to_rest();
  result_.events.resize(std::min(result_.events.size(), logged));
  eval_.set_resting(false);
  settling_ = false;
  user_.frozen_t = NAN;
  grid_k_at_budget_ = -1;
  if (!ok) {
    result_.message =
        "steady start (settling with every input held at t_start = " + rounded(opt_.t_start, 6) + " s): " + result_.message;
    result_.t_reached = opt_.t_start;
    return false;
  }
  if (opt_.max_step > 0) check(IDASetMaxStep(ida_, opt_.max_step), "IDASetMaxStep");
  return reinit_at(opt_.t_start);
}

// The settling's steps and state events, from consistent values, until at
// rest (true) or a failure, the settling's limits included (false, the
// message set).
bool IdaRun::integrate_to_rest() {
  restart_roots(nullptr);
  std::string moving;
  for (long steps = 0; !at_rest(&moving); ++steps) {
    throw_if_interrupted();
    if (t_ >= kMaxSettleTime * (1 - 1e-12) || steps >= kMaxSettleSteps) {
      fail("the circuit does not come to rest within " + std::to_string(steps) + " steps and " + rounded(t_, 6) +
           " s of settling; still moving: " + moving +
           ". Something keeps moving with every input held at t_start (a flange driven at a speed, a flow that "
           "nothing stops): start from given values (steady_start: false), or give it a stop or a load that "
           "holds it");
      return false;
    }
    double t_ret = t_;
    check(IDASetStopTime(ida_, kMaxSettleTime), "IDASetStopTime");
    const int flag = IDASolve(ida_, kMaxSettleTime, &t_ret, y_.get(), yp_.get(), IDA_ONE_STEP);
    if (flag < 0) {
      t_ = t_ret;
      fail("integration failed after " + rounded(t_ret, 6) + " s of settling: " + flag_text(flag, user_) + "." +
           step_failure_report(ida_, user_, y_.get(), yp_.get(), opt_.t_start, result_.events));
      return false;
    }
    const Next next = roots_.size() > 0 ? state_events(t_ret) : Next::step;
    if (next == Next::stop || (next == Next::restarted && !within_event_budget())) return false;
    if (next == Next::step) t_ = t_ret;  // a restart has set t_ to its event
  }
  return true;
}

// Whether no state would move by its absolute tolerance (atol of its
// typical magnitude: the scaled unknowns') over the run's length at its
// present rate; else the three fastest into `moving`, with their rates.
// (Not rtol |y|: a position driven away for ever would pass for resting
// once far enough.)
bool IdaRun::at_rest(std::string* moving) const {
  const double span = opt_.t_end - opt_.t_start;
  const double* yp = N_VGetArrayPointer(yp_.get());
  std::vector<std::pair<double, int>> fast;
  for (int i = 0; i < n_; ++i) {
    if (system_.differential()[i] == 0.0) continue;
    const double ratio = std::abs(yp[i]) * span / opt_.atol;
    if (ratio > 1.0) fast.emplace_back(ratio, i);
  }
  std::sort(fast.rbegin(), fast.rend());
  moving->clear();
  for (std::size_t k = 0; k < std::min<std::size_t>(3, fast.size()); ++k) {
    const int i = fast[k].second;
    char rate[32];
    std::snprintf(rate, sizeof rate, "%.3g", yp[i] * user_.nominal[i]);
    *moving += (k ? ", " : "") + system_.variable_names()[i] + " (d/dt = " + rate + " per s)";
  }
  return fast.empty();
}

// IDAReInit resets IDA's counters: add them up before every re-initialisation.
void IdaRun::accumulate_stats() {
  long v = 0;
  auto& s = result_.stats;
  IDAGetNumSteps(ida_, &v), s.steps += v;
  IDAGetNumResEvals(ida_, &v), s.residual_evals += v;
  IDAGetNumJacEvals(ida_, &v), s.jacobian_evals += v;
  IDAGetNumNonlinSolvIters(ida_, &v), s.nonlinear_iterations += v;
  IDAGetNumNonlinSolvConvFails(ida_, &v), s.nonlinear_failures += v;
  IDAGetNumLinSolvSetups(ida_, &v), s.linear_setups += v;
  IDAGetNumErrTestFails(ida_, &v), s.error_test_failures += v;
}

// Restart IDA from (t, y, yp) after an event that changed the modes: the
// integrals so far, consistent values, the root functions' sides (`fired`:
// the roots just handled, counted as crossed).
bool IdaRun::restart(const std::vector<int>* fired) {
  if (n_quad_ > 0) check(IDAGetQuadDky(ida_, t_, 0, q_.get()), "IDAGetQuadDky");
  ++result_.stats.reinitialisations;
  accumulate_stats();
  check(IDAReInit(ida_, t_, y_.get(), yp_.get()), "IDAReInit");
  if (n_quad_ > 0) check(IDAQuadReInit(ida_, q_.get()), "IDAQuadReInit");
  if (!consistent_ic() || !settle()) return false;
  restart_roots(fired);
  return true;
}

void IdaRun::restart_roots(const std::vector<int>* fired) {
  if (roots_.size() > 0) roots_at(t_, y_.get(), yp_.get(), roots_.low());
  roots_.start(t_, fired);
}

void IdaRun::roots_at(double tr, N_Vector yy, N_Vector yyp, std::vector<double>& g) {
  eval_.roots(model_t(tr), user_.physical_y(yy), user_.physical_yp(yyp), g.data());
  ++result_.stats.root_evals;
}

// y (and y') at tr in the last step, from IDA's interpolant.
void IdaRun::interpolate(double tr, N_Vector yy, N_Vector yyp, bool with_yp) {
  check(IDAGetDky(ida_, tr, 0, yy), "IDAGetDky");
  if (with_yp) check(IDAGetDky(ida_, tr, 1, yyp), "IDAGetDky");
}

// An output row at t from IDA's current y, y'.
void IdaRun::emit() {
  if (settling_) return;
  if (n_quad_ > 0) {
    double tq = t_;
    if (t_ > opt_.t_start && IDAGetQuad(ida_, &tq, q_.get()) >= 0)
      std::copy_n(N_VGetArrayPointer(q_.get()), n_quad_, quad_->values->begin());
  }
  output_(t_, user_.physical_y(y_.get()), user_.physical_yp(yp_.get()));
}

// An output row at t_out inside the last step, from the state yy, yyp there.
void IdaRun::emit_at(double t_out, N_Vector yy, N_Vector yyp) {
  if (settling_) return;
  if (n_quad_ > 0 && IDAGetQuadDky(ida_, t_out, 0, q_.get()) >= 0)
    std::copy_n(N_VGetArrayPointer(q_.get()), n_quad_, quad_->values->begin());
  output_(t_out, user_.physical_y(yy), user_.physical_yp(yyp));
}

// A checkpoint at the output row at t (its state yy, yyp: IDA's, or read
// off the last step's interpolant, over which the modes hold), with the
// integrals the row was given.
void IdaRun::keep_passing(double t, N_Vector yy, N_Vector yyp) {
  Checkpoint c;
  c.t = t;
  const double* y = user_.physical_y(yy);
  c.y.assign(y, y + n_);
  const double* yp = user_.physical_yp(yyp);
  c.yp.assign(yp, yp + n_);
  c.modes = eval_.modes();
  if (n_quad_ > 0) c.integrals = *quad_->values;
  passed_.push_back(std::move(c));
  while (next_passing_ < passing_.size() && passing_[next_passing_] <= t + eps_t_) ++next_passing_;
}

// Events at t_start, consistent values (a steady start's settling), the
// first output row. False on failure (result().message).
bool IdaRun::start() {
  prepare_run();
  // Events at (or before) t_start set the initial modes.
  while (next_event_ < events_.size() && events_[next_event_] <= opt_.t_start + eps_t_) {
    eval_.handle_time_event(events_[next_event_], user_.physical_y(y_.get()), user_.physical_yp(yp_.get()),
                              result_.events);
    ++next_event_;
  }
  if (!consistent_ic() || !settle()) return false;
  if (opt_.steady_start && !rest_start()) return false;
  emit();
  // The start's row is a checkpoint when one is due; the rows at events
  // are not (their roots sit at zero, counted as crossed by this run alone).
  if (passing_due(t_)) keep_passing(t_, y_.get(), yp_.get());
  restart_roots(nullptr);
  return true;
}

// The rows up to the checkpoint are its run's: this one's start after it.
bool IdaRun::resume(const Checkpoint& from) {
  if (from.y.size() != static_cast<std::size_t>(n_) || from.yp.size() != from.y.size() ||
      from.integrals.size() != static_cast<std::size_t>(n_quad_))
    throw std::invalid_argument("resume: a checkpoint of another system");
  prepare_run();
  t_ = from.t;
  next_event_ = std::upper_bound(events_.begin(), events_.end(), t_ + eps_t_) - events_.begin();
  while (grid_.pending() && grid_.next() <= t_ + eps_t_) ++grid_.k;
  eval_.restore_modes(from.modes);
  for (int i = 0; i < n_; ++i) {
    N_VGetArrayPointer(y_.get())[i] = from.y[i] / user_.nominal[i];
    N_VGetArrayPointer(yp_.get())[i] = from.yp[i] / user_.nominal[i];
  }
  check(IDAReInit(ida_, t_, y_.get(), yp_.get()), "IDAReInit");
  if (n_quad_ > 0) {
    std::copy(from.integrals.begin(), from.integrals.end(), N_VGetArrayPointer(q_.get()));
    *quad_->values = from.integrals;
    check(IDAQuadReInit(ida_, q_.get()), "IDAQuadReInit");
  }
  if (!consistent_ic() || !settle()) return false;
  restart_roots(nullptr);
  return true;
}

Checkpoint IdaRun::checkpoint() {
  Checkpoint c;
  c.t = t_;
  const double* y = user_.physical_y(y_.get());
  c.y.assign(y, y + n_);
  const double* yp = user_.physical_yp(yp_.get());
  c.yp.assign(yp, yp + n_);
  c.modes = eval_.modes();
  if (n_quad_ > 0) {
    check(IDAGetQuadDky(ida_, t_, 0, q_.get()), "IDAGetQuadDky");
    c.integrals.assign(N_VGetArrayPointer(q_.get()), N_VGetArrayPointer(q_.get()) + n_quad_);
  }
  return c;
}

// The time events up to t_end and the vectors a run's rows and events are
// read into.
void IdaRun::prepare_run() {
  start_clock_ = std::chrono::steady_clock::now();
  events_ = system_.time_events();
  // A disturbance's knots are stops too: no step straddles a kink of d(t)
  // (handle_time_event finds nothing due there and the step goes on).
  for (const auto& r : user_.disturbed) events_.insert(events_.end(), r.d->t.begin(), r.d->t.end());
  if (!user_.disturbed.empty()) {
    std::sort(events_.begin(), events_.end());
    events_.erase(std::unique(events_.begin(), events_.end()), events_.end());
  }
  events_.erase(std::remove_if(events_.begin(), events_.end(), [&](double te) { return te > opt_.t_end; }),
                events_.end());
  // Output rows in a step are read off IDA's interpolant: with IDA_NORMAL
  // every output time would also cost a root-function evaluation (IDA
  // checks the roots up to each tout), for outputs every ms about as many as
  // the steps.
  y_out_.reset(N_VClone(y_.get()));
  yp_out_.reset(N_VClone(y_.get()));
  N_VConst(0.0, yp_out_.get());  // stays 0 when the outputs read no y'
  y_ev_.reset(N_VClone(y_.get()));
  yp_ev_.reset(N_VClone(y_.get()));
}

// Integrate on to min(target, t_end); false once the run failed (the
// message set), and for every call after.
bool IdaRun::advance_to(double target) {
  if (!result_.message.empty()) return false;
  target_ = std::min(target, opt_.t_end);
  while (t_ < target_ - eps_t_) {
    throw_if_interrupted();
    if (step() == Next::stop) return false;
  }
  return result_.message.empty();
}

// A program changed the circuit's external inputs (Evaluator::set_external_input)
// at the present time: a discontinuity, handled as after an event -
// consistent values, event iteration, the roots' sides read again.
bool IdaRun::inputs_changed() {
  if (!result_.message.empty()) return false;
  user_.parts.valid = false;
  return restart(nullptr);
}

SolverResult IdaRun::finish_run() {
  finish();
  // The problem's size, also after a failed start (--stats then says what
  // was being solved).
  auto& s = result_.stats;
  s.variables = n_;
  s.netlist_variables = system_.full_size();
  s.explicit_variables = system_.explicit_size();
  s.nonzeros = system_.nnz();
  s.seconds_total = seconds_since(start_clock_);
  return result_;
}

// One step of IDA, its state events, output times and a stop at an event.
IdaRun::Next IdaRun::step() {
  const double t_event = next_event_ < events_.size() ? events_[next_event_] : std::numeric_limits<double>::infinity();
  const double t_stop = std::min(t_event, target_);
  check(IDASetStopTime(ida_, t_stop), "IDASetStopTime");
  double t_ret = t_;
  // tout matters only for the first step after a (re)initialisation (its
  // size), as it did with IDA_NORMAL.
  const int flag = IDASolve(ida_, std::min(grid_.next(), t_stop), &t_ret, y_.get(), yp_.get(), IDA_ONE_STEP);
  if (flag == IDA_CONV_FAIL) {
    if (recover(t_ret)) return Next::restarted;
    if (!result_.message.empty()) return Next::stop;  // the restart failed
  }
  if (flag < 0) {
    t_ = t_ret;
    emit();  // the last state IDA reached, for the partial results
    fail("integration failed at t = " + std::to_string(t_ret) + " s: " + flag_text(flag, user_) + "." +
         step_failure_report(ida_, user_, y_.get(), yp_.get(), t_ret, result_.events));
    return Next::stop;
  }
  const long k_before = grid_.k;
  if (roots_.size() > 0) {
    const Next next = state_events(t_ret);
    // A restart is work like a step: it counts against the budgets below
    // (resetting them let a chattering pair of events run forever).
    if (next == Next::restarted) ++steps_without_output_, ++steps_taken_;
    if (next == Next::restarted && !within_event_budget()) return Next::stop;
    if (next != Next::step) return next;
  }
  // Stopped at a time event or t_end: an output time within eps_t of it is
  // that row (below), emitted after the event is handled.
  const bool stopped = flag == IDA_TSTOP_RETURN;
  while (grid_.pending() && (stopped ? grid_.next() < t_ret - eps_t_ : grid_.next() <= t_ret))
    emit_interpolated(grid_.time(grid_.k++));
  t_ = t_ret;
  // IDA's own limit (IDASetMaxNumSteps) counts the steps of one IDASolve
  // call, i.e. now one step: keep its meaning, at most max_steps steps
  // between one output (or event) and the next.
  steps_without_output_ = (stopped || grid_.k > k_before) ? 0 : steps_without_output_ + 1;
  ++steps_taken_;
  if (steps_without_output_ >= opt_.max_steps)
    return too_much_work(std::to_string(opt_.max_steps) + " steps without reaching the next output time");
  if (opt_.max_total_steps > 0 && steps_taken_ >= opt_.max_total_steps)
    return too_much_work(std::to_string(opt_.max_total_steps) + " steps in all");
  if (!within_event_budget()) return Next::stop;
  return stopped ? stopped_at(t_event) : Next::step;
}

// A step budget ran out: the last state reached, for the partial results.
IdaRun::Next IdaRun::too_much_work(const std::string& budget) {
  emit();
  fail("integration failed at t = " + std::to_string(t_) + " s: IDA_TOO_MUCH_WORK (" + budget + ")");
  return Next::stop;
}

// IDA's corrector failed at every step size. The algebraic unknowns (nodes
// without volume, out of the error test) are held on their equations by
// the Newton test (AlgebraicNewtonTest); should they still have drifted off
// them, the states are accurate: restart from the start of the last step
// with consistent values, at most 3 times between two output times.
bool IdaRun::recover(double t_ret) {
  if (recoveries_ - recoveries_at_budget_ >= 3) return false;
  ++recoveries_;
  const std::string failure = flag_text(IDA_CONV_FAIL, user_) + "." + junction_failure_hint(ida_, system_, y_.get());
  double h = 0.0;
  IDAGetLastStep(ida_, &h);
  const double t_back = t_ret - h;
  if (h > 0.0 && t_back > opt_.t_start && IDAGetDky(ida_, t_back, 0, y_.get()) == IDA_SUCCESS &&
      IDAGetDky(ida_, t_back, 1, yp_.get()) == IDA_SUCCESS)
    t_ = t_back;
  else
    t_ = t_ret;
  if (restart(nullptr)) return true;
  result_.message = "integration failed at t = " + std::to_string(t_ret) + " s: " + failure +
                    " A restart from consistent values at t = " + std::to_string(t_) +
                    " s failed too: " + result_.message;
  return false;
}

// Events are bounded per output interval: a pair of events that undo each
// other (a contact and its release, a valve that closes what opens it)
// fires ever faster at one state, every one a restart that lets IDA take a
// fresh step, and the event log grows without end. More events or restarts
// than a run plausibly has between two output rows end the run, naming the
// events that repeat.
bool IdaRun::within_event_budget() {
  constexpr long kMaxRestarts = 1000;
  constexpr std::size_t kMaxEvents = 10000;
  if (grid_.k != grid_k_at_budget_) {
    grid_k_at_budget_ = grid_.k;
    events_at_budget_ = result_.events.size();
    restarts_at_budget_ = result_.stats.reinitialisations;
    recoveries_at_budget_ = recoveries_;
    t_at_budget_ = t_;
    return true;
  }
  if (result_.stats.reinitialisations - restarts_at_budget_ <= kMaxRestarts &&
      result_.events.size() - events_at_budget_ <= kMaxEvents)
    return true;
  emit();  // the last state reached, for the partial results
  fail(chatter_message());
  return false;
}

// The events since the last output time, most frequent first: the
// chattering pair and where.
std::string IdaRun::chatter_message() const {
  std::vector<std::pair<std::string, long>> counts;
  for (std::size_t i = events_at_budget_; i < result_.events.size(); ++i) {
    const auto& e = result_.events[i];
    const std::string key = e.component + " '" + (e.tag.empty() ? e.message : e.tag) + "'";
    auto it = std::find_if(counts.begin(), counts.end(), [&](const auto& c) { return c.first == key; });
    if (it == counts.end()) counts.emplace_back(key, 1);
    else ++it->second;
  }
  std::stable_sort(counts.begin(), counts.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string which;
  for (std::size_t i = 0; i < std::min<std::size_t>(2, counts.size()); ++i)
    which += (i ? " and " : "") + counts[i].first + " (" + std::to_string(counts[i].second) + " times)";
  const long restarts = result_.stats.reinitialisations - restarts_at_budget_;
  auto time = [](double t) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", t);
    return std::string(buf);
  };
  return "events chatter at t = " + time(t_) + " s: " + std::to_string(result_.events.size() - events_at_budget_) +
         " events and " + std::to_string(restarts) + " re-initialisations since t = " + time(t_at_budget_) +
         " s without reaching the next output time; repeating: " + (which.empty() ? "(none logged)" : which) +
         ". The circuit switches back and forth at one state: a contact, valve or switch that undoes its own "
         "event (give it hysteresis, damping or a different setting)";
}

// The state events in the step that ended at t_ret, in time order.
IdaRun::Next IdaRun::state_events(double t_ret) {
  roots_at(t_ret, y_.get(), yp_.get(), roots_.high());
  double h_last = 0.0;
  IDAGetLastStep(ida_, &h_last);
  auto g_at = [&](double c, std::vector<double>& g) {
    interpolate(c, y_ev_.get(), yp_ev_.get(), true);
    roots_at(c, y_ev_.get(), yp_ev_.get(), g);
  };
  double t_root = t_ret;
  while (roots_.locate(t_ret, h_last, g_at, t_root)) {
    while (!settling_ && grid_.pending() && grid_.next() < t_root - eps_t_) emit_interpolated(grid_.time(grid_.k++));
    interpolate(t_root, y_ev_.get(), yp_ev_.get(), true);
    const std::vector<int> fired = roots_.root_info();
    user_.parts.valid = false;  // the modes may have changed
    const bool reinit = eval_.handle_roots(model_t(t_root), user_.physical_y(y_ev_.get()), user_.physical_yp(yp_ev_.get()),
                                             fired.data(), result_.events);
    if (!settling_ && grid_.pending() && std::abs(t_root - grid_.next()) <= eps_t_) ++grid_.k;
    if (reinit) {
      // Restart from the event; IDA's step beyond it is discarded.
      N_VScale(1.0, y_ev_.get(), y_.get());
      N_VScale(1.0, yp_ev_.get(), yp_.get());
      t_ = t_root;
      if (!restart(&fired)) return Next::stop;
      emit();
      return Next::restarted;
    }
    emit_at(t_root, y_ev_.get(), yp_ev_.get());
    // Go on searching (t_root, t_n].
    roots_at(t_root, y_ev_.get(), yp_ev_.get(), roots_.low());
    roots_.passed(t_root, fired);
  }
  roots_.step_done(t_ret);
  return Next::step;
}

// IDA stopped at a time event or at t_end.
IdaRun::Next IdaRun::stopped_at(double t_event) {
  bool reinit = false;
  if (next_event_ < events_.size() && std::abs(t_ - t_event) <= eps_t_) {
    user_.parts.valid = false;
    reinit = eval_.handle_time_event(t_, user_.physical_y(y_.get()), user_.physical_yp(yp_.get()), result_.events);
    ++next_event_;
  }
  if (reinit && !restart(nullptr)) return Next::stop;
  const bool at_output = grid_.pending() && std::abs(t_ - grid_.next()) <= eps_t_;
  if (at_output) ++grid_.k;
  if (at_output || reinit) emit();
  return Next::step;
}

void IdaRun::finish() {
  if (user_.error) std::rethrow_exception(user_.error);
  if (result_.message.empty()) {
    result_.ok = true;
    result_.t_reached = t_;
    result_.warnings = eval_.end_notes(t_, user_.physical_y(y_.get()), user_.physical_yp(yp_.get()));
  }
  accumulate_stats();
  auto& s = result_.stats;
  // IDA counts its requests; those answered by recombining were no evaluation.
  s.jacobian_recombinations = user_.parts.recombined;
  s.recombined_retries = user_.parts.retried;
  s.jacobian_evals -= user_.parts.recombined;
  s.pattern_misses = eval_.pattern_misses();
  s.part_steps_max = s.steps;
  s.lu = lu_;
  s.seconds_residual = user_.seconds_residual;
  s.seconds_jacobian = user_.seconds_jacobian;
}


double DisturbanceFactor::operator()(double y, double yp, double y_other) const {
  switch (of) {
    case Of::value: return y - centre;
    case Of::rate: return yp;
    case Of::magnitude: return std::abs(y);
    case Of::sign: return std::tanh(y / width);
    case Of::bump: return std::exp(-0.5 * (y - centre) * (y - centre) / (width * width));
    case Of::difference: return y - y_other;
  }
  return 0.0;
}

namespace {
// Through (t[k], v[k]), linear between, constant outside.
double piecewise_linear(const std::vector<double>& t, const std::vector<double>& v, double time) {
  if (time <= t.front()) return v.front();
  if (time >= t.back()) return v.back();
  const std::size_t k = std::upper_bound(t.begin(), t.end(), time) - t.begin();
  const double w = (time - t[k - 1]) / (t[k] - t[k - 1]);
  return v[k - 1] + w * (v[k] - v[k - 1]);
}
}  // namespace

double Disturbance::at(double time) const { return piecewise_linear(t, rate, time); }

double Disturbance::time_shaped(double time) const {
  return at(time) * (per_held && !held.empty() ? piecewise_linear(held_t, held, time) : 1.0);
}

double Disturbance::withdrawal_share(double time, double y) const {
  if (held.empty()) return 1.0;
  const double h = piecewise_linear(held_t, held, time);
  return h > 0 ? std::clamp(y / h, 0.0, 1.0) : 1.0;
}

Integration::Integration(Evaluator& eval, const SolverOptions& options, OutputFn output, const Quadratures* quad)
    : run_(std::make_unique<IdaRun>(eval, options, std::move(output), quad)) {}
Integration::~Integration() = default;
bool Integration::start() { return run_->start(); }
bool Integration::resume(const Checkpoint& from) { return run_->resume(from); }
Checkpoint Integration::checkpoint() { return run_->checkpoint(); }
void Integration::keep_in_passing(std::vector<double> times) { run_->keep_in_passing(std::move(times)); }
std::vector<Checkpoint> Integration::passed() { return run_->passed(); }
bool Integration::advance_to(double t) { return run_->advance_to(t); }
bool Integration::inputs_changed() { return run_->inputs_changed(); }
double Integration::time() const { return run_->time(); }
const double* Integration::y() { return run_->y(); }
const double* Integration::yp() { return run_->yp(); }
const SolverResult& Integration::result() const { return run_->result(); }
SolverResult Integration::finish() { return run_->finish_run(); }

SolverResult simulate(Evaluator& eval, const SolverOptions& opt, const OutputFn& output, const Quadratures* quad) {
  Integration integration(eval, opt, output, quad);
  if (integration.start()) integration.advance_to(opt.t_end);
  return integration.finish();
}

}  // namespace pneumo
