// Relieving pressure regulator (pressure-reducing valve with secondary
// relief): the supply path in -> out opens as the outlet pressure falls
// below the set pressure p_set, fully open once it has fallen by `droop`;
// the relief path out -> exhaust opens once the outlet rises above
// p_set + relief_offset (a back-driven outlet), fully open relief_band
// higher. Both openings follow the C1 smoothstep of check_valve_flow.hpp,
// each path is an ISO 6358 resistance. So at any steady flow the outlet
// lies between p_set - droop (the supply path at full opening) and p_set;
// a larger flow needs a wider opening, so the outlet droops with flow.
// p_set is absolute: write `p_set: 4 barg` for 4 bar above ambient.
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/check_valve_flow.hpp"
#include "components/symbols.hpp"
#include "components/valve_command.hpp"

namespace pneumo::components {

class PressureRegulator final : public ComponentT<PressureRegulator> {
 public:
  enum Port { kIn, kOut, kExhaust };
  enum Obs { kMsupply, kMrelief, kOpenSupply, kOpenRelief, kPout };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "pressure_regulator";
    i.description =
        "Relieving pressure regulator: in -> out opens as p_out falls below p_set (fully open at p_set - droop), "
        "out -> exhaust opens above p_set + relief_offset (fully open relief_band higher); ISO 6358 paths. p_set "
        "absolute (write barg for gauge).";
    i.symbol = symbols::pressure_regulator();
    using P = ParameterSpec;
    i.parameters = {
        P::scalar("p_set", "Pa", "set outlet pressure, absolute: write e.g. 4 barg for gauge").positive().absolute(),
        P::scalar("droop", "Pa", "outlet pressure fall below p_set at which the supply path is fully open", 0.3e5)
            .positive(),
        P::scalar("C", "m3/(s*Pa)", "sonic conductance of the supply path when fully open").positive(),
        P::scalar("b", "1", "critical pressure ratio of the supply path", 0.3).range(0.0, 0.99),
        P::scalar("relief_offset", "Pa", "outlet pressure above p_set at which the relief path starts to open",
                  0.1e5)
            .non_negative(),
        P::scalar("relief_band", "Pa", "pressure rise over which the relief path opens fully", 0.3e5).positive(),
        P::scalar("relief_C", "m3/(s*Pa)", "sonic conductance of the relief path when fully open (default C)")
            .positive()
            .optional(),
        P::scalar("relief_b", "1", "critical pressure ratio of the relief path", 0.3).range(0.0, 0.99),
        fault_parameter("fault_p_set_shift", "Pa", "set pressure off its setting by this much (relief point with it)"),
    };
    i.ports = {{"in", Domain::pneumatic, Causality::acausal, "supply (1)"},
               {"out", Domain::pneumatic, Causality::acausal, "regulated outlet (2)"},
               {"exhaust", Domain::pneumatic, Causality::acausal, "relief exhaust (3)"}};
    i.observables = {{"m_flow", "kg/s", "mass flow in -> out through the supply path"},
                     {"m_flow_relief", "kg/s", "mass flow out -> exhaust through the relief path"},
                     {"opening", "1", "open fraction of the supply path"},
                     {"opening_relief", "1", "open fraction of the relief path"},
                     {"p_out", "Pa", "outlet pressure, absolute"}};
    i.equations = series_port_equations("in", "out", "exhaust");
    i.faults = {fault("supply_sag", "outlet pressure sags under flow (throttled supply path, worn spring)",
                      {fault_factor("C", 0.05, 2.0, 0.5), fault_factor("droop", 0.25, 10.0, 2.0)}),
                setting_fault("misadjusted", "regulates below or above its setting (knob turned, spring drifted)",
                      {fault_amount("dp", "fault_p_set_shift", "Pa", -1e5, 1e5, 1e4)})};
    return i;
  }

  explicit PressureRegulator(const Construction& c)
      : ComponentT(c),
        p_set_(c.params["p_set"] + c.params["fault_p_set_shift"]),
        droop_(c.params["droop"]),
        C_(c.params["C"]),
        b_(c.params["b"]),
        relief_at_(p_set_ + c.params["relief_offset"]),
        relief_band_(c.params["relief_band"]),
        relief_C_(c.params.has("relief_C") ? c.params["relief_C"] : C_),
        relief_b_(c.params["relief_b"]) {}

  template <class T>
  struct Flows {
    T open, open_r, m, m_r;  // supply in -> out, relief out -> exhaust
  };
  template <class T>
  Flows<T> flows(const Eval<T>& e) const {
    const auto in = e.gas_port(kIn), out = e.gas_port(kOut), ex = e.gas_port(kExhaust);
    Flows<T> f;
    f.open = check_valve_opening(T(p_set_ - out.p), 0.0, droop_);
    f.open_r = check_valve_opening(T(out.p - relief_at_), 0.0, relief_band_);
    f.m = iso6358_mass_flow(in.p, out.p, in.T_in, out.T_in, T(C_ * f.open), b_, 0.999, e.gas());
    f.m_r = iso6358_mass_flow(out.p, ex.p, out.T_in, ex.T_in, T(relief_C_ * f.open_r), relief_b_, 0.999, e.gas());
    return f;
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto in = e.gas_port(kIn), out = e.gas_port(kOut), ex = e.gas_port(kExhaust);
    const Flows<T> f = flows(e);
    series_port_rows(in, out, ex, f.m, f.m_r, e.gas(), r);
  }

  double observe(int k, const Eval<double>& e) const override {
    const Flows<double> f = flows(e);
    switch (k) {
      case kMsupply: return f.m;
      case kMrelief: return f.m_r;
      case kOpenSupply: return f.open;
      case kOpenRelief: return f.open_r;
      case kPout: return e.gas_port(kOut).p;
    }
    return 0.0;
  }

 private:
  double p_set_, droop_, C_, b_, relief_at_, relief_band_, relief_C_, relief_b_;
};

void register_pressure_regulator(Registry& r) { r.add<PressureRegulator>(); }

}  // namespace pneumo::components
