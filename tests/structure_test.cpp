// Structural analysis and degenerate-but-valid circuits.
//
// Two components that each fix the pressure of one node (two volumes, a
// source and a volume) joined with nothing in between pose a structurally
// singular DAE: it must be rejected before solving, with a message naming
// the components so the user can find them. Conversely a circuit where no
// gas can move (every throttle closed by C = 0 or by an opening signal 0) is
// perfectly regular and must stay at rest: a closed throttle passes exactly
// zero mass flow, so with all temperatures equal the pressures are constant
// to rounding (relative 1e-9 asserted, rtol 1e-8). With unequal temperatures
// the model's regularised upwinding (gas.m_flow_small = eps) lets an energy
// flow c_p (eps/2) (T_in - T) through a port at zero mass flow - a closed
// valve conducts about 2e-5 W per 40 K here. That leak, not zero, is the
// bound asserted in that case; any real mass flow would exceed it by orders
// of magnitude.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo {
namespace {

Circuit circuit_of(const std::string& text) {
  return elaborate(parse_netlist(text, "structure.yaml"), builtin_registry());
}

// Builds the System and returns the StructureError's message ("" if none).
std::string structure_error(const std::string& text) {
  try {
    System sys(circuit_of(text));
  } catch (const StructureError& e) {
    return e.what();
  }
  return "";
}

bool mentions(const std::string& msg, const std::string& word) { return msg.find(word) != std::string::npos; }

TEST(Structure, TwoVolumesConnectedDirectlyAreRejected) {
  const std::string msg = structure_error(R"(
components:
  tank1: {type: volume, V: 1 L, p0: 3 bar}
  tank2: {type: volume, V: 2 L, p0: 1 bar}
connections:
  - [tank1.port, tank2.port]
)");
  ASSERT_FALSE(msg.empty()) << "two volumes sharing one node must be a StructureError";
  EXPECT_TRUE(mentions(msg, "tank1")) << msg;
  EXPECT_TRUE(mentions(msg, "tank2")) << msg;
}

TEST(Structure, SourceConnectedDirectlyToVolumeIsRejected) {
  const std::string msg = structure_error(R"(
components:
  supply: {type: pressure_source, p: 6 bar}
  tank:   {type: volume, V: 1 L, p0: 1 bar}
connections:
  - [supply.port, tank.port]
)");
  ASSERT_FALSE(msg.empty()) << "a pressure source and a volume sharing one node must be a StructureError";
  EXPECT_TRUE(mentions(msg, "supply")) << msg;
  EXPECT_TRUE(mentions(msg, "tank")) << msg;
}

// The same volumes with a throttle between them are fine (the rejection
// above is about the topology, not the components).
TEST(Structure, VolumesWithThrottleBetweenAreAccepted) {
  EXPECT_NO_THROW(System sys(circuit_of(R"(
components:
  tank1: {type: volume, V: 1 L, p0: 3 bar}
  valve: {type: iso6358_throttle, C: 0.1 dm3/(s*bar)}
  tank2: {type: volume, V: 2 L, p0: 1 bar}
connections:
  - [tank1.port, valve.a]
  - [valve.b, tank2.port]
)")));
}

struct AtRest {
  std::string output;
  double p0;         // Pa, initial pressure
  double tolerance;  // relative, over the whole run
};

// Runs `text` and checks that every listed pressure output keeps its initial
// value throughout, and that the run reached t_end (2 s).
void expect_at_rest(const std::string& text, const std::vector<AtRest>& pressures) {
  const RunResult r = run_simulation(parse_netlist(text, "at_rest.yaml"), builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_NEAR(r.table.rows.back()[0], 2.0, 1e-12);
  for (const auto& [name, p0, tolerance] : pressures) {
    const int col = r.table.column(name);
    ASSERT_GE(col, 0) << name;
    double worst = 0.0;
    for (const auto& row : r.table.rows) worst = std::max(worst, std::abs(row[col] - p0) / p0);
    EXPECT_LT(worst, tolerance) << name << " moved (worst relative change " << worst << ")";
  }
}

// Relative pressure drift of a volume V at p0 over t through the zero-flow
// energy leak of the upwinding regularisation, for temperature differences
// up to dT at its port: dp/dt = (kappa-1)/V dU/dt, |dU/dt| <= c_p eps/2 dT.
double leak_bound(double V, double p0, double dT, double t) {
  const GasModel gas;
  return (gas.kappa - 1.0) / V * gas.cp() * 0.5 * gas.m_flow_small * dT * t / p0;
}

// Supply, two tanks at different pressures and temperatures and the
// atmosphere, every path between them closed with C = 0.
TEST(Structure, AllThrottlesClosedByZeroConductanceStayAtRest) {
  expect_at_rest(R"(
components:
  supply: {type: pressure_source, p: 6 bar}
  v1:     {type: iso6358_throttle, C: 0 m3/(s*Pa)}
  tank1:  {type: volume, V: 1 L, p0: 4 bar, T0: 320 K}
  v2:     {type: iso6358_throttle, C: 0 m3/(s*Pa)}
  tank2:  {type: volume, V: 0.5 L, p0: 2 bar, T0: 280 K}
  v3:     {type: iso6358_throttle, C: 0 m3/(s*Pa)}
  air:    {type: atmosphere}
connections:
  - [supply.port, v1.a]
  - [v1.b, tank1.port]
  - [tank1.port, v2.a]
  - [v2.b, tank2.port]
  - [tank2.port, v3.a]
  - [v3.b, air.port]
outputs: {p1: tank1.p, p2: tank2.p, T1: tank1.T}
simulation: {t_end: 2 s, rtol: 1e-8, atol: 1e-8, output_interval: 0.1 s}
)",
                 {{"p1", 4e5, 1e-9 + leak_bound(1e-3, 4e5, 40.0, 2.0)},
                  {"p2", 2e5, 1e-9 + leak_bound(0.5e-3, 2e5, 40.0, 2.0)}});
}

// The same closure by an `opening` signal of 0 (the valve's command), one
// signal driving both throttles; all gas at 293.15 K, so no leak either.
TEST(Structure, ThrottleClosedByZeroOpeningSignalStaysAtRest) {
  expect_at_rest(R"(
components:
  closed: {type: signal_source, kind: constant, value: 0}
  supply: {type: pressure_source, p: 6 bar}
  v1:     {type: iso6358_throttle, C: 0.4 dm3/(s*bar)}
  tank:   {type: volume, V: 1 L, p0: 3 bar}
  v2:     {type: iso6358_throttle, C: 0.4 dm3/(s*bar)}
  air:    {type: atmosphere}
connections:
  - [closed.y, v1.opening, v2.opening]
  - [supply.port, v1.a]
  - [v1.b, tank.port]
  - [tank.port, v2.a]
  - [v2.b, air.port]
outputs: {p: tank.p}
simulation: {t_end: 2 s, rtol: 1e-8, atol: 1e-8, output_interval: 0.1 s}
)",
                 {{"p", 3e5, 1e-9}});
}

// A valve that opens later: at rest until the step, then the tank fills
// towards the supply. Shows that the closed state above was the opening
// signal's doing and that integration continues through the event.
TEST(Structure, ClosedThrottleOpensOnStepAndFlowStarts) {
  const RunResult r = run_simulation(parse_netlist(R"(
components:
  cmd:    {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.5}
  supply: {type: pressure_source, p: 6 bar}
  valve:  {type: iso6358_throttle, C: 0.4 dm3/(s*bar)}
  tank:   {type: volume, V: 1 L, p0: 3 bar}
connections:
  - [cmd.y, valve.opening]
  - [supply.port, valve.a]
  - [valve.b, tank.port]
outputs: {p: tank.p}
simulation: {t_end: 2 s, rtol: 1e-8, atol: 1e-8, output_interval: 0.1 s}
)",
                                                   "step_open.yaml"),
                                     builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const int p = r.table.column("p");
  for (const auto& row : r.table.rows) {
    if (row[0] <= 0.5 - 1e-9) {
      EXPECT_NEAR(row[p], 3e5, 3e5 * 1e-9) << "t = " << row[0];
    }
  }
  EXPECT_GT(r.table.rows.back()[p], 5.5e5) << "the tank should have filled towards 6 bar after the step";
  EXPECT_LE(r.table.rows.back()[p], 6e5 * (1 + 1e-6));
}

}  // namespace
}  // namespace pneumo
