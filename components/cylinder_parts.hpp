// Parts the pneumatic cylinders share (the double-acting cylinder of
// components/cylinder.hpp, single_acting_cylinder): the gas state of a
// chamber, end-position cushioning (bore opening, needle throttle, check
// valve), elastic end stops, the wall area for gas-to-wall heat, piston
// friction, and one side of a piston (a chamber fed through a port,
// optionally cushioned).
//
// A chamber's state is (m, U): T = U / (m c_v) and p = (kappa - 1) U / V are
// evaluated in place. Its balances, with the port inflow m_in, H_in:
//   dm/dt = m_in,   dU/dt = H_in - p dV/dt + Q.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
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

// A fault parameter's value, its null 0 where the instance's type does not
// declare it (a cylinder without the part the fault belongs to).
inline double fault_or_none(const ParameterValues& p, const std::string& name) { return p.has(name) ? p[name] : 0.0; }

// The cushion paths' pressure ratio above which their flow is continued
// linearly in (1 - p2/p1) (iso6358_phi's r_lam): keeps the flow's slope
// finite at zero pressure drop, as the stand-alone throttles' default does.
inline constexpr double kCushionLaminarRatio = 0.999;

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

// A part's share of a component's description: its ports, internal
// variables, observables, rows (equation names) and roots. A component made
// of parts describes itself as the union of all of them, and an instance as
// the union of the parts it has, each list in the parts' order.
struct InfoPart {
  std::vector<PortSpec> ports;
  std::vector<VariableSpec> variables;
  std::vector<ObservableSpec> observables;
  std::vector<std::string> equations;
  int roots = 0;
};
inline void add_part(ComponentInfo& i, const InfoPart& part) {
  i.ports.insert(i.ports.end(), part.ports.begin(), part.ports.end());
  i.variables.insert(i.variables.end(), part.variables.begin(), part.variables.end());
  i.observables.insert(i.observables.end(), part.observables.begin(), part.observables.end());
  i.equations.insert(i.equations.end(), part.equations.begin(), part.equations.end());
  i.roots += part.roots;
}
// LuGre friction's bristle deflection z and its row (friction_model: lugre).
inline InfoPart lugre_part() {
  return {.variables = {{"z", "m", "LuGre bristle deflection", 1e-5}}, .equations = {"bristle dynamics"}};
}
// A piston friction's states: LuGre's z, or with presliding the seal's
// engagement (SealPresliding: one element, or a fast and a slow one), or
// none.
enum class FrictionState { none, lugre, presliding, presliding_two };
inline FrictionState friction_state_of(const ParameterValues& p) {
  if (p.text("friction_model") == "lugre") return FrictionState::lugre;
  if (!(p["friction_presliding"] > 0)) return FrictionState::none;
  return p["friction_presliding_slow"] > 0 ? FrictionState::presliding_two : FrictionState::presliding;
}

// A seal that deforms before it slides - an O-ring rolls and shears in its
// groove, a lip flexes - turns its friction over a travel after each
// reversal, not within the law's velocity band (friction_v_reg). Dahl's
// model (exponent 1): the seal's engagement w (-1 .. 1, a state) takes the
// place of the friction's sign, dw/dt = (v - |v| w) / distance, so w turns
// from -1 to 1 over a few distances of travel. A seal may turn in two
// stages - most of the force within a tenth of a millimetre, the rest over
// a millimetre or two - as the elements of a generalised Maxwell-slip
// model: a slow element of its own distance carries a share of the force,
// the engagement is (1 - share) w + share w_slow. The force is the
// friction's magnitude at the current speed - `at` (the whole friction as a
// function of the velocity) at the positive speed |v|, over the law's sign
// there - times minus the engagement. LuGre's bristles are that law's own
// presliding.
struct SealPresliding {
  double distance = 0, slow_distance = 0, slow_share = 0;  // m, m, 1; 0: none

  explicit SealPresliding(const ParameterValues& p)
      : distance(p["friction_presliding"]),
        slow_distance(p["friction_presliding_slow"]),
        slow_share(p["friction_presliding_slow_share"]) {
    if (distance > 0 && p.text("friction_model") == "lugre")
      throw ParameterError("friction_presliding",
                           "LuGre's bristles are its presliding (friction_sigma0); friction_presliding is for "
                           "friction_model preset and coulomb_viscous");
    if (slow_distance > 0 && !(distance > 0))
      throw ParameterError("friction_presliding_slow", "a slow presliding element needs friction_presliding > 0");
  }
  static std::vector<ParameterSpec> parameters() {
    using P = ParameterSpec;
    return {P::scalar("friction_presliding", "m",
                      "presliding distance: after each reversal the friction turns over this travel (the seal's "
                      "engagement, Dahl; e-folding distance); 0: within friction_v_reg",
                      0.0)
                .non_negative(),
            P::scalar("friction_presliding_slow", "m",
                      "a second, slow presliding element's distance (the force's second stage); 0: none", 0.0)
                .non_negative(),
            P::scalar("friction_presliding_slow_share", "1", "the slow element's share of the force", 0.0)
                .range(0.0, 1.0)};
  }
  bool on() const { return distance > 0; }
  bool two() const { return slow_distance > 0; }

  // The engagement (-1 .. 1) from the states at `var` (var + 1: the slow one).
  template <class T>
  T engagement(const Eval<T>& e, int var) const {
    return two() ? (1.0 - slow_share) * e.var(var) + slow_share * e.var(var + 1) : e.var(var);
  }
  // Their rows, r[0] (and r[1]).
  template <class T>
  void rows(const Eval<T>& e, int var, const T& v, double v_eps, T* r) const {
    const T speed = smooth_abs(v, v_eps);
    r[0] = e.der(var) - (v - speed * e.var(var)) / distance;
    if (two()) r[1] = e.der(var + 1) - (v - speed * e.var(var + 1)) / slow_distance;
  }
  // At rest, unengaged.
  void start(StartValues& sv, int var) const {
    sv.fix_var(var, 0.0);
    if (two()) sv.fix_var(var + 1, 0.0);
  }
  template <class T, class Friction>
  T engaged(const Friction& at, const T& v, const T& engagement, const FrictionLaw& law) const {
    const T speed = smooth_abs(v, law.v_eps);
    return at(speed) / smooth_sign(speed, law.v_reg) * engagement;
  }
};
inline void add_friction_state(ComponentInfo& i, FrictionState kind) {
  if (kind == FrictionState::lugre) add_part(i, lugre_part());
  if (kind == FrictionState::presliding || kind == FrictionState::presliding_two)
    add_part(i, {.variables = {{"w", "1", "seal engagement (friction_presliding: -1 .. 1)", 0.1}},
                 .equations = {"seal engagement"}});
  if (kind == FrictionState::presliding_two)
    add_part(i, {.variables = {{"w_slow", "1", "slow presliding element's engagement (-1 .. 1)", 0.1}},
                 .equations = {"slow element's engagement"}});
}
// The lists of `i` emptied, before its parts are added.
inline void clear_parts(ComponentInfo& i) {
  i.ports.clear();
  i.variables.clear();
  i.observables.clear();
  i.equations.clear();
  i.roots = 0;
}

// A stop that stiffens before the chamber it closes is empty. A linear
// spring alone lets a hard impact push the piston through the dead volume
// (a 1e6 N/m bumper takes 4.5 mm at 10 J; 0.5 mL on a 16 mm bore is 2.8 mm
// long), where the gas volume would vanish. A real stop is progressive
// (rubber, then the end cap's metal). Past half the `reach` (the penetration
// that would empty the chamber) the spring gains k reach g(s), s = pen /
// reach, g = ((s - 1/2) / (1 - s))^2: C1 where it starts, its energy grows
// as 1 / (1 - s), so an impact of 13 k reach^2 stops at s = 0.985. Beyond
// s = 0.999 (k reach^2 x 244 absorbed; tried only by the solver's
// iterations) g continues on its tangent.
struct StopHardening {
  static constexpr double kStart = 0.5, kLast = 0.999;
  static double g(double s) { return (s - kStart) * (s - kStart) / ((1 - s) * (1 - s)); }
  static double slope(double s) { return 2 * (s - kStart) * (1 - kStart) / ((1 - s) * (1 - s) * (1 - s)); }
  // The integral of g from kStart to s.
  static double G(double s) {
    const double a = 1 - kStart, u = 1 - s;
    return a * a / u - 2 * a * std::log(a / u) - u;
  }

  template <class T>
  static T force(const T& pen, double k, double reach) {
    const double s = value(pen) / reach;
    if (!(s > kStart)) return 0.0 * pen;
    const T sT = pen / reach;
    return select_lazy<T>(
        s < kLast,
        [&] {
          const T r = (sT - kStart) / (1.0 - sT);
          return T(k * reach * r * r);
        },
        [&] { return T(k * reach * (g(kLast) + slope(kLast) * (sT - kLast))); });
  }
  static double energy(double pen, double k, double reach) {
    const double s = pen / reach;
    if (!(s > kStart)) return 0.0;
    const double e = s < kLast ? G(s) : G(kLast) + (g(kLast) + slope(kLast) * (s - kLast) / 2) * (s - kLast);
    return k * reach * reach * e;
  }
};

// Elastic end stops at x = 0 and x = stroke: force = max(0, k pen + hardening
// + d pen_rate), never pulling; positive pushes toward +x. `reach_low` and
// `reach_high`: the penetration past x = 0 and past x = stroke that would
// empty the chamber on that side (infinite: a linear spring).
struct EndStops {
  double k, d;
  double reach_low = std::numeric_limits<double>::infinity();
  double reach_high = std::numeric_limits<double>::infinity();

  template <class T>
  T force(const T& x, const T& v, double stroke) const {
    const T zero = 0.0 * x;
    const T pen_low = -x, pen_high = x - stroke;
    const T F_low = select_lazy<T>(
        value(pen_low) > 0,
        [&] { return max(T(k * pen_low + StopHardening::force(pen_low, k, reach_low) - d * v), T(0.0)); },
        [&] { return zero; });
    const T F_high = select_lazy<T>(
        value(pen_high) > 0,
        [&] { return max(T(k * pen_high + StopHardening::force(pen_high, k, reach_high) + d * v), T(0.0)); },
        [&] { return zero; });
    return F_low - F_high;
  }
  // The stops stiffen before the chamber they close is empty: reaches from
  // the sides' travel_to_empty(); a side without gas volume (an open spring
  // side) is not limited.
  void hold_before_empty(double low, double high) {
    constexpr double none = std::numeric_limits<double>::infinity();
    reach_low = low > 0 ? low : none;
    reach_high = high > 0 ? high : none;
  }
  // The penetration of the stop at x = 0 that carries F >= 0 at rest, with a
  // spring of rate k_extra beside it (bisection past the linear range: the
  // force rises monotonically, and the linear answer bounds it).
  double rest_penetration_low(double F, double k_extra = 0.0) const {
    const double linear = F / (k + k_extra);
    if (!(linear > StopHardening::kStart * reach_low)) return linear;
    double lo = StopHardening::kStart * reach_low, hi = linear;
    for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
      const double mid = 0.5 * (lo + hi);
      ((k + k_extra) * mid + StopHardening::force(mid, k, reach_low) < F ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }
  // Elastic energy stored, k pen^2 / 2 and the hardening's.
  double energy(double x, double stroke) const {
    if (x < 0) return 0.5 * k * x * x + StopHardening::energy(-x, k, reach_low);
    if (x > stroke) return 0.5 * k * (x - stroke) * (x - stroke) + StopHardening::energy(x - stroke, k, reach_high);
    return 0.0;
  }
};

// End-position cushioning of one end: the bore opening (open in the main
// stroke, closing linearly over `ramp` before the plug engages - never a
// jump), the needle throttle and the return-stroke check valve, in parallel
// between the cushion volume EC and the channel ch behind the port.
struct Cushion {
  double C_bore, b_bore, ramp, C_cushion, b_cushion, C_check, b_check, crack, check_ramp;
  // Faults (diagnosis; 0 in a sound cylinder, CushionFaults below): a leak
  // past the cushion seal beside the needle, the seal's drag on the plug,
  // a leak past the cushioning screw's seal to the atmosphere.
  double C_seal_leak = 0, F_seal = 0, C_screw_leak = 0;
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
  auto path = [&](const T& C, double b) {
    return iso6358_mass_flow(p_EC, p_ch, T_EC, T_ch, C, b, kCushionLaminarRatio, gas);
  };
  const T m_bore = structural || value(open) > 0.0 ? path(T(c.C_bore * open), c.b_bore) : zero;
  const T m_throttle = path(T(c.C_cushion + 0.0 * x), c.b_cushion);
  const T check_open = min(max(T((p_ch - p_EC - c.crack) / c.check_ramp), T(0.0)), T(1.0));
  const T m_check = structural || value(check_open) > 0.0 ? path(T(c.C_check * check_open), c.b_check) : zero;
  if (c.C_seal_leak > 0) return m_bore + m_throttle + m_check + path(T(c.C_seal_leak + 0.0 * x), 0.3);
  return m_bore + m_throttle + m_check;
}

// The faults of one end's cushioning (diagnosis), 0 in a sound cylinder: a
// worn or damaged cushion seal lets the cushion volume leak into the channel
// beside the needle (the cushion pressure builds less and later), a tight
// or dry one drags on the plug while it is engaged (weighted by the closed
// share of the bore opening, so it starts over the same ramp), and the
// cushioning screw's seal (its O-ring, or the screw backed out of its
// thread) lets the cushion volume leak to the atmosphere outside. The
// parameters of the end whose names start with `prefix` ("" for
// cushioned_cylinder's cap end, "rod_", "cap_").
struct CushionFaults {
  static std::vector<ParameterSpec> parameters(const std::string& prefix) {
    using P = ParameterSpec;
    return {
        P::scalar(prefix + "fault_cushion_seal_leak_C", "m3/(s*Pa)",
                  "fault (diagnosis): conductance of a leak past the cushion seal, cushion volume <-> channel "
                  "(beside the needle); 0 = none",
                  0.0)
            .non_negative(),
        P::scalar(prefix + "fault_cushion_seal_F", "N",
                  "fault (diagnosis): drag of the cushion seal on the plug while it is engaged; 0 = none", 0.0)
            .non_negative(),
        P::scalar(prefix + "fault_cushion_screw_leak_C", "m3/(s*Pa)",
                  "fault (diagnosis): conductance of a leak past the cushioning screw's seal, cushion volume -> "
                  "atmosphere; 0 = none",
                  0.0)
            .non_negative(),
    };
  }
  // The faults a diagnosis names by them; `needs`: the parameter that gives
  // this end its cushioning ("" when it always has one).
  static std::vector<FaultSpec> faults(const std::string& prefix, const std::string& needs) {
    return {{prefix + "cushion_seal_leak", "leak past the cushion seal into the channel (worn or damaged seal)",
             {{"C", prefix + "fault_cushion_seal_leak_C", "m3/(s*Pa)", false, 0.0, 0.0, 2e-9, 1e-10, false}},
             needs},
            {prefix + "cushion_seal_friction", "drag of the cushion seal on the plug while cushioning (tight, dry seal)",
             {{"F", prefix + "fault_cushion_seal_F", "N", false, 0.0, 0.0, 200.0, 10.0, false}},
             needs},
            {prefix + "cushion_screw_leak",
             "leak from the cushion volume to the atmosphere past the cushioning screw (worn O-ring, screw backed out)",
             {{"C", prefix + "fault_cushion_screw_leak_C", "m3/(s*Pa)", false, 0.0, 0.0, 2e-9, 1e-10, false}},
             needs}};
  }
  static void read(const ParameterValues& p, const std::string& prefix, Cushion& c) {
    c.C_seal_leak = fault_or_none(p, prefix + "fault_cushion_seal_leak_C");
    c.F_seal = fault_or_none(p, prefix + "fault_cushion_seal_F");
    c.C_screw_leak = fault_or_none(p, prefix + "fault_cushion_screw_leak_C");
  }
};

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

// Mass and energy flowing into a side's gas besides its port's (a fault's
// leaks and wall heat; components/faults.hpp): H includes heat. Into the
// gas behind the port and into the gas at the piston - with cushioning the
// channel and the cushion annulus, without it one chamber.
template <class T>
struct ExtraInflow {
  T m, H;
  T m_piston = T(0.0), H_piston = T(0.0);
};

// Where CylinderSide::equations() writes its rows, from the pointer it is
// given: the chamber's four (mass, energy, gas law, outflow temperature),
// the wall's, the annulus' two and the tap's two; by default one block in
// that order. Outside the class so that it can be a default argument there.
struct CylinderSideRows {
  int chamber = 0, wall = 4, annulus = 5, tap = 7;
};

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

  // The cushioning of one end: engaged over the last `length` of travel,
  // the plug's column area A_col (the annulus is A - A_col), the annulus'
  // dead volume V0_EC and the paths joining annulus and channel.
  struct Cushioning {
    double length, A_col, V0_EC;
    Cushion paths;
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

  // The names of a side's rows: the chamber behind the port, the wall;
  // with cushioning the annulus' and a tap's. equation_names() are the
  // chamber's and the wall's in the default (contiguous) placement.
  static std::vector<std::string> chamber_equation_names(const std::string& chamber, const std::string& port) {
    return {"mass balance " + chamber, "energy balance " + chamber, "gas law " + chamber,
            "outflow temperature " + port};
  }
  static std::string wall_equation_name(const std::string& wall) { return "wall heat " + wall; }
  static std::vector<std::string> equation_names(const std::string& chamber, const std::string& port,
                                                 const std::string& wall) {
    auto names = chamber_equation_names(chamber, port);
    names.push_back(wall_equation_name(wall));
    return names;
  }
  static std::vector<std::string> annulus_equation_names(const std::string& annulus) {
    return {"mass balance " + annulus, "energy balance " + annulus};
  }
  // A cushion annulus' state (m_<var>, U_<var>, of the annulus called
  // `description`) and its rows.
  static InfoPart annulus_part(const std::string& var, const std::string& rows, const std::string& description) {
    return {.variables = {{"m_" + var, "kg", "gas mass, " + description, 0.0, "U_" + var},
                          {"U_" + var, "J", "internal energy, " + description}},
            .equations = annulus_equation_names(rows)};
  }
  static std::vector<std::string> tap_equation_names(const std::string& tap) {
    return {"tap " + tap + " pressure", "tap " + tap + " temperature"};
  }

  // A side of face area A (m2), dead volume V0 (m3, the channel's with
  // cushioning) and wall perimeter (m, for wall heat).
  CylinderSide(double A, double V0, double perimeter) : A_(A), V0_(V0), perimeter_(perimeter) {}

  // The same, with the cushioning read from the <end>_cushion_* parameters
  // when present; A_rod is the rod area inside the plug (the rod side's
  // sleeve column is A_plug - A_rod).
  CylinderSide(const ParameterValues& p, const std::string& end, double A, double V0, double perimeter, double A_rod,
               double stroke)
      : CylinderSide(A, V0, perimeter) {
    if (auto k = read_cushioning(p, end, A, A_rod, stroke)) cushion(*k);
  }
  // The cushioning of the end called `end` from its <end>_cushion_*
  // parameters (none without <end>_cushion_length), on a side of face area A.
  static std::optional<Cushioning> read_cushioning(const ParameterValues& p, const std::string& end, double A,
                                                   double A_rod, double stroke) {
    if (!has_cushion(p, end)) return std::nullopt;
    const std::string e = end + "_";
    for (const char* name : {"plug_diameter", "cushion_C"})
      if (!p.has(e + name))
        throw ParameterError(e + name, end + "-end cushioning (" + e + "cushion_length given) needs " + e + name);
    const double A_plug = circle_area(p[e + "plug_diameter"]);
    if (!(A_plug > A_rod && A_plug - A_rod < A))
      throw ParameterError(e + "plug_diameter", "the plug diameter must lie between the rod's and the bore's");
    Cushioning k{p[e + "cushion_length"], A_plug - A_rod, p[e + "dead_volume_cushion"],
                 Cushion{p[e + "bore_opening_C"], p[e + "bore_opening_b"], p[e + "bore_opening_ramp"],
                         p[e + "cushion_C"], p[e + "cushion_b"], p[e + "check_C"], p[e + "check_b"],
                         p[e + "check_cracking"], p[e + "check_ramp"]}};
    CushionFaults::read(p, e, k.paths);
    if (k.length + k.paths.ramp >= stroke)
      throw ParameterError(e + "cushion_length",
                           "the cushioning length (with its ramp) must be shorter than the stroke");
    return k;
  }

  // Splits the side into the cushion annulus and the channel.
  void cushion(const Cushioning& k) {
    cushioned_ = true;
    L_ = k.length;
    A_col_ = k.A_col;
    V0_EC_ = k.V0_EC;
    c_ = k.paths;
  }
  // A tapping port into the annulus (with cushioning): its flow enters the
  // annulus' balances; it adds the rows p = p_annulus and its T_out.
  void tap(int port) { tap_ = cushioned_ ? port : -1; }

  // Piston travel past this side's end that would empty its smallest gas
  // volume (the end stop's reach on this side).
  double travel_to_empty() const {
    return cushioned_ ? std::min(V0_ / A_col_, V0_EC_ / (A_ - A_col_)) : V0_ / A_;
  }

  bool cushioned() const { return cushioned_; }
  double cushion_length() const { return L_; }
  // The cushion seal's drag on the piston while the plug is engaged (a
  // fault; 0 without), opposing v.
  bool has_seal_drag() const { return cushioned_ && c_.F_seal > 0; }
  template <class T>
  T cushion_seal_drag(const Gas<T>& g, const T& v, double v_reg) const {
    if (!has_seal_drag()) return 0.0 * v;
    return -c_.F_seal * (1.0 - g.open) * tanh(v / v_reg);
  }
  double ramp() const { return c_.ramp; }
  int variables() const { return cushioned_ ? 4 : 2; }
  // The side's internal variables start at `first`: m, U (channel with
  // cushioning), then m_EC, U_EC; or at `annulus` for the annulus'.
  void set_first_variable(int first) { set_variables(first, first + 2); }
  void set_variables(int channel, int annulus) {
    k_ = channel;
    k_EC_ = annulus;
  }
  int rows() const { return cushioned_ ? (tap_ >= 0 ? 9 : 7) : 5; }
  using Rows = CylinderSideRows;

  // Pressures and temperatures at travel d from the side's end; the flow
  // between annulus and channel is gas()'s.
  template <class T>
  Gas<T> chambers(const Eval<T>& e, const T& d) const {
    const GasModel& gas = e.gas();
    Gas<T> g;
    const T& m = e.var(k_);
    const T& U = e.var(k_ + 1);
    g.T_gas = chamber_temperature(m, U, gas);
    g.m_x = g.H_x = 0.0 * d;
    g.open = 0.0 * d + 1.0;
    if (!cushioned_) {
      g.p = chamber_pressure(U, T(V0_ + A_ * d), gas);
      g.p_piston = g.p;
      g.T_piston = g.T_gas;
      return g;
    }
    g.p = chamber_pressure(U, T(V0_ + A_col_ * d), gas);
    g.T_piston = chamber_temperature(e.var(k_EC_), e.var(k_EC_ + 1), gas);
    g.p_piston = chamber_pressure(e.var(k_EC_ + 1), T(V0_EC_ + (A_ - A_col_) * d), gas);
    return g;
  }
  // With `gap` the travel left before the plug engages (d - L; a caller
  // may pass it as computed from its own coordinate).
  template <class T>
  Gas<T> gas(const Eval<T>& e, const T& d) const {
    return gas(e, d, T(d - L_));
  }
  template <class T>
  Gas<T> gas(const Eval<T>& e, const T& d, const T& gap) const {
    Gas<T> g = chambers(e, d);
    if (!cushioned_) return g;
    g.m_x = cushion_flow(c_, gap, g.p_piston, g.p, g.T_piston, g.T_gas, d, e.gas(), g.open);
    g.H_x = enthalpy_inflow(g.m_x, g.T_piston, g.T_gas, e.gas());
    return g;
  }

  // Pressure force of this side's gas on the piston, pushing it away from
  // this side's end (toward larger d).
  template <class T>
  T force(const Gas<T>& g) const {
    return cushioned_ ? T(annulus_force(g) + port_force(g)) : port_force(g);
  }
  // Its parts: of the gas behind the port (the channel's on the plug column
  // with cushioning) and of the annulus' (0 without).
  template <class T>
  T port_force(const Gas<T>& g) const {
    return g.p * (cushioned_ ? A_col_ : A_);
  }
  template <class T>
  T annulus_force(const Gas<T>& g) const {
    return cushioned_ ? T(g.p_piston * (A_ - A_col_)) : T(0.0 * g.p);
  }
  // p dV/dt of the side's gas (power to the piston) at dd/dt.
  template <class T>
  T p_dV(const Gas<T>& g, const T& d_dot) const {
    return force(g) * d_dot;
  }

  // The side's rows: balances, the port's pressure and outflow temperature,
  // the wall heat row; with cushioning the annulus' balances (and tap).
  template <class T>
  void equations(const Eval<T>& e, const GasPortView<T>& port, const HeatPortView<T>& heat, const Gas<T>& g,
                 const T& d, const T& d_dot, double wall_alpha, T* r,
                 const ExtraInflow<T>* extra = nullptr, const Rows& at = {}) const {
    const GasModel& gas = e.gas();
    e.reject_unless_positive(e.var(k_));
    e.reject_unless_positive(e.var(k_ + 1));
    const T H_port = enthalpy_inflow(port.m_flow, port.T_in, port.T_out, gas);
    const bool walls_at_gas_T = !(wall_alpha > 0);
    T* c = r + at.chamber;
    if (!cushioned_) {
      c[0] = e.der(k_) - port.m_flow;
      if (extra) c[0] -= extra->m + extra->m_piston;
      // p dV/dt with the port's pressure, which the gas-law row below makes
      // U's: the form the cushion rig's solver figures are measured with.
      c[1] = e.der(k_ + 1) - H_port + port.p * A_ * d_dot - heat.Q;
      if (extra) c[1] -= extra->H + extra->H_piston;
      c[2] = port.p - g.p;
      // With the heat port at the gas temperature the port's T_out is its
      // alias, which alias elimination folds into one unknown.
      c[3] = port.T_out - (walls_at_gas_T ? heat.T : g.T_gas);
    } else {
      c[0] = e.der(k_) - g.m_x - port.m_flow;
      c[1] = e.der(k_ + 1) - g.H_x - H_port + g.p * A_col_ * d_dot;
      if (extra) {
        c[0] -= extra->m;
        c[1] -= extra->H;
      }
      c[2] = port.p - g.p;
      c[3] = port.T_out - g.T_gas;
      annulus_equations(e, heat, g, d_dot, walls_at_gas_T, r + at.annulus, r + at.tap);
      if (c_.C_screw_leak > 0) screw_leak(g, gas, r + at.annulus);
      if (extra) {
        r[at.annulus] -= extra->m_piston;
        r[at.annulus + 1] -= extra->H_piston;
      }
    }
    if (wall_alpha > 0)
      r[at.wall] = heat.Q - wall_alpha * wall_area(d) * (heat.T - g.T_piston);
    else
      r[at.wall] = heat.T - g.T_piston;
  }

  // The walls of the gas at the piston at travel d from this end (m2).
  template <class T>
  T wall_area(const T& d) const {
    return chamber_wall_area(A_, perimeter_, d, V0_ + V0_EC_);
  }

  void start(StartValues& sv, const GasModel& gas, int port, int heat, double p0, double T0, double d) const {
    auto fill = [&](int k, double V) {
      const double mass = p0 * V / (gas.R * T0);
      sv.fix_var(k, mass);
      sv.fix_var(k + 1, mass * gas.cv() * T0);
    };
    fill(k_, V0_ + (cushioned_ ? A_col_ : A_) * d);
    if (cushioned_) fill(k_EC_, V0_EC_ + (A_ - A_col_) * d);
    for (int gas_port : {port, tap_}) {
      if (gas_port < 0) continue;
      sv.guess_pressure(gas_port, p0);
      sv.guess_temperature(gas_port, T0);
    }
    sv.guess_temperature(heat, T0);
  }

  // Internal energy of the side's gas, and of its cushion annulus alone
  // (0 without cushioning).
  double internal_energy(const Eval<double>& e) const {
    return e.var(k_ + 1) + cushion_internal_energy(e);
  }
  double cushion_internal_energy(const Eval<double>& e) const { return cushioned_ ? e.var(k_EC_ + 1) : 0.0; }
  // p dV/dt of the gas behind the port alone (the channel with cushioning,
  // else all of the side's gas) and of the annulus alone (0 without).
  double port_p_dV(const Gas<double>& g, double d_dot) const { return port_force(g) * d_dot; }
  double annulus_p_dV(const Gas<double>& g, double d_dot) const { return annulus_force(g) * d_dot; }
  // p dV/dt of the channel gas alone (the plug column; 0 without cushioning).
  double channel_p_dV(const Gas<double>& g, double d_dot) const { return cushioned_ ? port_p_dV(g, d_dot) : 0.0; }

 private:
  // The annulus' balances: flow to the channel, the piston's work, the
  // wall's heat and a tap's inflow; the tap's pressure and temperature.
  template <class T>
  void annulus_equations(const Eval<T>& e, const HeatPortView<T>& heat, const Gas<T>& g, const T& d_dot,
                         bool walls_at_gas_T, T* r, T* tap_rows) const {
    e.reject_unless_positive(e.var(k_EC_));
    e.reject_unless_positive(e.var(k_EC_ + 1));
    const T p_dV = annulus_force(g) * d_dot;
    if (tap_ < 0) {
      r[0] = e.der(k_EC_) + g.m_x;
      r[1] = e.der(k_EC_ + 1) + g.H_x + p_dV - heat.Q;
      return;
    }
    const auto tap = e.gas_port(tap_);
    const T H_tap = enthalpy_inflow(tap.m_flow, tap.T_in, tap.T_out, e.gas());
    r[0] = e.der(k_EC_) + g.m_x - tap.m_flow;
    r[1] = e.der(k_EC_ + 1) + g.H_x - H_tap + p_dV - heat.Q;
    tap_rows[0] = tap.p - g.p_piston;
    tap_rows[1] = tap.T_out - (walls_at_gas_T ? heat.T : g.T_piston);
  }

  // The cushioning screw's seal leaking (a fault): annulus -> atmosphere,
  // into the annulus' balances `r`.
  template <class T>
  void screw_leak(const Gas<T>& g, const GasModel& gas, T* r) const {
    const T zero = 0.0 * g.p_piston;
    const T p_amb = zero + gas.p_ambient, T_amb = zero + gas.T_ambient;
    const T m = iso6358_mass_flow(g.p_piston, p_amb, g.T_piston, T_amb, T(zero + c_.C_screw_leak), 0.3, 0.999, gas);
    r[0] += m;
    r[1] -= enthalpy_inflow(T(-m), T_amb, g.T_piston, gas);
  }

  double A_, V0_, perimeter_;
  bool cushioned_ = false;
  double L_ = 0, A_col_ = 0, V0_EC_ = 0;
  Cushion c_{};
  int k_ = 0, k_EC_ = 2, tap_ = -1;
};

// The piston of single_acting_cylinder (whose parameters, faults and stop
// events the `cylinder` preset declares too): the piston's areas and stroke, its two sides (cushioning read from the
// <end>_cushion_* parameters where the component offers them), end stops,
// wall heat, friction and initial state, with their parameters.
// The friction faults every piston declares (diagnosis), 0 in a sound
// cylinder: a breakaway force apart from the running friction, fading above
// 5 mm/s, and a friction growing with the pressure difference across the
// piston seal (the pressure term of the end-cushioning paper's eq. 8); a
// double-acting piston also declares the law growing with its chambers'
// own pressures (chamber_pressure_fault()).
struct FrictionFaults {
  double breakaway_F = 0, per_pressure = 0, per_chamber_pressure = 0;

  explicit FrictionFaults(const ParameterValues& p)
      : breakaway_F(p["fault_breakaway_F"]),
        per_pressure(p["fault_friction_per_pressure"]),
        per_chamber_pressure(p["fault_friction_per_chamber_pressure"]) {}

  static std::vector<ParameterSpec> parameters() {
    using P = ParameterSpec;
    return {
        P::scalar("fault_breakaway_F", "N",
                  "fault (diagnosis): breakaway force beyond the friction law, fading above 5 mm/s; 0 = none", 0.0)
            .non_negative(),
        P::scalar("fault_friction_per_pressure", "N/Pa",
                  "fault (diagnosis): running friction beyond the law per pascal across the piston seal "
                  "(e.g. 1e-5 N/Pa = 1 N/bar); 0 = none",
                  0.0)
            .non_negative(),
        P::scalar("fault_friction_per_chamber_pressure", "1/Pa",
                  "fault (diagnosis): the friction law's force grows by this share per pascal of the two chambers' "
                  "summed gauge pressure (pAB+; e.g. 1e-6 1/Pa = 10 % per bar); 0 = none",
                  0.0)
            .non_negative(),
    };
  }
  static std::vector<FaultSpec> faults() {
    return {
        {"friction_breakaway", "breakaway (stiction) force beyond the running friction (dry seals, long standstill)",
         {{"F", "fault_breakaway_F", "N", false, 0.0, 0.0, 200.0, 10.0, false}}},
        // Eq. 8 turns eq. 7's constant b into b0 + b1 p: a slope found in
        // the data moves the part at zero pressure too, so the law's scale
        // is fitted with it (a slope alone could only add friction).
        {"friction_pressure",
         "seal friction growing with the pressure across the seal beyond the law (seal squeeze, swelling: the "
         "pressure term of the end-cushioning paper's eq. 8), with the law's own share rescaled",
         {{"k", "fault_friction_per_pressure", "N/Pa", false, 0.0, 0.0, 1e-4, 5e-6, false},
          {"scale", "friction_scale", "1", true, 1.0, 0.25, 4.0, 1.0, true}}},
    };
  }

  // A double-acting piston's seal may be two lips, each pressed against
  // the bore by its own chamber: the pressures then press the whole seal
  // harder, and every part of its friction (dry, Stribeck, viscous) grows
  // with the sum of the chambers' gauge pressures - eq. 8 on pAB+ with each
  // coefficient c0 (1 + m pAB+), as the end-cushioning paper's Annex C set
  // has it - not with their difference (the piston's other pressure fault).
  static FaultSpec chamber_pressure_fault() {
    return {"friction_chamber_pressure",
            "seal friction growing in proportion with the chambers' own pressures beyond the law (lip seals "
            "pressed by their chambers: eq. 8 of the end-cushioning paper on pAB+), with the law's level rescaled",
            {{"m", "fault_friction_per_chamber_pressure", "1/Pa", false, 0.0, 0.0, 5e-6, 5e-7, false},
             {"scale", "friction_scale", "1", true, 1.0, 0.25, 4.0, 1.0, true}}};
  }
  // The law's force times this (1 without the fault).
  template <class T>
  T law_factor(const T& p_a, const T& p_b, double p_ambient) const {
    return 1.0 + per_chamber_pressure * (p_a + p_b - 2.0 * p_ambient);
  }

  bool any() const { return breakaway_F > 0 || per_pressure > 0; }
  // On the piston (+x), opposing v; p_a and p_b the pressures on either
  // side of the seal (|p_a - p_b| smoothed over 1 Pa). A fault at 0 adds no
  // term.
  template <class T>
  T force(const T& v, const T& p_a, const T& p_b, double v_reg) const {
    T F = 0.0 * v;
    if (breakaway_F > 0) F -= breakaway_F * exp(-(v / 5e-3) * (v / 5e-3)) * tanh(v / v_reg);
    if (per_pressure > 0) {
      const T dp = p_a - p_b;
      F -= per_pressure * sqrt(dp * dp + 1.0) * tanh(v / v_reg);
    }
    return F;
  }
};

// An event's tag and log message.
struct CylinderEvent {
  std::string tag, text;
};
// The events of the stops at x = 0 and x = stroke: a contact makes the
// force jump (the damping term acts from the first contact on), so the
// solver re-initialises there; leaving a stop is continuous (k pen - d v
// falls to 0 before pen does).
struct StopEvents {
  CylinderEvent zero_contact, zero_left, stroke_contact, stroke_left;

  // Crossing the stop at x = 0 (`at_zero`) or at x = stroke in direction dir.
  EventResult event(bool at_zero, int dir, const std::string& at) const {
    const bool contact = at_zero ? dir < 0 : dir > 0;
    const CylinderEvent& ev =
        at_zero ? (contact ? zero_contact : zero_left) : (contact ? stroke_contact : stroke_left);
    return {contact, ev.text + at, ev.tag};
  }
};

// Faults (diagnosis) of a piston's chambers, all 0 in a sound cylinder:
// leak conductances across the piston seal and past the rod seal, heat
// exchange of each chamber's gas with walls at the ambient temperature. A
// cylinder that declares none of their parameters has none of them.
struct ChamberFaults {
  double leak_piston_C = 0, leak_rod_C = 0, wall_alpha = 0;

  explicit ChamberFaults(const ParameterValues& p)
      : leak_piston_C(fault_or_none(p, "fault_piston_leak_C")),
        leak_rod_C(fault_or_none(p, "fault_rod_leak_C")),
        wall_alpha(fault_or_none(p, "fault_wall_alpha")) {}

  // Their parameters and the faults a diagnosis names by them.
  static std::vector<ParameterSpec> parameters() {
    using P = ParameterSpec;
    return {
        P::scalar("fault_piston_leak_C", "m3/(s*Pa)",
                  "fault (diagnosis): conductance of a leak across the piston seal, cap <-> rod side; 0 = none", 0.0)
            .non_negative(),
        P::scalar("fault_rod_leak_C", "m3/(s*Pa)",
                  "fault (diagnosis): conductance of a leak past the rod seal to the atmosphere; 0 = none", 0.0)
            .non_negative(),
        P::scalar("fault_wall_alpha", "W/(m2*K)",
                  "fault (diagnosis): heat transfer coefficient of each chamber's gas with its walls, at the ambient "
                  "temperature, over the chamber's wetted area (as wall_alpha's); 0 = none",
                  0.0)
            .non_negative(),
    };
  }
  static std::vector<FaultSpec> faults() {
    return {
        {"piston_seal_leak", "leak across the piston seal between the chambers (worn or damaged seal)",
         {{"C", "fault_piston_leak_C", "m3/(s*Pa)", false, 0.0, 0.0, 2e-9, 1e-10, false}}},
        {"rod_seal_leak", "leak past the rod seal to the atmosphere (worn rod seal, scored rod)",
         {{"C", "fault_rod_leak_C", "m3/(s*Pa)", false, 0.0, 0.0, 2e-9, 1e-10, false}}},
        {"wall_heat", "heat exchange of the chamber gas with the walls and surroundings (unmodelled)",
         {{"alpha", "fault_wall_alpha", "W/(m2*K)", false, 0.0, 0.0, 600.0, 30.0, false}}},
    };
  }

  // The fault flows into each side's gas: the piston-seal leak between the
  // gases at the piston (the cushion annuli while cushioning; `rod` null: a
  // vented spring side, where the leak goes to the atmosphere), the
  // rod-seal leak from the gas behind the rod side's port (at the head, where
  // the rod seal is) and the wall heat of the gas at the piston (the
  // chambers whose walls the heat ports are; a channel is adiabatic) over
  // each one's wetted area `wall_cap`, `wall_rod` (m2): a cushion volume's
  // short wall takes less heat than a long chamber's.
  // Null when the cylinder has none of these faults: the sound cylinder's
  // rows are untouched.
  template <class T>
  struct Flows {
    ExtraInflow<T> cap, rod;
  };
  bool any() const { return leak_piston_C > 0 || leak_rod_C > 0 || wall_alpha > 0; }
  template <class T>
  Flows<T> flows(const CylinderSide::Gas<T>& cap, const CylinderSide::Gas<T>* rod, const GasModel& gas,
                 const T& wall_cap, const T& wall_rod) const {
    const T zero = 0.0 * cap.p;
    Flows<T> f{{zero, zero, zero, zero}, {zero, zero, zero, zero}};
    const T p_amb = zero + gas.p_ambient, T_amb = zero + gas.T_ambient;
    const T& p_other = rod ? rod->p_piston : p_amb;
    const T& T_other = rod ? rod->T_piston : T_amb;
    if (leak_piston_C > 0) {
      const T m =
          iso6358_mass_flow(cap.p_piston, p_other, cap.T_piston, T_other, T(zero + leak_piston_C), 0.3, 0.999, gas);
      f.cap.m_piston -= m;
      f.cap.H_piston += enthalpy_inflow(T(-m), T_other, cap.T_piston, gas);
      f.rod.m_piston += m;
      f.rod.H_piston += enthalpy_inflow(m, cap.T_piston, T_other, gas);
    }
    if (rod && leak_rod_C > 0) {
      const T m = iso6358_mass_flow(rod->p, p_amb, rod->T_gas, T_amb, T(zero + leak_rod_C), 0.3, 0.999, gas);
      f.rod.m -= m;
      f.rod.H += enthalpy_inflow(T(-m), T_amb, rod->T_gas, gas);
    }
    if (wall_alpha > 0) {
      f.cap.H_piston += wall_alpha * wall_cap * (T_amb - cap.T_piston);
      if (rod) f.rod.H_piston += wall_alpha * wall_rod * (T_amb - rod->T_piston);
    }
    return f;
  }
};

struct Piston {
  double A, A_rod, stroke;
  CylinderSide cap, rod;
  EndStops stops;
  double wall_alpha;
  FrictionLaw friction;
  double x0, p0_cap, p0_rod, T0;
  ChamberFaults chamber_faults;
  FrictionFaults friction_faults;
  SealPresliding presliding;

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
        T0(p["T0"]),
        chamber_faults(p),
        friction_faults(p),
        presliding(p) {
    if (p["rod"] >= p["bore"]) throw ParameterError("rod", "rod diameter must be smaller than the bore");
    stops.hold_before_empty(cap.travel_to_empty(), rod.travel_to_empty());
  }

  // Stops, wall heat, friction; then the initial state.
  static std::vector<ParameterSpec> parameters(const std::string& p0_rod_meaning) {
    using P = ParameterSpec;
    std::vector<ParameterSpec> out = {
        P::scalar("stop_stiffness", "N/m", "end stop stiffness", 1e7).positive(),
        P::scalar("stop_damping", "N*s/m", "end stop damping", 3000.0).non_negative(),
        P::scalar("wall_alpha", "W/(m2*K)",
                  "gas-to-wall heat transfer coefficient; 0: heat ports at gas temperature (external convection); "
                  "> 0 with a heat port unconnected: that wall at the ambient temperature",
                  0.0)
            .non_negative(),
    };
    for (auto& f : FrictionLaw::parameters(false)) out.push_back(std::move(f));
    for (auto& f : SealPresliding::parameters()) out.push_back(std::move(f));
    const std::vector<ParameterSpec> initial = {
        P::scalar("x0", "m", "initial position; default: at rest against the stop at x = 0 at force equilibrium",
                  std::numeric_limits<double>::quiet_NaN()),
        P::scalar("p0_cap", "Pa", "initial cap-side pressure, absolute; default: ambient")
            .positive()
            .absolute()
            .ambient_pressure_by_default(),
        P::scalar("p0_rod", "Pa", "initial " + p0_rod_meaning + " pressure, absolute; default: ambient")
            .positive()
            .absolute()
            .ambient_pressure_by_default(),
        P::scalar("T0", "K", "initial gas temperature; default: ambient").positive().ambient_temperature_by_default(),
    };
    out.insert(out.end(), initial.begin(), initial.end());
    for (auto& f : ChamberFaults::parameters()) out.push_back(std::move(f));
    for (auto& f : FrictionFaults::parameters()) out.push_back(std::move(f));
    return out;
  }

  // What can fail in a piston (an FMEA of the seals, friction and walls);
  // `volumes`: the dead-volume parameters, a factor each.
  static std::vector<FaultSpec> faults(const std::vector<std::string>& volumes) {
    std::vector<FaultSpec> out = ChamberFaults::faults();
    out.insert(out.begin() + 2, FrictionLaw::running_fault());  // after the two leaks, as before
    for (auto& f : FrictionFaults::faults()) out.push_back(std::move(f));
    for (const auto& v : volumes) out.push_back(dead_volume_fault(v, true));
    return out;
  }

  // The fault of dead volume `v` (a factor). The gas at a port holds the
  // port's fitting and any hose the drawing leaves out before the next
  // component: often tens of times the drawn value, as a volume's
  // (volume.cpp). One inside the end cap is off by its machining.
  static FaultSpec dead_volume_fault(const std::string& v, bool at_port) {
    if (at_port)
      return {v + "_off", "dead volume " + v + " off (the port's fittings, a hose to the next component not drawn)",
              {{"k", v, "1", true, 1.0, 0.1, 100.0, 2.0, true}}};
    return {v + "_off", "dead volume " + v + " off (machining, fittings inside the end cap)",
            {{"k", v, "1", true, 1.0, 0.2, 10.0, 2.0, true}}};
  }

  template <class T>
  using FaultFlows = ChamberFaults::Flows<T>;
  bool has_fault_flows() const { return chamber_faults.any(); }
  // `x`: the piston's position (the cap side's travel).
  template <class T>
  FaultFlows<T> fault_flows(const CylinderSide::Gas<T>& cap, const CylinderSide::Gas<T>* rod, const GasModel& gas,
                            const T& x) const {
    return chamber_faults.flows(cap, rod, gas, this->cap.wall_area(x), this->rod.wall_area(T(stroke - x)));
  }
  // Roots 0 and 1: the stops at x = 0 and x = stroke.
  void stop_roots(double x, double* g) const {
    g[0] = x;
    g[1] = x - stroke;
  }
  static EventResult stop_event(int root, int dir, const std::string& at) {
    return stop_texts().event(root == 0, dir, at);
  }
  static StopEvents stop_texts() {
    return {{"retracted", "retracted: contact with the cap-end stop"},
            {"left_retracted", "leaves the retracted end"},
            {"extended", "extended: contact with the rod-end stop"},
            {"left_extended", "leaves the extended end"}};
  }
  static std::vector<EventSpec> stop_events() {
    return {{"retracted", "contact with the cap-end stop"},
            {"left_retracted", "leaves the retracted end"},
            {"extended", "contact with the rod-end stop"},
            {"left_extended", "leaves the extended end"}};
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
