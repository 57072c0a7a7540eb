// Convective heat transfer between two thermal ports: Q = alpha A (T_a - T_b)
// (paper [1] eq. 13), flowing from a to b.
#include "components/builtin.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class HeatConvection final : public ComponentT<HeatConvection> {
 public:
  enum Port { kA, kB };
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "heat_convection";
    i.description = "Convective heat transfer Q = alpha * A * (T_a - T_b) from port a to port b.";
    i.symbol = symbols::thermal_box("Q");
    i.parameters = {
        ParameterSpec::scalar("alpha", "W/(m2*K)", "heat transfer coefficient").non_negative(),
        ParameterSpec::scalar("A", "m2", "heat transfer area").non_negative(),
    };
    i.ports = {{"a", Domain::thermal, Causality::acausal, "side a"},
               {"b", Domain::thermal, Causality::acausal, "side b"}};
    i.observables = {{"Q", "W", "heat flow from a to b"}};
    i.equations = {"convection law", "energy balance"};
    return i;
  }
  explicit HeatConvection(const Construction& c) : ComponentT(c), G_(c.params["alpha"] * c.params["A"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto a = e.heat_port(kA);
    const auto b = e.heat_port(kB);
    r[0] = a.Q - G_ * (a.T - b.T);
    r[1] = a.Q + b.Q;
  }
  double observe(int, const Eval<double>& e) const override { return e.heat_port(kA).Q; }

 private:
  double G_;
};

void register_heat_convection(Registry& r) { r.add<HeatConvection>(); }

}  // namespace pneumo::components
