// Limit switch on a translational flange (a cylinder's rod, a slide): output
// 1 while the flange's position s is in the window position +- window / 2,
// with hysteresis (switching.hpp). No force. Switched by root functions, so
// the instant the cam reaches the switch is an event in the log
// (COMPONENT.on / COMPONENT.off).
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/switching.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class LimitSwitch final : public WindowSwitchComponent<LimitSwitch> {
 public:
  enum Port { kFlange, kOut };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "limit_switch";
    i.description =
        "Limit switch (no force): signal y = 1 while the flange position is within position +- window/2; once on, "
        "off only beyond the window widened by hysteresis. Switches at root-located events (tags on, off).";
    i.symbol = symbols::limit_switch();
    i.parameters = {
        ParameterSpec::scalar("position", "m", "where the switch sits (e.g. 0 for a retracted, the stroke for an "
                                                 "extended cylinder)"),
        ParameterSpec::scalar("window", "m", "length of travel over which the switch is actuated", 2e-3).positive(),
        ParameterSpec::scalar("hysteresis", "m", "extra travel beyond the window before it releases", 0.1e-3)
            .non_negative(),
        fault_parameter("fault_shift", "m", "switch sits this far off its position along the travel"),
    };
    i.ports = {{"flange", Domain::translational, Causality::acausal, "sensed flange (no force)"},
               {"y", Domain::signal, Causality::output, "switch state 0/1", true}};
    i.observables = {{"state", "1", "switch state 0/1"}};
    i.equations = {"no force", "switch output"};
    i.modes = 1;
    i.roots = 2;
    i.events = {{"on", "switches on"}, {"off", "switches off"}};
    i.follows_inputs = true;  // its state at the start is read from the initial position
    i.faults = {setting_fault("misplaced", "switches early or late: the switch slipped on its mounting or the cam is bent",
                      {fault_amount("ds", "fault_shift", "m", -20e-3, 20e-3, 1e-3)})};
    i.faults.back().needs_port = "y";
    return i;
  }

  explicit LimitSwitch(const Construction& c)
      : WindowSwitchComponent(c,
                              {c.params["position"] + c.params["fault_shift"] - 0.5 * c.params["window"],
                               c.params["position"] + c.params["fault_shift"] + 0.5 * c.params["window"],
                               c.params["hysteresis"]},
                              "s", "m") {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.flange(kFlange).f;
    r[1] = e.signal(kOut) - e.mode(0);
  }
  double measured(const Eval<double>& e) const { return e.flange(kFlange).s; }
};

void register_limit_switch(Registry& r) { r.add<LimitSwitch>(); }

}  // namespace pneumo::components
