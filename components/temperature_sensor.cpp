// Gas temperature sensor (e.g. the thermocouple of paper [1], tau = 15 ms) on
// a pneumatic port: draws no flow and measures the stream temperature T_in of
// the gas at the port through a first-order lag (sensor_lag.hpp). T_in is the
// framework's mix of the gas flowing INTO the node, so on a volume that
// discharges or is at rest it is the volume's gas temperature (the seed's
// cushion chamber); while the volume fills, it is the temperature of the
// incoming stream, like a probe sitting in the inlet jet - for the mean gas
// temperature of a filling chamber output the volume's T instead. A separate
// component from the pressure sensor because the two have separate lags and
// initial values and are usually placed independently.
#include <cmath>
#include <limits>

#include "components/builtin.hpp"
#include "components/sensor_lag.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class TemperatureSensor final : public ComponentT<TemperatureSensor> {
 public:
  enum Port { kPort, kT };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "temperature_sensor";
    i.description =
        "Gas temperature sensor (no flow): signal T = temperature of the gas arriving at the port, through a PT1 lag "
        "tau (paper [1]: thermocouple, tau = 15 ms).";
    i.symbol = symbols::gauge("port", "T", "T");
    i.parameters = {
        pt1_tau_parameter("the output"),
        ParameterSpec::scalar("T0", "K", "initial output if tau > 0 (default: ambient temperature)")
            .positive()
            .optional(),
    };
    for (auto& p : SensorCalibration::parameters("K")) i.parameters.push_back(std::move(p));
    i.ports = {{"port", Domain::pneumatic, Causality::acausal, "gas port (tapped, no flow)"},
               {"T", Domain::signal, Causality::output, "measured temperature, K", true}};
    // The output again as an observable, so that result columns carry the unit.
    i.observables = {{"T", "K", "measured temperature"}};
    i.equations = {"no flow", "stream temperature", "measured temperature"};
    i.faults = SensorCalibration::faults("K", 10.0);
    return i;
  }

  explicit TemperatureSensor(const Construction& c)
      : ComponentT(c),
        tau_(c.params["tau"]),
        cal_(c.params),
        T0_(c.params.has("T0") ? c.params["T0"] : std::numeric_limits<double>::quiet_NaN()) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto port = e.gas_port(kPort);
    r[0] = port.m_flow;
    r[1] = port.T_out - port.T_in;
    r[2] = pt1_residual(e, kT, cal_.reading(port.T_in), tau_);
  }

  double observe(int, const Eval<double>& e) const override { return e.signal(kT); }

  void start(StartValues& s, const GasModel& gas) const override {
    const double T0 = std::isnan(T0_) ? gas.T_ambient : T0_;
    pt1_start(s, port_offset(kT), tau_, T0);
  }

 private:
  double tau_;
  SensorCalibration cal_;
  double T0_;
};

void register_temperature_sensor(Registry& r) { r.add<TemperatureSensor>(); }

}  // namespace pneumo::components
