// The law shared by the shuttle valve (OR) and the two-pressure valve
// (AND): an outlet `out` joined to one of two inlets by a ball or a pair of
// discs. The fraction of the conductance open toward inlet 1 is a C1
// smoothstep of the pressure difference over `ramp`, half at equal
// pressures; the rest is open toward inlet 2. For the OR valve inlet 1
// connects when it is the higher, for the AND valve when it is the lower,
// so the AND valve's outlet carries pressure only when both inlets do.
// SelectorValveComponent<Kind> is the component; Kind gives its type name,
// description and which inlet wins (shuttle_valve.cpp, two_pressure_valve.cpp).
#pragma once

#include "components/check_valve_flow.hpp"
#include "components/faults.hpp"
#include "components/symbols.hpp"
#include "components/valve_command.hpp"
#include "framework/model/component.hpp"

namespace pneumo::components {

class SelectorValve {
 public:
  enum Port { kIn1, kIn2, kOut };

  static void describe(ComponentInfo& i) {
    i.parameters = {
        ParameterSpec::scalar("C", "m3/(s*Pa)", "sonic conductance inlet <-> outlet when fully open").positive(),
        ParameterSpec::scalar("b", "1", "critical pressure ratio", 0.3).range(0.0, 0.99),
        ParameterSpec::scalar("ramp", "Pa", "pressure difference over which the ball changes sides", 0.05e5)
            .positive(),
        ParameterSpec::scalar("fault_leakage", "1",
                              "fault (diagnosis): fraction of C open toward the inlet the ball seals (worn ball or "
                              "seat); 0 = none",
                              0.0)
            .range(0.0, 1.0),
    };
    i.ports = {{"in_1", Domain::pneumatic, Causality::acausal, "inlet 1"},
               {"in_2", Domain::pneumatic, Causality::acausal, "inlet 2"},
               {"out", Domain::pneumatic, Causality::acausal, "outlet (2)"}};
    i.observables = {{"m_flow_1", "kg/s", "mass flow in_1 -> out"},
                     {"m_flow_2", "kg/s", "mass flow in_2 -> out"},
                     {"opening_1", "1", "open fraction toward in_1"}};
    i.equations = {"flow at in_1", "flow at in_2", "flow at out", "temperature out of in_1",
                   "temperature out of in_2", "temperature out of out"};
    i.faults = {fault("restricted", "conductance off (dirt in the valve, an undersized fitting)",
                      {fault_factor("C", 0.05, 2.0, 0.5)}),
                fault("seat_leak", "the ball does not seal the other inlet (worn ball or seat): a fraction of C open "
                                   "toward it",
                      {fault_amount("leak", "fault_leakage", "1", 0.0, 0.2, 0.02)})};
  }

  // higher_wins: OR (shuttle), else AND (two-pressure).
  SelectorValve(const ParameterValues& p, bool higher_wins)
      : C_(p["C"]), b_(p["b"]), ramp_(p["ramp"]), leak_(p["fault_leakage"]), sign_(higher_wins ? 1.0 : -1.0) {}

  template <class T>
  void flows(const Eval<T>& e, T& open_1, T& m_1, T& m_2) const {
    const auto in1 = e.gas_port(kIn1), in2 = e.gas_port(kIn2), out = e.gas_port(kOut);
    open_1 = check_valve_opening(T(sign_ * (in1.p - in2.p)), -0.5 * ramp_, ramp_);
    const T to_1 = with_leakage(open_1, leak_), to_2 = with_leakage(T(1.0 - open_1), leak_);
    m_1 = iso6358_mass_flow(in1.p, out.p, in1.T_in, out.T_in, T(C_ * to_1), b_, 0.999, e.gas());
    m_2 = iso6358_mass_flow(in2.p, out.p, in2.T_in, out.T_in, T(C_ * to_2), b_, 0.999, e.gas());
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto in1 = e.gas_port(kIn1), in2 = e.gas_port(kIn2), out = e.gas_port(kOut);
    T open_1, m_1, m_2;
    flows(e, open_1, m_1, m_2);
    r[0] = in1.m_flow - m_1;
    r[1] = in2.m_flow - m_2;
    r[2] = out.m_flow + m_1 + m_2;
    r[3] = in1.T_out - out.T_in;
    r[4] = in2.T_out - out.T_in;
    r[5] = out.T_out - mix_temperature(m_1, in1.T_in, m_2, in2.T_in, e.gas());
  }

  double observe(int k, const Eval<double>& e) const {
    double open_1, m_1, m_2;
    flows(e, open_1, m_1, m_2);
    return k == 0 ? m_1 : k == 1 ? m_2 : open_1;
  }

 private:
  double C_, b_, ramp_, leak_, sign_;
};

template <class Kind>
class SelectorValveComponent final : public ComponentT<SelectorValveComponent<Kind>> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = Kind::type;
    i.description = Kind::description;
    i.symbol = symbols::logic_valve(!Kind::higher_wins);
    SelectorValve::describe(i);
    return i;
  }
  explicit SelectorValveComponent(const Construction& c)
      : ComponentT<SelectorValveComponent<Kind>>(c), law_(c.params, Kind::higher_wins) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    law_.equations(e, r);
  }
  double observe(int k, const Eval<double>& e) const override { return law_.observe(k, e); }

 private:
  SelectorValve law_;
};

}  // namespace pneumo::components
