// Check valve: passes flow from `in` to `out` once p_in - p_out exceeds the
// cracking pressure difference, opening over `ramp` to a full ISO 6358
// conductance C, b; blocks reverse flow (law in check_valve_flow.hpp).
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/check_valve_flow.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class CheckValve final : public ComponentT<CheckValve> {
 public:
  enum Port { kIn, kOut };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "check_valve";
    i.description =
        "Check valve in -> out: closed for p_in - p_out <= cracking, ISO 6358 conductance C opening C1-smoothly "
        "(smoothstep) over 'ramp' above cracking; reverse flow blocked; isenthalpic.";
    i.symbol = symbols::check_valve();
    i.parameters = {
        ParameterSpec::scalar("C", "m3/(s*Pa)", "sonic conductance when fully open, e.g. 1 dm3/(s*bar)").positive(),
        ParameterSpec::scalar("b", "1", "critical pressure ratio when open", 0.3).range(0.0, 0.99),
        ParameterSpec::scalar("cracking", "Pa", "cracking pressure difference, e.g. 0.2 bar", 2e4).non_negative(),
        ParameterSpec::scalar("ramp", "Pa", "pressure difference above cracking at which the valve is fully open", 2e4)
            .positive(),
        ParameterSpec::scalar("leakage", "1", "fraction of C always open, both directions (0 = tight)", 0.0)
            .range(0.0, 1.0),
    };
    i.ports = {{"in", Domain::pneumatic, Causality::acausal, "inlet (flow in -> out is allowed)"},
               {"out", Domain::pneumatic, Causality::acausal, "outlet"}};
    i.observables = {{"m_flow", "kg/s", "mass flow from in to out"}, {"opening", "1", "open fraction of C"}};
    i.equations = {"check valve mass flow", "mass balance", "stream temperature in", "stream temperature out"};
    i.faults = {fault("leak", "not closing tight: a fraction of its conductance always open",
                      {fault_amount("leak", "leakage", "1", 0.0, 0.2, 0.02)})};
    return i;
  }

  explicit CheckValve(const Construction& c)
      : ComponentT(c),
        C_(c.params["C"]),
        b_(c.params["b"]),
        cracking_(c.params["cracking"]),
        ramp_(c.params["ramp"]),
        leakage_(c.params["leakage"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto in = e.gas_port(kIn);
    const auto out = e.gas_port(kOut);
    const T m = check_valve_mass_flow(in.p, out.p, in.T_in, out.T_in, C_, b_, cracking_, ramp_, leakage_, e.gas());
    r[0] = in.m_flow - m;
    r[1] = in.m_flow + out.m_flow;
    r[2] = in.T_out - out.T_in;
    r[3] = out.T_out - in.T_in;
  }

  double observe(int k, const Eval<double>& e) const override {
    const auto in = e.gas_port(kIn), out = e.gas_port(kOut);
    return k == 0 ? in.m_flow : with_leakage(check_valve_opening(in.p - out.p, cracking_, ramp_), leakage_);
  }

 private:
  double C_, b_, cracking_, ramp_, leakage_;
};

void register_check_valve(Registry& r) { r.add<CheckValve>(); }

}  // namespace pneumo::components
