// Single-acting cylinder with spring return: pressure at port `cap` extends,
// the spring (preload F0 at x = 0, rate k) pushes back; x = 0 retracted,
// x = stroke extended.
//
//   F = p_cap A - (F0 + k x) - F_spring_side + F_friction + F_stops   (+x)
//
// The spring chamber is either vented (`spring_chamber: vented`: ambient
// pressure on the whole piston face, rod included: F_spring_side = p_amb A)
// or closed (a gas chamber with its own mass and energy balance,
// V = dead_volume_rod + (A - A_rod)(stroke - x), and a port `rod`, closed if
// unconnected - connect it to a throttle for a vent with resistance):
// F_spring_side = p_rod (A - A_rod) + p_amb A_rod. Chambers, stops and
// friction as in `cylinder` (components/cylinder_parts.hpp). Events:
// "retracted" / "extended" at the stop contacts.
#include <cmath>
#include <string>

#include "components/builtin.hpp"
#include "components/cylinder_parts.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class SingleActingCylinder final : public ComponentT<SingleActingCylinder> {
 public:
  enum Port { kCap, kFlange, kHeatCap, kRod, kHeatRod };
  enum Obs { kX, kV, kPcap, kTcap, kFspring, kFpressure, kFfric, kFstop, kProd, kTrod };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "single_acting_cylinder";
    i.description =
        "Single-acting cylinder with spring return: pressure at port cap extends, the spring (preload, rate) "
        "retracts; spring chamber vented to ambient or closed (gas chamber, port rod); x = 0 retracted.";
    i.symbol = symbols::single_acting_cylinder();
    using P = ParameterSpec;
    i.parameters = {
        P::scalar("bore", "m", "piston diameter").positive(),
        P::scalar("rod", "m", "rod diameter").positive(),
        P::scalar("stroke", "m", "stroke").positive(),
        P::scalar("spring_preload", "N", "spring force at x = 0 (retracted)", 0.0).non_negative(),
        P::scalar("spring_rate", "N/m", "spring rate").non_negative(),
        P::text("spring_chamber", {"vented", "closed"},
                "vented: ambient pressure in the spring chamber; closed: a gas chamber (port rod, closed if "
                "unconnected)",
                "vented"),
        P::scalar("dead_volume_cap", "m3", "cap-side volume at x = 0", 1e-6).positive(),
        P::scalar("dead_volume_rod", "m3", "spring chamber volume at x = stroke (closed chamber)", 1e-6).positive(),
    };
    for (auto& s : Piston::parameters("spring chamber (closed chamber)")) i.parameters.push_back(std::move(s));
    add_parts(i, true, FrictionState::lugre);
    i.faults = Piston::faults({"dead_volume_cap"});
    i.events = Piston::stop_events();
    i.faults.push_back({"spring_weak", "return spring weaker or stiffer than its data sheet (fatigue, wrong spring)",
                        {{"k", "spring_rate", "1", true, 1.0, 0.25, 2.0, 0.8, true}}});
    return i;
  }

  // A vented spring chamber has no gas state and no ports; LuGre (z) or a
  // friction_presliding (w) adds a friction state.
  static ComponentInfo instance_info(ComponentInfo i, const ParameterValues& p) {
    add_parts(i, p.text("spring_chamber") == "closed", friction_state_of(p));
    return i;
  }
  // In the order of the rows: the cap side's and the force balance, the
  // closed spring chamber's, the friction state's (LuGre's z, presliding's w).
  static void add_parts(ComponentInfo& i, bool closed, FrictionState friction_state) {
    using S = CylinderSide;
    clear_parts(i);
    InfoPart cap;
    cap.ports = {{"cap", Domain::pneumatic, Causality::acausal, "cap-side port: pressure extends"},
                 {"flange", Domain::translational, Causality::acausal, "rod end; position = x (0 retracted)"},
                 {"heat_cap", Domain::thermal, Causality::acausal, "wall of the cap-side chamber", true}};
    cap.variables = {{"m_cap", "kg", "gas mass, cap side", 0.0, "U_cap"}, {"U_cap", "J", "internal energy, cap side"}};
    cap.observables = {{"x", "m", "piston position (0 retracted, stroke extended)"},
                       {"v", "m/s", "piston velocity (> 0 extending)"},
                       {"p_cap", "Pa", "cap-side pressure, absolute"},
                       {"T_cap", "K", "cap-side gas temperature"},
                       {"F_spring", "N", "spring force on the piston (-x), F0 + k x"},
                       {"F_pressure", "N", "pressure force on the piston (+x), spring chamber side included"},
                       {"F_friction", "N", "friction force on the piston (+x)"},
                       {"F_stop", "N", "end stop force on the piston (+x)"},
                       {"p_rod", "Pa", "spring chamber pressure, absolute (ambient when vented)"}};
    cap.equations = S::equation_names("cap", "cap", "cap");
    cap.equations.push_back("force balance");
    cap.roots = 2;
    add_part(i, cap);
    if (closed)
      add_part(i, {.ports = {{"rod", Domain::pneumatic, Causality::acausal,
                              "spring chamber port (closed chamber; closed if unconnected)", true},
                             {"heat_rod", Domain::thermal, Causality::acausal,
                              "wall of the spring chamber (closed chamber)", true}},
                   .variables = {{"m_rod", "kg", "gas mass, spring chamber", 0.0, "U_rod"},
                                 {"U_rod", "J", "internal energy, spring chamber"}},
                   .observables = {{"T_rod", "K", "spring chamber gas temperature (closed chamber)"}},
                   .equations = S::equation_names("rod", "rod", "rod")});
    add_friction_state(i, friction_state);
  }

  explicit SingleActingCylinder(const Construction& c)
      : ComponentT(c),
        p_(c.params),
        F0_(c.params["spring_preload"]),
        k_(c.params["spring_rate"]),
        closed_(c.params.text("spring_chamber") == "closed") {
    p_.cap.set_first_variable(0);
    p_.rod.set_first_variable(2);
    z_var_ = closed_ ? 4 : 2;
    if (!closed_) p_.stops.hold_before_empty(p_.cap.travel_to_empty(), 0.0);  // the open side holds no gas
  }

  template <class T>
  struct State {
    CylinderSide::Gas<T> cap, rod;
    T F_spring, F_pressure, F_fric, F_stop;
  };

  template <class T>
  State<T> state(const Eval<T>& e) const {
    const auto fl = e.flange(kFlange);
    const double p_amb = e.gas().p_ambient;
    State<T> s;
    s.cap = p_.cap.gas(e, fl.s);
    const T spring_side = closed_ ? T(0.0 * fl.s) : T(0.0 * fl.s + p_amb * p_.A);
    if (closed_) s.rod = p_.rod.gas(e, T(p_.stroke - fl.s));
    s.F_spring = F0_ + k_ * fl.s;
    s.F_pressure = p_.cap.force(s.cap) - (closed_ ? T(p_.rod.force(s.rod) + p_amb * p_.A_rod) : spring_side);
    const T z = p_.presliding.on()        ? p_.presliding.engagement(e, z_var_)
                : p_.friction.has_state() ? e.var(z_var_)
                                          : T(0.0 * fl.v);
    const T& p_rod = closed_ ? s.rod.p_piston : spring_side;
    const T other = closed_ ? s.rod.p : T(0.0 * fl.s + p_amb);
    const FrictionFaults& ff = p_.friction_faults;
    const auto friction_at = [&](const T& v) {
      T F = piston_friction(p_.friction, v, z, p_rod, s.cap.p, s.cap.p, p_amb);
      if (ff.per_chamber_pressure > 0) F *= ff.law_factor(s.cap.p, other, p_amb);
      if (ff.any()) F += ff.force(v, s.cap.p, other, p_.friction.v_reg);
      return F;
    };
    s.F_fric = p_.presliding.on() ? p_.presliding.engaged(friction_at, fl.v, z, p_.friction) : friction_at(fl.v);
    s.F_stop = p_.stops.force(fl.s, fl.v, p_.stroke);
    return s;
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const State<T> s = state(e);
    const auto fl = e.flange(kFlange);
    const bool faulty = p_.has_fault_flows();
    const auto ff = faulty ? p_.fault_flows(s.cap, closed_ ? &s.rod : nullptr, e.gas(), fl.s) : Piston::FaultFlows<T>{};
    p_.cap.equations(e, e.gas_port(kCap), e.heat_port(kHeatCap), s.cap, fl.s, fl.v, p_.wall_alpha, r,
                     faulty ? &ff.cap : nullptr);
    r[5] = fl.f + s.F_pressure - s.F_spring + s.F_fric + s.F_stop;  // f = -F on the cylinder
    int row = 6;
    if (closed_) {
      p_.rod.equations(e, e.gas_port(kRod), e.heat_port(kHeatRod), s.rod, T(p_.stroke - fl.s), T(-fl.v), p_.wall_alpha,
                     r + row, faulty ? &ff.rod : nullptr);
      row += p_.rod.rows();
    }
    if (p_.friction.has_state()) r[row] = e.der(z_var_) - p_.friction.lugre_zdot(fl.v, e.var(z_var_));
    if (p_.presliding.on()) p_.presliding.rows(e, z_var_, fl.v, p_.friction.v_eps, r + row);
  }

  double observe(int k, const Eval<double>& e) const override { return observe(k, state(e), e); }
  // Outputs ask for several observables at one point: the state once.
  void observe_all(const int* ks, int n, const Eval<double>& e, double* out) const override {
    const State<double> s = state(e);
    for (int i = 0; i < n; ++i) out[i] = observe(ks[i], s, e);
  }
  double observe(int k, const State<double>& s, const Eval<double>& e) const {
    switch (k) {
      case kX: return e.flange(kFlange).s;
      case kV: return e.flange(kFlange).v;
      case kPcap: return s.cap.p;
      case kTcap: return s.cap.T_gas;
      case kFspring: return s.F_spring;
      case kFpressure: return s.F_pressure;
      case kFfric: return s.F_fric;
      case kFstop: return s.F_stop;
      case kProd: return closed_ ? s.rod.p : e.gas().p_ambient;
      case kTrod: return closed_ ? s.rod.T_gas : 0.0;
    }
    return 0.0;
  }

  void roots(const Eval<double>& e, double* g) const override { p_.stop_roots(e.flange(kFlange).s, g); }
  EventResult on_event(const Eval<double>& e, double*, EventKind, int root, int dir) const override {
    return Piston::stop_event(root, dir, " at v = " + std::to_string(e.flange(kFlange).v) + " m/s");
  }

  void start(StartValues& sv, const GasModel& gas) const override {
    double x = p_.x0;
    if (std::isnan(x)) {
      // Against the stop at x = 0, which carries what the spring and the
      // pressures leave (k_stop (-x) = -(F - k x)).
      const double side = closed_ ? p_.p0_rod * (p_.A - p_.A_rod) + gas.p_ambient * p_.A_rod : gas.p_ambient * p_.A;
      const double F = p_.p0_cap * p_.A - side - F0_;
      x = F < 0 ? -p_.stops.rest_penetration_low(-F, k_) : 0.0;
    }
    sv.fix_position(kFlange, x);
    p_.cap.start(sv, gas, kCap, kHeatCap, p_.p0_cap, p_.T0, x);
    if (closed_) p_.rod.start(sv, gas, kRod, kHeatRod, p_.p0_rod, p_.T0, p_.stroke - x);
    if (p_.friction.has_state()) sv.fix_var(z_var_, 0.0);
    if (p_.presliding.on()) p_.presliding.start(sv, z_var_);
  }

 private:
  Piston p_;
  double F0_, k_;
  bool closed_;
  int z_var_ = 2;
};

void register_single_acting_cylinder(Registry& r) { r.add<SingleActingCylinder>(); }

}  // namespace pneumo::components
