// Signal-domain components switched by events: limit and pressure switches,
// gates, timer, flip-flop and the sequencer, and the framework's event
// iteration that lets a step chain react at the instant an input jumps.
// Times are closed forms: timers and velocity-driven flanges make every
// switching instant known exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo {
namespace {

RunResult run_text(const std::string& yaml) {
  return run_simulation(parse_netlist(yaml, "signals.yaml"), builtin_registry());
}

// Time of the first event of `component` tagged `tag`; NaN if none.
double event_time(const RunResult& r, const std::string& component, const std::string& tag, int nth = 0) {
  for (const auto& e : r.solver.events)
    if (e.component == component && e.tag == tag && nth-- == 0) return e.t;
  return std::nan("");
}
// Index in the event log of that event; -1 if none.
int event_index(const RunResult& r, const std::string& component, const std::string& tag) {
  for (std::size_t i = 0; i < r.solver.events.size(); ++i)
    if (r.solver.events[i].component == component && r.solver.events[i].tag == tag) return static_cast<int>(i);
  return -1;
}
// Value of column `name` in the last row with time <= t.
double value_at(const RunResult& r, const std::string& name, double t) {
  const int c = r.table.column(name);
  EXPECT_GE(c, 0) << name;
  double v = std::nan("");
  for (const auto& row : r.table.rows)
    if (row[0] <= t + 1e-12) v = row[c];
  return v;
}

// A+ B+ B- A- where each "cylinder" is two on-delay timers (extended after
// its delay once commanded, retracted after another once released): the
// chain must advance at the instant each timer elapses, so the cycle ends at
// start + the four delays, and each step follows its transition's input.
constexpr const char* kTimerChain = R"yaml(
components:
  go:    {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.1 s}
  seq:   {type: sequencer, steps: "A+ B+ B- A-"}
  a_ext: {type: timer, delay: 0.2 s}
  b_ext: {type: timer, delay: 0.3 s}
  not_a: {type: not}
  not_b: {type: not}
  a_ret: {type: timer, delay: 0.25 s}
  b_ret: {type: timer, delay: 0.15 s}
connections:
  - [go.y, seq.start]
  - [seq.A, a_ext.in, not_a.in]
  - [seq.B, b_ext.in, not_b.in]
  - [not_a.y, a_ret.in]
  - [not_b.y, b_ret.in]
  - [a_ext.y, seq.A1]
  - [b_ext.y, seq.B1]
  - [a_ret.y, seq.A0]
  - [b_ret.y, seq.B0]
outputs: {A: seq.A, B: seq.B, step: seq.step}
simulation: {t_end: 1.5 s, output_interval: 10 ms}
)yaml";

TEST(Sequencer, StepsAdvanceAtTheirTransitionsEvents) {
  const RunResult r = run_text(kTimerChain);
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const double tol = 1e-9;
  EXPECT_NEAR(event_time(r, "seq", "cycle_start"), 0.1, tol);
  EXPECT_NEAR(event_time(r, "seq", "step_2"), 0.1 + 0.2, tol);
  EXPECT_NEAR(event_time(r, "seq", "step_3"), 0.3 + 0.3, tol);
  EXPECT_NEAR(event_time(r, "seq", "step_4"), 0.6 + 0.15, tol);
  EXPECT_NEAR(event_time(r, "seq", "cycle_end"), 0.75 + 0.25, tol);
  // Each step is entered right after (in the log) the event that made its
  // transition true, at the same instant.
  EXPECT_LT(event_index(r, "a_ext", "elapsed"), event_index(r, "seq", "step_2"));
  EXPECT_LT(event_index(r, "b_ext", "elapsed"), event_index(r, "seq", "step_3"));
  // B0 was already true at the start; B- makes it false, the timer restarts.
  EXPECT_NEAR(event_time(r, "b_ret", "elapsed", 1), 0.75, tol);
  EXPECT_LT(event_index(r, "seq", "step_3"), event_index(r, "seq", "step_4"));
  // Stored actions: A = 1 from A+ to A-, B = 1 from B+ to B-; once only.
  EXPECT_EQ(value_at(r, "A", 0.5), 1.0);
  EXPECT_EQ(value_at(r, "B", 0.5), 1.0);
  EXPECT_EQ(value_at(r, "B", 0.7), 0.0);
  EXPECT_EQ(value_at(r, "A", 0.7), 1.0);
  EXPECT_EQ(value_at(r, "A", 1.2), 0.0);
  EXPECT_EQ(value_at(r, "step", 1.4), 0.0);
  EXPECT_TRUE(std::isnan(event_time(r, "seq", "cycle_start", 1)));
}

// A parallel step (B+ C+) ends when both inputs are high (the slower one),
// named transitions, and two cycles back to back while start stays high.
TEST(Sequencer, ParallelStepWaitsForAllInputsAndCyclesRepeat) {
  const RunResult r = run_text(R"yaml(
components:
  go:   {type: signal_source, kind: step, value: 0, height: 1, t_start: 0}
  seq:  {type: sequencer, steps: "A+ (B+ C+) (A- B- C-)", transitions: "a_done b_done&c_done back", cycles: 2}
  ta:   {type: timer, delay: 0.1 s}
  tb:   {type: timer, delay: 0.2 s}
  tc:   {type: timer, delay: 0.35 s}
  na:   {type: not}
  back: {type: timer, delay: 0.05 s}
connections:
  - [go.y, seq.start]
  - [seq.A, ta.in, na.in]
  - [seq.B, tb.in]
  - [seq.C, tc.in]
  - [na.y, back.in]
  - [ta.y, seq.a_done]
  - [tb.y, seq.b_done]
  - [tc.y, seq.c_done]
  - [back.y, seq.back]
simulation: {t_end: 2 s, output_interval: 10 ms}
)yaml");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const double tol = 1e-9;
  // The `back` timer starts at t = 0 (A = 0) and is high from 0.05 s: it
  // does not end step 3 before step 3 has released A again.
  const double cycle = 0.1 + 0.35 + 0.05;
  EXPECT_NEAR(event_time(r, "seq", "step_2"), 0.1, tol);
  EXPECT_NEAR(event_time(r, "seq", "step_3"), 0.1 + 0.35, tol);
  EXPECT_NEAR(event_time(r, "seq", "cycle_end"), cycle, tol);
  EXPECT_NEAR(event_time(r, "seq", "cycle_start", 1), cycle, tol);
  EXPECT_NEAR(event_time(r, "seq", "cycle_end", 1), 2 * cycle, tol);
  EXPECT_TRUE(std::isnan(event_time(r, "seq", "cycle_start", 2)));
}

// The flange moves at 0.1 m/s from s = 0: a switch at 0 (window 10 mm) is on
// from the start and releases at 5 mm + hysteresis; one at 50 mm (window
// 20 mm, hysteresis 1 mm) is on from 40 mm to 61 mm.
TEST(LimitSwitch, WindowAndHysteresisAtClosedFormTimes) {
  const RunResult r = run_text(R"yaml(
components:
  drive: {type: velocity_source, v: 0.1 m/s, s0: 0}
  home:  {type: limit_switch, position: 0, window: 10 mm, hysteresis: 1 mm}
  mid:   {type: limit_switch, position: 50 mm, window: 20 mm, hysteresis: 1 mm}
connections:
  - [drive.flange, home.flange, mid.flange]
outputs: {home: home.y, mid: mid.y}
simulation: {t_end: 1 s, output_interval: 10 ms}
)yaml");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const double tol = 1e-7;  // root location on a linear s(t)
  EXPECT_EQ(r.table.rows.front()[r.table.column("home")], 1.0);
  EXPECT_NEAR(event_time(r, "home", "off"), 0.006 / 0.1, tol);
  EXPECT_NEAR(event_time(r, "mid", "on"), 0.040 / 0.1, tol);
  EXPECT_NEAR(event_time(r, "mid", "off"), 0.061 / 0.1, tol);
  EXPECT_EQ(value_at(r, "mid", 0.5), 1.0);
  EXPECT_EQ(value_at(r, "mid", 0.7), 0.0);
}

// A tank filling through a throttle: the pressure switch turns on where the
// tank pressure passes p_on (read off the output at the event).
TEST(PressureSwitch, TurnsOnWherePressurePassesSetting) {
  const RunResult r = run_text(R"yaml(
components:
  supply: {type: pressure_source, p: 4 bar}
  fill:   {type: iso6358_throttle, C: 0.5 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 0.5 L, p0: 1 bar}
  ps:     {type: pressure_switch, p_on: 2 barg}
connections:
  - [supply.port, fill.a]
  - [fill.b, tank.port, ps.port]
outputs: {p: tank.p, on: ps.y}
simulation: {t_end: 1 s, output_interval: 1 ms}
)yaml");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const double t_on = event_time(r, "ps", "on");
  ASSERT_FALSE(std::isnan(t_on));
  const double p_setting = 2e5 + 101325.0;
  // Linear interpolation of p between the output rows around the event.
  const int cp = r.table.column("p");
  for (std::size_t i = 1; i < r.table.rows.size(); ++i)
    if (r.table.rows[i][0] >= t_on) {
      const auto &a = r.table.rows[i - 1], &b = r.table.rows[i];
      const double p = a[cp] + (b[cp] - a[cp]) * (t_on - a[0]) / (b[0] - a[0]);
      EXPECT_NEAR(p, p_setting, 2e-4 * p_setting);
      break;
    }
  EXPECT_EQ(value_at(r, "on", t_on - 0.01), 0.0);
  EXPECT_EQ(value_at(r, "on", 0.99), 1.0);
}

// Gates, flip-flop and off-delay on two steps (S at 0.1 s, R at 0.3 s, both
// staying high): reset-dominant Q is 1 on [0.1, 0.3); set-dominant keeps 1;
// the off-delay timer on S and not R holds 1 until 0.3 + 0.2 s; an on-delay
// longer than that pulse never elapses.
TEST(Logic, GatesFlipFlopAndTimers) {
  const RunResult r = run_text(R"yaml(
components:
  s:     {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.1 s}
  rr:    {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.3 s}
  ff:    {type: flip_flop}
  ffs:   {type: flip_flop, dominant: set}
  nr:    {type: not}
  pulse: {type: and}
  any:   {type: or}
  hold:  {type: timer, kind: off_delay, delay: 0.2 s}
  late:  {type: timer, kind: on_delay, delay: 0.25 s}
connections:
  - [s.y, ff.S, ffs.S, pulse.in1, any.in1]
  - [rr.y, ff.R, ffs.R, nr.in, any.in2]
  - [nr.y, pulse.in2]
  - [pulse.y, hold.in, late.in]
outputs: {Q: ff.Q, Qn: ff.Qn, Qs: ffs.Q, pulse: pulse.y, any: any.y, hold: hold.y, late: late.y}
simulation: {t_end: 1 s, output_interval: 10 ms}
)yaml");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const double tol = 1e-9;
  EXPECT_NEAR(event_time(r, "ff", "set"), 0.1, tol);
  EXPECT_NEAR(event_time(r, "ff", "reset"), 0.3, tol);
  EXPECT_TRUE(std::isnan(event_time(r, "ffs", "reset")));
  EXPECT_EQ(value_at(r, "Qn", 0.2), 0.0);
  EXPECT_EQ(value_at(r, "Qs", 0.9), 1.0);
  EXPECT_EQ(value_at(r, "pulse", 0.05), 0.0);
  EXPECT_EQ(value_at(r, "pulse", 0.2), 1.0);
  EXPECT_EQ(value_at(r, "pulse", 0.35), 0.0);
  EXPECT_EQ(value_at(r, "any", 0.35), 1.0);
  EXPECT_NEAR(event_time(r, "hold", "set"), 0.1, tol);
  EXPECT_NEAR(event_time(r, "hold", "elapsed"), 0.5, tol);
  EXPECT_NEAR(event_time(r, "late", "cancel"), 0.3, tol);
  EXPECT_TRUE(std::isnan(event_time(r, "late", "elapsed")));
  EXPECT_EQ(value_at(r, "late", 0.9), 0.0);
}

// Q -> not -> S and Q -> R: the flip-flop sets and resets itself at one
// instant for ever; the event iteration stops with a clear message.
TEST(EventIteration, LoopThatNeverSettlesIsAnError) {
  const RunResult r = run_text(R"yaml(
components:
  ff:  {type: flip_flop}
  inv: {type: not}
connections:
  - [ff.Q, inv.in, ff.R]
  - [inv.y, ff.S]
simulation: {t_end: 1 s}
)yaml");
  EXPECT_FALSE(r.solver.ok);
  EXPECT_NE(r.solver.message.find("does not settle"), std::string::npos) << r.solver.message;
  EXPECT_NE(r.solver.message.find("ff"), std::string::npos) << r.solver.message;
}

// A valve commanded by a sequencer output (a signal that jumps at an event)
// keeps its switching time: the spool ramps at 1/t_switch_time from the
// command's instant, half open after half of it and 99 % open after 99 % of
// it (the drive's smooth end costs ~0.1 % of t_switch_time there).
TEST(Sequencer, CommandedValveKeepsItsSwitchingTime) {
  const RunResult r = run_text(R"yaml(
components:
  go:     {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.05 s}
  seq:    {type: sequencer, steps: "A+ A-", transitions: "T T"}
  hold:   {type: timer, delay: 0.1 s}
  supply: {type: pressure_source, p: 6 bar}
  valve:  {type: directional_valve_52, C: 0.5 dm3/(s*bar), t_switch_time: 20 ms}
  ca:     {type: volume, V: 0.1 L}
  cb:     {type: volume, V: 0.1 L}
  air:    {type: atmosphere}
connections:
  - [go.y, seq.start]
  - [seq.A, valve.command, hold.in]
  - [hold.y, seq.T]
  - [supply.port, valve.P]
  - [valve.A, ca.port]
  - [valve.B, cb.port]
  - [valve.R, air.port]
outputs: {x: valve.x}
simulation: {t_end: 0.2 s, output_interval: 0.1 ms}
)yaml");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const int cx = r.table.column("x");
  auto crossing = [&](double level) {
    const auto& rows = r.table.rows;
    for (std::size_t i = 1; i < rows.size(); ++i)
      if (rows[i - 1][cx] < level && rows[i][cx] >= level)
        return rows[i - 1][0] +
               (level - rows[i - 1][cx]) * (rows[i][0] - rows[i - 1][0]) / (rows[i][cx] - rows[i - 1][cx]);
    return std::nan("");
  };
  const double t_cmd = event_time(r, "seq", "cycle_start"), T = 0.02;
  EXPECT_NEAR(t_cmd, 0.05, 1e-9);
  EXPECT_NEAR(crossing(0.5) - t_cmd, 0.5 * T, 0.005 * T);
  EXPECT_NEAR(crossing(0.99) - t_cmd, 0.99 * T, 0.005 * T);
}

TEST(Sequencer, BadChainsAreInputErrorsAtTheirParameter) {
  auto error_of = [](const std::string& seq) -> InputError {
    try {
      elaborate(parse_netlist("components:\n  seq: {type: sequencer, " + seq + "}\n", "bad.yaml"), builtin_registry());
    } catch (const InputError& e) {
      return e;
    }
    ADD_FAILURE() << "no error for " << seq;
    return InputError({}, "", "", "");
  };
  const InputError a = error_of("steps: \"A+ B\"");
  EXPECT_EQ(a.parameter(), "steps");
  EXPECT_EQ(a.where().line, 2);
  EXPECT_NE(a.message().find("'B'"), std::string::npos) << a.message();
  EXPECT_EQ(error_of("steps: \"A+ (B+\"").parameter(), "steps");
  const InputError t = error_of("steps: \"A+ A-\", transitions: \"A1\"");
  EXPECT_EQ(t.parameter(), "transitions");
  EXPECT_NE(t.message().find("2 steps, 1 transitions"), std::string::npos) << t.message();
  EXPECT_EQ(error_of("steps: \"A+ A-\", transitions: \"A A0\"").parameter(), "transitions");
  EXPECT_EQ(error_of("steps: \"start+ A+\"").parameter(), "steps");
}

// A display unit must exist and fit the output's dimension; the error
// points at the unit's line.
TEST(OutputUnits, UnknownOrMismatchedUnitIsAnErrorAtItsLine) {
  auto error_of = [](const std::string& output) -> InputError {
    try {
      elaborate(parse_netlist("components:\n  tank: {type: volume, V: 1 L}\noutputs:\n  p: " + output + "\n",
                              "units.yaml"),
                builtin_registry());
    } catch (const InputError& e) {
      return e;
    }
    ADD_FAILURE() << "no error for " << output;
    return InputError({}, "", "", "");
  };
  const InputError wrong = error_of("{var: tank.p, unit: mm}");
  EXPECT_EQ(wrong.where().line, 4);
  EXPECT_NE(wrong.message().find("does not fit"), std::string::npos) << wrong.message();
  const InputError unknown = error_of("{var: tank.p, unit: furlong}");
  EXPECT_EQ(unknown.where().line, 4);
  EXPECT_NE(unknown.message().find("furlong"), std::string::npos) << unknown.message();
  EXPECT_NE(error_of("{var: tank.p, units: bar}").message().find("unknown key"), std::string::npos);
  EXPECT_NE(error_of("{unit: bar}").message().find("{var: component.variable}"), std::string::npos);
}

}  // namespace
}  // namespace pneumo
