// Inputs that used to run to exit 0 with a wrong or meaningless result
// (issue #29, components and gas constants), each checked against a
// physical fact or refused with a located error:
//   * adiabatic filling of volumes from 1e-12 m3 to 1 m3 ends at the
//     closed-form temperature (and stays there once the flow has stopped);
//   * a fixed_position on a cylinder's flange holds the rod where it says;
//   * a loop of logic gates, gas/ambient constants out of range, and a
//     sequencer step acting twice on one actuator are refused at load;
//   * out-of-range input signals (a pressure <= 0, a negative opening) are
//     reported once in the event log, naming the component and the time.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/core/error.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

// ---------------------------------------------------------------------------
// Adiabatic filling of a rigid volume V (p0, T0) from a source at p_s, T_s
// until the pressures are equal. Energy balance of the open system (no heat,
// no work): d(U) = c_p T_s dm with U = p V / (kappa - 1) and
// c_p = kappa R / (kappa - 1), so (p_s - p0) V = kappa R T_s (m_end - m0);
// with m0 = p0 V / (R T0) and T_end = p_s V / (R m_end):
//   T_end = p_s / (p0 / T0 + (p_s - p0) / (kappa T_s)),
// independent of V. For 6 bar from 1 bar, both at 293.15 K: 384.76 K.
double filling_temperature(double p_s, double T_s, double p0, double T0, double kappa) {
  return p_s / (p0 / T0 + (p_s - p0) / (kappa * T_s));
}

// The same throttle for every volume: the filling takes ~V / (1 L) s, and
// the run goes on long after it to where a smeared upwinding (a heat
// conductance c_p m_flow_small / 2 at zero flow) had pulled a 1e-8 m3
// volume back to the supply's temperature.
std::string filling_netlist(double V, double t_end) {
  return "gas: {R: 287.05 J/(kg*K), kappa: 1.4}\n"
         "components:\n"
         "  source: {type: pressure_source, p: 6 bar, T: 293.15 K}\n"
         "  valve:  {type: iso6358_throttle, C: 0.4 dm3/(s*bar), b: 0.3}\n"
         "  tank:   {type: volume, V: " + num(V) + " m3, p0: 1 bar, T0: 293.15 K}\n"
         "connections:\n"
         "  - [source.port, valve.a]\n"
         "  - [valve.b, tank.port]\n"
         "outputs:\n"
         "  p: tank.p\n"
         "  T: tank.T\n"
         "simulation:\n"
         "  t_end: " + num(t_end) + " s\n"
         "  rtol: 1e-8\n"
         "  atol: 1e-8\n"
         "  output_interval: " + num(t_end / 100) + " s\n";
}

void expect_closed_form_filling(double V, double t_end) {
  const double T_end = filling_temperature(6e5, 293.15, 1e5, 293.15, 1.4);
  const RunResult r = run_text(filling_netlist(V, t_end), "filling");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const auto p = column(r.table, "p"), T = column(r.table, "T");
  EXPECT_LT(rel_err(p.back(), 6e5), 1e-6) << "V = " << V << ": the volume has not reached the source pressure";
  EXPECT_LT(rel_err(T.back(), T_end), 1e-3) << "V = " << V << " m3: T = " << T.back() << " K, closed form " << T_end;
  // Once filled, nothing flows and nothing may change the temperature: the
  // second half of the run (all after the filling) stays at T_end.
  for (std::size_t i = T.size() / 2; i < T.size(); ++i)
    EXPECT_LT(rel_err(T[i], T_end), 1e-3) << "V = " << V << " m3, row " << i << ": T = " << T[i] << " K";
}

TEST(WrongSuccessPhysics, AdiabaticFillingOfA1e8M3Volume) { expect_closed_form_filling(1e-8, 4.0); }
TEST(WrongSuccessPhysics, AdiabaticFillingOfA1e12M3Volume) { expect_closed_form_filling(1e-12, 4.0); }
TEST(WrongSuccessPhysics, AdiabaticFillingOfA1M3Volume) { expect_closed_form_filling(1.0, 4000.0); }

// A micro-volume filled through a micro-throttle (C scaled with V from the
// 1 L case: the same 1 s filling, flows of 1e-12 kg/s): every flow is
// below the default m_flow_small (1e-7 kg/s), where the upwinding blends
// the two temperatures (ended at 428 K). The netlist sets that scale below
// its flows, as gas.m_flow_small's description asks, and the closed form
// holds again: the smoothing scale, not the volume, sets the accuracy.
TEST(WrongSuccessPhysics, AdiabaticFillingThroughAMicroThrottle) {
  std::string text = filling_netlist(1e-12, 4.0);
  text.replace(text.find("C: 0.4 dm3/(s*bar)"), 18, "C: 4e-18 m3/(s*Pa)");
  text.replace(text.find("kappa: 1.4}"), 11, "kappa: 1.4, m_flow_small: 1e-15 kg/s}");
  const double T_end = filling_temperature(6e5, 293.15, 1e5, 293.15, 1.4);
  const RunResult r = run_text(text, "micro_filling");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_LT(rel_err(column(r.table, "p").back(), 6e5), 1e-6);
  EXPECT_LT(rel_err(column(r.table, "T").back(), T_end), 1e-3) << column(r.table, "T").back() << " K";
}

// ---------------------------------------------------------------------------
// A cylinder's flange on a fixed_position: the rod is where the frame holds
// it. A cylinder starting retracted (no x0) on a frame at 50 mm cannot be
// both; that was run with the frame's s0 ignored (the rod held at 0).
const std::string kHeldCylinder = R"(
components:
  supply: {type: pressure_source, p: 6 bar g}
  valve:  {type: iso6358_throttle, C: 0.5 dm3/(s*bar), b: 0.3}
  cyl:    {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm}
  frame:  {type: fixed_position, s0: 50 mm}
connections:
  - [supply.port, valve.a]
  - [valve.b, cyl.cap]
  - [cyl.flange, frame.flange]
outputs:
  x: cyl.x
  p: cyl.p_cap
simulation:
  t_end: 1 s
  output_interval: 0.1 s
)";

TEST(WrongSuccessPhysics, FixedPositionAwayFromTheCylindersStartIsRefused) {
  const Netlist nl = parse_netlist(kHeldCylinder, "bad.yaml");
  try {
    elaborate(nl, builtin_registry());
    ADD_FAILURE() << "the frame's s0 and the cylinder's start position disagree, and it was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 10) << e.what();  // the connection
    const std::string m = e.what();
    for (const char* w : {"cyl.flange", "frame.flange", "0.05 m", "x0"}) EXPECT_NE(m.find(w), std::string::npos) << w << " in " << m;
  }
}

// Given the same start, the frame holds the rod at 50 mm under supply
// pressure (the frame, not the stops, carries the force) while the cap
// chamber fills to the supply pressure.
TEST(WrongSuccessPhysics, FixedPositionHoldsACylinderFlange) {
  std::string text = kHeldCylinder;
  text.replace(text.find("stroke: 100 mm}"), 15, "stroke: 100 mm, x0: 50 mm}");
  const RunResult r = run_text(text, "held_cylinder");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  for (double x : column(r.table, "x")) EXPECT_NEAR(x, 0.05, 1e-9);
  EXPECT_LT(rel_err(column(r.table, "p").back(), 101325.0 + 6e5), 1e-3);
}

// ---------------------------------------------------------------------------
// Refusals at load: InputError with the line of the mistake, the component
// and the parameter.
InputError load_error(const std::string& text) {
  try {
    elaborate(parse_netlist(text, "bad.yaml"), builtin_registry());
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return InputError({}, "", "", "");
}

void expect_error(const std::string& text, int line, const std::string& component, const std::string& parameter,
                  const std::vector<std::string>& words) {
  const InputError e = load_error(text);
  EXPECT_EQ(e.where().file, "bad.yaml") << e.what();
  EXPECT_EQ(e.where().line, line) << e.what();
  EXPECT_EQ(e.component(), component) << e.what();
  EXPECT_EQ(e.parameter(), parameter) << e.what();
  for (const auto& w : words) EXPECT_NE(std::string(e.what()).find(w), std::string::npos) << w << " in " << e.what();
}

// y = 1 - y has the one solution 0.5, which is no logic value; a loop of
// gates is refused at the connection that closes it.
TEST(WrongSuccessPhysics, NotGateFedByItsOwnOutputIsRefused) {
  expect_error("components:\n"
               "  g: {type: not}\n"
               "connections:\n"
               "  - [g.y, g.in]\n"
               "outputs:\n"
               "  y: g.y\n",
               4, "g", "", {"'g' -> 'g'", "flip-flop", "timer"});
}

TEST(WrongSuccessPhysics, LoopThroughTwoGatesIsRefusedNamingBoth) {
  expect_error("components:\n"
               "  run:  {type: signal_source, value: 1}\n"
               "  both: {type: and}\n"
               "  inv:  {type: not}\n"
               "connections:\n"
               "  - [run.y, both.in1]\n"
               "  - [both.y, inv.in]\n"
               "  - [inv.y, both.in2]\n"
               "outputs:\n"
               "  y: inv.y\n",
               8, "both", "", {"'both' -> 'inv' -> 'both'"});
}

// The same gates without the loop are accepted and compute logic values.
TEST(WrongSuccessPhysics, GatesWithoutALoopStillRun) {
  const RunResult r = run_text(R"(
components:
  run:  {type: signal_source, value: 1}
  inv:  {type: not}
  inv2: {type: not}
connections:
  - [run.y, inv.in]
  - [inv.y, inv2.in]
outputs:
  y: inv.y
  y2: inv2.y
simulation:
  t_end: 0.1 s
)",
                               "gates");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_NEAR(column(r.table, "y").back(), 0.0, 1e-12);
  EXPECT_NEAR(column(r.table, "y2").back(), 1.0, 1e-12);
}

// rho_ref = 0 makes every ISO 6358 conductance pass nothing.
TEST(WrongSuccessPhysics, GasReferenceDensityZeroIsRefused) {
  expect_error("gas: {R: 287 J/(kg*K),\n"
               "      rho_ref: 0}\n"
               "components:\n"
               "  tank: {type: volume, V: 1 L}\n",
               2, "", "gas.rho_ref", {"out of range", "> 0"});
}

TEST(WrongSuccessPhysics, GasConstantsOutOfRangeAreRefused) {
  expect_error("gas: {m_flow_small: -1e-7 kg/s}\ncomponents:\n  tank: {type: volume, V: 1 L}\n", 1, "",
               "gas.m_flow_small", {"out of range"});
  expect_error("gas: {kappa: 3}\ncomponents:\n  tank: {type: volume, V: 1 L}\n", 1, "", "gas.kappa",
               {"out of range"});
  expect_error("gas: {T_ref: 0 K}\ncomponents:\n  tank: {type: volume, V: 1 L}\n", 1, "", "gas.T_ref",
               {"out of range"});
}

// The ambient pressure is the datum of gauge pressures: "1 barg" would be
// measured against itself.
TEST(WrongSuccessPhysics, GaugeAmbientPressureIsRefused) {
  expect_error("title: t\nambient: {p: 1 barg}\ncomponents:\n  tank: {type: volume, V: 1 L}\n", 2, "", "ambient.p",
               {"gauge", "absolute"});
}

// "(B+ A-)" after "A+" is fine; "(A+ A-)" waits for A1 and A0 at once.
TEST(WrongSuccessPhysics, SequencerStepActingTwiceOnOneActuatorIsRefused) {
  expect_error("components:\n"
               "  seq:\n"
               "    type: sequencer\n"
               "    steps: \"A+ B+ (B- A+ A-)\"\n",
               4, "seq", "steps", {"step 3", "'A'"});
}

// ---------------------------------------------------------------------------
// Out-of-range input signals: a warning in the event log, once, by the
// component, at the time the signal leaves the range.
std::vector<EventLogEntry> warnings(const RunResult& r, const std::string& component) {
  std::vector<EventLogEntry> out;
  for (const auto& e : r.solver.events)
    if (e.component == component && e.message.find("warning") != std::string::npos) out.push_back(e);
  return out;
}

TEST(WrongSuccessPhysics, NegativeSourcePressureSignalIsReportedOnce) {
  // 3 bar, then -5 bar from 0.5 s.
  const RunResult r = run_text(R"(
components:
  sig:    {type: signal_source, kind: step, value: 300000, height: -800000, t_start: 0.5 s}
  source: {type: pressure_source, p: 3 bar}
  valve:  {type: iso6358_throttle, C: 0.4 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 1 L, p0: 3 bar}
connections:
  - [sig.y, source.p_in]
  - [source.port, valve.a]
  - [valve.b, tank.port]
outputs:
  p: tank.p
simulation:
  t_end: 1 s
)",
                               "negative_p");
  const auto w = warnings(r, "source");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NEAR(w[0].t, 0.5, 1e-9);
  EXPECT_NE(w[0].message.find("p_in"), std::string::npos) << w[0].message;
  EXPECT_NE(w[0].message.find("-500000"), std::string::npos) << w[0].message;
}

TEST(WrongSuccessPhysics, NegativeOpeningIsReportedOnceAtTheStart) {
  const RunResult r = run_text(R"(
components:
  sig:    {type: signal_source, value: -3}
  source: {type: pressure_source, p: 6 bar}
  valve:  {type: iso6358_throttle, C: 0.4 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 1 L, p0: 1 bar}
connections:
  - [sig.y, valve.opening]
  - [source.port, valve.a]
  - [valve.b, tank.port]
outputs:
  p: tank.p
simulation:
  t_end: 1 s
)",
                               "negative_opening");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const auto w = warnings(r, "valve");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].t, 0.0);
  EXPECT_NE(w[0].message.find("opening"), std::string::npos) << w[0].message;
  EXPECT_NE(w[0].message.find("-3"), std::string::npos) << w[0].message;
  // Taken as closed: nothing flows.
  EXPECT_NEAR(column(r.table, "p").back(), 1e5, 1.0);
}

// A ramp crossing 0 between events is found by the root: the warning comes
// at the crossing, 0.25 s (1 - 4 t).
TEST(WrongSuccessPhysics, OpeningRampingBelowZeroIsReportedWhereItCrosses) {
  const RunResult r = run_text(R"(
components:
  sig:    {type: signal_source, kind: ramp, value: 1, height: -4, t_start: 0 s, duration: 1 s}
  source: {type: pressure_source, p: 6 bar}
  valve:  {type: iso6358_throttle, C: 0.4 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 1 L, p0: 1 bar}
connections:
  - [sig.y, valve.opening]
  - [source.port, valve.a]
  - [valve.b, tank.port]
outputs:
  p: tank.p
simulation:
  t_end: 1 s
)",
                               "ramp_opening");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const auto w = warnings(r, "valve");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NEAR(w[0].t, 0.25, 1e-4);
}

}  // namespace
}  // namespace pneumo
