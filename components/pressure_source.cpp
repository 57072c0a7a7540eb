// Ideal pressure source: holds its port at a given absolute pressure and
// delivers gas at a given temperature, whatever the flow. An optional signal
// input replaces the pressure parameter (e.g. a supply pressure schedule).
#include "components/builtin.hpp"

namespace pneumo::components {

class PressureSource final : public ComponentT<PressureSource> {
 public:
  enum Port { kPort, kPressure };
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "pressure_source";
    i.description = "Ideal pressure source (absolute pressure p, delivered gas temperature T).";
    i.parameters = {
        ParameterSpec::scalar("p", "Pa", "pressure, absolute (write '6 barg' for gauge)").positive(),
        ParameterSpec::scalar("T", "K", "temperature of the delivered gas", 293.15).positive(),
    };
    i.ports = {{"port", Domain::pneumatic, Causality::acausal, "gas port"},
               {"p_in", Domain::signal, Causality::input, "pressure in Pa abs; replaces p when connected", true}};
    i.equations = {"pressure", "delivered temperature"};
    return i;
  }
  explicit PressureSource(const Construction& c) : ComponentT(c), p_(c.params["p"]), T_(c.params["T"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto port = e.gas_port(kPort);
    const T p = e.connected(kPressure) ? e.signal(kPressure) : T(p_);
    r[0] = port.p - p;
    r[1] = port.T_out - T_;
  }
  void start(StartValues& s, const GasModel&) const override {
    s.guess_pressure(kPort, p_);
    s.guess_temperature(kPort, T_);
  }

 private:
  double p_, T_;
};

void register_pressure_source(Registry& r) { r.add<PressureSource>(); }

}  // namespace pneumo::components
