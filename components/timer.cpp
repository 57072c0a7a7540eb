// Timer (time relay) on a 0/1 signal. on_delay: y rises `delay` after the
// input rose and stayed high, falls with the input. off_delay: y rises with
// the input, falls `delay` after it fell and stayed low. The due time is
// kept in a mode and reached as the root of t - t_due (a time event found at
// run time); input changes are read at roots of in - 0.5 and by the event
// iteration (an input that jumps at another component's event).
#include <string>

#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/switching.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class Timer final : public ComponentT<Timer> {
 public:
  enum Port { kIn, kOut };
  enum Mode { kState, kRunning, kDue };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "timer";
    i.description =
        "Time relay: on_delay - y = 1 once the input has been 1 for delay, 0 with the input; off_delay - y = 1 with "
        "the input, 0 once it has been 0 for delay. Events: start, elapsed, cancel, reset (on_delay), set (off_delay).";
    i.symbol = symbols::function_block("T");
    i.parameters = {
        ParameterSpec::text("kind", {"on_delay", "off_delay"}, "which edge is delayed", "on_delay"),
        ParameterSpec::scalar("delay", "s", "delay").positive(),
    };
    i.ports = {{"in", Domain::signal, Causality::input, "input 0/1"},
               {"y", Domain::signal, Causality::output, "delayed output 0/1", true}};
    i.observables = {{"state", "1", "output 0/1"}};
    i.equations = {"timer output"};
    i.modes = 3;  // output, running, due time
    i.roots = 2;  // t - t_due, in - 0.5
    i.events = {{"start", "the delay starts"},
                {"elapsed", "the delay has elapsed: the output switches"},
                {"cancel", "the input changed back before the delay"},
                {"set", "off_delay: the output goes to 1 with the input"},
                {"reset", "on_delay: the output goes to 0 with the input"}};
    i.follows_inputs = true;
    i.faults = {setting_fault("misadjusted", "delay off its setting (dial turned, drifted)", {fault_factor("delay", 0.5, 2.0, 1.1)})};
    i.faults.back().needs_port = "y";
    return i;
  }

  explicit Timer(const Construction& c)
      : ComponentT(c), on_delay_(c.params.text("kind") == "on_delay"), delay_(c.params["delay"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.signal(kOut) - e.mode(kState);
  }
  double observe(int, const Eval<double>& e) const override { return e.mode(kState); }

  void roots(const Eval<double>& e, double* g) const override {
    g[0] = e.mode(kRunning) > 0.5 ? e.t() - e.mode(kDue) : -1.0;
    g[1] = e.signal(kIn) - 0.5;
  }
  EventResult on_event(const Eval<double>& e, double* modes, EventKind, int root, int direction) const override {
    if (root == 0) {
      if (modes[kRunning] < 0.5) return {};
      modes[kRunning] = 0.0;
      modes[kState] = on_delay_ ? 1.0 : 0.0;  // the opposite of armed
      return {true, "delay elapsed, output " + std::string(on_delay_ ? "1" : "0"), "elapsed"};
    }
    return follow(e, modes, high(e.signal(kIn), direction));
  }
  EventResult on_inputs_changed(const Eval<double>& e, double* modes) const override {
    return follow(e, modes, high(e.signal(kIn)));
  }

 private:
  // `in`: the input's level. The timer runs while the timed level lasts
  // (on_delay: 1, off_delay: 0) with the output at `armed`.
  EventResult follow(const Eval<double>& e, double* modes, bool in) const {
    const double armed = on_delay_ ? 0.0 : 1.0;
    const bool running = modes[kRunning] > 0.5;
    if (in == on_delay_) {
      if (running || modes[kState] != armed) return {};
      modes[kRunning] = 1.0;
      modes[kDue] = e.t() + delay_;
      return {true, "started, due at t = " + format_number(modes[kDue]) + " s", "start"};
    }
    if (running) {
      modes[kRunning] = 0.0;
      return {true, "cancelled: the input changed back before the delay", "cancel"};
    }
    if (modes[kState] == armed) return {};
    modes[kState] = armed;
    return {true, "output " + format_number(armed) + " with the input", on_delay_ ? "reset" : "set"};
  }

  bool on_delay_;
  double delay_;
};

void register_timer(Registry& r) { r.add<Timer>(); }

}  // namespace pneumo::components
