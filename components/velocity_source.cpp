// A flange moved at a prescribed velocity (a drive of infinite power), from
// the parameter v or a signal input; its position integrates from s0.
#include "components/builtin.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class VelocitySource final : public ComponentT<VelocitySource> {
 public:
  enum Port { kFlange, kV };
  enum Obs { kF, kP };
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "velocity_source";
    i.description = "Drives the flange at velocity v (signal 'v_in' replaces v); starts at position s0.";
    i.symbol = symbols::mechanical("v", {{"flange", 0, 20, 'l'}, {"v_in", 40, 20, 'r'}});
    i.parameters = {ParameterSpec::scalar("v", "m/s", "velocity in +s", 0.0),
                    ParameterSpec::scalar("s0", "m", "initial position", 0.0)};
    i.ports = {{"flange", Domain::translational, Causality::acausal, "driven flange"},
               {"v_in", Domain::signal, Causality::input, "velocity in m/s; replaces v when connected", true}};
    i.observables = {{"F", "N", "force the drive exerts on the flange (+s)"}, {"P", "W", "drive power F v"}};
    i.equations = {"prescribed velocity"};
    return i;
  }
  explicit VelocitySource(const Construction& c) : ComponentT(c), v_(c.params["v"]), s0_(c.params["s0"]) {}
  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const T v = e.connected(kV) ? e.signal(kV) : T(v_);
    r[0] = e.flange(kFlange).v - v;
  }
  void start(StartValues& s, const GasModel&) const override { s.fix_position(kFlange, s0_); }
  double observe(int k, const Eval<double>& e) const override {
    const auto fl = e.flange(kFlange);
    return k == kF ? -fl.f : -fl.f * fl.v;
  }

 private:
  double v_, s0_;
};

void register_velocity_source(Registry& r) { r.add<VelocitySource>(); }

}  // namespace pneumo::components
