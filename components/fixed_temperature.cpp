// Ideal heat reservoir: holds its port at a fixed temperature.
#include "components/builtin.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class FixedTemperature final : public ComponentT<FixedTemperature> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "fixed_temperature";
    i.description = "Heat reservoir at a fixed temperature (default: ambient).";
    i.symbol = symbols::thermal_box("T");
    i.parameters = {ParameterSpec::scalar("T", "K", "temperature; 0 = the netlist's ambient temperature", 0.0)
                        .non_negative()};
    i.ports = {{"port", Domain::thermal, Causality::acausal, "heat port"}};
    i.equations = {"fixed temperature"};
    return i;
  }
  explicit FixedTemperature(const Construction& c) : ComponentT(c), T_(c.params["T"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.heat_port(0).T - (T_ > 0 ? T_ : e.gas().T_ambient);
  }
  void start(StartValues& s, const GasModel& gas) const override {
    s.guess_temperature(0, T_ > 0 ? T_ : gas.T_ambient);
  }

 private:
  double T_;
};

void register_fixed_temperature(Registry& r) { r.add<FixedTemperature>(); }

}  // namespace pneumo::components
