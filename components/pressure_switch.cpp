// Pressure switch on a pneumatic port (draws no flow): output 1 once the
// absolute pressure reaches p_on, back to 0 when it falls below
// p_on - hysteresis. Gauge settings are written with a gauge unit
// ("4 barg"). Switched by root functions (tags on, off).
#include <limits>

#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/switching.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class PressureSwitch final : public WindowSwitchComponent<PressureSwitch> {
 public:
  enum Port { kPort, kOut };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "pressure_switch";
    i.description =
        "Pressure switch (no flow): signal y = 1 from p >= p_on (absolute; write '4 barg' for gauge) until p < p_on - "
        "hysteresis. Switches at root-located events (tags on, off).";
    i.symbol = symbols::gauge("port", "y", "p>");
    i.parameters = {
        ParameterSpec::scalar("p_on", "Pa", "switching pressure, absolute").positive().absolute(),
        ParameterSpec::scalar("hysteresis", "Pa", "fall below p_on before it releases", 0.2e5).non_negative(),
        fault_parameter("fault_p_on_shift", "Pa", "switching pressure off its setting by this much"),
    };
    i.ports = {{"port", Domain::pneumatic, Causality::acausal, "gas port (tapped, no flow)"},
               {"y", Domain::signal, Causality::output, "switch state 0/1", true}};
    i.observables = {{"state", "1", "switch state 0/1"}};
    i.equations = {"no flow", "stream temperature", "switch output"};
    i.modes = 1;
    i.roots = 2;
    i.events = {{"on", "switches on"}, {"off", "switches off"}};
    i.follows_inputs = true;  // its state at the start is read from the initial pressure
    i.faults = {setting_fault("misadjusted", "switches below or above its setting (set screw turned, spring drifted)",
                      {fault_amount("dp", "fault_p_on_shift", "Pa", -1e5, 1e5, 1e4)})};
    i.faults.back().needs_port = "y";
    return i;
  }

  explicit PressureSwitch(const Construction& c)
      : WindowSwitchComponent(c,
                              {c.params["p_on"] + c.params["fault_p_on_shift"], std::numeric_limits<double>::infinity(),
                               c.params["hysteresis"]},
                              "p", "Pa") {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto port = e.gas_port(kPort);
    r[0] = port.m_flow;
    r[1] = port.T_out - port.T_in;
    r[2] = e.signal(kOut) - e.mode(0);
  }
  double measured(const Eval<double>& e) const { return e.gas_port(kPort).p; }
};

void register_pressure_switch(Registry& r) { r.add<PressureSwitch>(); }

}  // namespace pneumo::components
