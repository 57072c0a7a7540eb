// Discrete signal helpers shared by the switching components (limit and
// pressure switches, timer, flip-flop, sequencer). Their outputs are 0/1
// modes changed only at events: a root of a measured quantity, or the event
// iteration after another component's modes changed
// (Component::on_inputs_changed), so the integrator never steps across a jump.
#pragma once

#include <cmath>
#include <sstream>
#include <string>
#include <utility>

#include "framework/model/component.hpp"

namespace pneumo::components {

// A signal read as a logic level: high above 0.5. At a root of u - 0.5 the
// located point may sit exactly on 0.5; the crossing's direction decides.
inline bool high(double u, int direction = 0) { return direction != 0 ? direction > 0 : u > 0.5; }

inline std::string format_number(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

// On while a measured quantity q is in [lo, hi]; once on, off only when q
// leaves (lo - h, hi + h): the hysteresis h keeps a switch at rest on an
// edge (a piston on its end stop) from chattering. hi may be +infinity.
struct WindowSwitch {
  double lo, hi, h;

  // Root functions: both positive exactly while the state should stay as it is
  // (on: inside the widened window; off: these cross into the window).
  void roots(double q, double mode, double* g) const {
    const double widen = mode > 0.5 ? h : 0.0;
    g[0] = q - (lo - widen);
    g[1] = std::isinf(hi) ? 1.0 : (hi + widen) - q;
  }
  // Sets the mode from q; `what` names q in the log ("s", "p").
  EventResult update(double q, double* mode, const std::string& what, const std::string& unit) const {
    const bool on = *mode > 0.5;
    const bool next = on ? (q > lo - h && q < hi + h) : (q >= lo && q <= hi);
    if (next == on) return {};
    *mode = next ? 1.0 : 0.0;
    return {true, std::string(next ? "on" : "off") + " at " + what + " = " + format_number(q) + " " + unit,
            next ? "on" : "off"};
  }
};

// Base of the switches on a measured quantity (limit_switch,
// pressure_switch): state in mode 0, observable 0 the state, switched at the
// roots of its window and, at the start, by the event iteration. The derived
// class defines  double measured(const Eval<double>&) const.
template <class Derived>
class WindowSwitchComponent : public ComponentT<Derived> {
 public:
  WindowSwitchComponent(const Construction& c, WindowSwitch window, std::string what, std::string unit)
      : ComponentT<Derived>(c), window_(window), what_(std::move(what)), unit_(std::move(unit)) {}

  double observe(int, const Eval<double>& e) const override { return e.mode(0); }
  void roots(const Eval<double>& e, double* g) const override { window_.roots(measured(e), e.mode(0), g); }
  EventResult on_event(const Eval<double>& e, double* modes, EventKind, int, int) const override {
    return on_inputs_changed(e, modes);
  }
  EventResult on_inputs_changed(const Eval<double>& e, double* modes) const override {
    return window_.update(measured(e), modes, what_, unit_);
  }

 private:
  double measured(const Eval<double>& e) const { return static_cast<const Derived&>(*this).measured(e); }

  WindowSwitch window_;
  std::string what_, unit_;
};

}  // namespace pneumo::components
