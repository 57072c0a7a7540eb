// The atmosphere: a pressure source at the network's ambient pressure and
// temperature (netlist section `ambient:`), so exhausts need no numbers.
#include "components/builtin.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class Atmosphere final : public ComponentT<Atmosphere> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "atmosphere";
    i.description = "Ambient air: pressure and temperature from the netlist's 'ambient' section.";
    i.symbol = symbols::atmosphere();
    i.ports = {{"port", Domain::pneumatic, Causality::acausal, "gas port"}};
    i.equations = {"ambient pressure", "ambient temperature"};
    return i;
  }
  explicit Atmosphere(const Construction& c) : ComponentT(c) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto port = e.gas_port(0);
    r[0] = port.p - e.gas().p_ambient;
    r[1] = port.T_out - e.gas().T_ambient;
  }
  void start(StartValues& s, const GasModel& gas) const override {
    s.guess_pressure(0, gas.p_ambient);
    s.guess_temperature(0, gas.T_ambient);
  }
};

void register_atmosphere(Registry& r) { r.add<Atmosphere>(); }

}  // namespace pneumo::components
