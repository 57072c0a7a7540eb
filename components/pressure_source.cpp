// Ideal pressure source: holds its port at a given absolute pressure and
// delivers gas at a given temperature, whatever the flow. An optional signal
// input replaces the pressure parameter (e.g. a supply pressure schedule).
// Its declared fault is a supply line that throttles: an ISO 6358
// resistance between the source and the port, so the port pressure sags
// with the square of a small flow and the delivered flow chokes.
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/iso6358_flow.hpp"
#include "components/signal_watch.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class PressureSource final : public ComponentT<PressureSource> {
 public:
  enum Port { kPort, kPressure };
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
    i.ports = {{"port", Domain::pneumatic, Causality::acausal, "gas port"},
               {"p_in", Domain::signal, Causality::input, "pressure in Pa abs; replaces p when connected", true}};
    i.equations = {"pressure", "delivered temperature"};
    SignalWatch::declare(i);
    i.faults = {fault("supply_sag", "supply pressure sags under flow (a long, kinked or undersized supply line)",
                      {line_restriction_amount()})};
    return i;
  }
  explicit PressureSource(const Construction& c)
      : ComponentT(c),
        p_(c.params["p"]),
        T_(c.params["T"]),
        restriction_(c.params["fault_line_restriction"]),
        line_b_(c.params["fault_line_b"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto port = e.gas_port(kPort);
    const T p = e.connected(kPressure) ? e.signal(kPressure) : T(p_);
    // Without the fault the row reads no flow at all: the structure (a source
    // joined to a source is singular, the port's pressure an alias) stays the
    // sound one.
    r[0] = restriction_ > 0 ? T(port.p - p * line_ratio(T(-port.m_flow), p, e.gas())) : T(port.p - p);
    r[1] = port.T_out - T_;
  }
  // p_port / p of the throttling line at the delivered flow (m_flow is into
  // the source): the flow function the line needs for it, inverted.
  template <class T>
  T line_ratio(const T& delivered, const T& p, const GasModel& gas) const {
    const T x = delivered * restriction_ / (gas.rho_ref * p * std::sqrt(gas.T_ref / T_));
    return iso6358_ratio_for_flow(x, line_b_, 0.999);
  }
  void start(StartValues& s, const GasModel&) const override {
    s.guess_pressure(kPort, p_);
    s.guess_temperature(kPort, T_);
  }
  void initial_modes(double*) const override { watch_.reset(); }
  void roots(const Eval<double>& e, double* g) const override { g[0] = watch_.root(e); }
  EventResult on_event(const Eval<double>&, double*, EventKind, int, int direction) const override {
    return watch_.crossed(direction);
  }
  EventResult on_inputs_changed(const Eval<double>& e, double*) const override { return watch_.check(e); }

 private:
  double p_, T_, restriction_, line_b_;
  // No absolute pressure is 0 or negative; flows toward such a "pressure"
  // are those into a vacuum (choked), whatever the value.
  const SignalWatch watch_{kPressure, "p_in", "Pa", 1.0, "an absolute pressure, at least 1 Pa",
                           "the flows toward the source are those into a vacuum"};
};

void register_pressure_source(Registry& r) { r.add<PressureSource>(); }

}  // namespace pneumo::components
