// Point mass on a translational flange: ds/dt = v, m dv/dt = f (f is the sum
// of forces the connected components exert on it).
#include <cmath>
#include <limits>

#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class TranslationalMass final : public ComponentT<TranslationalMass> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "translational_mass";
    i.description = "Sliding mass: ds/dt = v, m dv/dt = sum of forces on the flange.";
    i.symbol = symbols::mechanical("m", {{"flange", 0, 20, 'l'}});
    i.parameters = {
        ParameterSpec::scalar("m", "kg", "mass").positive(),
        ParameterSpec::scalar("s0", "m", "initial position; default: set by the connected components (or 0)",
                              std::numeric_limits<double>::quiet_NaN()),
        ParameterSpec::scalar("v0", "m/s", "initial velocity", 0.0),
    };
    i.ports = {{"flange", Domain::translational, Causality::acausal, "flange"}};
    i.observables = {{"s", "m", "position"},
                     {"v", "m/s", "velocity"},
                     {"E_kin", "J", "kinetic energy 1/2 m v^2", "kinetic_energy"}};
    i.equations = {"Newton's law"};
    // A drawn mass is often the bare tool: the workpiece it carries, a
    // heavier gripper or a clamp fitted later can weigh many times as much
    // (and the drawing can hold a part that is not there), so 0.1-10 times.
    i.faults = {fault("mass_off", "moved mass off its value (other tooling, payload)",
                      {fault_factor("m", 0.1, 10.0, 1.3)})};
    return i;
  }
  explicit TranslationalMass(const Construction& c)
      : ComponentT(c), m_(c.params["m"]), s0_(c.params["s0"]), v0_(c.params["v0"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto fl = e.flange(0);
    r[0] = m_ * fl.a - fl.f;
  }
  void start(StartValues& s, const GasModel&) const override {
    if (std::isnan(s0_)) s.guess_position(0, 0.0);
    else s.fix_position(0, s0_);
    s.fix_velocity(0, v0_);
  }
  double observe(int k, const Eval<double>& e) const override {
    const auto fl = e.flange(0);
    switch (k) {
      case 0: return fl.s;
      case 1: return fl.v;
      default: return 0.5 * m_ * fl.v * fl.v;
    }
  }

 private:
  double m_, s0_, v0_;
};

void register_translational_mass(Registry& r) { r.add<TranslationalMass>(); }

}  // namespace pneumo::components
