// Pressure sensor on a pneumatic port: draws no flow, outputs the absolute
// pressure through a first-order lag (sensor_lag.hpp).
#include <cmath>
#include <limits>

#include "components/builtin.hpp"
#include "components/sensor_lag.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class PressureSensor final : public ComponentT<PressureSensor> {
 public:
  enum Port { kPort, kP };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "pressure_sensor";
    i.description = "Pressure sensor (no flow): signal p = absolute pressure at the port, through a PT1 lag tau.";
    i.symbol = symbols::gauge("port", "p", "p");
    i.parameters = {
        pt1_tau_parameter("the output"),
        ParameterSpec::scalar("p0", "Pa", "initial output if tau > 0 (default: ambient pressure)")
            .positive()
            .optional().absolute(),
    };
    for (auto& p : SensorCalibration::parameters("Pa")) i.parameters.push_back(std::move(p));
    i.ports = {{"port", Domain::pneumatic, Causality::acausal, "gas port (tapped, no flow)"},
               {"p", Domain::signal, Causality::output, "measured pressure, Pa absolute", true}};
    // The output again as an observable, so that result columns carry the unit.
    i.observables = {{"p", "Pa", "measured pressure, absolute"}};
    i.equations = {"no flow", "stream temperature", "measured pressure"};
    i.faults = SensorCalibration::faults("Pa", 1e5);
    return i;
  }

  explicit PressureSensor(const Construction& c)
      : ComponentT(c),
        tau_(c.params["tau"]),
        cal_(c.params),
        p0_(c.params.has("p0") ? c.params["p0"] : std::numeric_limits<double>::quiet_NaN()) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto port = e.gas_port(kPort);
    r[0] = port.m_flow;
    r[1] = port.T_out - port.T_in;
    r[2] = pt1_residual(e, kP, cal_.reading(port.p), tau_);
  }

  double observe(int, const Eval<double>& e) const override { return e.signal(kP); }

  void start(StartValues& s, const GasModel& gas) const override {
    const double p0 = std::isnan(p0_) ? gas.p_ambient : p0_;
    pt1_start(s, port_offset(kP), tau_, p0);
  }

 private:
  double tau_;
  SensorCalibration cal_;
  double p0_;
};

void register_pressure_sensor(Registry& r) { r.add<PressureSensor>(); }

}  // namespace pneumo::components
