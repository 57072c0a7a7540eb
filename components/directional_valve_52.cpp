// 5/2 directional valve: actuated (state 1) P -> A and B -> R, at rest
// (state 0) P -> B and A -> R (both exhausts joined in R); each path an
// ISO 6358 resistance; the spool follows a schedule or a command signal with
// a linear ramp (valve_command.hpp).
#include "components/builtin.hpp"
#include "components/symbols.hpp"
#include "components/valve_command.hpp"

namespace pneumo::components {

class DirectionalValve52 final : public SpoolValve<DirectionalValve52> {
 public:
  enum Port { kP, kA, kB, kR, kCommand };
  enum Var { kX };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "directional_valve_52";
    i.description =
        "5/2 directional valve: state 1 P -> A and B -> R, state 0 P -> B and A -> R (exhausts joined in R); each "
        "path ISO 6358 (C, b); the spool ramps linearly over t_switch_time after each command from 'schedule' (time "
        "events) or the signal 'command'.";
    i.symbol = symbols::valve_52();
    i.parameters = ValvePath::parameters({"PA", "PB", "AR", "BR"});
    for (auto& p : SpoolDrive::parameters()) i.parameters.push_back(std::move(p));
    five_port_valve_info(i);
    i.ports.push_back(
        {"command", Domain::signal, Causality::input, "commanded state 0/1 (overrides 'schedule')", true, 0.0});
    i.variables = {{"x", "1", "spool position: 0 rest (P -> B, A -> R), 1 actuated (P -> A, B -> R)", 1.0}};
    i.modes = kModes;
    i.roots = kRoots;
    i.follows_inputs = true;  // a delayed command (a fault) follows the signals
    i.faults = SpoolDrive::faults();
    i.events = SpoolDrive::events();
    i.faults.push_back(ValvePath::leakage_fault());
    i.faults.push_back(ValvePath::supply_restriction_fault());
    return i;
  }

  explicit DirectionalValve52(const Construction& c)
      : SpoolValve(c, kCommand, kX, "P->A, B->R", "P->B, A->R"),
        PA_(c.params, "PA"),
        PB_(c.params, "PB"),
        AR_(c.params, "AR"),
        BR_(c.params, "BR") {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto P = e.gas_port(kP), A = e.gas_port(kA), B = e.gas_port(kB), R = e.gas_port(kR);
    const GasModel& gas = e.gas();
    const T x = SpoolDrive::actuated_fraction(e, kX);
    const T m_PA = PA_.mass_flow(P, A, x, gas);
    const T m_BR = BR_.mass_flow(B, R, x, gas);
    const T m_PB = PB_.mass_flow(P, B, T(1.0 - x), gas);
    const T m_AR = AR_.mass_flow(A, R, T(1.0 - x), gas);
    five_port_rows(P, A, B, R, m_PA, m_PB, m_AR, m_BR, gas, r);
    r[8] = spool_row(e);
  }

 private:
  ValvePath PA_, PB_, AR_, BR_;
};

void register_directional_valve_52(Registry& r) { r.add<DirectionalValve52>(); }

}  // namespace pneumo::components
