// Isentropic orifice (convergent nozzle): paper [1] eq. 14, paper [2] eq. 8-11,
// the law in components/nozzle_flow.hpp. Flow in both directions, choked
// below the critical pressure ratio (0.528 for kappa 1.4), continued C1 and
// linearly through zero pressure drop above `laminar_ratio`. The effective
// area is Cd A, given as A or as the diameter d; the optional signal
// `opening` scales it (1 = fully open), as in iso6358_throttle.
#include <cmath>
#include <numbers>

#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/nozzle_flow.hpp"
#include "components/signal_watch.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class Nozzle final : public ComponentT<Nozzle> {
 public:
  enum Port { kA, kB, kOpening };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "nozzle";
    i.description =
        "Isentropic orifice: m_flow = Cd A p1 sqrt(2 kappa/((kappa-1) R T1)) psi(p2/p1), choked below "
        "(2/(kappa+1))^(kappa/(kappa-1)); both directions; isenthalpic. Give A or d. Optional signal 'opening' "
        "scales the area (1 = fully open).";
    i.symbol = symbols::nozzle();
    i.parameters = {
        ParameterSpec::scalar("A", "m2", "geometric flow area, e.g. 1.2 mm2 (or give d)").positive().optional(),
        ParameterSpec::scalar("d", "m", "orifice diameter, e.g. 1.5 mm (or give A)").positive().optional(),
        ParameterSpec::scalar("Cd", "1", "discharge coefficient (paper [2]: C_q = 0.95-0.98)", 0.95).range(0.0, 1.0),
        ParameterSpec::scalar("laminar_ratio", "1",
                              "pressure ratio above which psi is continued by a quadratic in (1 - p2/p1) that is "
                              "linear at zero pressure drop; must exceed the critical ratio",
                              0.999)
            .open_range(0.0, 1.0),
    };
    i.ports = {
        {"a", Domain::pneumatic, Causality::acausal, "port a"},
        {"b", Domain::pneumatic, Causality::acausal, "port b"},
        {"opening", Domain::signal, Causality::input, "fraction of the area that is open (default 1)", true, 1.0}};
    i.observables = {{"m_flow", "kg/s", "mass flow from a to b"}};
    i.equations = {"isentropic nozzle mass flow", "mass balance", "stream temperature a", "stream temperature b"};
    SignalWatch::declare(i);
    i.faults = {fault("clogged", "discharge coefficient off (nozzle partly clogged or worn)",
                      {fault_factor("Cd", 0.1, 1.05, 0.7)})};
    return i;
  }

  explicit Nozzle(const Construction& c) : ComponentT(c), Cd_(c.params["Cd"]), laminar_(c.params["laminar_ratio"]) {
    const bool has_A = c.params.has("A"), has_d = c.params.has("d");
    if (has_A == has_d)
      throw ParameterError(has_A ? "d" : "A", "give exactly one of the area 'A' and the diameter 'd'");
    A_ = has_A ? c.params["A"] : std::numbers::pi / 4.0 * c.params["d"] * c.params["d"];
    // The critical ratio depends on kappa, known only with the network's gas;
    // it stays below exp(-1/2) = 0.607 for every kappa > 1.
    if (laminar_ <= 0.607)
      throw ParameterError("laminar_ratio",
                           "laminar_ratio must exceed the critical pressure ratio (0.528 for kappa 1.4, below 0.607 "
                           "for any kappa > 1)");
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto a = e.gas_port(kA);
    const auto b = e.gas_port(kB);
    const T opening = max(e.signal(kOpening), T(0.0));
    const NozzleLaw law(e.gas().kappa, laminar_);
    const T m = nozzle_mass_flow(a.p, b.p, a.T_in, b.T_in, T(Cd_ * A_ * opening), law, e.gas());
    r[0] = a.m_flow - m;
    r[1] = a.m_flow + b.m_flow;
    r[2] = a.T_out - b.T_in;  // isenthalpic throttling of an ideal gas keeps its temperature
    r[3] = b.T_out - a.T_in;
  }

  double observe(int, const Eval<double>& e) const override { return e.gas_port(kA).m_flow; }

  void initial_modes(double*) const override { watch_.reset(); }
  void roots(const Eval<double>& e, double* g) const override { g[0] = watch_.root(e); }
  EventResult on_event(const Eval<double>&, double*, EventKind, int, int direction) const override {
    return watch_.crossed(direction);
  }
  EventResult on_inputs_changed(const Eval<double>& e, double*) const override { return watch_.check(e); }

 private:
  double Cd_, laminar_, A_ = 0.0;
  // Negative openings are taken as closed.
  const SignalWatch watch_{kOpening, "opening", "", -1e-6, ">= 0", "taken as 0 (closed) while below 0"};
};

void register_nozzle(Registry& r) { r.add<Nozzle>(); }

}  // namespace pneumo::components
