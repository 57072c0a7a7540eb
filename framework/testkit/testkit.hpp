// Checks for component authors (library pneumo::testkit). Each returns a
// report; call them from your own tests, e.g. with GoogleTest:
//
//   const Registry reg = testkit::with_builtin(register_my_component);
//   for (const auto& c : testkit::check_jacobian(kSnippet, reg))
//     EXPECT_TRUE(c.passed()) << c.report();
//   for (const auto& c : testkit::check_conservation(kClosedCircuit, reg,
//                                                    {testkit::mass_of({"a", "b"}),
//                                                     testkit::energy_of({"a", "b"})}))
//     EXPECT_TRUE(c.passed(1e-12)) << c.report();
//
// tests/jacobian_test.cpp runs check_jacobian over every built-in type.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "framework/assembly/evaluator.hpp"
#include "framework/model/registry.hpp"
#include "framework/solver/ida_solver.hpp"

namespace pneumo::testkit {

// The built-in component types plus those `add` registers (a component's
// register function, called directly: tests need no plugin file).
Registry with_builtin(const std::function<void(Registry&)>& add);

// ---------------------------------------------------------------------------
// The AD Jacobian against central finite differences of the residual.
//
// Entries are compared scaled by their variable's magnitude,
// S_ij = J_ij max(|y_j|, nominal_j) (the change of F_i for a relative change
// of y_j), so that rows mixing Pa, kg and K compare like with like. A
// central difference with relative step 1e-6 has truncation error ~1e-12 and
// rounding error ~1e-10 of the row's largest scaled entry; the error of an
// entry is |S_ad - S_fd| / max(|S_ad|, 1e-3 max_j |S_ij|). Where the
// residual has a kink inside the stencil (choked/subsonic switch, end stop
// contact) forward and backward differences disagree; such entries are
// skipped and counted, and must stay rare. Also checked: Evaluator::jacobian(cj)
// (the matrix IDA factorises) equals dF/dy + cj dF/dy' on the structural
// pattern and has nothing outside it, and every variable whose derivative
// appears is flagged differential.
struct JacobianCheck {
  double t = 0.0;
  int variables = 0;
  double worst = 0.0;       // worst scaled relative error, AD against FD
  std::string worst_where;  // "dF/dy row 3, tank.m: AD ..., FD ..."
  int compared = 0;         // entries compared
  int kinks = 0;            // entries skipped at kinks
  long pattern_misses = 0;  // AD entries outside the structural pattern (the evaluator's count so far)
  std::vector<std::string> problems;  // assembled matrix and pattern findings

  // worst < tolerance, more entries compared than variables, kinks at most
  // max(2, compared/50), no pattern misses and no problems.
  bool passed(double tolerance = 1e-5) const;
  std::string report() const;
};

// At one point; the evaluator's discrete modes must be those of the point.
JacobianCheck check_jacobian_at(const Evaluator& eval, double t, const std::vector<double>& y,
                                const std::vector<double>& yp);

// Integrates `t_short` from the consistent initial point with `options`'
// tolerances and checks at the initial point and at t_short (flows, heat
// and motion under way). Throws std::runtime_error if the integration fails.
std::vector<JacobianCheck> check_jacobian(const System& system, const SolverOptions& options, double t_short);
// The same for a netlist given as YAML text (its simulation tolerances).
std::vector<JacobianCheck> check_jacobian(const std::string& netlist_yaml, const Registry& registry,
                                          double t_short = 0.05, const std::string& name = "snippet.yaml");

// ---------------------------------------------------------------------------
// Conservation over a closed circuit (no sources or sinks, no heat or work
// across the boundary): a stored quantity, the sum of factor * variable
// over its terms, must keep its initial value at every output time.
struct Term {
  std::string ref;      // "component.variable", as in a netlist's outputs
  double factor = 1.0;  // e.g. a heat capacity C for a thermal mass's T
};
struct Balance {
  std::string name;  // "mass", "energy"
  std::vector<Term> terms;
};
// Mass and internal energy of gas volumes: their `m` and `U`.
Balance mass_of(const std::vector<std::string>& volumes);
Balance energy_of(const std::vector<std::string>& volumes);

struct ConservationCheck {
  std::string name;
  bool solver_ok = false;
  std::string solver_message;
  int rows = 0;
  double initial = 0.0;      // sum at t_start
  double final_value = 0.0;  // sum at t_end
  double worst = 0.0;        // max over rows of |sum - initial| / |initial|
  double worst_t = 0.0;

  bool passed(double tolerance) const;
  std::string report() const;
};

// Runs the netlist (its own simulation settings) and checks each balance.
std::vector<ConservationCheck> check_conservation(const std::string& netlist_yaml, const Registry& registry,
                                                  const std::vector<Balance>& balances,
                                                  const std::string& name = "closed_circuit.yaml");

}  // namespace pneumo::testkit
