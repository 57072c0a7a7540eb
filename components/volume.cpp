// Rigid gas volume: mass and energy balance of an ideal gas, optional heat
// port to a wall. An optional second gas port makes it a through-flow
// volume (a line, a fitting between two resistances): gas entering at one
// port mixes with the contents and leaves at the other, which a one-port
// volume on a three-port node cannot do (it sees only the net flow). States m and U (not p and T) so that mass and energy are
// conserved by construction, to the solver's tolerance. The temperature is
// no unknown of its own: T = U / (m c_v) and p = (kappa - 1) U / V (m R T / V
// of an ideal gas) are evaluated in place, so the pressure row does not depend
// on T; T stays an output as an observable. The port temperatures remain
// unknowns (the connected components read them), all aliases of one.
// Declared faults: the volume off its value, and - where the volume is a
// line between two components - the line restricting the flow through it:
// an ISO 6358 resistance between the gas and port_b.
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/enthalpy_flow.hpp"
#include "components/iso6358_flow.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class Volume final : public ComponentT<Volume> {
 public:
  enum Port { kPort, kHeat, kPortB };
  enum Var { kM, kU };
  enum Observable { kP, kT };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "volume";
    i.description = "Rigid gas volume with mass and energy balance (ideal gas); optional heat port to a wall and optional second gas "
        "port (through-flow volume).";
    i.symbol = symbols::volume();
    i.parameters = {
        ParameterSpec::scalar("V", "m3", "volume").positive(),
        ParameterSpec::scalar("p0", "Pa", "initial pressure, absolute; default: ambient")
            .positive()
            .absolute()
            .ambient_pressure_by_default(),
        ParameterSpec::scalar("T0", "K", "initial gas temperature; default: ambient")
            .positive()
            .ambient_temperature_by_default(),
    };
    for (auto& p : line_restriction_parameters("a resistance between the gas and port_b", "that resistance"))
      i.parameters.push_back(std::move(p));
    i.ports = {{"port", Domain::pneumatic, Causality::acausal, "gas port"},
               {"heat", Domain::thermal, Causality::acausal, "heat port to the wall (insulated if unconnected)", true},
               {"port_b", Domain::pneumatic, Causality::acausal, "second gas port (closed if unconnected)", true}};
    i.variables = {{"m", "kg", "gas mass", 0.0, "U"}, {"U", "J", "internal energy of the gas"}};
    i.observables = {{"p", "Pa", "pressure, absolute"}, {"T", "K", "gas temperature, U / (m c_v)"}};
    i.equations = {"mass balance",        "energy balance",
                   "gas law p = (kappa - 1) U / V",
                   "outflow temperature", "wall temperature seen by the heat port",
                   "pressure at port_b",  "outflow temperature at port_b"};
    // A volume often stands for lines and fittings whose volume was guessed:
    // a longer hose or an added fitting holds tens of times the drawn value.
    i.faults = {fault("volume_off", "volume off its value (a longer line or more fittings than drawn, a larger reservoir, a dent)",
                      {fault_factor("V", 0.1, 100.0, 1.5)}),
                fault("line_restriction", "the line drawn as this volume restricts the flow through it (long, kinked or "
                      "undersized hose, a fitting too small)",
                      {line_restriction_amount()})};
    i.faults.back().needs_port = "port_b";
    return i;
  }

  explicit Volume(const Construction& c)
      : ComponentT(c),
        V_(c.params["V"]),
        p0_(c.params["p0"]),
        T0_(c.params["T0"]),
        restriction_(c.params["fault_line_restriction"]),
        line_b_(c.params["fault_line_b"]) {}

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto port = e.gas_port(kPort);
    const auto heat = e.heat_port(kHeat);
    const auto port_b = e.gas_port(kPortB);
    const T& m = e.var(kM);
    const T& U = e.var(kU);
    const GasModel& gas = e.gas();
    e.reject_unless_positive(m);
    e.reject_unless_positive(U);  // T > 0 for m > 0
    const T Tg = U / (m * gas.cv());
    // Outflows carry the port's T_out, the very value the downstream side
    // reads as T_in (U / (m c_v) equals it only to the Newton tolerance), so
    // that energy leaving here is exactly the energy arriving there.
    const T H = enthalpy_inflow(port.m_flow, port.T_in, port.T_out, gas) +
                enthalpy_inflow(port_b.m_flow, port_b.T_in, port_b.T_out, gas);
    r[0] = e.der(kM) - port.m_flow - port_b.m_flow;
    r[1] = e.der(kU) - H - heat.Q;
    // Each algebraic equation is solved for its own variable (p in Pa): a
    // row written as p V - (kappa - 1) U would scale with V and leave Newton
    // matrices of tiny volumes numerically singular.
    r[2] = port.p - (gas.kappa - 1.0) * U / V_;
    // The heat port's temperature carries T; the outflow temperatures are
    // written as its aliases (not as T_out - U / (m c_v)) so that alias
    // elimination folds them into one unknown, as it folded them into the
    // former T variable.
    r[3] = port.T_out - heat.T;
    r[4] = heat.T - Tg;
    r[5] = restriction_ > 0 ? line_row(port, port_b, heat.T, gas) : T(port_b.p - port.p);
    r[6] = port_b.T_out - heat.T;
  }
  // The flow into port_b through the restricting line. Without the fault the
  // row reads no flow at all: port_b's pressure stays an alias of the gas'.
  template <class T>
  T line_row(const GasPortView<T>& port, const GasPortView<T>& port_b, const T& T_gas, const GasModel& gas) const {
    const T C = 0.0 * port.p + 1.0 / restriction_;
    return port_b.m_flow - iso6358_mass_flow(port_b.p, port.p, port_b.T_in, T_gas, C, line_b_, 0.999, gas);
  }

  double observe(int k, const Eval<double>& e) const override {
    if (k == kT) return e.var(kU) / (e.var(kM) * e.gas().cv());
    return e.gas_port(kPort).p;
  }

  void start(StartValues& s, const GasModel& gas) const override {
    const double m0 = p0_ * V_ / (gas.R * T0_);
    s.fix_var(kM, m0);
    s.fix_var(kU, m0 * gas.cv() * T0_);
    s.guess_pressure(kPort, p0_);
    s.guess_temperature(kPort, T0_);
    s.guess_temperature(kHeat, T0_);
    s.guess_pressure(kPortB, p0_);
    s.guess_temperature(kPortB, T0_);
  }

 private:
  double V_, p0_, T0_, restriction_, line_b_;
};

void register_volume(Registry& r) { r.add<Volume>(); }

}  // namespace pneumo::components
