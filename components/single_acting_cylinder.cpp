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
#include <limits>

#include "components/builtin.hpp"
#include "components/cylinder_parts.hpp"

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
        P::scalar("stop_stiffness", "N/m", "end stop stiffness", 1e7).positive(),
        P::scalar("stop_damping", "N*s/m", "end stop damping", 3000.0).non_negative(),
        P::scalar("wall_alpha", "W/(m2*K)",
                  "gas-to-wall heat transfer coefficient; 0: heat ports at gas temperature (external convection)", 0.0)
            .non_negative(),
    };
    for (auto& f : FrictionLaw::parameters(false)) i.parameters.push_back(std::move(f));
    const std::vector<ParameterSpec> initial = {
        P::scalar("x0", "m", "initial position; default: at rest against the stop at x = 0 at force equilibrium",
                  std::numeric_limits<double>::quiet_NaN()),
        P::scalar("p0_cap", "Pa", "initial cap-side pressure, absolute", 101325.0).positive(),
        P::scalar("p0_rod", "Pa", "initial spring chamber pressure, absolute (closed chamber)", 101325.0).positive(),
        P::scalar("T0", "K", "initial gas temperature", 293.15).positive(),
    };
    i.parameters.insert(i.parameters.end(), initial.begin(), initial.end());
    i.ports = {{"cap", Domain::pneumatic, Causality::acausal, "cap-side port: pressure extends"},
               {"flange", Domain::translational, Causality::acausal, "rod end; position = x (0 retracted)"},
               {"heat_cap", Domain::thermal, Causality::acausal, "wall of the cap-side chamber", true},
               {"rod", Domain::pneumatic, Causality::acausal, "spring chamber port (closed chamber; closed if unconnected)",
                true},
               {"heat_rod", Domain::thermal, Causality::acausal, "wall of the spring chamber (closed chamber)", true}};
    i.variables = {{"m_cap", "kg", "gas mass, cap side"},
                   {"U_cap", "J", "internal energy, cap side"},
                   {"m_rod", "kg", "gas mass, spring chamber"},
                   {"U_rod", "J", "internal energy, spring chamber"},
                   {"z", "m", "LuGre bristle deflection", 1e-5}};
    i.observables = {{"x", "m", "piston position (0 retracted, stroke extended)"},
                     {"v", "m/s", "piston velocity (> 0 extending)"},
                     {"p_cap", "Pa", "cap-side pressure, absolute"},
                     {"T_cap", "K", "cap-side gas temperature"},
                     {"F_spring", "N", "spring force on the piston (-x), F0 + k x"},
                     {"F_pressure", "N", "pressure force on the piston (+x), spring chamber side included"},
                     {"F_friction", "N", "friction force on the piston (+x)"},
                     {"F_stop", "N", "end stop force on the piston (+x)"},
                     {"p_rod", "Pa", "spring chamber pressure, absolute (ambient when vented)"},
                     {"T_rod", "K", "spring chamber gas temperature (closed chamber)"}};
    i.equations = {"mass balance cap", "energy balance cap", "gas law cap", "outflow temperature cap",
                   "wall heat cap",    "force balance",      "mass balance rod", "energy balance rod",
                   "gas law rod",      "outflow temperature rod", "wall heat rod", "bristle dynamics"};
    i.roots = 2;
    return i;
  }

  // A vented spring chamber has no gas state and no ports; LuGre adds z.
  static ComponentInfo instance_info(ComponentInfo i, const ParameterValues& p) {
    auto drop = [](auto& list, auto pred) { std::erase_if(list, pred); };
    if (p.text("spring_chamber") == "vented") {
      drop(i.ports, [](const PortSpec& s) { return s.name == "rod" || s.name == "heat_rod"; });
      drop(i.variables, [](const VariableSpec& s) { return s.name == "m_rod" || s.name == "U_rod"; });
      drop(i.equations, [](const std::string& s) { return s.ends_with(" rod"); });
      drop(i.observables, [](const ObservableSpec& s) { return s.name == "T_rod"; });
    }
    if (p.text("friction_model") != "lugre") {
      drop(i.variables, [](const VariableSpec& s) { return s.name == "z"; });
      drop(i.equations, [](const std::string& s) { return s == "bristle dynamics"; });
    }
    return i;
  }

  explicit SingleActingCylinder(const Construction& c)
      : ComponentT(c),
        A_(circle_area(c.params["bore"])),
        A_rod_(circle_area(c.params["rod"])),
        stroke_(c.params["stroke"]),
        F0_(c.params["spring_preload"]),
        k_(c.params["spring_rate"]),
        closed_(c.params.text("spring_chamber") == "closed"),
        cap_(c.params, "cap", A_, c.params["dead_volume_cap"], kCylinderPi * c.params["bore"], 0.0, stroke_),
        rod_(c.params, "rod", A_ - A_rod_, c.params["dead_volume_rod"],
             kCylinderPi * (c.params["bore"] + c.params["rod"]), A_rod_, stroke_),
        stops_{c.params["stop_stiffness"], c.params["stop_damping"]},
        wall_alpha_(c.params["wall_alpha"]),
        friction_(FrictionLaw::from(c.params)),
        x0_(c.params["x0"]),
        p0_cap_(c.params["p0_cap"]),
        p0_rod_(c.params["p0_rod"]),
        T0_(c.params["T0"]) {
    if (c.params["rod"] >= c.params["bore"]) throw ParameterError("rod", "rod diameter must be smaller than the bore");
    cap_.set_first_variable(0);
    rod_.set_first_variable(2);
    z_var_ = closed_ ? 4 : 2;
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
    s.cap = cap_.gas(e, fl.s);
    const T spring_side = closed_ ? T(0.0 * fl.s) : T(0.0 * fl.s + p_amb * A_);
    if (closed_) s.rod = rod_.gas(e, T(stroke_ - fl.s));
    s.F_spring = F0_ + k_ * fl.s;
    s.F_pressure = cap_.force(s.cap) - (closed_ ? T(rod_.force(s.rod) + p_amb * A_rod_) : spring_side);
    const T z = friction_.has_state() ? e.var(z_var_) : T(0.0 * fl.v);
    const T& p_rod = closed_ ? s.rod.p_piston : spring_side;
    s.F_fric = piston_friction(friction_, fl.v, z, p_rod, s.cap.p, s.cap.p, p_amb);
    s.F_stop = stops_.force(fl.s, fl.v, stroke_);
    return s;
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const State<T> s = state(e);
    const auto fl = e.flange(kFlange);
    cap_.equations(e, e.gas_port(kCap), e.heat_port(kHeatCap), s.cap, fl.s, fl.v, wall_alpha_, r);
    r[5] = fl.f + s.F_pressure - s.F_spring + s.F_fric + s.F_stop;  // f = -F on the cylinder
    int row = 6;
    if (closed_) {
      rod_.equations(e, e.gas_port(kRod), e.heat_port(kHeatRod), s.rod, T(stroke_ - fl.s), T(-fl.v), wall_alpha_,
                     r + row);
      row += rod_.rows();
    }
    if (friction_.has_state()) r[row] = e.der(z_var_) - friction_.lugre_zdot(fl.v, e.var(z_var_));
  }

  double observe(int k, const Eval<double>& e) const override {
    const State<double> s = state(e);
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

  void roots(const Eval<double>& e, double* g) const override {
    g[0] = e.flange(kFlange).s;
    g[1] = e.flange(kFlange).s - stroke_;
  }
  EventResult on_event(const Eval<double>& e, double*, EventKind, int root, int dir) const override {
    const std::string at = " at v = " + std::to_string(e.flange(kFlange).v) + " m/s";
    if (root == 0)
      return dir > 0 ? EventResult{false, "leaves the retracted end" + at, "left_retracted"}
                     : EventResult{true, "retracted: contact with the cap-end stop" + at, "retracted"};
    return dir > 0 ? EventResult{true, "extended: contact with the rod-end stop" + at, "extended"}
                   : EventResult{false, "leaves the extended end" + at, "left_extended"};
  }

  void start(StartValues& sv, const GasModel& gas) const override {
    double x = x0_;
    if (std::isnan(x)) {
      // Against the stop at x = 0, which carries what the spring and the
      // pressures leave (k_stop (-x) = -(F - k x)).
      const double side = closed_ ? p0_rod_ * (A_ - A_rod_) + gas.p_ambient * A_rod_ : gas.p_ambient * A_;
      const double F = p0_cap_ * A_ - side - F0_;
      x = F < 0 ? F / (stops_.k + k_) : 0.0;
    }
    sv.fix_position(kFlange, x);
    cap_.start(sv, gas, kCap, kHeatCap, p0_cap_, T0_, x);
    if (closed_) rod_.start(sv, gas, kRod, kHeatRod, p0_rod_, T0_, stroke_ - x);
    if (friction_.has_state()) sv.fix_var(z_var_, 0.0);
  }

 private:
  double A_, A_rod_, stroke_, F0_, k_;
  bool closed_;
  CylinderSide cap_, rod_;
  EndStops stops_;
  double wall_alpha_;
  FrictionLaw friction_;
  double x0_, p0_cap_, p0_rod_, T0_;
  int z_var_ = 2;
};

void register_single_acting_cylinder(Registry& r) { r.add<SingleActingCylinder>(); }

}  // namespace pneumo::components
