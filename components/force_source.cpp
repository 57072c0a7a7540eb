// A force acting on a flange (a load), constant or from a signal input.
#include "components/builtin.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class ForceSource final : public ComponentT<ForceSource> {
 public:
  enum Port { kFlange, kForce };
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "force_source";
    i.description = "Force F pushing the connected flange in +s direction (signal 'F_in' replaces F).";
    i.symbol = symbols::mechanical("F", {{"flange", 0, 20, 'l'}, {"F_in", 40, 20, 'r'}});
    i.parameters = {ParameterSpec::scalar("F", "N", "force in +s direction", 0.0)};
    i.ports = {{"flange", Domain::translational, Causality::acausal, "flange"},
               {"F_in", Domain::signal, Causality::input, "force in N; replaces F when connected", true}};
    i.equations = {"applied force"};
    return i;
  }
  explicit ForceSource(const Construction& c) : ComponentT(c), F_(c.params["F"]) {}
  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const T F = e.connected(kForce) ? e.signal(kForce) : T(F_);
    r[0] = e.flange(kFlange).f + F;  // the flange pushes back on the source with -F
  }

 private:
  double F_;
};

void register_force_source(Registry& r) { r.add<ForceSource>(); }

}  // namespace pneumo::components
