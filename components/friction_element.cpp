// Friction between a flange and the ground (the frame), with the friction
// laws of components/friction.hpp: the eq. 4/7/8 presets of paper [1],
// Coulomb + viscous, or LuGre (paper [3] eq. 8, bristle state z).
#include "components/builtin.hpp"
#include "components/friction.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class FrictionElement final : public ComponentT<FrictionElement> {
 public:
  enum Obs { kF, kZ, kP };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "friction_element";
    i.description =
        "Friction of a flange sliding against the ground: friction_model preset (paper [1] eq. 4/7/8 sets), "
        "coulomb_viscous, or lugre (paper [3] eq. 8 with the bristle deflection z as a state).";
    i.symbol = symbols::mechanical("fric", {{"flange", 0, 20, 'l'}});
    i.parameters = FrictionLaw::parameters(false);
    // The value of the set's pressure p (its kind - friction_pressure for
    // custom, built into a preset - only says which chamber pressure a
    // cylinder would use; here there are no chambers).
    i.parameters.push_back(ParameterSpec::scalar("pressure", "Pa",
                                                 "pressure p of a pressure-dependent set (p_AB-, p_AB+ or p_EC as a "
                                                 "difference to ambient: write 3 bar for 3 bar_rel); unused by sets "
                                                 "without pressure",
                                                 0.0));
    i.ports = {{"flange", Domain::translational, Causality::acausal, "the sliding flange"}};
    i.observables = {{"F", "N", "friction force on the flange (+s)"},
                     {"z", "m", "bristle deflection (lugre; 0 otherwise)"},
                     {"P", "W", "friction power F v (<= 0: dissipated)"}};
    i.equations = {"friction force"};
    i.faults = {FrictionLaw::running_fault()};
    return i;
  }

  // LuGre adds its bristle state.
  static ComponentInfo instance_info(ComponentInfo i, const ParameterValues& p) {
    if (p.text("friction_model") == "lugre") {
      i.variables.push_back({"z", "m", "LuGre bristle deflection", 1e-5});
      i.equations.push_back("bristle dynamics dz/dt");
    }
    return i;
  }

  explicit FrictionElement(const Construction& c)
      : ComponentT(c), law_(FrictionLaw::from(c.params)),
        p_bar_(law_.main.pressure == FrictionPressure::none ? 0.0 : c.params["pressure"] / 1e5) {}

  template <class T>
  T z(const Eval<T>& e) const {
    return law_.has_state() ? e.var(0) : T(0.0 * e.flange(0).v);
  }
  template <class T>
  T force(const Eval<T>& e) const {
    const T& v = e.flange(0).v;
    return law_.force(law_.main, v, z(e), T(p_bar_ + 0.0 * v));
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.flange(0).f + force(e);  // f: the flange's force on this element = -F
    if (law_.has_state()) r[1] = e.der(0) - law_.lugre_zdot(e.flange(0).v, e.var(0));
  }

  void start(StartValues& s, const GasModel&) const override {
    if (law_.has_state()) s.fix_var(0, 0.0);
  }

  double observe(int k, const Eval<double>& e) const override {
    switch (k) {
      case kF: return force(e);
      case kZ: return z(e);
      case kP: return force(e) * e.flange(0).v;
    }
    return 0.0;
  }

 private:
  FrictionLaw law_;
  double p_bar_;
};

void register_friction_element(Registry& r) { r.add<FrictionElement>(); }

}  // namespace pneumo::components
