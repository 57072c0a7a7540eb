// A steady start (issue 36): `simulation: {steady_start: true}` starts a run
// from the rest state the circuit settles into with its valves in their
// initial positions and every time-dependent input held at t_start - no
// `p0` written by hand, external forces in the piston's equilibrium, the
// gas at the ambient temperature after the long wait a rest state means.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

constexpr double kAmbient = 101325.0;
constexpr double kSupply = 6e5 + kAmbient;  // 6 bar g
constexpr double kPi = 3.14159265358979323846;

std::string replace_once(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// The shipped meter-out cylinder, outputs every 0.5 ms and the lines'
// pressures and the rod side's temperature among them; with `hand_set`
// false its start pressures (line_A, line_B p0, cyl p0_rod) deleted.
std::string meter_out(bool hand_set, bool steady) {
  std::string s = read_file(std::string(PNEUMO_SOURCE_DIR) + "/netlists/meter_out_cylinder.yaml");
  s = replace_once(s, "output_interval: 5 ms", "output_interval: 0.5 ms");
  s = replace_once(s, "  p_rod: cyl.p_rod\n",
                   "  p_rod: cyl.p_rod\n  T_rod: cyl.T_rod\n  p_line_A: line_A.p\n  p_line_B: line_B.p\n");
  if (!hand_set) {
    s = replace_once(s, "V: 5 cm3, p0: 0 bar g}", "V: 5 cm3}");
    s = replace_once(s, "V: 5 cm3, p0: 6 bar g}", "V: 5 cm3}");
    s = replace_once(s, "stroke: 100 mm, p0_rod: 6 bar g,", "stroke: 100 mm,");
  }
  if (steady) s += "  steady_start: true\n";
  return s;
}

// The time at which column x first reaches `level` (linear between rows).
double time_at(const ResultsTable& t, const std::string& x, double level) {
  const int c = t.column(x);
  for (std::size_t i = 1; i < t.rows.size(); ++i) {
    const double a = t.rows[i - 1][c], b = t.rows[i][c];
    if (a < level && b >= level)
      return t.rows[i - 1][0] + (level - a) / (b - a) * (t.rows[i][0] - t.rows[i - 1][0]);
  }
  return NAN;
}

double first(const ResultsTable& t, const std::string& x) { return t.rows.front()[t.column(x)]; }

// The largest |v| over the rows with t <= t_max.
double max_speed_until(const ResultsTable& t, double t_max) {
  const int c = t.column("v");
  double v = 0.0;
  for (const auto& row : t.rows)
    if (row[0] <= t_max) v = std::max(v, std::abs(row[c]));
  return v;
}

TEST(SteadyStart, MeterOutCylinderWithoutStartPressuresRestsAtTheHandSetOnes) {
  const RunResult hand = run_text(meter_out(true, false), "meter_out_hand_set");
  const RunResult steady = run_text(meter_out(false, true), "meter_out_steady");
  ASSERT_TRUE(hand.solver.ok) << hand.solver.message;
  ASSERT_TRUE(steady.solver.ok) << steady.solver.message;
  const ResultsTable& t = steady.table;
  EXPECT_EQ(t.rows.front()[0], 0.0);
  // At rest the valve joins line_B and the rod side to the supply and
  // line_A and the cap side to the atmosphere (through the silencer).
  EXPECT_LT(rel_err(first(t, "p_rod"), kSupply), 1e-3);
  EXPECT_LT(rel_err(first(t, "p_line_B"), kSupply), 1e-3);
  EXPECT_LT(rel_err(first(t, "p_cap"), kAmbient), 1e-3);
  EXPECT_LT(rel_err(first(t, "p_line_A"), kAmbient), 1e-3);
  // The gas at the ambient temperature, as the hand-set start has it (an
  // adiabatic filling would leave the rod side near 380 K).
  EXPECT_NEAR(first(t, "T_rod"), 293.15, 0.05);
  // Against the stop at x = 0, not moving.
  EXPECT_LT(std::abs(first(t, "x")), 1e-4);
  EXPECT_LT(max_speed_until(t, 0.05), 1e-6);
  // The first stroke (the valve switches at 0.1 s) as with the hand-set start.
  const double stroke_hand = time_at(hand.table, "x", 0.095) - 0.1;
  const double stroke_steady = time_at(t, "x", 0.095) - 0.1;
  ASSERT_TRUE(std::isfinite(stroke_hand) && std::isfinite(stroke_steady));
  EXPECT_LT(rel_err(stroke_steady, stroke_hand), 0.01) << stroke_steady << " s vs " << stroke_hand << " s";
  // What the steady start repairs: the same netlist without it starts the
  // rod side at ambient, and its first stroke differs (issue 36: 20 %).
  const RunResult forgot = run_text(meter_out(false, false), "meter_out_forgot");
  ASSERT_TRUE(forgot.solver.ok) << forgot.solver.message;
  EXPECT_GT(rel_err(time_at(forgot.table, "x", 0.095) - 0.1, stroke_hand), 0.05);
}

// A cylinder hanging from its cap end with a load on the rod (gravity
// pulls it out, +x), held up by the rod side, which the valve at rest feeds.
std::string hanging_load(bool steady) {
  std::string s = R"(
components:
  supply: {type: pressure_source, p: 6 bar g, T: 293.15 K}
  valve:  {type: directional_valve_52, C: 1 dm3/(s*bar), b: 0.3}
  air:    {type: atmosphere}
  cyl:    {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, p0_rod: 6 bar g,
           friction_model: coulomb_viscous, friction_FC: 20 N, friction_viscous: 100 N*s/m}
  load:   {type: translational_mass, m: 20 kg}
  weight: {type: force_source, F: 196.133 N}
connections:
  - [supply.port, valve.P]
  - [valve.A, cyl.cap]
  - [valve.B, cyl.rod]
  - [valve.R, air.port]
  - [cyl.flange, load.flange, weight.flange]
outputs:
  x: cyl.x
  v: cyl.v
  p_cap: cyl.p_cap
  p_rod: cyl.p_rod
simulation:
  t_end: 20 ms
  output_interval: 0.1 ms
)";
  if (steady) s += "  steady_start: true\n";
  return s;
}

TEST(SteadyStart, HangingLoadStartsAtRestAgainstTheStopThatCarriesIt) {
  const RunResult r = run_text(hanging_load(true), "hanging_load");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_LT(max_speed_until(r.table, 0.01), 1e-6);
  // The stop (1e7 N/m) carries the pressure force less the weight.
  const double A = kPi * 0.032 * 0.032 / 4, A_rod = kPi * 0.012 * 0.012 / 4;
  const double F = first(r.table, "p_cap") * A - first(r.table, "p_rod") * (A - A_rod) - kAmbient * A_rod + 196.133;
  ASSERT_LT(F, 0.0);
  EXPECT_LT(rel_err(first(r.table, "x"), F / 1e7), 1e-3);
  EXPECT_LT(rel_err(first(r.table, "p_rod"), kSupply), 1e-3);
  // The given start puts the piston where the pressures alone hold it: the
  // weight is missing from that equilibrium and the piston moves at t = 0.
  const RunResult given = run_text(hanging_load(false), "hanging_load_given");
  ASSERT_TRUE(given.solver.ok) << given.solver.message;
  EXPECT_GT(max_speed_until(given.table, 0.01), 1e-4);
}

// A cylinder standing upright with a load on its rod, the cap side fed
// and the rod side closed (a gas spring of the air it started with): the
// piston comes to rest where the compressed rod-side air, the weight and
// the ambient pressure on the rod balance the supply on the cap side.
TEST(SteadyStart, LoadOnAGasSpringRestsAtTheIsothermalForceEquilibrium) {
  const std::string text = R"(
components:
  supply: {type: pressure_source, p: 3 bar g, T: 293.15 K}
  feed:   {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.3}
  cyl:    {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, dead_volume_rod: 2 cm3,
           friction_model: coulomb_viscous, friction_FC: 0 N, friction_viscous: 200 N*s/m}
  load:   {type: translational_mass, m: 5 kg}
  weight: {type: force_source, F: -49.033 N}
connections:
  - [supply.port, feed.a]
  - [feed.b, cyl.cap]
  - [cyl.flange, load.flange, weight.flange]
outputs:
  x: cyl.x
  v: cyl.v
  p_cap: cyl.p_cap
  p_rod: cyl.p_rod
  T_rod: cyl.T_rod
simulation:
  t_end: 20 ms
  output_interval: 0.1 ms
  steady_start: true
)";
  const RunResult r = run_text(text, "gas_spring");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_LT(max_speed_until(r.table, 0.01), 1e-6);
  const double A = kPi * 0.032 * 0.032 / 4, A_rod = kPi * 0.012 * 0.012 / 4, A_ring = A - A_rod;
  const double p_cap = 3e5 + kAmbient;
  EXPECT_LT(rel_err(first(r.table, "p_cap"), p_cap), 1e-3);
  // Viscous friction vanishes at rest (Coulomb friction would make every
  // position within its band a rest): p_rod A_ring = p_cap A - p_amb A_rod - m g.
  const double p_rod = (p_cap * A - kAmbient * A_rod - 49.033) / A_ring;
  EXPECT_LT(rel_err(first(r.table, "p_rod"), p_rod), 1e-3);
  // The rod side's air (ambient pressure at x = 0, 2 cm3 + the full ring)
  // compressed isothermally: p V = p_amb V0.
  const double V0 = 2e-6 + A_ring * 0.1;
  const double x = 0.1 - (kAmbient * V0 / p_rod - 2e-6) / A_ring;
  EXPECT_LT(std::abs(first(r.table, "x") - x), 1e-4 * 0.1) << first(r.table, "x") << " vs " << x;
  EXPECT_NEAR(first(r.table, "T_rod"), 293.15, 0.05);
}

TEST(SteadyStart, CircuitThatNeverComesToRestIsAnErrorNamingWhatMoves) {
  // A flange driven at a constant speed (and the sled it tows) moves
  // whatever time is held at.
  const std::string text = R"(
components:
  drive: {type: velocity_source, v: 0.1 m/s}
  rope:  {type: spring_damper, k: 1000 N/m, d: 50 N*s/m}
  sled:  {type: translational_mass, m: 1 kg}
connections:
  - [drive.flange, rope.a]
  - [rope.b, sled.flange]
outputs:
  s: sled.s
simulation:
  t_end: 1 s
  steady_start: true
)";
  const RunResult r = run_simulation(parse_netlist(text, "never_at_rest"), builtin_registry());
  EXPECT_FALSE(r.solver.ok);
  EXPECT_NE(r.solver.message.find("steady start"), std::string::npos) << r.solver.message;
  EXPECT_NE(r.solver.message.find("sled"), std::string::npos) << r.solver.message;
  EXPECT_TRUE(r.table.rows.empty());
}

}  // namespace
}  // namespace pneumo
