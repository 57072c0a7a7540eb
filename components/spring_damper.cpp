// Linear spring and damper in parallel between two flanges.
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class SpringDamper final : public ComponentT<SpringDamper> {
 public:
  enum Port { kA, kB };
  enum Obs { kF, kE, kP };
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "spring_damper";
    i.description =
        "Spring k and damper d in parallel between flanges a and b: tension F = k (s_b - s_a - L0) + d (v_b - v_a) "
        "pulls a towards b and b towards a.";
    i.symbol = symbols::mechanical("spring", {{"a", 0, 20, 'l'}, {"b", 60, 20, 'r'}}, 60);
    i.parameters = {
        ParameterSpec::scalar("k", "N/m", "spring stiffness").non_negative(),
        ParameterSpec::scalar("d", "N*s/m", "damping coefficient", 0.0).non_negative(),
        ParameterSpec::scalar("L0", "m", "unstretched length s_b - s_a", 0.0),
    };
    i.ports = {{"a", Domain::translational, Causality::acausal, "flange a"},
               {"b", Domain::translational, Causality::acausal, "flange b"}};
    i.observables = {{"F", "N", "tension (positive when stretched)"},
                     {"E", "J", "spring energy k (s_b - s_a - L0)^2 / 2"},
                     {"P_damper", "W", "power dissipated in the damper (>= 0)"}};
    i.equations = {"force at a", "force at b"};
    i.faults = {fault("spring_off", "spring stiffness off its value (fatigue, a broken coil, the wrong spring)",
                      {fault_factor("k", 0.05, 2.0, 0.7)})};
    return i;
  }
  explicit SpringDamper(const Construction& c)
      : ComponentT(c), k_(c.params["k"]), d_(c.params["d"]), L0_(c.params["L0"]) {}

  template <class T>
  T tension(const Eval<T>& e) const {
    const auto a = e.flange(kA), b = e.flange(kB);
    return k_ * (b.s - a.s - L0_) + d_ * (b.v - a.v);
  }
  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const T F = tension(e);
    r[0] = e.flange(kA).f + F;  // the spring pulls a in +s: a pushes back with -F
    r[1] = e.flange(kB).f - F;
  }
  double observe(int k, const Eval<double>& e) const override {
    const double stretch = e.flange(kB).s - e.flange(kA).s - L0_;
    const double dv = e.flange(kB).v - e.flange(kA).v;
    switch (k) {
      case kF: return tension(e);
      case kE: return 0.5 * k_ * stretch * stretch;
      case kP: return d_ * dv * dv;
    }
    return 0.0;
  }

 private:
  double k_, d_, L0_;
};

void register_spring_damper(Registry& r) { r.add<SpringDamper>(); }

}  // namespace pneumo::components
