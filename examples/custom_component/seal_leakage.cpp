// Gas leaking through the annular gap of a seal (a worn piston-rod seal, a
// clearance-fit spool): isothermal, compressible, laminar (Poiseuille) flow
// through a slot of width pi d, height h and length L. Integrating
// m = -rho w h^3/(12 mu) dp/dx with rho = p/(R T) along the gap gives
//   m_flow = pi d h^3 / (24 mu L) (p_a^2 - p_b^2) / (R T_up),
// a leakage that grows with p_a^2 - p_b^2, not with p_a - p_b: the same
// gap leaks 35/3 = 11.7 times as much at 6 bar as at 2 bar (against 1 bar),
// where a linear leakage law would give 5 times.
// Like a throttle, the gap stores nothing and does no work: the gas leaves
// with the temperature it arrived with (isenthalpic).
#include "seal_leakage.hpp"

#include "framework/model/component.hpp"
#include "framework/plugin/plugin_api.hpp"

namespace seal_example {

using namespace pneumo;

class SealLeakage final : public ComponentT<SealLeakage> {
 public:
  enum Port { kA, kB };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "seal_leakage";
    i.description =
        "Laminar leakage through a seal gap (compressible Poiseuille flow): m_flow = pi d h^3/(24 mu L) "
        "(p_a^2 - p_b^2)/(R T_upstream), both directions; isenthalpic. Example of an out-of-tree plugin.";
    i.parameters = {
        ParameterSpec::scalar("d", "m", "seal diameter (the gap's width is pi d)").positive(),
        ParameterSpec::scalar("h", "m", "radial gap height").positive(),
        ParameterSpec::scalar("L", "m", "gap length in the flow direction").positive(),
        ParameterSpec::scalar("mu", "Pa*s", "dynamic viscosity of the gas (air at 20 degC: 18.1e-6 Pa s)", 18.1e-6)
            .positive(),
    };
    i.ports = {{"a", Domain::pneumatic, Causality::acausal, "high-pressure side"},
               {"b", Domain::pneumatic, Causality::acausal, "low-pressure side"}};
    i.observables = {{"m_flow", "kg/s", "leakage mass flow from a to b"}};
    i.equations = {"gap mass flow", "mass balance", "stream temperature a", "stream temperature b"};
    // What can fail, for `pneumo diagnose` without a catalogue: a worn seal's
    // gap grows (the flow grows with h^3), as a factor on h.
    i.faults = {{"worn", "seal gap wider than built (wear)", {{"k", "h", "1", true, 1.0, 0.5, 3.0, 1.2, true}}}};
    return i;
  }

  explicit SealLeakage(const Construction& c) : ComponentT(c) {
    const double d = c.params["d"], h = c.params["h"], L = c.params["L"], mu = c.params["mu"];
    if (h > 0.1 * d) throw ParameterError("h", "the gap must be narrow against the diameter (h <= d/10)");
    K_ = 3.141592653589793 * d * h * h * h / (24.0 * mu * L);
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto a = e.gas_port(kA);
    const auto b = e.gas_port(kB);
    // The gas temperature is that of the side it comes from; at p_a = p_b,
    // where the choice switches, the flow is zero either way.
    const T T_up = select(value(a.p) >= value(b.p), a.T_in, b.T_in);
    const T m = K_ * (a.p * a.p - b.p * b.p) / (e.gas().R * T_up);
    r[0] = a.m_flow - m;
    r[1] = a.m_flow + b.m_flow;
    r[2] = a.T_out - b.T_in;
    r[3] = b.T_out - a.T_in;
  }

  double observe(int, const Eval<double>& e) const override { return e.gas_port(kA).m_flow; }

 private:
  double K_;  // pi d h^3 / (24 mu L), m s
};

void register_seal_leakage(Registry& registry) { registry.add<SealLeakage>(); }

}  // namespace seal_example

PNEUMO_PLUGIN("seal leakage example", registry) { seal_example::register_seal_leakage(registry); }
