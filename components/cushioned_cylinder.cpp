// Double-acting cylinder with integrated end-position cushioning at the cap
// end (seed paper 000, fig. 1; ../shared/rigs/cushion-rig.yaml).
//
// x = 0 fully extended, x = stroke at the cap. The cap side is split into
//   EC: the cushion annulus around the plug, V_EC = V0_EC + (A_B - A_CP)(stroke - x)
//   ch: the plug column plus outflow channel, V_ch = V0_ch + A_CP (stroke - x)
// joined by the bore opening (open in the main stroke, closing linearly over
// a short ramp before the plug engages - never a jump), the needle cushion
// throttle (C from the opening z in revolutions, b linear in C) and a check
// valve for the return stroke. Port B is the channel's outlet, port A the
// rod-side chamber. Each gas volume has its own mass and energy balance;
// heat ports to the walls are optional (adiabatic if unconnected).
//
// Force on the rod flange in +x (eq. 1-3 in one expression; the cushioning
// terms vanish smoothly in the main stroke because p_EC = p_ch there):
//   F = p_A A_A + p_amb A_R - p_EC (A_B - A_CP) - p_ch A_CP + F_friction + F_stops
// Friction: seed 000 eq. 4/7/8 (components/friction.hpp), with a separate
// coefficient set in the cushioning zone blended over the bore-opening ramp.
// End stops: elastic, force = max(0, k pen + d pen_rate), never pulling.
#include <cmath>
#include <limits>

#include "components/builtin.hpp"
#include "components/enthalpy_flow.hpp"
#include "components/friction.hpp"
#include "components/iso6358_flow.hpp"

namespace pneumo::components {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

class CushionedCylinder final : public ComponentT<CushionedCylinder> {
 public:
  enum Port { kA, kB, kFlange, kHeatA, kHeatCap };
  enum Var { kMA, kUA, kTA, kMEC, kUEC, kTEC, kMch, kUch, kTch };
  enum Obs { kX, kV, kPA, kPEC, kPch, kTAo, kTECo, kTcho, kFfric, kFstop, kOpen, kCushionFlow };
  enum Root { kRampStart, kCushionEntry, kStopRod, kStopCap };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "cushioned_cylinder";
    i.description =
        "Double-acting cylinder with end-position cushioning at the cap end (plug, cushion annulus, needle throttle, "
        "check valve), mass and energy balance in each chamber, Stribeck-type friction (seed 000 eq. 4/7/8), elastic "
        "end stops. x = 0 extended, x = stroke at the cap; port A rod side, port B cap-side outlet.";
    using P = ParameterSpec;
    i.parameters = {
        P::scalar("bore", "m", "piston diameter").positive(),
        P::scalar("rod", "m", "rod diameter").positive(),
        P::scalar("stroke", "m", "stroke").positive(),
        P::scalar("plug_diameter", "m", "cushioning plug diameter").positive(),
        P::scalar("cushion_length", "m", "cushioning length (plug engages at x = stroke - cushion_length)")
            .positive(),
        P::scalar("dead_volume_rod_side", "m3", "rod-side chamber volume at x = 0").positive(),
        P::scalar("dead_volume_cushion", "m3", "cushion annulus volume at x = stroke").positive(),
        P::scalar("dead_volume_channel", "m3", "outflow channel volume at x = stroke").positive(),
        P::scalar("bore_opening_C", "m3/(s*Pa)", "conductance cushion volume <-> channel while the plug is out")
            .positive(),
        P::scalar("bore_opening_b", "1", "critical pressure ratio of the bore opening", 0.5).range(0, 0.99),
        P::scalar("bore_opening_ramp", "m", "travel over which the bore opening closes", 0.0005).positive(),
        P::table("cushion_C_of_z", {"rev", "m3/(s*Pa)"}, "cushion throttle C over opening z, piecewise linear"),
        P::scalar("cushion_b0", "1", "b of the cushion throttle at C = 0 (b = b0 + slope C/C_max)", 0.3)
            .range(0, 0.99),
        P::scalar("cushion_b_slope", "1", "slope of b over C/C_max", 0.0).range(-1, 1),
        P::scalar("z_EC", "rev", "cushion throttle opening, revolutions").non_negative(),
        P::scalar("check_C", "m3/(s*Pa)", "conductance of the return-stroke check valve", 2e-9).non_negative(),
        P::scalar("check_b", "1", "critical pressure ratio of the check valve", 0.3).range(0, 0.99),
        P::scalar("check_cracking", "Pa", "cracking pressure difference of the check valve", 2e4).non_negative(),
        P::scalar("check_ramp", "Pa", "pressure rise from cracking to fully open", 2e4).positive(),
        P::scalar("stop_stiffness", "N/m", "end stop stiffness", 1e7).positive(),
        P::scalar("stop_damping", "N*s/m", "end stop damping", 3000.0).non_negative(),
        P::text("friction", friction_preset_names(), "friction coefficient set in the main stroke", "none"),
        P::text("friction_cushion", friction_preset_names(),
                "friction coefficient set in the cushioning zone (default: same as main stroke)", std::nullopt)
            .optional(),
        P::scalar("friction_scale", "1", "factor on the friction force", 1.0).non_negative(),
        P::scalar("friction_v_reg", "m/s", "velocity scale of the tanh sign regularisation", 1e-4).positive(),
        P::scalar("friction_v_eps", "m/s", "velocity below which |v| is rounded (|v|^a stays smooth)", 1e-6)
            .positive(),
        P::scalar("x0", "m", "initial position; default: at rest against the stop at x = 0 at force equilibrium",
                  kNaN),
        P::scalar("p0_A", "Pa", "initial rod-side pressure, absolute", 101325.0).positive(),
        P::scalar("p0_cap", "Pa", "initial cap-side pressure (cushion volume and channel), absolute", 101325.0)
            .positive(),
        P::scalar("T0", "K", "initial gas temperature", 293.15).positive(),
    };
    i.ports = {{"A", Domain::pneumatic, Causality::acausal, "rod-side chamber port"},
               {"B", Domain::pneumatic, Causality::acausal, "cap-side outlet (outflow channel)"},
               {"flange", Domain::translational, Causality::acausal, "rod end; position = x"},
               {"heat_A", Domain::thermal, Causality::acausal, "wall of the rod-side chamber", true},
               {"heat_cap", Domain::thermal, Causality::acausal, "wall of the cushion volume", true}};
    i.variables = {{"m_A", "kg", "gas mass, rod side"},        {"U_A", "J", "internal energy, rod side"},
                   {"T_A", "K", "gas temperature, rod side"},   {"m_EC", "kg", "gas mass, cushion volume"},
                   {"U_EC", "J", "internal energy, cushion volume"}, {"T_EC", "K", "gas temperature, cushion volume"},
                   {"m_ch", "kg", "gas mass, channel"},         {"U_ch", "J", "internal energy, channel"},
                   {"T_ch", "K", "gas temperature, channel"}};
    i.observables = {{"x", "m", "piston position (0 extended, stroke at the cap)"},
                     {"v", "m/s", "piston velocity"},
                     {"p_A", "Pa", "rod-side pressure, absolute"},
                     {"p_EC", "Pa", "cushion volume pressure, absolute"},
                     {"p_ch", "Pa", "channel pressure, absolute"},
                     {"T_A", "K", "rod-side gas temperature"},
                     {"T_EC", "K", "cushion volume gas temperature"},
                     {"T_ch", "K", "channel gas temperature"},
                     {"F_friction", "N", "friction force on the piston (+x)"},
                     {"F_stop", "N", "end stop force on the piston (+x)"},
                     {"bore_open", "1", "bore opening fraction"},
                     {"m_flow_cushion", "kg/s", "flow cushion volume -> channel (bore, throttle, check valve)"}};
    i.equations = {"mass balance A",       "energy balance A",    "gas law A",           "U_A = m c_v T",
                   "outflow temperature A", "mass balance EC",     "energy balance EC",   "U_EC = m c_v T",
                   "mass balance ch",      "energy balance ch",   "gas law ch",          "U_ch = m c_v T",
                   "outflow temperature B", "force balance",       "wall temperature A",  "wall temperature cap"};
    i.roots = 4;
    return i;
  }

  explicit CushionedCylinder(const Construction& c) : ComponentT(c) {
    const auto& p = c.params;
    A_B_ = kPi * p["bore"] * p["bore"] / 4;
    A_R_ = kPi * p["rod"] * p["rod"] / 4;
    A_A_ = A_B_ - A_R_;
    A_CP_ = kPi * p["plug_diameter"] * p["plug_diameter"] / 4;
    if (p["rod"] >= p["bore"]) throw ParameterError("rod", "rod diameter must be smaller than the bore");
    if (p["plug_diameter"] >= p["bore"])
      throw ParameterError("plug_diameter", "plug diameter must be smaller than the bore");
    stroke_ = p["stroke"];
    L_ = p["cushion_length"];
    if (L_ >= stroke_) throw ParameterError("cushion_length", "cushion length must be shorter than the stroke");
    V0_A_ = p["dead_volume_rod_side"];
    V0_EC_ = p["dead_volume_cushion"];
    V0_ch_ = p["dead_volume_channel"];
    C_bore_ = p["bore_opening_C"];
    b_bore_ = p["bore_opening_b"];
    ramp_ = p["bore_opening_ramp"];
    const Table& t = p.table("cushion_C_of_z");
    require_increasing(t, "cushion_C_of_z", "opening z");
    double C_max = 0;
    for (const auto& row : t) C_max = std::max(C_max, row[1]);
    C_cushion_ = interpolate(t, p["z_EC"]);
    b_cushion_ = p["cushion_b0"] + p["cushion_b_slope"] * (C_max > 0 ? C_cushion_ / C_max : 0.0);
    if (!(b_cushion_ >= 0 && b_cushion_ < 0.999))
      throw ParameterError("cushion_b_slope", "b of the cushion throttle leaves [0, 0.999) at this opening");
    C_check_ = p["check_C"];
    b_check_ = p["check_b"];
    crack_ = p["check_cracking"];
    check_ramp_ = p["check_ramp"];
    k_stop_ = p["stop_stiffness"];
    d_stop_ = p["stop_damping"];
    friction_main_ = friction_presets().at(p.text("friction"));
    friction_cushion_ = friction_presets().at(p.has("friction_cushion") ? p.text("friction_cushion")
                                                                        : p.text("friction"));
    friction_scale_ = p["friction_scale"];
    v_reg_ = p["friction_v_reg"];
    v_eps_ = p["friction_v_eps"];
    x0_ = p["x0"];
    p0_A_ = p["p0_A"];
    p0_cap_ = p["p0_cap"];
    T0_ = p["T0"];
  }

  // Everything derived from the local variables, for equations and outputs.
  template <class T>
  struct State {
    T x, v, p_A, p_EC, p_ch, V_A, V_EC, V_ch, open, m_x, H_x, F_fric, F_stop;
  };

  template <class T>
  State<T> state(const Eval<T>& e) const {
    const GasModel& gas = e.gas();
    const auto fl = e.flange(kFlange);
    const auto A = e.gas_port(kA);
    State<T> s;
    s.x = fl.s;
    s.v = fl.v;
    s.p_A = A.p;
    s.V_A = V0_A_ + A_A_ * s.x;
    s.V_EC = V0_EC_ + (A_B_ - A_CP_) * (stroke_ - s.x);
    s.V_ch = V0_ch_ + A_CP_ * (stroke_ - s.x);
    const T& T_EC = e.var(kTEC);
    const T& T_ch = e.var(kTch);
    s.p_EC = e.var(kMEC) * gas.R * T_EC / s.V_EC;
    s.p_ch = e.var(kMch) * gas.R * T_ch / s.V_ch;
    // Bore opening fraction: 1 in the main stroke, 0 once the plug engages.
    const T z = (stroke_ - L_ - s.x) / ramp_;
    s.open = min(max(z, T(0.0)), T(1.0));
    // Flows from EC to ch: bore opening and cushion throttle in parallel, the
    // check valve (ch -> EC) opening linearly above its cracking pressure.
    const T m_bore = iso6358_mass_flow(s.p_EC, s.p_ch, T_EC, T_ch, T(C_bore_ * s.open), b_bore_, 0.999, gas);
    const T m_throttle = iso6358_mass_flow(s.p_EC, s.p_ch, T_EC, T_ch, T(C_cushion_ + 0.0 * s.x), b_cushion_,
                                           0.999, gas);
    const T check_open = min(max(T((s.p_ch - s.p_EC - crack_) / check_ramp_), T(0.0)), T(1.0));
    const T m_check = iso6358_mass_flow(s.p_EC, s.p_ch, T_EC, T_ch, T(C_check_ * check_open), b_check_, 0.999, gas);
    s.m_x = m_bore + m_throttle + m_check;
    s.H_x = enthalpy_inflow(s.m_x, T_EC, T_ch, gas);  // EC -> ch
    // Friction: main-stroke and cushioning-zone sets blended by the opening.
    const T F_main = friction_force(friction_main_, s.v, s.p_A, s.p_EC, s.p_EC, gas.p_ambient, v_reg_, v_eps_);
    const T F_cush = friction_force(friction_cushion_, s.v, s.p_A, s.p_EC, s.p_EC, gas.p_ambient, v_reg_, v_eps_);
    s.F_fric = friction_scale_ * (s.open * F_main + (1.0 - s.open) * F_cush);
    // Elastic end stops (never pulling).
    const T pen_rod = -s.x, pen_cap = s.x - stroke_;
    const T F_rod = select(value(pen_rod) > 0, max(T(k_stop_ * pen_rod - d_stop_ * s.v), T(0.0)), T(0.0 * s.x));
    const T F_cap = select(value(pen_cap) > 0, max(T(k_stop_ * pen_cap + d_stop_ * s.v), T(0.0)), T(0.0 * s.x));
    s.F_stop = F_rod - F_cap;
    return s;
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const GasModel& gas = e.gas();
    const auto A = e.gas_port(kA);
    const auto B = e.gas_port(kB);
    const auto fl = e.flange(kFlange);
    const auto hA = e.heat_port(kHeatA);
    const auto hC = e.heat_port(kHeatCap);
    const State<T> s = state(e);
    for (int k : {kMA, kTA, kMEC, kTEC, kMch, kTch}) e.reject_unless_positive(e.var(k));
    // Rod-side chamber A (volume grows with x).
    const T H_A = enthalpy_inflow(A.m_flow, A.T_in, e.var(kTA), gas);
    r[0] = e.der(kMA) - A.m_flow;
    r[1] = e.der(kUA) - H_A + A.p * A_A_ * s.v - hA.Q;
    r[2] = A.p - e.var(kMA) * gas.R * e.var(kTA) / s.V_A;  // solved for p (scaling)
    r[3] = e.var(kTA) - e.var(kUA) / (e.var(kMA) * gas.cv());
    r[4] = A.T_out - e.var(kTA);
    // Cushion annulus EC (volume shrinks with x).
    r[5] = e.der(kMEC) + s.m_x;
    r[6] = e.der(kUEC) + s.H_x - s.p_EC * (A_B_ - A_CP_) * s.v - hC.Q;
    r[7] = e.var(kTEC) - e.var(kUEC) / (e.var(kMEC) * gas.cv());
    // Channel ch: inflow from EC, outflow through port B.
    const T H_B = enthalpy_inflow(B.m_flow, B.T_in, e.var(kTch), gas);
    r[8] = e.der(kMch) - s.m_x - B.m_flow;
    r[9] = e.der(kUch) - s.H_x - H_B - s.p_ch * A_CP_ * s.v;
    r[10] = B.p - e.var(kMch) * gas.R * e.var(kTch) / s.V_ch;
    r[11] = e.var(kTch) - e.var(kUch) / (e.var(kMch) * gas.cv());
    r[12] = B.T_out - e.var(kTch);
    // Force balance: the flange pulls on the cylinder with f = -F.
    const T F = s.p_A * A_A_ + gas.p_ambient * A_R_ - s.p_EC * (A_B_ - A_CP_) - s.p_ch * A_CP_ + s.F_fric + s.F_stop;
    r[13] = fl.f + F;
    r[14] = hA.T - e.var(kTA);
    r[15] = hC.T - e.var(kTEC);
  }

  double observe(int k, const Eval<double>& e) const override {
    const State<double> s = state(e);
    switch (k) {
      case kX: return s.x;
      case kV: return s.v;
      case kPA: return s.p_A;
      case kPEC: return s.p_EC;
      case kPch: return s.p_ch;
      case kTAo: return e.var(kTA);
      case kTECo: return e.var(kTEC);
      case kTcho: return e.var(kTch);
      case kFfric: return s.F_fric;
      case kFstop: return s.F_stop;
      case kOpen: return s.open;
      case kCushionFlow: return s.m_x;
    }
    return 0.0;
  }

  void roots(const Eval<double>& e, double* g) const override {
    const double x = e.flange(kFlange).s;
    g[kRampStart] = x - (stroke_ - L_ - ramp_);
    g[kCushionEntry] = x - (stroke_ - L_);
    g[kStopRod] = x;
    g[kStopCap] = x - stroke_;
  }

  // Every root is a kink of the residual (opening ramp ends, stop contact):
  // re-initialising there keeps IDA's history from straddling it.
  EventResult on_event(const Eval<double>& e, double*, EventKind, int root, int dir) const override {
    const double v = e.flange(kFlange).v;
    const std::string vs = " at v = " + std::to_string(v) + " m/s";
    switch (root) {
      case kRampStart: return {true, dir > 0 ? "bore opening starts to close" + vs : "bore opening fully open" + vs};
      case kCushionEntry: return {true, dir > 0 ? "enters the cushioning zone" + vs : "leaves the cushioning zone" + vs};
      case kStopRod: return {true, dir < 0 ? "contact with the rod-end stop" + vs : "leaves the rod-end stop" + vs};
      case kStopCap: return {true, dir > 0 ? "impact on the cap-end stop" + vs : "leaves the cap-end stop" + vs};
    }
    return {};
  }

  void start(StartValues& sv, const GasModel& gas) const override {
    double x = x0_;
    if (std::isnan(x)) {
      // At rest against the rod-end stop: the stop carries the net pressure
      // force (friction is zero at v = 0).
      const double F = p0_A_ * A_A_ + gas.p_ambient * A_R_ - p0_cap_ * A_B_;
      x = F < 0 ? F / k_stop_ : 0.0;
    }
    sv.fix_position(kFlange, x);
    const double V_A = V0_A_ + A_A_ * x;
    const double V_EC = V0_EC_ + (A_B_ - A_CP_) * (stroke_ - x);
    const double V_ch = V0_ch_ + A_CP_ * (stroke_ - x);
    auto gas_state = [&](int m, int U, int Tv, double p, double V) {
      const double mass = p * V / (gas.R * T0_);
      sv.fix_var(m, mass);
      sv.fix_var(U, mass * gas.cv() * T0_);
      sv.guess_var(Tv, T0_);
    };
    gas_state(kMA, kUA, kTA, p0_A_, V_A);
    gas_state(kMEC, kUEC, kTEC, p0_cap_, V_EC);
    gas_state(kMch, kUch, kTch, p0_cap_, V_ch);
    sv.guess_pressure(kA, p0_A_);
    sv.guess_pressure(kB, p0_cap_);
    sv.guess_temperature(kA, T0_);
    sv.guess_temperature(kB, T0_);
    sv.guess_temperature(kHeatA, T0_);
    sv.guess_temperature(kHeatCap, T0_);
  }

 private:
  double A_B_, A_R_, A_A_, A_CP_, stroke_, L_, V0_A_, V0_EC_, V0_ch_;
  double C_bore_, b_bore_, ramp_, C_cushion_, b_cushion_, C_check_, b_check_, crack_, check_ramp_;
  double k_stop_, d_stop_;
  FrictionCoefficients friction_main_, friction_cushion_;
  double friction_scale_, v_reg_, v_eps_;
  double x0_, p0_A_, p0_cap_, T0_;
};

void register_cushioned_cylinder(Registry& r) { r.add<CushionedCylinder>(); }

}  // namespace pneumo::components
