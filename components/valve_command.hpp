// Spool drive shared by the directional valves (directional_valve_32,
// directional_valve_52, directional_valve_53): the spool position x (0 =
// rest, 1 = actuated; the 5/3 valve's -1 / 0 / 1: solenoid 12, centre,
// solenoid 14) is a
// differential state moving toward the commanded state at the constant rate
// 1/t_switch_time, i.e. a LINEAR opening ramp lasting t_switch_time for a
// full stroke (a command arriving mid-ramp turns the spool around at once).
//
// The command comes from either
//  * the netlist: `schedule: [[t0, state], [t1, state], ...]` (states 0/1).
//    The whole spool trajectory is then known in advance: every command
//    instant and every end of a ramp (a kink of x) is a time event, the
//    discrete mode counts the events passed and fixes dx/dt between them, so
//    no integration step straddles a switch and the event log shows each one;
//  * a signal input `command` (0/1, e.g. from a controller): then
//    t_switch_time dx/dt = tanh((u - x)/0.01), the same ramp rate, ending in an
//    exponential approach over 1 % of the stroke so the right-hand side stays
//    smooth (switching instants are then not known in advance and are not
//    events). A connected `command` port overrides the schedule. With a
//    delay fault the spool follows the command as it acts instead: the
//    signals' level (0/1; the 5/3 valve's -1/0/1), held in a mode and
//    changed `delay` after the signals changed - at the root of t - t_due,
//    the change itself seen by the event iteration (a sequencer's or a
//    switch's jump) or at the root where the signals leave the held level
//    by half a step. A command that returns before its delay has passed is
//    lost, as a short pulse on a sticky spool is.
// The paths are ISO 6358 resistances whose conductance is scaled by the open
// fraction of the path, x for the paths open when actuated and 1 - x for the
// others (linear crossover, so at mid-stroke all paths are half open).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "components/iso6358_flow.hpp"
#include "components/switching.hpp"
#include "framework/model/component.hpp"

namespace pneumo::components {

// A spool state a schedule may command: its value, what it connects (for
// the event log) and the word of its event tags (command_WORD, switched_WORD).
struct SpoolState {
  double value;
  std::string name, word;
};

class SpoolDrive {
 public:
  // `states` describes the commandable states for the parameter texts;
  // `lowest` is the lowest of them (the highest is 1).
  static std::vector<ParameterSpec> parameters(const std::string& states = "0 rest, 1 actuated",
                                               double lowest = 0.0) {
    return {
        ParameterSpec::scalar("t_switch_time", "s", "duration of a full spool stroke (linear opening ramp)", 0.01)
            .positive(),
        ParameterSpec::scalar("initial", "1", "spool state before the first command: " + states, 0.0)
            .range(lowest, 1.0),
        ParameterSpec::table("schedule", {"s", "1"},
                             "[[t, state], ...]: at time t the spool is commanded to a state (" + states +
                                 "; increasing t)",
                             false),
        ParameterSpec::scalar("fault_delay_actuate", "s",
                              "fault (diagnosis): a command away from rest acts this late; 0 = none", 0.0)
            .non_negative(),
        ParameterSpec::scalar("fault_delay_release", "s",
                              "fault (diagnosis): a command back toward rest acts this late; 0 = none", 0.0)
            .non_negative(),
    };
  }

  // The spool's faults: late switching per direction, a slow stroke.
  // `command_port`: the signal that commands it (the 5/3 valve's first).
  static std::vector<FaultSpec> faults(const std::string& command_port = "command") {
    // The delays act on commands, a schedule's or a signal's: a valve with
    // neither has none.
    return {{"delay_actuate", "switches late when actuated (sticky spool, slow pilot, solenoid)",
             {{"delay", "fault_delay_actuate", "s", false, 0.0, 0.0, 0.1, 0.01, false}},
             "schedule",
             command_port},
            {"delay_release", "switches late when released (weak return spring, sticky spool)",
             {{"delay", "fault_delay_release", "s", false, 0.0, 0.0, 0.1, 0.01, false}},
             "schedule",
             command_port},
            {"slow_switching", "spool stroke slower (or faster) than its data sheet",
             {{"k", "t_switch_time", "1", true, 1.0, 0.25, 20.0, 2.0, true}}}};
  }

  // The tags of a schedule's events, per state word: the command acts
  // (command_WORD) and the spool has arrived (switched_WORD).
  static std::vector<EventSpec> events(const std::vector<std::string>& words = {"off", "on"}) {
    std::vector<EventSpec> out;
    for (const auto& w : words)
      out.push_back({"command_" + w, "a command to state '" + w + "' acts (scheduled, or a signal's delayed by a fault)"});
    for (const auto& w : words) out.push_back({"switched_" + w, "the spool has arrived in state '" + w + "'"});
    return out;
  }

  SpoolDrive(const ParameterValues& p, std::string actuated, std::string rest)
      : SpoolDrive(p, {{0.0, std::move(rest), "off"}, {1.0, std::move(actuated), "on"}}) {}

  SpoolDrive(const ParameterValues& p, const std::vector<SpoolState>& states)
      : t_switch_(p["t_switch_time"]),
        x0_(p["initial"]),
        delay_actuate_(p["fault_delay_actuate"]),
        delay_release_(p["fault_delay_release"]),
        states_(states) {
    std::string allowed;
    for (const auto& s : states) allowed += (allowed.empty() ? "" : ", ") + format_number(s.value);
    if (!state(x0_)) throw ParameterError("initial", "initial must be one of " + allowed);
    if (!p.has("schedule")) return;
    const Table& rows = p.table("schedule");
    require_increasing(rows, "schedule", "times");
    const std::vector<double> acts = acting_times(rows);
    double x = x0_;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const double t = acts[i], s = rows[i][1];
      const SpoolState* st = state(s);
      if (!st) {
        std::ostringstream msg;
        msg << "schedule states must be one of " << allowed << ", row " << i + 1 << " has " << s;
        throw ParameterError("schedule", msg.str());
      }
      const double t_next = i + 1 < rows.size() ? acts[i + 1] : std::numeric_limits<double>::infinity();
      const double rate = s == x ? 0.0 : (s > x ? 1.0 : -1.0) / t_switch_;
      add(t, rate, "command " + format_number(s) + " (" + st->name + ")", "command_" + st->word);
      const double t_end = t + std::abs(s - x) * t_switch_;
      if (s != x && t_end <= t_next) {
        add(t_end, 0.0, "spool at " + format_number(s) + ": " + st->name + " fully open",
            "switched_" + st->word);
        x = s;
      } else if (s != x) {
        x += rate * (t_next - t);  // turned around by the next command
      }
    }
  }

  // Driven by the command value u (signal inputs).
  template <class T>
  T driven(const Eval<T>& e, const T& u, int k_x) const {
    return t_switch_ * e.der(k_x) - tanh((u - e.var(k_x)) / 0.01);
  }
  // Following the schedule.
  template <class T>
  T scheduled(const Eval<T>& e, int k_x) const {
    const auto k = static_cast<std::size_t>(e.mode(0));
    return e.der(k_x) - (k == 0 ? 0.0 : rates_[k - 1]);
  }
  // Open fraction of the paths open when actuated; 1 - it for the others.
  // Not clamped: x stays in [0, 1] by construction (piecewise-linear
  // trajectory integrated exactly; the tanh drive approaches u without
  // overshoot), and a clamp would put kinks exactly at the rest positions.
  template <class T>
  static T actuated_fraction(const Eval<T>& e, int k_x) {
    return e.var(k_x);
  }

  double x0() const { return x0_; }
  std::vector<double> time_events() const { return times_; }
  // Whether a delay fault is set, and the delay of a command from state
  // `from` to `to` (away from rest: actuating; toward it: releasing).
  bool delayed() const { return delay_actuate_ > 0.0 || delay_release_ > 0.0; }
  double delay(double from, double to) const {
    return std::abs(to) > std::abs(from) ? delay_actuate_ : to != from ? delay_release_ : 0.0;
  }
  // The state of value v, for messages and tags (nullptr: none).
  const SpoolState* state(double v) const {
    for (const auto& s : states_)
      if (s.value == v) return &s;
    return nullptr;
  }

  EventResult on_event(const Eval<double>& e, double* modes, bool signal_driven) const {
    if (signal_driven) return {};
    auto k = static_cast<std::size_t>(modes[0]);
    EventResult res;
    const double tol = 1e-12 * std::max(1.0, std::abs(e.t()));
    while (k < times_.size() && times_[k] <= e.t() + tol) {
      if (!res.message.empty()) res.message += "; ";
      res.message += messages_[k];
      res.tag = tags_[k];  // of coinciding events, the last
      ++k;
      res.changed = true;
    }
    modes[0] = static_cast<double>(k);
    return res;
  }

 private:
  // When each scheduled command acts: its time, later by the delay of its
  // direction (away from rest or toward it), never before the one before.
  // Without delays, the schedule's own times.
  std::vector<double> acting_times(const Table& rows) const {
    std::vector<double> out;
    double x = x0_;
    for (const auto& row : rows) {
      const double d = delay(x, row[1]);
      out.push_back(out.empty() ? row[0] + d : std::max(row[0] + d, out.back()));
      x = row[1];
    }
    return out;
  }

  void add(double t, double rate_after, std::string message, std::string tag) {
    times_.push_back(t);
    rates_.push_back(rate_after);
    messages_.push_back(std::move(message));
    tags_.push_back(std::move(tag));
  }

  double t_switch_, x0_, delay_actuate_, delay_release_;
  std::vector<SpoolState> states_;
  std::vector<double> times_, rates_;  // event k at times_[k]; dx/dt = rates_[k] after it
  std::vector<std::string> messages_, tags_;
};

// Base of the directional valves: the spool variable, its start value, the
// schedule's time events, a signal-driven spool's delayed command, and
// their handling, which do not depend on the valve's paths. The derived
// valve declares its ports and paths, `modes = kModes`, `roots = kRoots`,
// `follows_inputs`, and writes its spool's row with spool_row(e).
template <class Derived>
class SpoolValve : public ComponentT<Derived> {
 public:
  // The schedule's events passed; the command acting on a signal-driven
  // spool with a delay fault (NaN until the start has been read), the one
  // due next (NaN: none) and when it is due.
  enum Mode { kPassed, kHeld, kPending, kDue, kModes };
  // t - t_due; the signals' distance from the level last commanded.
  static constexpr int kRoots = 2;

  SpoolValve(const Construction& c, int command_port, int spool_var, std::string actuated, std::string rest)
      : ComponentT<Derived>(c),
        spool_(c.params, std::move(actuated), std::move(rest)),
        command_port_(command_port),
        spool_var_(spool_var) {}
  // A valve with a second command port (-1: none): the spool follows the
  // signals once either is connected.
  SpoolValve(const Construction& c, int command_port, int second_command_port, int spool_var,
             const std::vector<SpoolState>& states)
      : ComponentT<Derived>(c),
        spool_(c.params, states),
        command_port_(command_port),
        second_command_port_(second_command_port),
        spool_var_(spool_var) {}

  void start(StartValues& s, const GasModel&) const override { s.fix_var(spool_var_, spool_.x0()); }
  void initial_modes(double* modes) const override {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    modes[kPassed] = 0.0;
    modes[kHeld] = modes[kPending] = nan;
    modes[kDue] = 0.0;
  }
  std::vector<double> time_events() const override { return spool_.time_events(); }
  void roots(const Eval<double>& e, double* g) const override {
    g[0] = g[1] = 1.0;
    if (!delayed(e)) return;
    // Read the signals even before the start's level is held (the nearest
    // level stands in), so that assembly sees what these roots read.
    const double u = command(e);
    const bool pending = !std::isnan(e.mode(kPending));
    const double latest = pending ? e.mode(kPending) : std::isnan(e.mode(kHeld)) ? std::round(u) : e.mode(kHeld);
    g[0] = pending ? e.t() - e.mode(kDue) : -1.0;
    g[1] = 0.5 - std::abs(u - latest);
  }
  EventResult on_event(const Eval<double>& e, double* modes, EventKind kind, int root, int) const override {
    if (kind == EventKind::time) return spool_.on_event(e, modes, signal_driven(e));
    return root == 0 ? act(modes) : follow(e, modes);
  }
  EventResult on_inputs_changed(const Eval<double>& e, double* modes) const override {
    return delayed(e) ? follow(e, modes) : EventResult{};
  }

 protected:
  template <class T>
  bool signal_driven(const Eval<T>& e) const {
    return e.connected(command_port_) || (second_command_port_ >= 0 && e.connected(second_command_port_));
  }
  // The signals' command: the first port's, less the second's (5/3: 14 - 12).
  template <class T>
  T command(const Eval<T>& e) const {
    if (second_command_port_ < 0) return e.signal(command_port_);
    return T(e.signal(command_port_) - e.signal(second_command_port_));
  }
  // The spool's row: the schedule's, or driven by the signals - as they
  // act, held in a mode, where a delay fault delays them.
  template <class T>
  T spool_row(const Eval<T>& e) const {
    if (!signal_driven(e)) return spool_.scheduled(e, spool_var_);
    if (!spool_.delayed() || std::isnan(e.mode(kHeld))) return spool_.driven(e, command(e), spool_var_);
    return spool_.driven(e, T(e.mode(kHeld)), spool_var_);
  }

  SpoolDrive spool_;
  int command_port_, second_command_port_ = -1, spool_var_;

 private:
  template <class T>
  bool delayed(const Eval<T>& e) const {
    return spool_.delayed() && signal_driven(e);
  }
  // The level the signals command now (the nearest state).
  double level(const Eval<double>& e) const { return std::round(command(e)); }
  std::string state_text(double v) const {
    const SpoolState* s = spool_.state(v);
    return s ? format_number(v) + " (" + s->name + ")" : format_number(v);
  }
  // The pending command acts.
  EventResult act(double* modes) const {
    if (std::isnan(modes[kPending])) return {};
    const double v = modes[kPending];
    modes[kHeld] = v;
    modes[kPending] = std::numeric_limits<double>::quiet_NaN();
    const SpoolState* s = spool_.state(v);
    return {true, "command " + state_text(v) + " acts, late", s ? "command_" + s->word : ""};
  }
  // The signals changed (or the start is read): the new level is due after
  // its direction's delay, at once without one; back at the acting level
  // before that, the pending command is lost.
  EventResult follow(const Eval<double>& e, double* modes) const {
    const double u = level(e);
    if (std::isnan(modes[kHeld])) {
      modes[kHeld] = u;  // the command standing at the start has acted
      return {};
    }
    const bool pending = !std::isnan(modes[kPending]);
    if (u == (pending ? modes[kPending] : modes[kHeld])) return {};
    modes[kPending] = std::numeric_limits<double>::quiet_NaN();
    if (u == modes[kHeld]) return {true, "command back to " + state_text(u) + " before the delayed one acted", ""};
    const double d = spool_.delay(modes[kHeld], u);
    if (d <= 0.0) {
      modes[kHeld] = u;
      return {true, "", ""};
    }
    modes[kPending] = u;
    modes[kDue] = e.t() + d;
    return {true, "command " + state_text(u) + " due at t = " + format_number(modes[kDue]) + " s", ""};
  }
};

// One flow path of a valve: an ISO 6358 resistance. Parameters C and b are
// common to all paths; C_XY and b_XY override them for path X -> Y.
struct ValvePath {
  double C, b, leakage;

  static std::vector<ParameterSpec> parameters(const std::vector<std::string>& paths) {
    std::vector<ParameterSpec> out{
        ParameterSpec::scalar("C", "m3/(s*Pa)", "sonic conductance of each path, e.g. 0.5 dm3/(s*bar)").positive(),
        ParameterSpec::scalar("b", "1", "critical pressure ratio of each path", 0.3).range(0.0, 0.99),
    };
    for (const auto& p : paths) {
      const std::string name = std::string(1, p[0]) + " -> " + p[1];
      out.push_back(ParameterSpec::scalar("C_" + p, "m3/(s*Pa)", "conductance of path " + name + " (default C)")
                        .positive()
                        .optional());
      out.push_back(ParameterSpec::scalar("b_" + p, "1", "critical pressure ratio of path " + name + " (default b)")
                        .range(0.0, 0.99)
                        .optional());
    }
    out.push_back(ParameterSpec::scalar("fault_supply_factor", "1",
                                        "fault (diagnosis): factor on the conductance of every path from P (dirt, a "
                                        "kinked or undersized fitting at the supply port); 1 = none",
                                        1.0)
                      .positive());
    out.push_back(ParameterSpec::scalar("fault_leakage", "1",
                                        "fault (diagnosis): fraction of each path's C open whatever the spool (worn "
                                        "spool or seals); 0 = none",
                                        0.0)
                      .range(0.0, 1.0));
    return out;
  }
  static FaultSpec leakage_fault() {
    return {"internal_leak", "leaks across the spool (worn spool or seals): every path a little open",
            {{"leak", "fault_leakage", "1", false, 0.0, 0.0, 0.1, 0.01, false}}};
  }
  // The supply port throttled: a restriction in series with every path
  // from P, as one factor on their conductances.
  static FaultSpec supply_restriction_fault() {
    return {"supply_restricted", "the supply port throttled (dirt, a kinked or undersized fitting at P)",
            {{"k", "fault_supply_factor", "1", false, 1.0, 0.05, 1.0, 0.5, true}}};
  }
  ValvePath(const ParameterValues& v, const std::string& path)
      : C((v.has("C_" + path) ? v["C_" + path] : v["C"]) * (path[0] == 'P' ? v["fault_supply_factor"] : 1.0)),
        b(v.has("b_" + path) ? v["b_" + path] : v["b"]),
        leakage(v["fault_leakage"]) {}

  // Mass flow from `from` to `to` with the fraction `open` of C open (and
  // the leakage fraction whatever `open`: at 0, C open exactly).
  template <class T>
  T mass_flow(const GasPortView<T>& from, const GasPortView<T>& to, const T& open, const GasModel& gas) const {
    return iso6358_mass_flow(from.p, to.p, from.T_in, to.T_in, T(C * with_leakage(open, leakage)), b, 0.999,
                             gas);
  }
};

// Temperature of gas leaving a valve port that two paths feed: the mix of
// what arrives through each, weighted by the (smoothly upwinded) flow toward
// the port. Never 0/0: smooth_pos is positive at zero flow.
template <class T>
T mix_temperature(const T& m1_toward, const T& T1, const T& m2_toward, const T& T2, const GasModel& gas) {
  const T w1 = smooth_pos(m1_toward, gas.m_flow_small), w2 = smooth_pos(m2_toward, gas.m_flow_small);
  return (w1 * T1 + w2 * T2) / (w1 + w2);
}

// Ports P, A, B, R and the row names of a five-port valve (exhausts joined
// in R; the 5/2 and 5/3 valves), the spool's row last.
inline void five_port_valve_info(ComponentInfo& i) {
  i.ports = {{"P", Domain::pneumatic, Causality::acausal, "supply (1)"},
             {"A", Domain::pneumatic, Causality::acausal, "working port A (4)"},
             {"B", Domain::pneumatic, Causality::acausal, "working port B (2)"},
             {"R", Domain::pneumatic, Causality::acausal, "exhaust of A and B (3, 5)"}};
  i.equations = {"flow at P",
                 "flow at A",
                 "flow at B",
                 "flow at R",
                 "temperature out of P",
                 "temperature out of A",
                 "temperature out of B",
                 "temperature out of R",
                 "spool motion"};
}

// The eight port rows of a five-port valve (exhausts joined in R) from its
// four path flows P -> A, P -> B, A -> R, B -> R (5/2 and 5/3 valves).
template <class T>
void five_port_rows(const GasPortView<T>& P, const GasPortView<T>& A, const GasPortView<T>& B,
                    const GasPortView<T>& R, const T& m_PA, const T& m_PB, const T& m_AR, const T& m_BR,
                    const GasModel& gas, T* r) {
  r[0] = P.m_flow - (m_PA + m_PB);
  r[1] = A.m_flow - (m_AR - m_PA);
  r[2] = B.m_flow - (m_BR - m_PB);
  r[3] = R.m_flow + m_AR + m_BR;
  r[4] = P.T_out - mix_temperature(T(-m_PA), A.T_in, T(-m_PB), B.T_in, gas);
  r[5] = A.T_out - mix_temperature(m_PA, P.T_in, T(-m_AR), R.T_in, gas);
  r[6] = B.T_out - mix_temperature(m_PB, P.T_in, T(-m_BR), R.T_in, gas);
  r[7] = R.T_out - mix_temperature(m_AR, A.T_in, m_BR, B.T_in, gas);
}

// Row names for series_port_rows, with the valve's port names.
inline std::vector<std::string> series_port_equations(const std::string& in, const std::string& mid,
                                                      const std::string& ex) {
  return {"flow at " + in,          "flow at " + mid,          "flow at " + ex,
          "temperature out of " + in, "temperature out of " + mid, "temperature out of " + ex};
}

// The six port rows of a valve with a path in -> mid and a path mid -> ex
// (3/2 valve and quick exhaust valve P -> A -> R, pressure regulator).
template <class T>
void series_port_rows(const GasPortView<T>& in, const GasPortView<T>& mid, const GasPortView<T>& ex, const T& m_in,
                      const T& m_ex, const GasModel& gas, T* r) {
  r[0] = in.m_flow - m_in;
  r[1] = mid.m_flow - (m_ex - m_in);
  r[2] = ex.m_flow + m_ex;
  r[3] = in.T_out - mid.T_in;
  r[4] = mid.T_out - mix_temperature(m_in, in.T_in, T(-m_ex), ex.T_in, gas);
  r[5] = ex.T_out - mid.T_in;
}

}  // namespace pneumo::components
