// Double-acting cylinder with integrated end-position cushioning at the cap
// end and optionally at the rod end (seed paper 000, fig. 1;
// ../shared/rigs/cushion-rig.yaml).
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
// Friction (components/friction.hpp, `friction_model`): seed 000 eq. 4/7/8
// presets or custom eq. 8 coefficients (`friction: custom`, friction_b0 ...
// as `pneumo fit friction -o` writes them), with a separate set in the
// cushioning zone (`friction_cushion`, preset or custom friction_cushion_*)
// blended over the bore-opening ramp; or Coulomb + viscous; or LuGre (seed
// 002 eq. 8, bristle state z as an internal variable - the piston can stick).
// End stops: elastic, force = max(0, k pen + d pen_rate), never pulling.
//
// Rod-end cushioning (present when `rod_plug_diameter` is given; the
// instance then has the extra chamber, port and roots - instance_info): the
// rod side splits the same way into the rod cushion annulus ECr,
//   V_ECr = V0_ECr + (A_B - A_CPr) x,
// and the rod-side channel behind port A, V_A = V0_A + (A_CPr - A_R) x, with
// its own bore opening (closing over a ramp before x = rod_cushion_length),
// needle throttle and check valve. Without it the rod side is one chamber.
//
// Ports A and B are closed when unconnected (a gas spring). With
// cushion_taps: yes the ports EC and EC_rod tap the cushion volumes
// (sensors, leakage throttles): their flow enters that volume's balances,
// p = p_EC, T_out = T_EC; closed when unconnected.
//
// Heat: with wall_alpha = 0 the heat ports are at the gas temperature
// (insulated if unconnected; external heat_convection does the transfer).
// With wall_alpha > 0 they are the walls and the gas exchanges
//   Q = wall_alpha A(x) (T_wall - T_gas)
// with them (seed 002 eq. 2), A(x) = both end faces + the lateral bore (and
// rod, rod side) surface over the chamber's current length (stroke travel
// plus dead volume / piston area). heat_A acts on the rod chamber (ECr with
// rod cushioning), heat_cap on the cushion annulus EC; the channels are
// adiabatic.
//
// Energy audit observables (W, positive into the gas unless said): H_* the
// enthalpy flow in at each port, P_pdV_* = p dV/dt the work each chamber's
// gas does on the piston, Q_* heat, H_cushion* the enthalpy flow through
// the cushion throttles/bore opening, P_friction = F_friction v and P_stop =
// F_stop v (<= 0 when dissipating; P_stop also stores E_stop), U_gas.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "components/builtin.hpp"
#include "components/cylinder_parts.hpp"

namespace pneumo::components {

namespace {
constexpr double kPi = kCylinderPi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

class CushionedCylinder final : public ComponentT<CushionedCylinder> {
 public:
  enum Port { kA, kB, kFlange, kHeatA, kHeatCap, kTapEC, kTapECr };
  // Internal variables; rod cushioning adds kMECr.., LuGre adds z (index z_var_).
  // Each chamber's state is (m, U): its temperature U / (m c_v) and pressure
  // (kappa - 1) U / V are evaluated in place rather than carried as unknowns
  // (a row and a column fewer per chamber); they remain observables.
  enum Var { kMA, kUA, kMEC, kUEC, kMch, kUch, kMECr, kUECr };
  enum Obs {
    kX, kV, kPA, kPEC, kPch, kTAo, kTECo, kTcho, kFfric, kFstop, kOpen, kCushionFlow,
    kZ, kFpressure, kHA, kHB, kHEC, kPdVA, kPdVEC, kPdVch, kPdV, kQA, kQcap, kHcushion, kPfric, kPstop, kEstop,
    kUgas,
    // rod cushioning only
    kPECr, kTECro, kOpenR, kCushionFlowR, kHECr, kPdVECr, kHcushionR
  };
  enum Root { kRampStart, kCushionEntry, kStopRod, kStopCap, kRodRampStart, kRodCushionEntry };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "cushioned_cylinder";
    i.description =
        "Double-acting cylinder with end-position cushioning at the cap end and optionally at the rod end (plug, "
        "cushion annulus, needle throttle, check valve), mass and energy balance in each chamber, friction (seed 000 "
        "eq. 4/7/8 presets, Coulomb + viscous, LuGre), optional gas-to-wall heat transfer, elastic end stops. x = 0 "
        "extended, x = stroke at the cap; port A rod side, port B cap-side outlet (both closed if unconnected).";
    using P = ParameterSpec;
    i.parameters = {
        P::scalar("bore", "m", "piston diameter").positive(),
        P::scalar("rod", "m", "rod diameter; 0: rodless (both sides full bore area, seed 001's MY3B)").non_negative(),
        P::scalar("stroke", "m", "stroke").positive(),
        P::scalar("plug_diameter", "m", "cushioning plug diameter").positive(),
        P::scalar("cushion_length", "m", "cushioning length (plug engages at x = stroke - cushion_length)")
            .positive(),
        P::scalar("dead_volume_rod_side", "m3",
                  "rod-side chamber volume at x = 0 (with rod cushioning: the rod-side channel behind port A)")
            .positive(),
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
        // Rod-end cushioning: present when rod_plug_diameter is given. The
        // throttle/valve parameters default to their cap-end values.
        P::scalar("rod_plug_diameter", "m", "rod-end cushion sleeve diameter (> rod); enables rod-end cushioning")
            .positive()
            .optional(),
        P::scalar("rod_cushion_length", "m", "rod-end cushioning length (engages at x = rod_cushion_length)")
            .positive()
            .optional(),
        P::scalar("rod_dead_volume_cushion", "m3", "rod cushion annulus volume at x = 0").positive().optional(),
        P::scalar("rod_bore_opening_C", "m3/(s*Pa)", "rod end: bore opening conductance (default bore_opening_C)")
            .positive()
            .optional(),
        P::scalar("rod_bore_opening_b", "1", "rod end: bore opening b (default bore_opening_b)")
            .range(0, 0.99)
            .optional(),
        P::scalar("rod_bore_opening_ramp", "m", "rod end: bore opening ramp (default bore_opening_ramp)")
            .positive()
            .optional(),
        P::table("rod_cushion_C_of_z", {"rev", "m3/(s*Pa)"}, "rod end: throttle C(z) (default cushion_C_of_z)",
                 false),
        P::scalar("rod_cushion_b0", "1", "rod end: b0 (default cushion_b0)").range(0, 0.99).optional(),
        P::scalar("rod_cushion_b_slope", "1", "rod end: b slope (default cushion_b_slope)").range(-1, 1).optional(),
        P::scalar("z_EC_rod", "rev", "rod end: throttle opening (default z_EC)").non_negative().optional(),
        P::scalar("rod_check_C", "m3/(s*Pa)", "rod end: check valve C (default check_C)").non_negative().optional(),
        P::scalar("rod_check_b", "1", "rod end: check valve b (default check_b)").range(0, 0.99).optional(),
        P::scalar("rod_check_cracking", "Pa", "rod end: cracking pressure (default check_cracking)")
            .non_negative()
            .optional(),
        P::scalar("rod_check_ramp", "Pa", "rod end: check valve ramp (default check_ramp)").positive().optional(),
        P::scalar("stop_stiffness", "N/m", "end stop stiffness", 1e7).positive(),
        P::scalar("stop_damping", "N*s/m", "end stop damping", 3000.0).non_negative(),
        P::text("cushion_taps", {"no", "yes"},
                "yes: ports EC (and EC_rod) tap the cushion volumes (sensors, leakage throttles); closed when "
                "unconnected, but each adds an algebraic pressure to the step-size control, so they are off by "
                "default",
                "no"),
        P::scalar("wall_alpha", "W/(m2*K)",
                  "gas-to-wall heat transfer coefficient; 0: heat ports at gas temperature (external convection)", 0.0)
            .non_negative(),
    };
    for (auto& f : FrictionLaw::parameters(true)) i.parameters.push_back(std::move(f));
    const std::vector<ParameterSpec> initial = {
        P::scalar("x0", "m", "initial position; default: at rest against the stop at x = 0 at force equilibrium",
                  kNaN),
        P::scalar("p0_A", "Pa", "initial rod-side pressure (with rod cushioning also ECr), absolute", 101325.0)
            .positive(),
        P::scalar("p0_cap", "Pa", "initial cap-side pressure (cushion volume and channel), absolute", 101325.0)
            .positive(),
        P::scalar("T0", "K", "initial gas temperature", 293.15).positive(),
    };
    i.parameters.insert(i.parameters.end(), initial.begin(), initial.end());
    i.ports = {{"A", Domain::pneumatic, Causality::acausal, "rod-side chamber port (closed if unconnected)", true},
               {"B", Domain::pneumatic, Causality::acausal, "cap-side outlet (outflow channel; closed if unconnected)",
                true},
               {"flange", Domain::translational, Causality::acausal, "rod end; position = x"},
               {"heat_A", Domain::thermal, Causality::acausal, "wall of the rod-side chamber (ECr with rod cushioning)",
                true},
               {"heat_cap", Domain::thermal, Causality::acausal, "wall of the cushion volume", true},
               {"EC", Domain::pneumatic, Causality::acausal, "tapping into the cushion volume EC (closed if unconnected)",
                true},
               {"EC_rod", Domain::pneumatic, Causality::acausal,
                "tapping into the rod cushion volume (rod cushioning only; closed if unconnected)", true}};
    i.variables = {{"m_A", "kg", "gas mass, rod side"},        {"U_A", "J", "internal energy, rod side"},
                   {"m_EC", "kg", "gas mass, cushion volume"},  {"U_EC", "J", "internal energy, cushion volume"},
                   {"m_ch", "kg", "gas mass, channel"},         {"U_ch", "J", "internal energy, channel"},
                   {"m_EC_rod", "kg", "gas mass, rod cushion volume"},
                   {"U_EC_rod", "J", "internal energy, rod cushion volume"},
                   {"z", "m", "LuGre bristle deflection", 1e-5}};
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
                     {"m_flow_cushion", "kg/s", "flow cushion volume -> channel (bore, throttle, check valve)"},
                     {"z", "m", "LuGre bristle deflection (0 for other friction models)"},
                     {"F_pressure", "N", "pressure force on the piston (+x), ambient on the rod included"},
                     {"H_A", "W", "enthalpy flow into the gas at port A"},
                     {"H_B", "W", "enthalpy flow into the gas at port B"},
                     {"H_EC", "W", "enthalpy flow into the gas at the tapping port EC"},
                     {"P_pdV_A", "W", "p dV/dt of the rod-side chamber (port A's volume)"},
                     {"P_pdV_EC", "W", "p dV/dt of the cushion volume"},
                     {"P_pdV_ch", "W", "p dV/dt of the channel"},
                     {"P_pdV", "W", "sum of p dV/dt over all chambers: power from the gas to the piston"},
                     {"Q_A", "W", "heat flow into the gas through heat_A"},
                     {"Q_cap", "W", "heat flow into the gas through heat_cap"},
                     {"H_cushion", "W", "enthalpy flow cushion volume -> channel"},
                     {"P_friction", "W", "friction power F_friction v (<= 0)"},
                     {"P_stop", "W", "end stop power F_stop v"},
                     {"E_stop", "J", "elastic energy stored in the end stops, k pen^2 / 2"},
                     {"U_gas", "J", "internal energy of the gas in all chambers"},
                     {"p_EC_rod", "Pa", "rod cushion volume pressure, absolute"},
                     {"T_EC_rod", "K", "rod cushion volume gas temperature"},
                     {"bore_open_rod", "1", "rod-end bore opening fraction"},
                     {"m_flow_cushion_rod", "kg/s", "flow rod cushion volume -> rod-side channel"},
                     {"H_EC_rod", "W", "enthalpy flow into the gas at the tapping port EC_rod"},
                     {"P_pdV_EC_rod", "W", "p dV/dt of the rod cushion volume"},
                     {"H_cushion_rod", "W", "enthalpy flow rod cushion volume -> rod-side channel"}};
    i.equations = {"mass balance A",       "energy balance A",    "gas law A",
                   "outflow temperature A", "mass balance EC",     "energy balance EC",
                   "mass balance ch",      "energy balance ch",   "gas law ch",
                   "outflow temperature B", "force balance",       "wall heat A",         "wall heat cap",
                   "tap EC pressure",      "tap EC temperature",  "mass balance ECr",    "energy balance ECr",
                   "tap EC_rod pressure", "tap EC_rod temperature", "bristle dynamics"};
    i.roots = 6;
    return i;
  }

  // Drops what this instance lacks: rod cushioning (port EC_rod, the ECr
  // chamber, its observables and roots) and the LuGre state.
  static ComponentInfo instance_info(ComponentInfo i, const ParameterValues& p) {
    const bool rod = p.has("rod_plug_diameter");
    const bool lugre = p.text("friction_model") == "lugre";
    auto erase_names = [](auto& list, const std::vector<std::string>& names) {
      std::erase_if(list, [&](const auto& item) {
        return std::find(names.begin(), names.end(), item.name) != names.end();
      });
    };
    auto erase_strings = [](std::vector<std::string>& list, const std::vector<std::string>& names) {
      std::erase_if(list, [&](const std::string& s) { return std::find(names.begin(), names.end(), s) != names.end(); });
    };
    if (p.text("cushion_taps") != "yes") {
      erase_names(i.ports, {"EC", "EC_rod"});
      erase_strings(i.equations,
                    {"tap EC pressure", "tap EC temperature", "tap EC_rod pressure", "tap EC_rod temperature"});
    }
    if (!rod) {
      erase_names(i.ports, {"EC_rod"});
      erase_names(i.variables, {"m_EC_rod", "U_EC_rod"});
      erase_names(i.observables, {"p_EC_rod", "T_EC_rod", "bore_open_rod", "m_flow_cushion_rod", "H_EC_rod",
                                  "P_pdV_EC_rod", "H_cushion_rod"});
      erase_strings(i.equations,
                    {"mass balance ECr", "energy balance ECr", "tap EC_rod pressure",
                     "tap EC_rod temperature"});
      i.roots = 4;
    }
    if (!lugre) {
      erase_names(i.variables, {"z"});
      erase_strings(i.equations, {"bristle dynamics"});
    }
    return i;
  }

  explicit CushionedCylinder(const Construction& c) : ComponentT(c), friction_(FrictionLaw::from(c.params)) {
    const auto& p = c.params;
    A_B_ = kPi * p["bore"] * p["bore"] / 4;
    A_R_ = kPi * p["rod"] * p["rod"] / 4;
    A_A_ = A_B_ - A_R_;
    A_CP_ = kPi * p["plug_diameter"] * p["plug_diameter"] / 4;
    bore_ = p["bore"];
    rod_d_ = p["rod"];
    if (p["rod"] >= p["bore"]) throw ParameterError("rod", "rod diameter must be smaller than the bore");
    if (p["plug_diameter"] >= p["bore"])
      throw ParameterError("plug_diameter", "plug diameter must be smaller than the bore");
    stroke_ = p["stroke"];
    L_ = p["cushion_length"];
    if (L_ >= stroke_) throw ParameterError("cushion_length", "cushion length must be shorter than the stroke");
    V0_A_ = p["dead_volume_rod_side"];
    V0_EC_ = p["dead_volume_cushion"];
    V0_ch_ = p["dead_volume_channel"];
    cap_ = read_cushion(p, "");
    stops_ = EndStops{p["stop_stiffness"], p["stop_damping"]};
    wall_alpha_ = p["wall_alpha"];
    friction_main_ = friction_.main;
    friction_cushion_ = friction_.cushion;
    friction_scale_ = friction_.scale;
    v_reg_ = friction_.v_reg;
    v_eps_ = friction_.v_eps;
    x0_ = p["x0"];
    p0_A_ = p["p0_A"];
    p0_cap_ = p["p0_cap"];
    T0_ = p["T0"];
    rod_ = p.has("rod_plug_diameter");
    taps_ = p.text("cushion_taps") == "yes";
    A_colr_ = A_A_;
    if (rod_) {
      const double d = p["rod_plug_diameter"];
      if (!(d > p["rod"] && d < p["bore"]))
        throw ParameterError("rod_plug_diameter", "the rod-end sleeve diameter must lie between rod and bore");
      for (const char* name : {"rod_cushion_length", "rod_dead_volume_cushion"})
        if (!p.has(name))
          throw ParameterError(name, std::string("rod-end cushioning (rod_plug_diameter given) needs ") + name);
      A_CPr_ = kPi * d * d / 4;
      A_colr_ = A_CPr_ - A_R_;
      L_r_ = p["rod_cushion_length"];
      V0_ECr_ = p["rod_dead_volume_cushion"];
      rodc_ = read_cushion(p, "rod_");
      if (L_ + cap_.ramp + L_r_ + rodc_.ramp >= stroke_)
        throw ParameterError("rod_cushion_length",
                             "the cushioning zones (with their bore-opening ramps) at both ends overlap");
    }
    z_var_ = rod_ ? 8 : 6;
    if (2 + static_cast<int>(info().variables.size()) > kMemoKey)
      throw std::logic_error("cushioned_cylinder: the state memo's key is too short for its variables");
  }

  // Everything derived from the local variables, for equations and outputs.
  template <class T>
  struct State {
    T x, v, p_A, p_EC, p_ch, V_A, V_EC, V_ch, open, m_x, H_x, F_fric, F_stop, z;
    T T_A, T_EC, T_ch;                          // gas temperatures U / (m c_v)
    T p_ECr, V_ECr, open_r, m_xr, H_xr, T_ECr;  // rod cushioning only
    T F_pressure;
  };

  // Everything derived from the local variables. It reads only the
  // position, the velocity and the chambers' masses and energies (not the
  // port pressures: p_A too comes from U_A / V_A, which the gas-law row
  // makes the port's pressure), so the framework can solve the ports'
  // pressures and the flange force from it in one pass. For double it is
  // memoised on those inputs: one residual call evaluates the cylinder
  // twice at the same state (the explicitly solved unknowns first, then
  // IDA's rows), and outputs observe it at a point just evaluated.
  template <class T>
  std::conditional_t<std::is_same_v<T, double>, const State<double>&, State<T>> state(const Eval<T>& e) const {
    if constexpr (std::is_same_v<T, double>) {
      const int n = static_cast<int>(info().variables.size());
      double key[kMemoKey];
      key[0] = e.flange(kFlange).s;
      key[1] = e.flange(kFlange).v;
      for (int k = 0; k < n; ++k) key[2 + k] = e.var(k);
      if (memo_valid_ && std::equal(key, key + 2 + n, memo_key_)) return memo_state_;
      memo_state_ = compute_state(e);
      std::copy_n(key, 2 + n, memo_key_);
      memo_valid_ = true;
      return memo_state_;
    } else {
      return compute_state(e);
    }
  }

  // The position, velocity and the chambers' volumes, pressures and
  // temperatures: all that the gas observables need.
  template <class T>
  void gas_state(const Eval<T>& e, State<T>& s) const {
    const GasModel& gas = e.gas();
    const auto fl = e.flange(kFlange);
    s.x = fl.s;
    s.v = fl.v;
    s.V_A = V0_A_ + A_colr_ * s.x;
    s.p_A = chamber_pressure(e.var(kUA), s.V_A, gas);
    s.V_EC = V0_EC_ + (A_B_ - A_CP_) * (stroke_ - s.x);
    s.V_ch = V0_ch_ + A_CP_ * (stroke_ - s.x);
    s.T_A = chamber_temperature(e.var(kMA), e.var(kUA), gas);
    s.T_EC = chamber_temperature(e.var(kMEC), e.var(kUEC), gas);
    s.T_ch = chamber_temperature(e.var(kMch), e.var(kUch), gas);
    s.p_EC = chamber_pressure(e.var(kUEC), s.V_EC, gas);
    s.p_ch = chamber_pressure(e.var(kUch), s.V_ch, gas);
    if (rod_) {
      s.T_ECr = chamber_temperature(e.var(kMECr), e.var(kUECr), gas);
      s.V_ECr = V0_ECr_ + (A_B_ - A_CPr_) * s.x;
      s.p_ECr = chamber_pressure(e.var(kUECr), s.V_ECr, gas);
    } else {
      s.p_ECr = s.V_ECr = s.T_ECr = 0.0 * s.x;
    }
  }
  // Observables read off gas_state() alone.
  static bool gas_observable(int k) {
    return (k >= kX && k <= kTcho) || k == kUgas || k == kPECr || k == kTECro;
  }

  template <class T>
  State<T> compute_state(const Eval<T>& e) const {
    const GasModel& gas = e.gas();
    State<T> s;
    gas_state(e, s);
    const T& T_EC = s.T_EC;
    const T& T_ch = s.T_ch;
    const T gap = stroke_ - L_ - s.x;
    s.m_x = cushion_flow(cap_, gap, s.p_EC, s.p_ch, T_EC, T_ch, s.x, gas, s.open);  // EC -> ch
    s.H_x = enthalpy_inflow(s.m_x, T_EC, T_ch, gas);
    const T zero = 0.0 * s.x;
    s.z = friction_.has_state() ? e.var(z_var_) : zero;
    if (rod_) {
      const T& T_ECr = s.T_ECr;
      const T gap_r = s.x - L_r_;
      s.m_xr = cushion_flow(rodc_, gap_r, s.p_ECr, s.p_A, T_ECr, s.T_A, s.x, gas, s.open_r);  // ECr -> A
      s.H_xr = enthalpy_inflow(s.m_xr, T_ECr, s.T_A, gas);
    } else {
      s.m_xr = s.H_xr = zero;
      s.open_r = zero + 1.0;
    }
    // Friction.
    if (friction_.model == FrictionModel::preset) {
      const T p_rod = rod_ ? s.p_ECr : s.p_A;  // the rod-side pressure at the piston
      // Main-stroke and cushioning-zone sets blended by the openings. A set
      // whose weight is 0 (the opening clamped at 0 or 1, so its derivative
      // is 0 too) is not evaluated, except for the structural pattern.
      constexpr bool structural = std::is_same_v<T, Pattern>;
      const double open = value(s.open), open_r = value(s.open_r);
      const T F_main = structural || (open > 0.0 && open_r > 0.0)
                           ? friction_force(friction_main_, s.v, p_rod, s.p_EC, s.p_EC, gas.p_ambient, v_reg_, v_eps_)
                           : zero;
      const T F_cush = structural || open < 1.0 ? friction_force(friction_cushion_, s.v, p_rod, s.p_EC, s.p_EC,
                                                                 gas.p_ambient, v_reg_, v_eps_)
                                                : zero;
      if (!rod_) {
        s.F_fric = friction_scale_ * (s.open * F_main + (1.0 - s.open) * F_cush);
      } else {
        const T F_cush_r = structural || open_r < 1.0 ? friction_force(friction_cushion_, s.v, p_rod, s.p_EC, s.p_ECr,
                                                                       gas.p_ambient, v_reg_, v_eps_)
                                                      : zero;
        s.F_fric = friction_scale_ *
                   (s.open * s.open_r * F_main + (1.0 - s.open) * F_cush + (1.0 - s.open_r) * F_cush_r);
      }
    } else {
      s.F_fric = friction_.force(friction_main_, s.v, s.z, zero);
    }
    s.F_stop = stops_.force(s.x, s.v, stroke_);
    if (!rod_)
      s.F_pressure = s.p_A * A_A_ + gas.p_ambient * A_R_ - s.p_EC * (A_B_ - A_CP_) - s.p_ch * A_CP_;
    else
      s.F_pressure = s.p_A * A_colr_ + s.p_ECr * (A_B_ - A_CPr_) + gas.p_ambient * A_R_ - s.p_EC * (A_B_ - A_CP_) -
                     s.p_ch * A_CP_;
    return s;
  }

  // Wall areas of the rod-side and cap-side chambers (wall_alpha > 0).
  template <class T>
  T wall_area_rod(const T& x) const {
    const double V0 = V0_A_ + (rod_ ? V0_ECr_ : 0.0);
    return chamber_wall_area(A_A_, kPi * (bore_ + rod_d_), x, V0);
  }
  template <class T>
  T wall_area_cap(const T& x) const {
    return chamber_wall_area(A_B_, kPi * bore_, T(stroke_ - x), V0_EC_ + V0_ch_);
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const GasModel& gas = e.gas();
    const auto A = e.gas_port(kA);
    const auto B = e.gas_port(kB);

    const auto fl = e.flange(kFlange);
    const auto hA = e.heat_port(kHeatA);
    const auto hC = e.heat_port(kHeatCap);
    // T > 0 <=> U > 0 for m > 0; checked before state() divides by m.
    for (int k : {kMA, kUA, kMEC, kUEC, kMch, kUch}) e.reject_unless_positive(e.var(k));
    if (rod_) {
      e.reject_unless_positive(e.var(kMECr));
      e.reject_unless_positive(e.var(kUECr));
    }
    const auto& s = state(e);  // the memo itself for double
    // Rod-side chamber A (volume grows with x); with rod cushioning the
    // rod-side channel, fed from ECr, adiabatic.
    // Port outflows carry the port's T_out, the value the connected side
    // reads as its T_in, so that the energy crossing a port balances exactly
    // (U / (m c_v) equals T_out only to the Newton tolerance).
    const T H_A = enthalpy_inflow(A.m_flow, A.T_in, A.T_out, gas);
    if (!rod_) {
      r[0] = e.der(kMA) - A.m_flow;
      r[1] = e.der(kUA) - H_A + A.p * A_A_ * s.v - hA.Q;
    } else {
      r[0] = e.der(kMA) - A.m_flow - s.m_xr;
      r[1] = e.der(kUA) - H_A - s.H_xr + A.p * A_colr_ * s.v;
    }
    r[2] = A.p - (gas.kappa - 1.0) * e.var(kUA) / s.V_A;  // solved for p (scaling)
    // With wall_alpha = 0 the heat ports equal the gas temperatures; the
    // other port temperatures of the same gas are then written as their
    // aliases (not as T_out - U / (m c_v)) so that alias elimination folds
    // them into one unknown per chamber.
    const bool walls_at_gas_T = !(wall_alpha_ > 0);
    r[3] = A.T_out - (walls_at_gas_T && !rod_ ? hA.T : s.T_A);
    // Cushion annulus EC (volume shrinks with x), tapped by port EC.
    if (!taps_) {
      r[4] = e.der(kMEC) + s.m_x;
      r[5] = e.der(kUEC) + s.H_x - s.p_EC * (A_B_ - A_CP_) * s.v - hC.Q;
    } else {
      const auto tap = e.gas_port(kTapEC);
      const T H_tap = enthalpy_inflow(tap.m_flow, tap.T_in, tap.T_out, gas);
      r[4] = e.der(kMEC) + s.m_x - tap.m_flow;
      r[5] = e.der(kUEC) + s.H_x - H_tap - s.p_EC * (A_B_ - A_CP_) * s.v - hC.Q;
    }
    // Channel ch: inflow from EC, outflow through port B.
    const T H_B = enthalpy_inflow(B.m_flow, B.T_in, B.T_out, gas);
    r[6] = e.der(kMch) - s.m_x - B.m_flow;
    r[7] = e.der(kUch) - s.H_x - H_B - s.p_ch * A_CP_ * s.v;
    r[8] = B.p - (gas.kappa - 1.0) * e.var(kUch) / s.V_ch;
    r[9] = B.T_out - s.T_ch;
    // Force balance: the flange pulls on the cylinder with f = -F.
    const T F = s.F_pressure + s.F_fric + s.F_stop;
    r[10] = fl.f + F;
    // Walls: at the gas temperature, or exchanging heat with the gas.
    const T& T_gas_A = rod_ ? s.T_ECr : s.T_A;
    if (wall_alpha_ > 0) {
      r[11] = hA.Q - wall_alpha_ * wall_area_rod(s.x) * (hA.T - T_gas_A);
      r[12] = hC.Q - wall_alpha_ * wall_area_cap(s.x) * (hC.T - s.T_EC);
    } else {
      r[11] = hA.T - T_gas_A;
      r[12] = hC.T - s.T_EC;
    }
    int row = 13;
    if (taps_) {
      const auto tap = e.gas_port(kTapEC);
      r[row++] = tap.p - s.p_EC;
      r[row++] = tap.T_out - (walls_at_gas_T ? hC.T : s.T_EC);
    }
    if (rod_) {
      // Rod cushion annulus ECr (volume grows with x), tapped by EC_rod.
      T m_tap = 0.0 * s.x, H_tap = 0.0 * s.x;
      if (taps_) {
        const auto tapr = e.gas_port(kTapECr);
        m_tap = tapr.m_flow;
        H_tap = enthalpy_inflow(tapr.m_flow, tapr.T_in, tapr.T_out, gas);
      }
      r[row++] = e.der(kMECr) + s.m_xr - m_tap;
      r[row++] = e.der(kUECr) + s.H_xr - H_tap + s.p_ECr * (A_B_ - A_CPr_) * s.v - hA.Q;
      if (taps_) {
        const auto tapr = e.gas_port(kTapECr);
        r[row++] = tapr.p - s.p_ECr;
        r[row++] = tapr.T_out - (walls_at_gas_T ? hA.T : s.T_ECr);
      }
    }
    if (friction_.has_state()) r[row++] = e.der(z_var_) - friction_.lugre_zdot(s.v, e.var(z_var_));
  }

  double observe(int k, const Eval<double>& e) const override { return observe(k, state(e), e); }
  void observe_all(const int* ks, int n, const Eval<double>& e, double* out) const override {
    // Result files usually ask for positions, pressures and temperatures
    // only: those skip the flows and forces (most of state()'s work).
    State<double> s{};
    if (std::all_of(ks, ks + n, gas_observable))
      gas_state(e, s);
    else
      s = state(e);
    for (int i = 0; i < n; ++i) out[i] = observe(ks[i], s, e);
  }

  // Observable k from the state computed once for all observables asked.
  double observe(int k, const State<double>& s, const Eval<double>& e) const {
    const GasModel& gas = e.gas();
    auto inflow = [&](int port) {
      const auto g = e.gas_port(port);
      return enthalpy_inflow(g.m_flow, g.T_in, g.T_out, gas);
    };
    const double pdV_A = s.p_A * A_colr_ * s.v;
    const double pdV_EC = -s.p_EC * (A_B_ - A_CP_) * s.v;
    const double pdV_ch = -s.p_ch * A_CP_ * s.v;
    const double pdV_ECr = rod_ ? s.p_ECr * (A_B_ - A_CPr_) * s.v : 0.0;
    switch (k) {
      case kX: return s.x;
      case kV: return s.v;
      case kPA: return s.p_A;
      case kPEC: return s.p_EC;
      case kPch: return s.p_ch;
      case kTAo: return s.T_A;
      case kTECo: return s.T_EC;
      case kTcho: return s.T_ch;
      case kFfric: return s.F_fric;
      case kFstop: return s.F_stop;
      case kOpen: return s.open;
      case kCushionFlow: return s.m_x;
      case kZ: return s.z;
      case kFpressure: return s.F_pressure;
      case kHA: return inflow(kA);
      case kHB: return inflow(kB);
      case kHEC: return taps_ ? inflow(kTapEC) : 0.0;
      case kPdVA: return pdV_A;
      case kPdVEC: return pdV_EC;
      case kPdVch: return pdV_ch;
      case kPdV: return pdV_A + pdV_EC + pdV_ch + pdV_ECr;
      case kQA: return e.heat_port(kHeatA).Q;
      case kQcap: return e.heat_port(kHeatCap).Q;
      case kHcushion: return s.H_x;
      case kPfric: return s.F_fric * s.v;
      case kPstop: return s.F_stop * s.v;
      case kEstop: return stops_.energy(s.x, stroke_);
      case kUgas: return e.var(kUA) + e.var(kUEC) + e.var(kUch) + (rod_ ? e.var(kUECr) : 0.0);
      case kPECr: return s.p_ECr;
      case kTECro: return s.T_ECr;
      case kOpenR: return s.open_r;
      case kCushionFlowR: return s.m_xr;
      case kHECr: return taps_ ? inflow(kTapECr) : 0.0;
      case kPdVECr: return pdV_ECr;
      case kHcushionR: return s.H_xr;
    }
    return 0.0;
  }

  void roots(const Eval<double>& e, double* g) const override {
    const double x = e.flange(kFlange).s;
    g[kRampStart] = x - (stroke_ - L_ - cap_.ramp);
    g[kCushionEntry] = x - (stroke_ - L_);
    g[kStopRod] = x;
    g[kStopCap] = x - stroke_;
    if (rod_) {
      g[kRodRampStart] = x - (L_r_ + rodc_.ramp);
      g[kRodCushionEntry] = x - L_r_;
    }
  }

  // A stop contact makes the force jump (the stop's damping term d v acts
  // from the first contact on): IDA is re-initialised there, so that no step
  // straddles it. Leaving a stop is continuous (see below). The ends of a
  // bore-opening ramp are kinks of a flow area only (continuous flows): they
  // are logged at their exact times and IDA's error control steps over them,
  // as over any steep part of a flow law (re-initialising there cost 6 % more
  // work for the same trajectory).
  EventResult on_event(const Eval<double>& e, double*, EventKind, int root, int dir) const override {
    const double v = e.flange(kFlange).v;
    const std::string vs = " at v = " + std::to_string(v) + " m/s";
    const bool up = dir > 0;  // x growing: toward the cap
    switch (root) {
      case kRampStart:
        return up ? EventResult{false, "bore opening starts to close" + vs, "bore_closing"}
                  : EventResult{false, "bore opening fully open" + vs, "bore_open"};
      case kCushionEntry:
        return up ? EventResult{false, "enters the cushioning zone" + vs, "cushion_entry"}
                  : EventResult{false, "leaves the cushioning zone" + vs, "cushion_exit"};
      // Only a contact starts with a jump; leaving, the stop force has
      // already fallen to 0 (k pen - d v reaches 0 before pen does).
      case kStopRod:
        return up ? EventResult{false, "leaves the rod-end stop" + vs, "rod_stop_left"}
                  : EventResult{true, "contact with the rod-end stop" + vs, "rod_stop_contact"};
      case kStopCap:
        return up ? EventResult{true, "impact on the cap-end stop" + vs, "cap_impact"}
                  : EventResult{false, "leaves the cap-end stop" + vs, "cap_stop_left"};
      case kRodRampStart:
        return up ? EventResult{false, "rod-end bore opening fully open" + vs, "rod_bore_open"}
                  : EventResult{false, "rod-end bore opening starts to close" + vs, "rod_bore_closing"};
      case kRodCushionEntry:
        return up ? EventResult{false, "leaves the rod-end cushioning zone" + vs, "rod_cushion_exit"}
                  : EventResult{false, "enters the rod-end cushioning zone" + vs, "rod_cushion_entry"};
    }
    return {};
  }

  // The cap-end cushioning's energy balance (cylinder_parts.hpp), from the
  // cushion entry to the piston's first standstill or reversal.
  std::optional<EnergyAuditSpec> energy_audit(const GasModel& gas) const override {
    CushionAuditNames n;
    n.title = "cap-end cushioning";
    n.opens_at = "cushion_entry";
    n.open_description = "cushion entry";
    n.closes_when = "v";
    n.drive_description = "work of the rod-side gas and ambient on the piston";
    n.drive_changes = {{"x", gas.p_ambient * A_R_}};
    n.drive_integrals = {{"P_pdV_A", 1.0}};
    if (rod_) n.drive_integrals.push_back({"P_pdV_EC_rod", 1.0});
    n.U_cushion = "U_EC";
    n.Q_wall = "Q_cap";
    n.P_pdV_channel = "P_pdV_ch";
    n.channel_port = "B";
    n.outflows = {{"H_cushion", 1.0}};
    if (taps_) n.outflows.push_back({"H_EC", -1.0});  // the tap's gas leaves too, not through the throttle
    return cushion_energy_audit(n, gas);
  }

  void start(StartValues& sv, const GasModel& gas) const override {
    double x = x0_;
    if (std::isnan(x)) {
      // At rest against the rod-end stop: the stop carries the net pressure
      // force (friction is zero at v = 0).
      const double F = p0_A_ * A_A_ + gas.p_ambient * A_R_ - p0_cap_ * A_B_;
      x = F < 0 ? F / stops_.k : 0.0;
    }
    sv.fix_position(kFlange, x);
    const double V_A = V0_A_ + A_colr_ * x;
    const double V_EC = V0_EC_ + (A_B_ - A_CP_) * (stroke_ - x);
    const double V_ch = V0_ch_ + A_CP_ * (stroke_ - x);
    auto gas_state = [&](int m, int U, double p, double V) {
      const double mass = p * V / (gas.R * T0_);
      sv.fix_var(m, mass);
      sv.fix_var(U, mass * gas.cv() * T0_);
    };
    gas_state(kMA, kUA, p0_A_, V_A);
    gas_state(kMEC, kUEC, p0_cap_, V_EC);
    gas_state(kMch, kUch, p0_cap_, V_ch);
    sv.guess_pressure(kA, p0_A_);
    sv.guess_pressure(kB, p0_cap_);
    if (taps_) sv.guess_pressure(kTapEC, p0_cap_);
    sv.guess_temperature(kA, T0_);
    sv.guess_temperature(kB, T0_);
    if (taps_) sv.guess_temperature(kTapEC, T0_);
    sv.guess_temperature(kHeatA, T0_);
    sv.guess_temperature(kHeatCap, T0_);
    if (rod_) {
      gas_state(kMECr, kUECr, p0_A_, V0_ECr_ + (A_B_ - A_CPr_) * x);
      if (taps_) {
        sv.guess_pressure(kTapECr, p0_A_);
        sv.guess_temperature(kTapECr, T0_);
      }
    }
    if (friction_.has_state()) sv.fix_var(z_var_, 0.0);
  }

 private:
  // The throttle/valve parameters of one end; the rod end's default to the
  // cap end's.
  static Cushion read_cushion(const ParameterValues& p, const std::string& prefix) {
    auto get = [&](const std::string& name) { return p.has(prefix + name) ? p[prefix + name] : p[name]; };
    Cushion c;
    c.C_bore = get("bore_opening_C");
    c.b_bore = get("bore_opening_b");
    c.ramp = get("bore_opening_ramp");
    const std::string table = p.has(prefix + "cushion_C_of_z") ? prefix + "cushion_C_of_z" : "cushion_C_of_z";
    const Table& t = p.table(table);
    require_increasing(t, table, "opening z");
    double C_max = 0;
    for (const auto& row : t) C_max = std::max(C_max, row[1]);
    const std::string z_name = prefix.empty() ? "z_EC" : (p.has("z_EC_rod") ? "z_EC_rod" : "z_EC");
    c.C_cushion = interpolate(t, p[z_name]);
    c.b_cushion = get("cushion_b0") + get("cushion_b_slope") * (C_max > 0 ? c.C_cushion / C_max : 0.0);
    if (!(c.b_cushion >= 0 && c.b_cushion < 0.999))
      throw ParameterError(prefix + "cushion_b_slope", "b of the cushion throttle leaves [0, 0.999) at this opening");
    c.C_check = get("check_C");
    c.b_check = get("check_b");
    c.crack = get("check_cracking");
    c.check_ramp = get("check_ramp");
    return c;
  }

  double A_B_, A_R_, A_A_, A_CP_, bore_, rod_d_, stroke_, L_, V0_A_, V0_EC_, V0_ch_;
  Cushion cap_{}, rodc_{};
  EndStops stops_{};
  double wall_alpha_;
  FrictionLaw friction_;
  FrictionCoefficients friction_main_, friction_cushion_;
  double friction_scale_, v_reg_, v_eps_;
  double x0_, p0_A_, p0_cap_, T0_;
  bool rod_ = false, taps_ = false;
  double A_CPr_ = 0, A_colr_ = 0, L_r_ = 0, V0_ECr_ = 0;
  int z_var_ = 6;
  // state<double>() memo: its inputs (s, v, internal variables) and result.
  static constexpr int kMemoKey = 2 + 9;
  mutable bool memo_valid_ = false;
  mutable double memo_key_[kMemoKey] = {};
  mutable State<double> memo_state_{};
};

void register_cushioned_cylinder(Registry& r) { r.add<CushionedCylinder>(); }

}  // namespace pneumo::components
