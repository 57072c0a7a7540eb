// 3/2 directional valve: actuated (state 1) P -> A, at rest (state 0)
// A -> R; each path an ISO 6358 resistance; the spool follows a schedule or
// a command signal with a linear ramp (valve_command.hpp).
#include "components/builtin.hpp"
#include "components/symbols.hpp"
#include "components/valve_command.hpp"

namespace pneumo::components {

class DirectionalValve32 final : public SpoolValve<DirectionalValve32> {
 public:
  enum Port { kP, kA, kR, kCommand };
  enum Var { kX };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "directional_valve_32";
    i.description =
        "3/2 directional valve: state 1 P -> A, state 0 A -> R; each path ISO 6358 (C, b); the spool ramps linearly "
        "over t_switch_time after each command from 'schedule' (time events) or the signal 'command'.";
    i.symbol = symbols::valve_32();
    i.parameters = ValvePath::parameters({"PA", "AR"});
    for (auto& p : SpoolDrive::parameters()) i.parameters.push_back(std::move(p));
    i.ports = {{"P", Domain::pneumatic, Causality::acausal, "supply"},
               {"A", Domain::pneumatic, Causality::acausal, "working port"},
               {"R", Domain::pneumatic, Causality::acausal, "exhaust"},
               {"command", Domain::signal, Causality::input, "commanded state 0/1 (overrides 'schedule')", true, 0.0}};
    i.variables = {{"x", "1", "spool position: 0 rest (A -> R open), 1 actuated (P -> A open)", 1.0}};
    i.modes = kModes;
    i.roots = kRoots;
    i.follows_inputs = true;  // a delayed command (a fault) follows the signals
    i.equations = {
        "flow at P",   "flow at A", "flow at R", "temperature out of P", "temperature out of A", "temperature out of R",
        "spool motion"};
    i.faults = SpoolDrive::faults();
    i.events = SpoolDrive::events();
    i.faults.push_back(ValvePath::leakage_fault());
    i.faults.push_back(ValvePath::supply_restriction_fault());
    return i;
  }

  explicit DirectionalValve32(const Construction& c)
      : SpoolValve(c, kCommand, kX, "P->A", "A->R"), PA_(c.params, "PA"), AR_(c.params, "AR") {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto P = e.gas_port(kP), A = e.gas_port(kA), R = e.gas_port(kR);
    const GasModel& gas = e.gas();
    const T x = SpoolDrive::actuated_fraction(e, kX);
    const T m_PA = PA_.mass_flow(P, A, x, gas);
    const T m_AR = AR_.mass_flow(A, R, T(1.0 - x), gas);
    series_port_rows(P, A, R, m_PA, m_AR, gas, r);
    r[6] = spool_row(e);
  }

 private:
  ValvePath PA_, AR_;
};

void register_directional_valve_32(Registry& r) { r.add<DirectionalValve32>(); }

}  // namespace pneumo::components
