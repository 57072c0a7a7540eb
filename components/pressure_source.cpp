// Ideal pressure source: holds its port at a given absolute pressure and
// delivers gas at a given temperature, whatever the flow. An optional signal
// input replaces the pressure parameter (e.g. a supply pressure schedule).
// Its declared fault is a supply line that throttles: an ISO 6358
// resistance between the source and the port, so the port pressure sags
// with the square of a small flow and the delivered flow chokes - and the
// gas such a line holds behind the resistance (a long hose), which covers
// the first burst of a consumer's demand and refills after it:
//
//   source p --[1/C, b]-- line gas (V: m, U) -- port
//
// Without a line volume the line is the resistance alone (no state); without
// the resistance the port is the source's.
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/enthalpy_flow.hpp"
#include "components/iso6358_flow.hpp"
#include "components/signal_watch.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class PressureSource final : public ComponentT<PressureSource> {
 public:
  enum Port { kPort, kPressure };
  enum Var { kM, kU };  // the supply line's gas (with a line volume only)
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "pressure_source";
    i.description = "Ideal pressure source (absolute pressure p, delivered gas temperature T).";
    i.symbol = symbols::pressure_source();
    i.parameters = {
        ParameterSpec::scalar("p", "Pa", "pressure, absolute (write '6 barg' for gauge)").positive().absolute(),
        ParameterSpec::scalar("T", "K", "temperature of the delivered gas; default: ambient")
            .positive()
            .ambient_temperature_by_default(),
    };
    for (auto& p : line_restriction_parameters("a throttling supply line between the source and its port",
                                               "that supply line"))
      i.parameters.push_back(std::move(p));
    i.parameters.push_back(fault_parameter("fault_line_volume", "m3",
                                           "gas volume of that supply line behind its resistance (a hose of 6 mm "
                                           "bore and 5 m holds 141 cm3)")
                               .non_negative());
    i.ports = {{"port", Domain::pneumatic, Causality::acausal, "gas port"},
               {"p_in", Domain::signal, Causality::input, "pressure in Pa abs; replaces p when connected", true}};
    i.variables = {{"m_line", "kg", "gas mass of the supply line (fault_line_volume; 0 without)", 0.0, "U_line"},
                   {"U_line", "J", "internal energy of the supply line's gas (0 without a line volume)"}};
    i.equations = {"pressure", "delivered temperature", "supply line mass balance", "supply line energy balance"};
    SignalWatch::declare(i);
    i.faults = {fault("supply_sag",
                      "supply pressure sags under flow (a long, kinked or undersized supply line: its resistance and "
                      "the gas it holds)",
                      {line_restriction_amount(), fault_amount("V", "fault_line_volume", "m3", 0.0, 1e-3, 2e-5)})};
    return i;
  }
  explicit PressureSource(const Construction& c)
      : ComponentT(c),
        p_(c.params["p"]),
        T_(c.params["T"]),
        restriction_(c.params["fault_line_restriction"]),
        line_b_(c.params["fault_line_b"]),
        line_V_(c.params["fault_line_volume"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto port = e.gas_port(kPort);
    const T p = e.connected(kPressure) ? e.signal(kPressure) : T(p_);
    if (holds_gas()) return line_gas(e, port, p, r);
    // Without the fault the rows read no flow at all: the structure (a source
    // joined to a source is singular, the port's pressure an alias) stays the
    // sound one, and the line's gas is the constant 0 that assembly removes.
    r[0] = restriction_ > 0 ? T(port.p - p * line_ratio(T(-port.m_flow), p, e.gas())) : T(port.p - p);
    r[1] = port.T_out - T_;
    r[2] = e.var(kM);
    r[3] = e.var(kU);
  }
  // The line's gas as a volume's (volume.cpp): fed through the resistance
  // from the source, drawn from at the port.
  template <class T>
  void line_gas(const Eval<T>& e, const GasPortView<T>& port, const T& p, T* r) const {
    const GasModel& gas = e.gas();
    const T& m = e.var(kM);
    const T& U = e.var(kU);
    e.reject_unless_positive(m);
    e.reject_unless_positive(U);
    const T T_line = U / (m * gas.cv());
    const T p_line = (gas.kappa - 1.0) * U / line_V_;
    const T C = 0.0 * p + 1.0 / restriction_;
    const T fed = iso6358_mass_flow(p, p_line, T(T_), T_line, C, line_b_, 0.999, gas);
    r[0] = port.p - p_line;
    r[1] = port.T_out - T_line;
    r[2] = e.der(kM) - fed - port.m_flow;
    r[3] = e.der(kU) - enthalpy_inflow(fed, T(T_), T_line, gas) -
           enthalpy_inflow(port.m_flow, port.T_in, port.T_out, gas);
  }
  bool holds_gas() const { return restriction_ > 0 && line_V_ > 0; }
  // p_port / p of the throttling line at the delivered flow (m_flow is into
  // the source): the flow function the line needs for it, inverted.
  template <class T>
  T line_ratio(const T& delivered, const T& p, const GasModel& gas) const {
    const T x = delivered * restriction_ / (gas.rho_ref * p * std::sqrt(gas.T_ref / T_));
    return iso6358_ratio_for_flow(x, line_b_, 0.999);
  }
  void start(StartValues& s, const GasModel& gas) const override {
    s.guess_pressure(kPort, p_);
    s.guess_temperature(kPort, T_);
    // A line volume starts full, at the source's pressure and temperature.
    const double m0 = holds_gas() ? p_ * line_V_ / (gas.R * T_) : 0.0;
    s.fix_var(kM, m0);
    s.fix_var(kU, m0 * gas.cv() * T_);
  }
  void initial_modes(double*) const override { watch_.reset(); }
  void roots(const Eval<double>& e, double* g) const override { g[0] = watch_.root(e); }
  EventResult on_event(const Eval<double>&, double*, EventKind, int, int direction) const override {
    return watch_.crossed(direction);
  }
  EventResult on_inputs_changed(const Eval<double>& e, double*) const override { return watch_.check(e); }

 private:
  double p_, T_, restriction_, line_b_, line_V_;
  // No absolute pressure is 0 or negative; flows toward such a "pressure"
  // are those into a vacuum (choked), whatever the value.
  const SignalWatch watch_{kPressure, "p_in", "Pa", 1.0, "an absolute pressure, at least 1 Pa",
                           "the flows toward the source are those into a vacuum"};
};

void register_pressure_source(Registry& r) { r.add<PressureSource>(); }

}  // namespace pneumo::components
