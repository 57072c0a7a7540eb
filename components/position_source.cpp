// A flange made to follow a prescribed position s_ref (parameter s or signal
// 's_in') by a stiff servo of infinite power: its velocity is the
// feed-forward 'v_in' (when connected) plus (s_ref - s)/tau. A hard
// constraint s = s_ref(t) would differentiate a replayed, quantised
// position twice through the rod's mass (a higher-index DAE); the servo
// keeps the DAE index 1 and follows within tau * |dv_ref| of the reference.
// Like velocity_source it sets the flange's velocity: the flange must carry
// no mass of its own (a cylinder's rod, a sensor, a friction element); a
// translational_mass goes behind a spring_damper.
#include "components/builtin.hpp"

namespace pneumo::components {

class PositionSource final : public ComponentT<PositionSource> {
 public:
  enum Port { kFlange, kS, kV };
  enum Obs { kF, kP };
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "position_source";
    i.description =
        "Moves the flange to follow position s (signal 's_in' replaces s) as a stiff servo of infinite power: "
        "v = v_in + (s_ref - s)/tau, v_in the optional velocity feed-forward (a data_signal's dy). Starts at s0.";
    i.parameters = {ParameterSpec::scalar("s", "m", "prescribed position", 0.0),
                    ParameterSpec::scalar("s0", "m", "initial position", 0.0),
                    ParameterSpec::scalar("tau", "s", "servo time constant", 1e-3).positive()};
    i.ports = {{"flange", Domain::translational, Causality::acausal, "driven flange"},
               {"s_in", Domain::signal, Causality::input, "position in m; replaces s when connected", true},
               {"v_in", Domain::signal, Causality::input, "velocity feed-forward in m/s", true}};
    i.observables = {{"F", "N", "force the drive exerts on the flange (+s)"}, {"P", "W", "drive power F v"}};
    i.equations = {"position servo"};
    return i;
  }
  explicit PositionSource(const Construction& c)
      : ComponentT(c), s_(c.params["s"]), s0_(c.params["s0"]), tau_(c.params["tau"]) {}
  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto fl = e.flange(kFlange);
    const T s_ref = e.connected(kS) ? e.signal(kS) : T(s_);
    const T v_ff = e.connected(kV) ? e.signal(kV) : T(0.0);
    r[0] = fl.v - v_ff - (s_ref - fl.s) / tau_;
  }
  void start(StartValues& s, const GasModel&) const override { s.fix_position(kFlange, s0_); }
  double observe(int k, const Eval<double>& e) const override {
    const auto fl = e.flange(kFlange);
    return k == kF ? -fl.f : -fl.f * fl.v;
  }

 private:
  double s_, s0_, tau_;
};

void register_position_source(Registry& r) { r.add<PositionSource>(); }

}  // namespace pneumo::components
