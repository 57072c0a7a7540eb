// Lumped thermal capacity: C dT/dt = Q (a wall, a cylinder body).
#include "components/builtin.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class ThermalMass final : public ComponentT<ThermalMass> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "thermal_mass";
    i.description = "Lumped heat capacity C dT/dt = Q.";
    i.symbol = symbols::thermal_box("C");
    i.parameters = {
        ParameterSpec::scalar("C", "J/K", "heat capacity (mass times specific heat)").positive(),
        ParameterSpec::scalar("T0", "K", "initial temperature; default: ambient").positive().ambient_temperature_by_default(),
    };
    i.ports = {{"port", Domain::thermal, Causality::acausal, "heat port"}};
    i.equations = {"energy balance"};
    return i;
  }
  explicit ThermalMass(const Construction& c) : ComponentT(c), C_(c.params["C"]), T0_(c.params["T0"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto port = e.heat_port(0);
    r[0] = C_ * e.yp(e.port_offset(0)) - port.Q;
  }
  void start(StartValues& s, const GasModel&) const override { s.fix_local(port_offset(0), T0_); }

 private:
  double C_, T0_;
};

void register_thermal_mass(Registry& r) { r.add<ThermalMass>(); }

}  // namespace pneumo::components
