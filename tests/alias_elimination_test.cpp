// Alias elimination (AssemblyOptions::eliminate_aliases, the default): the cushion
// rig keeps its physics (same trajectory as the unreduced system to within
// the solver tolerance) with about half the unknowns, and the reduced
// system's AD Jacobian still equals finite differences of its residual.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "framework/testkit/testkit.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

const std::string kRig = std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml";

TEST(AliasElimination, RigKeepsItsTrajectoryWithFewerUnknowns) {
  const Netlist nl = load_netlist(kRig);
  AssemblyOptions keep;
  keep.eliminate_aliases = false;
  System full(elaborate(nl, builtin_registry()), keep);
  AssemblyOptions opt;
  opt.eliminate_aliases = true;
  System reduced(elaborate(nl, builtin_registry()), opt);
  EXPECT_EQ(reduced.full_size(), full.size());
  EXPECT_LT(reduced.size(), full.size() * 2 / 3) << reduced.size() << " of " << full.size();
  // With explicit elimination (the default) IDA integrates exactly the
  // rig's states: x, v and (m, U) of the chambers A, EC, ch and line B; the
  // other 41 unknowns are solved inside the residual.
  EXPECT_EQ(reduced.size(), 10);
  EXPECT_EQ(reduced.size() + reduced.explicit_size(), 22);
  for (double d : reduced.differential()) EXPECT_EQ(d, 1.0);
  std::cout << "unknowns: " << full.size() << " -> " << reduced.size() << "\n";

  const RunResult a = run_system(full, solver_options(nl.simulation));
  const RunResult b = run_system(reduced, solver_options(nl.simulation));
  ASSERT_TRUE(a.solver.ok) << a.solver.message;
  ASSERT_TRUE(b.solver.ok) << b.solver.message;
  // Same events, at the same times to within 0.5 ms.
  ASSERT_EQ(a.solver.events.size(), b.solver.events.size());
  for (std::size_t k = 0; k < a.solver.events.size(); ++k) {
    EXPECT_EQ(a.solver.events[k].message.substr(0, 20), b.solver.events[k].message.substr(0, 20));
    EXPECT_NEAR(a.solver.events[k].t, b.solver.events[k].t, 5e-4) << a.solver.events[k].message;
  }
  // x on the common 1 ms grid within 0.1 mm (0.1 % of the stroke), p_EC within 0.5 % of its peak.
  const int cx = a.table.column("x"), cp = a.table.column("p_EC");
  double dx = 0, dp = 0, p_peak = 0;
  std::size_t j = 0;
  for (const auto& row : a.table.rows) {
    while (j < b.table.rows.size() && b.table.rows[j][0] < row[0]) ++j;
    if (j >= b.table.rows.size() || b.table.rows[j][0] != row[0]) continue;
    dx = std::max(dx, std::abs(row[cx] - b.table.rows[j][cx]));
    dp = std::max(dp, std::abs(row[cp] - b.table.rows[j][cp]));
    p_peak = std::max(p_peak, row[cp]);
  }
  std::cout << "max |dx| " << dx << " m, max |dp_EC| " << dp << " Pa\n";
  EXPECT_LT(dx, 1e-4);
  EXPECT_LT(dp, 5e-3 * p_peak);
}

TEST(AliasElimination, ReducedJacobianMatchesFiniteDifferences) {
  const Netlist nl = load_netlist(kRig);
  AssemblyOptions opt;
  opt.eliminate_aliases = true;
  System sys(elaborate(nl, builtin_registry()), opt);
  Evaluator eval(sys);
  const int n = sys.size();
  std::vector<double> y, yp;
  sys.start_values(y, yp);
  for (int i = 0; i < n; ++i) yp[i] = 0.01 * sys.nominal()[i];
  std::vector<double> dFdy, dFdyp;
  eval.jacobian_parts(0.0, y.data(), yp.data(), dFdy, dFdyp);
  // Central differences; an entry whose forward and backward differences
  // disagree has a kink inside the stencil (stops, regularised |x| at zero
  // flow) and is skipped, as in jacobian_test. Entries are compared scaled by
  // the variable's magnitude, relative to the largest entry of their row.
  std::vector<double> F0(n), Fp(n), Fm(n);
  ASSERT_EQ(eval.residual(0.0, y.data(), yp.data(), F0.data()), 0);
  std::vector<double> fd(static_cast<std::size_t>(n) * n), kink(fd.size()), scale(n);
  for (int j = 0; j < n; ++j) {
    scale[j] = std::max(std::abs(y[j]), sys.nominal()[j]);
    const double h = 1e-6 * scale[j];
    auto yy = y;
    yy[j] = y[j] + h;
    ASSERT_EQ(eval.residual(0.0, yy.data(), yp.data(), Fp.data()), 0);
    yy[j] = y[j] - h;
    ASSERT_EQ(eval.residual(0.0, yy.data(), yp.data(), Fm.data()), 0);
    for (int i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i) * n + j;
      fd[k] = (Fp[i] - Fm[i]) / (2 * h);
      kink[k] = std::abs((Fp[i] - F0[i]) - (F0[i] - Fm[i])) / h;
    }
  }
  int compared = 0;
  double worst = 0;
  for (int i = 0; i < n; ++i) {
    double row = 0;
    for (int j = 0; j < n; ++j) row = std::max(row, std::abs(dFdy[static_cast<std::size_t>(i) * n + j]) * scale[j]);
    if (row == 0) continue;
    for (int j = 0; j < n; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * n + j;
      const double ad = dFdy[k] * scale[j], f = fd[k] * scale[j];
      if (ad == 0 && f == 0) continue;
      const double denom = std::max(std::abs(ad), 1e-3 * row);
      if (kink[k] * scale[j] > 1e-4 * denom) continue;
      ++compared;
      worst = std::max(worst, std::abs(ad - f) / denom);
    }
  }
  EXPECT_GT(compared, n);
  EXPECT_LT(worst, 1e-5);
  // The assembled dF/dy + cj dF/dy' agrees with the parts.
  std::vector<double> values(sys.nnz());
  const double cj = 1e3;
  eval.jacobian(0.0, y.data(), yp.data(), cj, values.data());
  EXPECT_EQ(eval.pattern_misses(), 0);
  for (int c = 0; c < n; ++c)
    for (long p = sys.col_ptr()[c]; p < sys.col_ptr()[c + 1]; ++p) {
      const std::size_t k = static_cast<std::size_t>(sys.row_idx()[p]) * n + c;
      EXPECT_NEAR(values[p], dFdy[k] + cj * dFdyp[k], 1e-9 * (std::abs(values[p]) + 1));
    }
}

// A signal that is a function of time without modes or time events (y = rate t).
class Clock final : public ComponentT<Clock> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "alias_test_clock";
    i.description = "y = rate t (alias elimination test)";
    i.parameters = {ParameterSpec::scalar("rate", "1/s", "slope")};
    i.ports = {{"y", Domain::signal, Causality::output, "rate t"}};
    return i;
  }
  explicit Clock(const Construction& c) : ComponentT(c), rate_(c.params["rate"]) {}
  template <class T>
  void equations(const Eval<T>& e, T* r) const { r[0] = e.signal(0) - rate_ * e.t(); }

 private:
  double rate_;
};

// A row that sets a variable to a function of time alone looks like a
// constant at any one time; it must stay an unknown (checked at three
// times), while a source's fixed pressure and temperature are folded.
TEST(AliasElimination, FunctionOfTimeIsNoConstant) {
  const Registry reg = testkit::with_builtin([](Registry& r) { r.add<Clock>(); });
  const Netlist nl = parse_netlist(R"(
components:
  source: {type: pressure_source, p: 6 bar, T: 300 K}
  clock:  {type: alias_test_clock, rate: 2}
  valve:  {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 1 L, p0: 1 bar, T0: 300 K}
connections:
  - [source.port, valve.a]
  - [clock.y, valve.opening]
  - [valve.b, tank.port]
outputs: {y: clock.y, p: tank.p, m: tank.m}
simulation: {t_end: 0.4 s, output_interval: 10 ms}
)",
                                   "clock.yaml");
  // Alias elimination alone keeps the clock's signal as an unknown...
  AssemblyOptions aliases_only;
  aliases_only.eliminate_explicit = false;
  System by_alias(elaborate(nl, reg), aliases_only);
  const auto& names = by_alias.variable_names();
  auto has = [&](const std::string& prefix) {
    return std::any_of(names.begin(), names.end(), [&](const std::string& n) { return n.rfind(prefix, 0) == 0; });
  };
  EXPECT_TRUE(has("value at {clock.y")) << "the clock's signal was folded into a constant";
  EXPECT_FALSE(has("p at {source.port")) << "the source's fixed pressure is still an unknown";
  // ...and explicit elimination (the default) computes it from t in every
  // residual call: the run below checks y = 2 t either way.
  System sys(elaborate(nl, reg));
  EXPECT_LT(sys.size(), by_alias.size());
  const RunResult r = run_system(sys, solver_options(nl.simulation));
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const int cy = r.table.column("y"), cp = r.table.column("p"), cm = r.table.column("m");
  for (const auto& row : r.table.rows) EXPECT_NEAR(row[cy], 2.0 * row[0], 1e-9) << "t = " << row[0];
  // The valve stays choked (tank below 0.3 x 6 bar), so the inflow is
  // proportional to the opening 2 t and the mass gained grows as t^2: from
  // 0.2 s to 0.4 s four times (a constant opening would give twice).
  ASSERT_LT(r.table.rows.back()[cp], 0.3 * 6e5);
  double m0 = r.table.rows.front()[cm], m_02 = 0, m_04 = 0;
  for (const auto& row : r.table.rows) {
    if (std::abs(row[0] - 0.2) < 1e-9) m_02 = row[cm];
    if (std::abs(row[0] - 0.4) < 1e-9) m_04 = row[cm];
  }
  EXPECT_NEAR((m_04 - m0) / (m_02 - m0), 4.0, 1e-3);
}

// A signal whose equation changes its coefficient at a time event (y = 1,
// then 2 y = 1): solved explicitly at assembly, it no longer may be after
// the event, and the run stops with an error naming the equation instead of
// going on with a wrong value.
class SwitchingGain final : public ComponentT<SwitchingGain> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "alias_test_switching_gain";
    i.description = "y = 1, from t = 5 ms on 2 y = 1 (explicit elimination test)";
    i.ports = {{"y", Domain::signal, Causality::output, "1, then 0.5"}};
    i.equations = {"switching gain"};
    i.modes = 1;
    return i;
  }
  explicit SwitchingGain(const Construction& c) : ComponentT(c) {}
  template <class T>
  void equations(const Eval<T>& e, T* r) const { r[0] = (1.0 + e.mode(0)) * e.signal(0) - 1.0; }
  std::vector<double> time_events() const override { return {0.005}; }
  EventResult on_event(const Eval<double>&, double* modes, EventKind, int, int) const override {
    modes[0] = 1.0;
    return {true, "gain doubled"};
  }
};

TEST(ExplicitElimination, ARowThatChangesAtAnEventIsAnError) {
  const Registry reg = testkit::with_builtin([](Registry& r) { r.add<SwitchingGain>(); });
  const Netlist nl = parse_netlist(R"(
components:
  source: {type: pressure_source, p: 6 bar, T: 300 K}
  gain:   {type: alias_test_switching_gain}
  valve:  {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 1 L, p0: 1 bar, T0: 300 K}
connections:
  - [source.port, valve.a]
  - [gain.y, valve.opening]
  - [valve.b, tank.port]
outputs: {m: tank.m}
simulation: {t_end: 0.01 s, output_interval: 1 ms}
)",
                                   "gain.yaml");
  System sys(elaborate(nl, reg));
  try {
    (void)run_system(sys, solver_options(nl.simulation));
    FAIL() << "the changed equation went unnoticed";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("switching gain"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no longer gives it linearly"), std::string::npos) << e.what();
  }
  // Without explicit elimination the signal is an unknown of IDA and the
  // run goes through: the opening halves at 5 ms.
  AssemblyOptions keep;
  keep.eliminate_explicit = false;
  System plain(elaborate(nl, reg), keep);
  const RunResult r = run_system(plain, solver_options(nl.simulation));
  EXPECT_TRUE(r.solver.ok) << r.solver.message;
}

// IDA's root checks solve only the explicit unknowns the root functions
// read, with those they depend on: a throttle's opening root reads a step
// signal's output; another's reads a gauge's reading, itself solved from
// the tank's pressure (p = (kappa - 1) U / V). Evaluated first (partly
// expanded) and again after a residual at the same point (whole expansion
// cached), the roots agree to the bit at the start and at states moved by
// up to 30 %; at the start they are their closed forms.
TEST(ExplicitElimination, RootChecksSolveWhatTheRootsRead) {
  const Netlist nl = parse_netlist(R"(
components:
  supply: {type: pressure_source, p: 4 bar}
  cmd:    {type: signal_source, kind: step, value: 0.5, height: 0.5, t_start: 0.1 s}
  fill:   {type: iso6358_throttle, C: 0.5 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 0.5 L, p0: 1 bar}
  gauge:  {type: pressure_sensor, fault_gain: 4e-6}
  bleed:  {type: iso6358_throttle, C: 0.05 dm3/(s*bar), b: 0.3}
  vent:   {type: atmosphere}
connections:
  - [supply.port, fill.a]
  - [cmd.y, fill.opening]
  - [fill.b, tank.port, gauge.port, bleed.a]
  - [gauge.p, bleed.opening]
  - [bleed.b, vent.port]
outputs: {p: tank.p}
)",
                                   "roots.yaml");
  // Roots in component order: the supply's watch of its (unconnected)
  // pressure input, 1; the throttle's opening + 1e-6, the command 0.5 before
  // its step; the bleed's opening + 1e-6, the reading 4e-6 p of 1 bar.
  const std::vector<double> at_start = {1.0, 0.5 + 1e-6, 0.4 + 1e-6};
  const std::vector<Netlist> nets = {nl, load_netlist(kRig)};
  for (std::size_t n = 0; n < nets.size(); ++n) {
    System sys(elaborate(nets[n], builtin_registry()));
    const Evaluator eval(sys);
    ASSERT_GT(sys.explicit_size(), 0);
    std::vector<double> y0, yp0;
    sys.start_values(y0, yp0);
    std::vector<double> partly(sys.n_roots()), whole(sys.n_roots()), F(sys.size());
    for (int pass = 0; pass < 4; ++pass) {
      std::vector<double> y = y0;
      for (std::size_t i = 0; i < y.size(); ++i) y[i] *= 1.0 + 0.1 * pass * std::sin(1.0 + static_cast<double>(i));
      const double t = 0.05 * pass;
      eval.roots(t, y.data(), yp0.data(), partly.data());
      (void)eval.residual(t, y.data(), yp0.data(), F.data());
      eval.roots(t, y.data(), yp0.data(), whole.data());
      for (int k = 0; k < sys.n_roots(); ++k) EXPECT_EQ(partly[k], whole[k]) << nets[n].file << " root " << k;
      if (n == 0 && pass == 0) {
        ASSERT_EQ(partly.size(), at_start.size());
        for (std::size_t k = 0; k < at_start.size(); ++k) EXPECT_NEAR(partly[k], at_start[k], 1e-9) << k;
      }
    }
  }
}

// A tube at a valve's port beside a flow control is a three-port node: its
// stream temperatures are mixing rows that no equation gives explicitly
// (IDA keeps them), and once they are IDA's every flow there follows from
// a throttle's row or the node's balance. So IDA's algebraic unknowns are
// exactly the mixing rows' - a flow kept as an IDA unknown (a tear the
// mixing temperatures made unnecessary) would make IDA iterate on it - and
// the two cylinders move as without any reduction.
TEST(ExplicitElimination, JunctionFlowsAreSolvedOnceTheMixingTemperaturesAreTorn) {
  const Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/sequence_ab.yaml");
  System sys(elaborate(nl, builtin_registry()));
  const long algebraic = std::count(sys.differential().begin(), sys.differential().end(), 0.0);
  EXPECT_EQ(algebraic, sys.stream_mixing_rows());
  for (int i = 0; i < sys.size(); ++i) {
    if (sys.differential()[i] != 0.0) continue;
    EXPECT_EQ(sys.variable_names()[i].find("m_flow"), std::string::npos) << sys.variable_names()[i];
  }

  AssemblyOptions keep;
  keep.eliminate_aliases = false;
  System full(elaborate(nl, builtin_registry()), keep);
  const RunResult a = run_system(full, solver_options(nl.simulation));
  const RunResult b = run_system(sys, solver_options(nl.simulation));
  ASSERT_TRUE(a.solver.ok) << a.solver.message;
  ASSERT_TRUE(b.solver.ok) << b.solver.message;
  ASSERT_EQ(a.table.rows.size(), b.table.rows.size());
  // Positions within 0.1 mm on the common grid (strokes of 100 mm).
  double dx = 0;
  for (const char* x : {"x_A", "x_B"}) {
    const int c = a.table.column(x);
    for (std::size_t k = 0; k < a.table.rows.size(); ++k)
      dx = std::max(dx, std::abs(a.table.rows[k][c] - b.table.rows[k][c]));
  }
  EXPECT_LT(dx, 1e-4);
}

// The reduced systems' AD Jacobians (one derivative direction per distinct
// unknown of a block) against finite differences along a run, on circuits
// with a three-port mixing node (its stream temperatures kept) and a heat
// path (heat-port temperatures folded into the gas temperature).
TEST(AliasElimination, ReducedJacobiansOfMixingAndHeatCircuits) {
  const std::vector<std::string> circuits = {test_support::kThreePortMixingCircuit,
                                             test_support::kTankWithWallCircuit};
  for (const auto& text : circuits) {
    const Netlist nl = parse_netlist(text, "reduced.yaml");
    AssemblyOptions keep;
    keep.eliminate_aliases = false;
    System full(elaborate(nl, builtin_registry()), keep);
    System sys(elaborate(nl, builtin_registry()));
    EXPECT_LT(sys.size(), full.size());
    std::cout << "unknowns: " << full.size() << " -> " << sys.size() << "\n";
    for (const auto& check : testkit::check_jacobian(sys, solver_options(nl.simulation), 0.05))
      EXPECT_TRUE(check.passed(1e-5)) << check.report();
  }
}

}  // namespace
}  // namespace pneumo
