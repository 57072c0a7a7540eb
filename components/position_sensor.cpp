// Position sensor on a translational flange: exerts no force, outputs the
// position s and velocity v through first-order lags (sensor_lag.hpp).
#include "components/builtin.hpp"
#include "components/sensor_lag.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class PositionSensor final : public ComponentT<PositionSensor> {
 public:
  enum Port { kFlange, kS, kV };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "position_sensor";
    i.description = "Position/velocity sensor (no force): signals s and v of the flange, through a PT1 lag tau.";
    i.symbol = symbols::position_sensor();
    i.parameters = {
        pt1_tau_parameter("both outputs"),
        ParameterSpec::scalar("s0", "m", "initial position output if tau > 0", 0.0),
        ParameterSpec::scalar("v0", "m/s", "initial velocity output if tau > 0", 0.0),
    };
    // One transducer: its calibration acts on the position; the velocity is its derivative.
    for (auto& p : SensorCalibration::parameters("m")) i.parameters.push_back(std::move(p));
    i.ports = {{"flange", Domain::translational, Causality::acausal, "flange (no force)"},
               {"s", Domain::signal, Causality::output, "measured position, m", true},
               {"v", Domain::signal, Causality::output, "measured velocity, m/s", true}};
    // The outputs again as observables, so that result columns carry the units.
    i.observables = {{"s", "m", "measured position"}, {"v", "m/s", "measured velocity"}};
    i.equations = {"no force", "measured position", "measured velocity"};
    i.faults = SensorCalibration::faults("m", 0.01);
    return i;
  }

  explicit PositionSensor(const Construction& c)
      : ComponentT(c), tau_(c.params["tau"]), cal_(c.params), s0_(c.params["s0"]), v0_(c.params["v0"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto fl = e.flange(kFlange);
    r[0] = fl.f;
    r[1] = pt1_residual(e, kS, cal_.reading(fl.s), tau_);
    r[2] = pt1_residual(e, kV, T(cal_.gain * fl.v), tau_);
  }

  double observe(int k, const Eval<double>& e) const override { return e.signal(k == 0 ? kS : kV); }

  void start(StartValues& s, const GasModel&) const override {
    if (tau_ > 0.0) {
      s.fix_local(port_offset(kS), s0_);
      s.fix_local(port_offset(kV), v0_);
    }
  }

 private:
  double tau_;
  SensorCalibration cal_;
  double s0_, v0_;
};

void register_position_sensor(Registry& r) { r.add<PositionSensor>(); }

}  // namespace pneumo::components
