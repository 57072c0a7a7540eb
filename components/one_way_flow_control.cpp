// One-way flow control valve (throttle with a check valve in parallel), as
// used for meter-out speed control: flow a -> b only through the throttle
// (ISO 6358 C, b, optional `opening` signal); flow b -> a through the
// throttle and, above its cracking pressure, the check valve (free flow).
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/check_valve_flow.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class OneWayFlowControl final : public ComponentT<OneWayFlowControl> {
 public:
  enum Port { kA, kB, kOpening };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "one_way_flow_control";
    i.description =
        "Throttle (ISO 6358 C, b) with a check valve in parallel: a -> b throttled, b -> a free through the check "
        "valve (opens above check_cracking). Meter-out: a on the cylinder side. Optional signal 'opening' scales the "
        "throttle's C.";
    i.symbol = symbols::one_way_flow_control();
    i.parameters = {
        ParameterSpec::scalar("C", "m3/(s*Pa)", "sonic conductance of the throttle, e.g. 0.1 dm3/(s*bar)")
            .non_negative(),
        ParameterSpec::scalar("b", "1", "critical pressure ratio of the throttle", 0.5).range(0.0, 0.99),
        ParameterSpec::scalar("laminar_ratio", "1", "throttle: pressure ratio above which the flow is linear", 0.999)
            .open_range(0.0, 1.0),
        ParameterSpec::scalar("check_C", "m3/(s*Pa)", "sonic conductance of the open check valve", 1e-8).positive(),
        ParameterSpec::scalar("check_b", "1", "critical pressure ratio of the check valve", 0.3).range(0.0, 0.99),
        ParameterSpec::scalar("check_cracking", "Pa", "cracking pressure difference p_b - p_a of the check valve", 1e4)
            .non_negative(),
        ParameterSpec::scalar("check_ramp", "Pa", "pressure difference above cracking for a fully open check valve",
                              2e4)
            .positive(),
        fault_parameter("check_leakage", "1", "fraction of the check valve's C always open, both directions")
            .range(0.0, 1.0),
    };
    i.ports = {{"a", Domain::pneumatic, Causality::acausal, "port a (throttled outflow a -> b)"},
               {"b", Domain::pneumatic, Causality::acausal, "port b (free flow b -> a)"},
               {"opening", Domain::signal, Causality::input, "fraction of the throttle's C that is open (default 1)",
                true, 1.0}};
    i.observables = {{"m_flow", "kg/s", "mass flow from a to b"},
                     {"m_flow_check", "kg/s", "part of it through the check valve"}};
    i.equations = {"throttle + check valve mass flow", "mass balance", "stream temperature a", "stream temperature b"};
    i.faults = {setting_fault("misadjusted", "throttle conductance off its setting (needle misadjusted or clogged)",
                      {fault_factor("C", 0.1, 4.0, 0.7)}),
                fault("check_leak", "check valve not closing tight (a fraction of its conductance always open)",
                      {fault_amount("leak", "check_leakage", "1", 0.0, 0.2, 0.02)})};
    return i;
  }

  explicit OneWayFlowControl(const Construction& c)
      : ComponentT(c),
        C_(c.params["C"]),
        b_(c.params["b"]),
        laminar_(c.params["laminar_ratio"]),
        check_C_(c.params["check_C"]),
        check_b_(c.params["check_b"]),
        cracking_(c.params["check_cracking"]),
        ramp_(c.params["check_ramp"]),
        leakage_(c.params["check_leakage"]) {
    if (laminar_ <= b_) throw ParameterError("laminar_ratio", "laminar_ratio must be larger than b");
  }

  template <class T>
  T check_flow(const Eval<T>& e) const {  // a -> b, i.e. <= 0
    const auto a = e.gas_port(kA), b = e.gas_port(kB);
    return -check_valve_mass_flow(b.p, a.p, b.T_in, a.T_in, check_C_, check_b_, cracking_, ramp_, leakage_, e.gas());
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto a = e.gas_port(kA);
    const auto b = e.gas_port(kB);
    const T opening = max(e.signal(kOpening), T(0.0));
    const T m_throttle = iso6358_mass_flow(a.p, b.p, a.T_in, b.T_in, T(C_ * opening), b_, laminar_, e.gas());
    r[0] = a.m_flow - (m_throttle + check_flow(e));
    r[1] = a.m_flow + b.m_flow;
    r[2] = a.T_out - b.T_in;
    r[3] = b.T_out - a.T_in;
  }

  double observe(int k, const Eval<double>& e) const override { return k == 0 ? e.gas_port(kA).m_flow : check_flow(e); }

 private:
  double C_, b_, laminar_, check_C_, check_b_, cracking_, ramp_, leakage_;
};

void register_one_way_flow_control(Registry& r) { r.add<OneWayFlowControl>(); }

}  // namespace pneumo::components
