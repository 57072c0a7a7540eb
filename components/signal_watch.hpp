// An input signal that a component can use only above some value (an
// absolute pressure > 0, an opening >= 0) and otherwise clamps. The clamp
// keeps the run going; the user is told once a run, in the event log, naming
// the component (the log's), the input, its value and the time (the
// event's): when the input starts out of range or jumps there (the event
// iteration), or crosses out of range (a root). Whether a signal is constant
// is not known at load, so a constant out-of-range input is reported at
// t = 0.
//
// A component with a watch declares one root and follows_inputs (declare),
// and forwards initial_modes, roots, on_event and on_inputs_changed here.
// "Told" is no mode: a component with modes is kept out of alias
// elimination (its rows could change at events), which slowed the cushion
// rig measurably for a flag that changes no equation. It is kept per thread
// (framework/model/per_thread.hpp: threads may integrate one System at
// once), reset at every run's start (initial_modes); a thread runs one
// integration of a System at a time.
#pragma once

#include <sstream>
#include <string>

#include "framework/model/component.hpp"
#include "framework/model/per_thread.hpp"

namespace pneumo::components {

class SignalWatch {
 public:
  // `threshold`: values below are out of range; `range` and `then` as the
  // user reads them ("an absolute pressure, at least 1 Pa"; what the
  // component does with such values).
  SignalWatch(int port, std::string name, std::string unit, double threshold, std::string range, std::string then)
      : port_(port), name_(std::move(name)), unit_(std::move(unit)), threshold_(threshold), range_(std::move(range)),
        then_(std::move(then)) {}

  static void declare(ComponentInfo& i) {
    i.roots += 1;
    i.follows_inputs = true;
  }
  void reset() const { told_.get() = false; }
  // Unconnected, the input holds its default, which is in range.
  double root(const Eval<double>& e) const { return e.connected(port_) ? e.signal(port_) - threshold_ : 1.0; }

  // At the start and after every event.
  EventResult check(const Eval<double>& e) const {
    if (told_.get() || !(root(e) < 0.0)) return {};
    std::ostringstream v;
    v << e.signal(port_) << (unit_.empty() ? "" : " ") << unit_;
    return tell("= " + v.str() + " is out of range");
  }
  // The root crossing: direction < 0 leaves the range.
  EventResult crossed(int direction) const {
    if (direction > 0 || told_.get()) return {};
    return tell("leaves its range here");
  }

 private:
  EventResult tell(const std::string& what) const {
    told_.get() = true;
    return {false, "warning: input '" + name_ + "' " + what + " (" + range_ + "); " + then_ + " (said once a run)"};
  }
  int port_;
  std::string name_, unit_;
  double threshold_;
  std::string range_, then_;
  PerThread<bool, 64> told_;
};

}  // namespace pneumo::components
