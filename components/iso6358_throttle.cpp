// ISO 6358 pneumatic resistance (paper [1] eq. 15-16): sonic conductance C and
// critical pressure ratio b, flow in both directions. Above the pressure
// ratio `laminar_ratio` the flow function is continued linearly in (1 - r),
// so the mass flow is a smooth function of p_a - p_b through zero and the
// Jacobian stays finite there.
//
// Fault opening_late (diagnosis): a path driven by a command that opens and
// closes late - a slow solenoid or pilot, a sticky spool. The opening then
// follows the command through four equal first-order lags of d/4 each: a
// command step reaches the path as the S-curve 1 - e^-s (1 + s + s^2/2 +
// s^3/6), s = 4 t / d, half open after 0.92 d, its mean delay d. (A pure
// dead time has no state a DAE could carry; the lag chain is its smooth
// stand-in.) The chain starts closed: a command open at t = 0 opens late too.
#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/iso6358_flow.hpp"
#include "components/signal_watch.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class Iso6358Throttle final : public ComponentT<Iso6358Throttle> {
 public:
  enum Port { kA, kB, kOpening };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "iso6358_throttle";
    i.description =
        "ISO 6358 flow resistance (throttle, valve path, fitting): m_flow = C rho_ref p1 sqrt(T_ref/T1) phi(p2/p1, "
        "b), both directions; isenthalpic. Optional signal 'opening' scales C (1 = fully open).";
    i.symbol = symbols::throttle();
    i.parameters = {
        ParameterSpec::scalar("C", "m3/(s*Pa)", "sonic conductance, e.g. 0.4 dm3/(s*bar)").non_negative(),
        ParameterSpec::scalar("b", "1", "critical pressure ratio", 0.5).range(0.0, 0.999),
        ParameterSpec::scalar("laminar_ratio", "1",
                              "pressure ratio above which the flow is linear in (1 - p2/p1)", 0.999)
            .open_range(0.0, 1.0),
        fault_parameter("fault_opening_delay", "s",
                        "mean delay of the opening behind its command (four lags of d/4; needs 'opening' connected)")
            .non_negative(),
    };
    i.ports = {{"a", Domain::pneumatic, Causality::acausal, "port a"},
               {"b", Domain::pneumatic, Causality::acausal, "port b"},
               {"opening", Domain::signal, Causality::input, "fraction of C that is open (default 1)", true, 1.0}};
    i.observables = {{"m_flow", "kg/s", "mass flow from a to b"}};
    i.equations = {"ISO 6358 mass flow", "mass balance", "stream temperature a", "stream temperature b"};
    SignalWatch::declare(i);
    // Not a setting: the element stands for a needle as often as for a
    // valve's path, a silencer or a fitting, which nobody turns.
    i.faults = {fault("misadjusted", "conductance off its setting (throttle misadjusted, silencer or filter clogged)",
                      {fault_factor("C", 0.1, 4.0, 0.7)})};
    FaultSpec late = fault("opening_late",
                           "the path opens and closes late behind its command (slow solenoid or pilot, sticky spool)",
                           {fault_amount("d", "fault_opening_delay", "s", 0.0, 0.1, 0.005)});
    late.needs_port = "opening";
    i.faults.push_back(std::move(late));
    return i;
  }

  // The late opening's lag chain: its stages are states.
  static constexpr int kStages = 4;
  static ComponentInfo instance_info(ComponentInfo i, const ParameterValues& p) {
    if (!(p["fault_opening_delay"] > 0)) return i;
    for (int k = 1; k <= kStages; ++k) {
      i.variables.push_back({"opening_" + std::to_string(k), "1", "opening after lag stage " + std::to_string(k), 1.0});
      i.equations.push_back("opening lag " + std::to_string(k));
    }
    return i;
  }

  explicit Iso6358Throttle(const Construction& c)
      : ComponentT(c),
        C_(c.params["C"]),
        b_(c.params["b"]),
        laminar_(c.params["laminar_ratio"]),
        tau_(c.params["fault_opening_delay"] / kStages) {
    if (laminar_ <= b_) throw ParameterError("laminar_ratio", "laminar_ratio must be larger than b");
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto a = e.gas_port(kA);
    const auto b = e.gas_port(kB);
    const T command = max(e.signal(kOpening), T(0.0));
    const T opening = tau_ > 0 ? max(e.var(kStages - 1), T(0.0)) : command;
    const T m = iso6358_mass_flow(a.p, b.p, a.T_in, b.T_in, T(C_ * opening), b_, laminar_, e.gas());
    r[0] = a.m_flow - m;
    r[1] = a.m_flow + b.m_flow;
    r[2] = a.T_out - b.T_in;  // throttling of an ideal gas keeps its temperature
    r[3] = b.T_out - a.T_in;
    for (int k = 0; tau_ > 0 && k < kStages; ++k)
      r[4 + k] = e.der(k) - ((k == 0 ? command : e.var(k - 1)) - e.var(k)) / tau_;
  }

  void start(StartValues& s, const GasModel&) const override {
    for (int k = 0; tau_ > 0 && k < kStages; ++k) s.fix_var(k, 0.0);
  }

  double observe(int, const Eval<double>& e) const override { return e.gas_port(kA).m_flow; }

  void initial_modes(double*) const override { watch_.reset(); }
  void roots(const Eval<double>& e, double* g) const override { g[0] = watch_.root(e); }
  EventResult on_event(const Eval<double>&, double*, EventKind, int, int direction) const override {
    return watch_.crossed(direction);
  }
  EventResult on_inputs_changed(const Eval<double>& e, double*) const override { return watch_.check(e); }

 private:
  double C_, b_, laminar_;
  double tau_;  // of each lag stage of a late opening (0: none)
  // Negative openings are taken as closed.
  const SignalWatch watch_{kOpening, "opening", "", -1e-6, ">= 0", "taken as 0 (closed) while below 0"};
};

void register_iso6358_throttle(Registry& r) { r.add<Iso6358Throttle>(); }

}  // namespace pneumo::components
