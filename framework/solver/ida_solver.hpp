// Time integration of an assembled System with SUNDIALS IDA and the sparse
// KLU direct solver, using the AD Jacobian dF/dy + cj dF/dy'.
//
// Events: time events (the solver stops exactly there) and state events
// (IDA root-finding). When an event changes a discrete mode the integrator
// is re-initialised and consistent initial values recomputed (IDACalcIC),
// so no step ever straddles a discontinuity.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "framework/assembly/evaluator.hpp"
#include "framework/model/simulation_options.hpp"
#include "framework/solver/timed_linear_solver.hpp"

namespace pneumo {

// A known additive source on one state's balance: the residual is evaluated
// as F(t, y, y' - d), so the state follows y_i' = f_i(t, y) + d - a mass,
// energy, momentum, ... that the equations do not have. d is piecewise
// linear in time through (t[k], rate[k]), constant outside, plus `terms`
// that read the state (a form the diagnosis proposes: a spring, a bump of
// friction, a mass), in the SI unit of the state per second. Gas is never
// mass alone: a disturbance of a gas mass whose component declares its
// internal energy (VariableSpec::internal_energy) moves that energy by the
// gas's enthalpy, d kappa U / m - a leak takes the chamber's gas as it is.
// The terms' slopes in the values and rates they read are in IDA's Newton
// matrix (disturbed_matrix.hpp; a quantity's unknowns found by moving each
// in turn). Set by programs (the diagnosis), not by netlists.
struct DisturbanceFactor {
  enum class Of { value, rate, magnitude, sign, bump, difference };
  Of of = Of::value;
  std::string variable;          // a System unknown, else COMPONENT.QUANTITY as outputs name it (rate: an unknown)
  std::string other;             // difference: value of variable - value of other
  double centre = 0, width = 1;  // value: y - centre; sign: tanh(y / width); bump: exp(-((y - centre) / width)^2 / 2)
  double operator()(double y, double yp, double y_other) const;
};
struct DisturbanceTerm {
  double coefficient = 0;
  std::vector<DisturbanceFactor> factors;  // none: a constant
};
struct Disturbance {
  std::string variable;  // System::variable_names(), a differential variable
  std::vector<double> t, rate;
  std::vector<DisturbanceTerm> terms = {};
  // What the state held along the run the rate was fitted on (times and
  // values; empty: nothing). A balance cannot give more than it holds: with
  // it, a withdrawal (d < 0) is scaled by min(1, y / held(t)), so a mass or
  // an energy taken out at the rate one trajectory allowed stays positive
  // on another (a chamber that reaches its dead volume earlier).
  std::vector<double> held_t = {}, held = {};
  // The knots' rates are per unit of what the state held (1/s): the
  // time-shaped part is rate(t) x held(t), a shape that follows the content
  // - a chamber at its dead volume holds a few hundredths of its full charge,
  // and a rate one knot gives the full chamber would heat that gas by
  // thousands of kelvin.
  bool per_held = false;
  double at(double time) const;           // the knots' rate at `time`
  double time_shaped(double time) const;  // at(time), times held(time) when per_held
  double withdrawal_share(double time, double y) const;
};

// The netlist's settings (simulation_options.hpp: units, defaults, ranges)
// and what only programs set.
struct SolverOptions : SimulationSettings {
  long max_steps = 1000000;
  // Steps of the whole integration (restarts count as steps); 0: no limit.
  // A caller that knows what the run costs unperturbed bounds a perturbed
  // one that crawls at a fine step size all the way, reaching every output.
  long max_total_steps = 0;
  // Whether the outputs read y' (run_system sets it from its ProbeSet):
  // without, the output rows skip interpolating y'.
  bool outputs_read_yp = true;
  // Threads for the independent parts of a circuit (run_circuit): 0 = the
  // hardware's, 1 = one part after another.
  int threads = 0;
  // Additive sources on states' balances; a name the System does not have,
  // or an algebraic variable, throws std::invalid_argument at simulate().
  std::vector<Disturbance> disturbances;
  // Time the residual, Newton matrix and LU calls (SolverStats::
  // seconds_residual, seconds_jacobian, lu.setup_seconds, lu.solve_seconds;
  // 0 without): two clock readings a call, about 5 % of a small circuit's
  // run, so only benchmarks that take the time apart ask for it.
  bool time_phases = false;
};

struct SolverStats {
  long steps = 0;
  long residual_evals = 0;
  long jacobian_evals = 0;           // fresh evaluations (of both parts when reused)
  long jacobian_recombinations = 0;  // IDA's requests answered from the last evaluation's parts
  long recombined_retries = 0;       // Newton iterations that failed on a recombined matrix, retried on a fresh one at the same step
  long nonlinear_iterations = 0;
  long nonlinear_failures = 0;
  long linear_setups = 0;  // Newton matrices IDA asked for (evaluated or recombined), each factorised
  LinearSolverCounts lu;   // the sparse LU's work and time (timed_linear_solver.hpp)
  long error_test_failures = 0;
  long root_evals = 0;
  long reinitialisations = 0;
  long pattern_misses = 0;
  int variables = 0;           // unknowns IDA integrates
  int netlist_variables = 0;   // unknowns of the netlist's equations
  int explicit_variables = 0;  // of those, solved inside the residual
  long nonzeros = 0;
  // A circuit integrated as independent parts (run_circuit): how many, and
  // the steps of the part that took most (steps is their sum).
  int parts = 1;
  long part_steps_max = 0;
  // Where the time went (steady clock, seconds): residuals (explicit
  // unknowns included), Newton matrices (AD, recombination), and the whole
  // integration (the rest, besides those and the LU: IDA's own work, roots,
  // outputs, events).
  double seconds_residual = 0, seconds_jacobian = 0, seconds_total = 0;
};

struct SolverResult {
  bool ok = false;
  std::string message;  // why it stopped, when !ok
  double t_reached = 0.0;
  SolverStats stats;
  std::vector<EventLogEntry> events;
  // What components say of the state a successful run ended in
  // (Component::at_end): "seq: ended in step 2 ..., waiting for B1".
  std::vector<std::string> warnings;
};

// A run's state at one instant (Integration::checkpoint): the time, the
// physical y and y', the System's modes and the integrals so far. Another
// run of the same System - with other disturbances - resumes from it
// (Integration::resume) as after an event: consistent values recomputed
// there, nothing before it integrated again.
struct Checkpoint {
  double t = 0.0;
  std::vector<double> y, yp, modes, integrals;
};

// Called at t_start, at every output time, and after every event.
using OutputFn = std::function<void(double t, const double* y, const double* yp)>;

// Outputs integrated over time by the solver (IDAS quadratures): the
// integral from t_start of each integrand, updated in *values before each
// OutputFn call.
struct Quadratures {
  std::vector<Probe> integrands;
  std::vector<double> atol;  // absolute tolerance of each integral, in its unit
  std::vector<double>* values = nullptr;
};

// Integrate from the system's start values. Never throws on solver failure:
// the result says what happened and where (t_reached); throws only for
// programming errors in components (exceptions from residuals).
SolverResult simulate(Evaluator& eval, const SolverOptions& options, const OutputFn& output,
                      const Quadratures* quadratures = nullptr);

}  // namespace pneumo
