// Quick exhaust valve: a disc between the inlet P (1), the working port A
// (2, at the cylinder) and a large exhaust R (3). While P is higher than A
// the disc seals R and the flow passes P -> A; once A is higher than P (the
// supply line vented) the disc seals P and A exhausts straight through R,
// without the way back through the line and the directional valve. Each
// path opens C1-smoothly (check_valve_flow.hpp) over `ramp` once its
// pressure difference exceeds `cracking`; both are shut in between, so the
// disc never leaves both paths open at once (but for a worn disc's leak,
// the fault disc_leak: a fraction of A -> R always open). ISO 6358 paths.
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/check_valve_flow.hpp"
#include "components/symbols.hpp"
#include "components/valve_command.hpp"

namespace pneumo::components {

class QuickExhaustValve final : public ComponentT<QuickExhaustValve> {
 public:
  enum Port { kP, kA, kR };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "quick_exhaust_valve";
    i.description =
        "Quick exhaust valve: P -> A while p_P > p_A (R sealed), A -> R while p_A > p_P (P sealed); each path opens "
        "C1-smoothly over 'ramp' above 'cracking'; ISO 6358 paths.";
    i.symbol = symbols::quick_exhaust_valve();
    using P = ParameterSpec;
    i.parameters = {
        P::scalar("C_PA", "m3/(s*Pa)", "sonic conductance P -> A when open").positive(),
        P::scalar("C_AR", "m3/(s*Pa)", "sonic conductance A -> R when open (the large exhaust)").positive(),
        P::scalar("b", "1", "critical pressure ratio of both paths", 0.3).range(0.0, 0.99),
        P::scalar("cracking", "Pa", "pressure difference at which the disc starts to move", 0.1e5).non_negative(),
        P::scalar("ramp", "Pa", "pressure difference above cracking at which a path is fully open", 0.2e5).positive(),
        P::scalar("fault_leakage", "1",
                  "fault (diagnosis): fraction of C_AR open whatever the disc (worn or dirty disc); 0 = none", 0.0)
            .range(0.0, 1.0),
    };
    i.ports = {{"P", Domain::pneumatic, Causality::acausal, "inlet from the directional valve (1)"},
               {"A", Domain::pneumatic, Causality::acausal, "working port to the cylinder (2)"},
               {"R", Domain::pneumatic, Causality::acausal, "exhaust (3)"}};
    i.observables = {{"m_flow_PA", "kg/s", "mass flow P -> A"}, {"m_flow_AR", "kg/s", "mass flow A -> R"}};
    i.equations = series_port_equations("P", "A", "R");
    i.faults = {fault("exhaust_misadjusted", "exhaust path conductance off (silencer clogged, worn disc)",
                      {fault_factor("C_AR", 0.1, 4.0, 0.7)}),
                fault("disc_leak", "the disc does not seal the exhaust (worn or dirty disc): a fraction of the exhaust "
                                   "path always open",
                      {fault_amount("leak", "fault_leakage", "1", 0.0, 0.2, 0.02)})};
    return i;
  }

  explicit QuickExhaustValve(const Construction& c)
      : ComponentT(c),
        C_PA_(c.params["C_PA"]),
        C_AR_(c.params["C_AR"]),
        b_(c.params["b"]),
        cracking_(c.params["cracking"]),
        ramp_(c.params["ramp"]),
        leak_(c.params["fault_leakage"]) {}

  template <class T>
  void flows(const Eval<T>& e, T& m_PA, T& m_AR) const {
    const auto P = e.gas_port(kP), A = e.gas_port(kA), R = e.gas_port(kR);
    const T open_PA = check_valve_opening(T(P.p - A.p), cracking_, ramp_);
    const T open_AR = check_valve_opening(T(A.p - P.p), cracking_, ramp_);
    m_PA = iso6358_mass_flow(P.p, A.p, P.T_in, A.T_in, T(C_PA_ * open_PA), b_, 0.999, e.gas());
    m_AR = iso6358_mass_flow(A.p, R.p, A.T_in, R.T_in, T(C_AR_ * with_leakage(open_AR, leak_)), b_, 0.999, e.gas());
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    T m_PA, m_AR;
    flows(e, m_PA, m_AR);
    series_port_rows(e.gas_port(kP), e.gas_port(kA), e.gas_port(kR), m_PA, m_AR, e.gas(), r);
  }

  double observe(int k, const Eval<double>& e) const override {
    double m_PA, m_AR;
    flows(e, m_PA, m_AR);
    return k == 0 ? m_PA : m_AR;
  }

 private:
  double C_PA_, C_AR_, b_, cracking_, ramp_, leak_;
};

void register_quick_exhaust_valve(Registry& r) { r.add<QuickExhaustValve>(); }

}  // namespace pneumo::components
