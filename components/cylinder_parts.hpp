// Parts the pneumatic cylinders share (cushioned_cylinder, cylinder,
// single_acting_cylinder): the gas state of a chamber, end-position
// cushioning (bore opening, needle throttle, check valve), elastic end stops,
// the wall area for gas-to-wall heat, piston friction, and one side of a
// piston (a chamber fed through a port, optionally cushioned).
//
// A chamber's state is (m, U): T = U / (m c_v) and p = (kappa - 1) U / V are
// evaluated in place. Its balances, with the port inflow m_in, H_in:
//   dm/dt = m_in,   dU/dt = H_in - p dV/dt + Q.
#pragma once

#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "components/enthalpy_flow.hpp"
#include "components/friction.hpp"
#include "components/iso6358_flow.hpp"
#include "framework/model/component.hpp"

namespace pneumo::components {

inline constexpr double kCylinderPi = 3.14159265358979323846;

inline double circle_area(double d) { return kCylinderPi * d * d / 4; }

template <class T>
T chamber_pressure(const T& U, const T& V, const GasModel& gas) {
  return (gas.kappa - 1.0) * U / V;
}
template <class T>
T chamber_temperature(const T& m, const T& U, const GasModel& gas) {
  return U / (m * gas.cv());
}

// Wall area of a chamber of face area A (both end faces) and lateral
// perimeter `perimeter` over its length: piston travel d plus the dead volume
// V0 spread over A.
template <class T>
T chamber_wall_area(double A, double perimeter, const T& d, double V0) {
  return 2.0 * A + perimeter * (d + V0 / A);
}

// Elastic end stops at x = 0 and x = stroke: force = max(0, k pen + d pen_rate),
// never pulling; positive pushes toward +x.
struct EndStops {
  double k, d;

  template <class T>
  T force(const T& x, const T& v, double stroke) const {
    const T zero = 0.0 * x;
    const T pen_low = -x, pen_high = x - stroke;
    const T F_low = select_lazy<T>(
        value(pen_low) > 0, [&] { return max(T(k * pen_low - d * v), T(0.0)); }, [&] { return zero; });
    const T F_high = select_lazy<T>(
        value(pen_high) > 0, [&] { return max(T(k * pen_high + d * v), T(0.0)); }, [&] { return zero; });
    return F_low - F_high;
  }
  // Elastic energy stored, k pen^2 / 2.
  double energy(double x, double stroke) const {
    const double pen = x < 0 ? -x : x > stroke ? x - stroke : 0.0;
    return 0.5 * k * pen * pen;
  }
};

// End-position cushioning of one end: the bore opening (open in the main
// stroke, closing linearly over `ramp` before the plug engages - never a
// jump), the needle throttle and the return-stroke check valve, in parallel
// between the cushion volume EC and the channel ch behind the port.
struct Cushion {
  double C_bore, b_bore, ramp, C_cushion, b_cushion, C_check, b_check, crack, check_ramp;
};

// Flow EC -> ch; `gap` is the travel left before the plug engages, `open`
// receives the bore opening fraction (1 in the main stroke, 0 engaged).
template <class T>
T cushion_flow(const Cushion& c, const T& gap, const T& p_EC, const T& p_ch, const T& T_EC, const T& T_ch, const T& x,
               const GasModel& gas, T& open) {
  const T z = gap / c.ramp;
  open = min(max(z, T(0.0)), T(1.0));
  // The check valve (ch -> EC) opens linearly above its cracking pressure.
  // A path whose conductance is exactly 0 (the bore closed by the plug, the
  // check valve shut: clamped, so with zero derivative too) carries no flow
  // and is not evaluated, except for the structural pattern.
  constexpr bool structural = std::is_same_v<T, Pattern>;
  const T zero = 0.0 * x;
  const T m_bore = structural || value(open) > 0.0
                       ? iso6358_mass_flow(p_EC, p_ch, T_EC, T_ch, T(c.C_bore * open), c.b_bore, 0.999, gas)
                       : zero;
  const T m_throttle = iso6358_mass_flow(p_EC, p_ch, T_EC, T_ch, T(c.C_cushion + 0.0 * x), c.b_cushion, 0.999, gas);
  const T check_open = min(max(T((p_ch - p_EC - c.crack) / c.check_ramp), T(0.0)), T(1.0));
  const T m_check = structural || value(check_open) > 0.0
                        ? iso6358_mass_flow(p_EC, p_ch, T_EC, T_ch, T(c.C_check * check_open), c.b_check, 0.999, gas)
                        : zero;
  return m_bore + m_throttle + m_check;
}

// Friction on the piston (+x) of a cylinder without a separate cushioning
// set: the preset's eq. 4/7/8 with the chamber pressures p_A (for pAB-/pAB+
// with p_B) and p_EC (for pEC), or the pressure-free models.
template <class T>
T piston_friction(const FrictionLaw& law, const T& v, const T& z, const T& p_A, const T& p_B, const T& p_EC,
                  double p_ambient) {
  if (law.model == FrictionModel::preset)
    return law.scale * friction_force(law.main, v, p_A, p_B, p_EC, p_ambient, law.v_reg, law.v_eps);
  return law.force(law.main, v, z, T(0.0 * v));
}

// One side of a piston: a gas chamber whose volume grows with the piston's
// distance d from that side's end, V = V0 + A d, behind a port. With
// cushioning the chamber splits into the cushion annulus at the piston,
//   V_EC = V0_EC + (A - A_col) d,
// and the channel behind the port, V_ch = V0 + A_col d (the plug's column),
// joined by cushion_flow(); the plug engages at d = L. The heat port is the
// wall of the chamber at the piston (the annulus); the channel is adiabatic.
class CylinderSide {
 public:
  template <class T>
  struct Gas {
    T p, T_gas;                      // at the port (channel with cushioning)
    T p_piston, T_piston;            // at the piston (annulus with cushioning)
    T m_x = T(0.0), H_x = T(0.0);    // cushion flow EC -> ch and its enthalpy
    T open = T(1.0);                 // bore opening fraction
  };

  // Cushioning parameters of the end called `end` ("cap", "rod"); present
  // when <end>_cushion_length is given.
  static std::vector<ParameterSpec> cushion_parameters(const std::string& end) {
    using P = ParameterSpec;
    const std::string e = end + "_";
    return {
        P::scalar(e + "cushion_length", "m", "cushioning length at the " + end + " end; gives that end cushioning")
            .positive()
            .optional(),
        P::scalar(e + "plug_diameter", "m", "cushioning plug (or sleeve) diameter at the " + end + " end")
            .positive()
            .optional(),
        P::scalar(e + "cushion_C", "m3/(s*Pa)", "needle throttle conductance at the " + end + " end (its setting)")
            .non_negative()
            .optional(),
        P::scalar(e + "cushion_b", "1", "needle throttle critical pressure ratio", 0.3).range(0, 0.99),
        P::scalar(e + "dead_volume_cushion", "m3", "cushion annulus volume with the piston at the " + end + " end",
                  1e-6)
            .positive(),
        P::scalar(e + "bore_opening_C", "m3/(s*Pa)", "conductance of the bore opening while the plug is out", 5e-8)
            .positive(),
        P::scalar(e + "bore_opening_b", "1", "critical pressure ratio of the bore opening", 0.5).range(0, 0.99),
        P::scalar(e + "bore_opening_ramp", "m", "travel over which the bore opening closes", 0.0005).positive(),
        P::scalar(e + "check_C", "m3/(s*Pa)", "conductance of the cushion's check valve", 2e-9).non_negative(),
        P::scalar(e + "check_b", "1", "critical pressure ratio of the check valve", 0.3).range(0, 0.99),
        P::scalar(e + "check_cracking", "Pa", "cracking pressure difference of the check valve", 2e4).non_negative(),
        P::scalar(e + "check_ramp", "Pa", "pressure rise from cracking to fully open", 2e4).positive(),
    };
  }
  static bool has_cushion(const ParameterValues& p, const std::string& end) { return p.has(end + "_cushion_length"); }

  // A side of face area A (m2), dead volume V0 (m3), wall perimeter
  // (m, for wall heat), rod area A_rod inside the plug (the rod side's
  // sleeve column is A_plug - A_rod); cushioning read when present.
  CylinderSide(const ParameterValues& p, const std::string& end, double A, double V0, double perimeter, double A_rod,
               double stroke)
      : A_(A), V0_(V0), perimeter_(perimeter) {
    if (!has_cushion(p, end)) return;
    const std::string e = end + "_";
    for (const char* name : {"plug_diameter", "cushion_C"})
      if (!p.has(e + name))
        throw ParameterError(e + name, end + "-end cushioning (" + e + "cushion_length given) needs " + e + name);
    cushioned_ = true;
    L_ = p[e + "cushion_length"];
    const double A_plug = circle_area(p[e + "plug_diameter"]);
    if (!(A_plug > A_rod && A_plug - A_rod < A))
      throw ParameterError(e + "plug_diameter", "the plug diameter must lie between the rod's and the bore's");
    A_col_ = A_plug - A_rod;
    V0_EC_ = p[e + "dead_volume_cushion"];
    c_ = Cushion{p[e + "bore_opening_C"], p[e + "bore_opening_b"], p[e + "bore_opening_ramp"],
                 p[e + "cushion_C"],      p[e + "cushion_b"],      p[e + "check_C"],
                 p[e + "check_b"],        p[e + "check_cracking"], p[e + "check_ramp"]};
    if (L_ + c_.ramp >= stroke)
      throw ParameterError(e + "cushion_length", "the cushioning length (with its ramp) must be shorter than the stroke");
  }

  bool cushioned() const { return cushioned_; }
  double cushion_length() const { return L_; }
  int variables() const { return cushioned_ ? 4 : 2; }
  // The side's internal variables start at `first`: m, U (channel with
  // cushioning), then m_EC, U_EC.
  void set_first_variable(int first) { k_ = first; }
  int rows() const { return cushioned_ ? 7 : 5; }

  template <class T>
  Gas<T> gas(const Eval<T>& e, const T& d) const {
    const GasModel& gas = e.gas();
    Gas<T> g;
    const T& m = e.var(k_);
    const T& U = e.var(k_ + 1);
    g.T_gas = chamber_temperature(m, U, gas);
    if (!cushioned_) {
      g.p = chamber_pressure(U, T(V0_ + A_ * d), gas);
      g.p_piston = g.p;
      g.T_piston = g.T_gas;
      g.m_x = g.H_x = 0.0 * d;
      g.open = 0.0 * d + 1.0;
      return g;
    }
    g.p = chamber_pressure(U, T(V0_ + A_col_ * d), gas);
    g.T_piston = chamber_temperature(e.var(k_ + 2), e.var(k_ + 3), gas);
    g.p_piston = chamber_pressure(e.var(k_ + 3), T(V0_EC_ + (A_ - A_col_) * d), gas);
    g.m_x = cushion_flow(c_, T(d - L_), g.p_piston, g.p, g.T_piston, g.T_gas, d, gas, g.open);
    g.H_x = enthalpy_inflow(g.m_x, g.T_piston, g.T_gas, gas);
    return g;
  }

  // Pressure force of this side's gas on the piston, pushing it away from
  // this side's end (toward larger d).
  template <class T>
  T force(const Gas<T>& g) const {
    return cushioned_ ? T(g.p_piston * (A_ - A_col_) + g.p * A_col_) : T(g.p * A_);
  }
  // p dV/dt of the side's gas (power to the piston) at dd/dt.
  template <class T>
  T p_dV(const Gas<T>& g, const T& d_dot) const {
    return force(g) * d_dot;
  }

  // The side's rows: balances, the port's pressure and outflow temperature,
  // the wall heat row.
  template <class T>
  void equations(const Eval<T>& e, const GasPortView<T>& port, const HeatPortView<T>& heat, const Gas<T>& g,
                 const T& d, const T& d_dot, double wall_alpha, T* r) const {
    const GasModel& gas = e.gas();
    for (int k = 0; k < variables(); ++k) e.reject_unless_positive(e.var(k_ + k));
    const T H_port = enthalpy_inflow(port.m_flow, port.T_in, port.T_out, gas);
    const bool walls_at_gas_T = !(wall_alpha > 0);
    if (!cushioned_) {
      r[0] = e.der(k_) - port.m_flow;
      r[1] = e.der(k_ + 1) - H_port + g.p * A_ * d_dot - heat.Q;
      r[2] = port.p - g.p;
      // With the heat port at the gas temperature the port's T_out is its
      // alias, which alias elimination folds into one unknown.
      r[3] = port.T_out - (walls_at_gas_T ? heat.T : g.T_gas);
    } else {
      r[0] = e.der(k_) - g.m_x - port.m_flow;
      r[1] = e.der(k_ + 1) - g.H_x - H_port + g.p * A_col_ * d_dot;
      r[2] = port.p - g.p;
      r[3] = port.T_out - g.T_gas;
      r[5] = e.der(k_ + 2) + g.m_x;
      r[6] = e.der(k_ + 3) + g.H_x + g.p_piston * (A_ - A_col_) * d_dot - heat.Q;
    }
    if (wall_alpha > 0)
      r[4] = heat.Q - wall_alpha * chamber_wall_area(A_, perimeter_, d, V0_ + V0_EC_) * (heat.T - g.T_piston);
    else
      r[4] = heat.T - g.T_piston;
  }

  void start(StartValues& sv, const GasModel& gas, int port, int heat, double p0, double T0, double d) const {
    auto fill = [&](int k, double V) {
      const double mass = p0 * V / (gas.R * T0);
      sv.fix_var(k, mass);
      sv.fix_var(k + 1, mass * gas.cv() * T0);
    };
    fill(k_, V0_ + (cushioned_ ? A_col_ : A_) * d);
    if (cushioned_) fill(k_ + 2, V0_EC_ + (A_ - A_col_) * d);
    if (port >= 0) {
      sv.guess_pressure(port, p0);
      sv.guess_temperature(port, T0);
    }
    sv.guess_temperature(heat, T0);
  }

  // Internal energy of the side's gas, and of its cushion annulus alone
  // (0 without cushioning).
  double internal_energy(const Eval<double>& e) const {
    return e.var(k_ + 1) + (cushioned_ ? e.var(k_ + 3) : 0.0);
  }
  double cushion_internal_energy(const Eval<double>& e) const { return cushioned_ ? e.var(k_ + 3) : 0.0; }
  // p dV/dt of the channel gas alone (the plug column; 0 without cushioning).
  double channel_p_dV(const Gas<double>& g, double d_dot) const { return cushioned_ ? g.p * A_col_ * d_dot : 0.0; }

 private:
  double A_, V0_, perimeter_;
  bool cushioned_ = false;
  double L_ = 0, A_col_ = 0, V0_EC_ = 0;
  Cushion c_{};
  int k_ = 0;
};

// What `cylinder` and `single_acting_cylinder` share besides their rows: the
// piston's areas and stroke, its two sides (cushioning read from the
// <end>_cushion_* parameters where the component offers them), end stops,
// wall heat, friction and initial state, with their parameters.
struct Piston {
  double A, A_rod, stroke;
  CylinderSide cap, rod;
  EndStops stops;
  double wall_alpha;
  FrictionLaw friction;
  double x0, p0_cap, p0_rod, T0;

  explicit Piston(const ParameterValues& p)
      : A(circle_area(p["bore"])),
        A_rod(circle_area(p["rod"])),
        stroke(p["stroke"]),
        cap(p, "cap", A, p["dead_volume_cap"], kCylinderPi * p["bore"], 0.0, stroke),
        rod(p, "rod", A - A_rod, p["dead_volume_rod"], kCylinderPi * (p["bore"] + p["rod"]), A_rod, stroke),
        stops{p["stop_stiffness"], p["stop_damping"]},
        wall_alpha(p["wall_alpha"]),
        friction(FrictionLaw::from(p)),
        x0(p["x0"]),
        p0_cap(p["p0_cap"]),
        p0_rod(p["p0_rod"]),
        T0(p["T0"]) {
    if (p["rod"] >= p["bore"]) throw ParameterError("rod", "rod diameter must be smaller than the bore");
  }

  // Stops, wall heat, friction; then the initial state.
  static std::vector<ParameterSpec> parameters(const std::string& p0_rod_meaning) {
    using P = ParameterSpec;
    std::vector<ParameterSpec> out = {
        P::scalar("stop_stiffness", "N/m", "end stop stiffness", 1e7).positive(),
        P::scalar("stop_damping", "N*s/m", "end stop damping", 3000.0).non_negative(),
        P::scalar("wall_alpha", "W/(m2*K)",
                  "gas-to-wall heat transfer coefficient; 0: heat ports at gas temperature (external convection)", 0.0)
            .non_negative(),
    };
    for (auto& f : FrictionLaw::parameters(false)) out.push_back(std::move(f));
    const std::vector<ParameterSpec> initial = {
        P::scalar("x0", "m", "initial position; default: at rest against the stop at x = 0 at force equilibrium",
                  std::numeric_limits<double>::quiet_NaN()),
        P::scalar("p0_cap", "Pa", "initial cap-side pressure, absolute", 101325.0).positive(),
        P::scalar("p0_rod", "Pa", "initial " + p0_rod_meaning + " pressure, absolute", 101325.0).positive(),
        P::scalar("T0", "K", "initial gas temperature", 293.15).positive(),
    };
    out.insert(out.end(), initial.begin(), initial.end());
    return out;
  }

  // Roots 0 and 1: the stops at x = 0 and x = stroke.
  void stop_roots(double x, double* g) const {
    g[0] = x;
    g[1] = x - stroke;
  }
  // A stop contact makes the force jump (the damping term acts from the
  // first contact on): the solver re-initialises there. Leaving a stop is
  // continuous (k pen - d v falls to 0 before pen does).
  static EventResult stop_event(int root, int dir, const std::string& at) {
    if (root == 0)
      return dir > 0 ? EventResult{false, "leaves the retracted end" + at, "left_retracted"}
                     : EventResult{true, "retracted: contact with the cap-end stop" + at, "retracted"};
    return dir > 0 ? EventResult{true, "extended: contact with the rod-end stop" + at, "extended"}
                   : EventResult{false, "leaves the extended end" + at, "left_extended"};
  }
};

// The energy balance of a cushioned end, from its cushion entry to the
// piston's first standstill or reversal (cushioned_cylinder, cylinder). The
// gas leaving the cushion volume carries its internal energy u = h / kappa
// and was pushed out with the flow work p / rho = h (kappa - 1) / kappa: the
// compression of the cushion gas (all of it, including what has left) is
// dU + H_out / kappa; the flow work is what the throttle and bore opening
// dissipate. `outflows` are the enthalpy flows leaving the cushion volume
// through the throttle (+1) or elsewhere (a tap: -1, its gas leaves too but
// not through the throttle).
struct CushionAuditNames {
  std::string title, opens_at, open_description, closes_when, drive_description;
  std::vector<std::pair<std::string, double>> drive_changes, drive_integrals;
  std::string U_cushion, Q_wall, P_pdV_channel, channel_port;
  std::vector<std::pair<std::string, double>> outflows;
};
inline EnergyAuditSpec cushion_energy_audit(const CushionAuditNames& n, const GasModel& gas) {
  using K = EnergyTerm::Kinetic;
  const double k = gas.kappa;
  std::vector<std::pair<std::string, double>> compression, throttle;
  for (const auto& [name, sign] : n.outflows) {
    compression.push_back({name, sign / k});
    throttle.push_back({name, sign * (k - 1.0) / k});
  }
  EnergyAuditSpec a;
  a.title = n.title;
  a.opens_at = n.opens_at;
  a.open_description = n.open_description;
  a.closes_when_not_positive = n.closes_when;
  a.kinetic_port = "flange";
  a.terms = {
      {"kinetic_energy_at_entry", "kinetic energy at cushion entry", true, {}, {}, K::at_open},
      {"driving_work", n.drive_description, true, n.drive_changes, n.drive_integrals},
      {"cushion_gas_compression", "compression of the cushion gas (its internal energy)", false,
       {{n.U_cushion, 1.0}}, compression},
      {"cushion_throttle_dissipation", "flow work through the cushion throttle / bore opening", false, {}, throttle},
      {"heat_to_walls", "heat from the cushion gas to the walls", false, {}, {{n.Q_wall, -1.0}}},
      {"channel_work", "work on the plug column / channel gas (expelled at port " + n.channel_port + ")", false, {},
       {{n.P_pdV_channel, -1.0}}},
      {"friction", "dissipated by friction", false, {}, {{"P_friction", -1.0}}},
      {"end_stop", "absorbed by the end stop (damping + spring)", false, {}, {{"P_stop", -1.0}}},
      {"kinetic_energy_at_end", "kinetic energy left at the end", false, {}, {}, K::at_close},
  };
  return a;
}

}  // namespace pneumo::components
