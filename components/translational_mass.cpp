// Point mass on a translational flange: ds/dt = v, m dv/dt = f (f is the sum
// of forces the connected components exert on it).
#include "components/builtin.hpp"

namespace pneumo::components {

class TranslationalMass final : public ComponentT<TranslationalMass> {
 public:
  enum Var { kV };
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "translational_mass";
    i.description = "Sliding mass: ds/dt = v, m dv/dt = sum of forces on the flange.";
    i.parameters = {
        ParameterSpec::scalar("m", "kg", "mass").positive(),
        ParameterSpec::scalar("s0", "m", "initial position", 0.0),
        ParameterSpec::scalar("v0", "m/s", "initial velocity", 0.0),
    };
    i.ports = {{"flange", Domain::translational, Causality::acausal, "flange"}};
    i.variables = {{"v", "m/s", "velocity"}};
    i.observables = {{"s", "m", "position"}};
    i.equations = {"Newton's law", "kinematics"};
    return i;
  }
  explicit TranslationalMass(const Construction& c)
      : ComponentT(c), m_(c.params["m"]), s0_(c.params["s0"]), v0_(c.params["v0"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto fl = e.flange(0);
    r[0] = m_ * e.der(kV) - fl.f;
    r[1] = fl.v - e.var(kV);
  }
  void start(StartValues& s, const GasModel&) const override {
    s.fix_position(0, s0_);
    s.fix_var(kV, v0_);
  }
  double observe(int, const Eval<double>& e) const override { return e.flange(0).s; }

 private:
  double m_, s0_, v0_;
};

void register_translational_mass(Registry& r) { r.add<TranslationalMass>(); }

}  // namespace pneumo::components
