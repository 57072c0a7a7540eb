// Pressure relief valve (spring chamber vented to ambient): closed while the
// inlet pressure is below the set pressure p_set, opening C1-smoothly over
// the pressure band `band` above it to a full ISO 6358 conductance C, b
// (the opening law of check_valve_flow.hpp, referred to p_set instead of
// the outlet). p_set is absolute like every pressure parameter: write
// `p_set: 5 barg` (or `5 bar g`, `5 bar(g)`) for 5 bar above ambient.
// In a circuit fed through a resistance the inlet therefore levels off
// between p_set and p_set + band, where the relieved flow matches the feed.
// A seat that does not close tight leaves a fraction `leakage` of C open.
#include "components/builtin.hpp"
#include "components/check_valve_flow.hpp"
#include "components/faults.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class ReliefValve final : public ComponentT<ReliefValve> {
 public:
  enum Port { kIn, kOut };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "relief_valve";
    i.description =
        "Pressure relief valve in -> out: closed for p_in <= p_set (absolute; write barg for gauge), ISO 6358 "
        "conductance C opening C1-smoothly over 'band' above p_set (a fraction 'leakage' always open); isenthalpic.";
    i.symbol = symbols::relief_valve();
    i.parameters = {
        ParameterSpec::scalar("p_set", "Pa", "set (cracking) pressure, absolute: write e.g. 5 barg for gauge")
            .positive().absolute(),
        ParameterSpec::scalar("band", "Pa", "pressure rise above p_set at which the valve is fully open", 0.5e5)
            .positive(),
        ParameterSpec::scalar("C", "m3/(s*Pa)", "sonic conductance when fully open, e.g. 1 dm3/(s*bar)").positive(),
        ParameterSpec::scalar("b", "1", "critical pressure ratio when open", 0.3).range(0.0, 0.99),
        ParameterSpec::scalar("leakage", "1", "fraction of C open below p_set (0 = tight)", 0.0).range(0.0, 1.0),
        fault_parameter("fault_p_set_shift", "Pa", "set pressure off its setting by this much"),
    };
    i.ports = {{"in", Domain::pneumatic, Causality::acausal, "inlet: the protected pressure (1)"},
               {"out", Domain::pneumatic, Causality::acausal, "outlet: exhaust or atmosphere (3)"}};
    i.observables = {{"m_flow", "kg/s", "relieved mass flow in -> out"}, {"opening", "1", "open fraction of C"}};
    i.equations = {"relief mass flow", "mass balance", "stream temperature in", "stream temperature out"};
    i.faults = {setting_fault("misadjusted", "opens below or above its setting (spring drifted, set screw turned)",
                      {fault_amount("dp", "fault_p_set_shift", "Pa", -1e5, 1e5, 1e4)}),
                fault("seat_leak", "not closing tight below its setting (worn or dirty seat): a fraction of C open",
                      {fault_amount("leak", "leakage", "1", 0.0, 0.2, 0.02)})};
    return i;
  }

  explicit ReliefValve(const Construction& c)
      : ComponentT(c),
        p_set_(c.params["p_set"] + c.params["fault_p_set_shift"]),
        band_(c.params["band"]),
        C_(c.params["C"]),
        b_(c.params["b"]),
        leakage_(c.params["leakage"]) {}

  template <class T>
  T opening(const T& p_in) const {
    return with_leakage(check_valve_opening(T(p_in - p_set_), 0.0, band_), leakage_);
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto in = e.gas_port(kIn), out = e.gas_port(kOut);
    const T m = iso6358_mass_flow(in.p, out.p, in.T_in, out.T_in, T(C_ * opening(in.p)), b_, 0.999, e.gas());
    r[0] = in.m_flow - m;
    r[1] = in.m_flow + out.m_flow;
    r[2] = in.T_out - out.T_in;
    r[3] = out.T_out - in.T_in;
  }

  double observe(int k, const Eval<double>& e) const override {
    return k == 0 ? e.gas_port(kIn).m_flow : opening(e.gas_port(kIn).p);
  }

 private:
  double p_set_, band_, C_, b_, leakage_;
};

void register_relief_valve(Registry& r) { r.add<ReliefValve>(); }

}  // namespace pneumo::components
