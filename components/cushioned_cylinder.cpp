// Double-acting cylinder with integrated end-position cushioning at the cap
// end and optionally at the rod end (seed paper 000, fig. 1;
// ../shared/rigs/cushion-rig.yaml).
//
// x = 0 fully extended, x = stroke at the cap. The cap side is a
// CylinderSide (components/cylinder_parts.hpp) at travel stroke - x, split into
//   EC: the cushion annulus around the plug, V_EC = V0_EC + (A_B - A_CP)(stroke - x)
//   ch: the plug column plus outflow channel, V_ch = V0_ch + A_CP (stroke - x)
// joined by the bore opening (open in the main stroke, closing linearly over
// a short ramp before the plug engages - never a jump), the needle cushion
// throttle (C from the opening z in revolutions, b linear in C) and a check
// valve for the return stroke. Port B is the channel's outlet, port A the
// rod-side chamber's (a CylinderSide at travel x). Each gas volume has its
// own mass and energy balance; heat ports to the walls are optional
// (adiabatic if unconnected).
//
// Force on the rod flange in +x (eq. 1-3 in one expression; the cushioning
// terms vanish smoothly in the main stroke because p_EC = p_ch there):
//   F = p_A A_A + p_amb A_R - p_EC (A_B - A_CP) - p_ch A_CP + F_friction + F_stops
// Friction (components/friction.hpp, `friction_model`): paper [1] eq. 4/7/8
// presets or custom eq. 8 coefficients (`friction: custom`, friction_b0 ...
// as `pneumo fit friction -o` writes them), with a separate set in the
// cushioning zone (`friction_cushion`, preset or custom friction_cushion_*)
// blended over the bore-opening ramp; or Coulomb + viscous; or LuGre (seed
// 002 eq. 8, bristle state z as an internal variable - the piston can stick).
// End stops: elastic, force = max(0, k pen + d pen_rate), never pulling.
//
// Rod-end cushioning (present when `rod_plug_diameter` is given; the
// instance then has the extra chamber, port and roots): the rod side splits
// the same way into the rod cushion annulus ECr,
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
// with them (paper [3] eq. 2; a heat port left unconnected is a wall at the
// ambient temperature), A(x) = both end faces + the lateral bore (and
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
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "components/builtin.hpp"
#include "components/cylinder_parts.hpp"
#include "components/symbols.hpp"

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
        "cushion annulus, needle throttle, check valve), mass and energy balance in each chamber, friction (paper [1] "
        "eq. 4/7/8 presets, Coulomb + viscous, LuGre), optional gas-to-wall heat transfer, elastic end stops. x = 0 "
        "extended, x = stroke at the cap; port A rod side, port B cap-side outlet (both closed if unconnected).";
    i.symbol = symbols::cushioned_cylinder();
    using P = ParameterSpec;
    i.parameters = {
        P::scalar("bore", "m", "piston diameter").positive(),
        P::scalar("rod", "m", "rod diameter; 0: rodless (both sides full bore area, paper [2]'s MY3B)").non_negative(),
        P::scalar("stroke", "m", "stroke").positive(),
        P::scalar("plug_diameter", "m", "cushioning plug diameter").positive(),
        P::scalar("cushion_length", "m", "cushioning length (plug engages at x = stroke - cushion_length)")
            .positive(),
        P::scalar("dead_volume_rod_side", "m3",
                  "rod-side chamber volume at x = 0 (with rod cushioning: the rod-side channel behind port A)")
            .positive(),
        P::scalar("dead_volume_cushion", "m3", "cushion annulus volume at x = stroke").positive(),
        P::scalar("dead_volume_channel", "m3", "outflow channel volume at x = stroke").positive(),
    };
    for (auto* list : {cap_cushion_parameters, rod_cushion_parameters, wall_parameters})
      for (auto& s : list()) i.parameters.push_back(std::move(s));
    for (auto& f : FrictionLaw::parameters(true)) i.parameters.push_back(std::move(f));
    for (auto& s : initial_parameters()) i.parameters.push_back(std::move(s));
    for (auto& f : FrictionFaults::parameters()) i.parameters.push_back(std::move(f));
    add_parts(i, true, true, true);
    i.faults = {
        {"friction_running", "friction off (seal wear, lubrication, side load), as a factor on the friction",
         {{"k", "friction_scale", "1", true, 1.0, 0.25, 4.0, 1.3, true}}},
        {"cushion_needle_misadjusted", "cushion needle opening off its setting (turned, clogged)",
         {{"k", "z_EC", "1", true, 1.0, 0.2, 5.0, 1.3, true}}},
        {"cushion_check_off", "cushion check valve conductance off (sticking, leaking)",
         {{"k", "check_C", "1", true, 1.0, 0.1, 10.0, 2.0, true}}},
        {"bore_opening_off", "bore opening conductance off (worn or tight cushion seal)",
         {{"k", "bore_opening_C", "1", true, 1.0, 0.2, 5.0, 1.5, true}}},
    };
    i.events = {{"cushion_entry", "enters the cap-end cushioning zone"},
                {"cushion_exit", "leaves the cap-end cushioning zone"},
                {"bore_closing", "the bore opening starts to close"},
                {"bore_open", "the bore opening is fully open"},
                {"cap_impact", "impact on the cap-end stop"},
                {"cap_stop_left", "leaves the cap-end stop"},
                {"rod_stop_contact", "contact with the rod-end stop"},
                {"rod_stop_left", "leaves the rod-end stop"},
                {"rod_cushion_entry", "enters the rod-end cushioning zone (rod cushioning)"},
                {"rod_cushion_exit", "leaves the rod-end cushioning zone (rod cushioning)"},
                {"rod_bore_closing", "the rod-end bore opening starts to close (rod cushioning)"},
                {"rod_bore_open", "the rod-end bore opening is fully open (rod cushioning)"}};
    for (auto& f : FrictionFaults::faults()) i.faults.push_back(std::move(f));
    for (const char* v : {"dead_volume_rod_side", "dead_volume_cushion", "dead_volume_channel"})
      i.faults.push_back({std::string(v) + "_off", std::string("volume ") + v + " off (fittings, machining)",
                          {{"k", v, "1", true, 1.0, 0.3, 3.0, 1.5, true}}});
    return i;
  }

  // The parts this instance has: taps, rod cushioning, the LuGre state.
  static ComponentInfo instance_info(ComponentInfo i, const ParameterValues& p) {
    add_parts(i, p.text("cushion_taps") == "yes", p.has("rod_plug_diameter"), p.text("friction_model") == "lugre");
    return i;
  }

  explicit CushionedCylinder(const Construction& c)
      : ComponentT(c),
        A_B_(circle_area(c.params["bore"])),
        A_R_(circle_area(c.params["rod"])),
        stroke_(c.params["stroke"]),
        cap_(A_B_, c.params["dead_volume_channel"], kPi * c.params["bore"]),
        rod_side_(A_B_ - A_R_, c.params["dead_volume_rod_side"], kPi * (c.params["bore"] + c.params["rod"])),
        stops_{c.params["stop_stiffness"], c.params["stop_damping"]},
        wall_alpha_(c.params["wall_alpha"]),
        friction_(FrictionLaw::from(c.params)),
        friction_faults_(c.params),
        x0_(c.params["x0"]),
        p0_A_(c.params["p0_A"]),
        p0_cap_(c.params["p0_cap"]),
        T0_(c.params["T0"]),
        taps_(c.params.text("cushion_taps") == "yes") {
    const auto& p = c.params;
    if (p["rod"] >= p["bore"]) throw ParameterError("rod", "rod diameter must be smaller than the bore");
    if (p["plug_diameter"] >= p["bore"])
      throw ParameterError("plug_diameter", "plug diameter must be smaller than the bore");
    if (p["cushion_length"] >= stroke_)
      throw ParameterError("cushion_length", "cushion length must be shorter than the stroke");
    cap_.cushion({p["cushion_length"], circle_area(p["plug_diameter"]), p["dead_volume_cushion"], read_cushion(p, "")});
    if (p.has("rod_plug_diameter")) add_rod_cushioning(p);
    stops_.hold_before_empty(rod_side_.travel_to_empty(), cap_.travel_to_empty());  // x = 0 is the rod end
    if (taps_) {
      cap_.tap(kTapEC);
      rod_side_.tap(kTapECr);  // none without rod cushioning
    }
    cap_.set_variables(kMch, kMEC);
    rod_side_.set_variables(kMA, kMECr);
    z_var_ = rod_side_.cushioned() ? 8 : 6;
    // Each part's rows where add_parts() names them.
    cap_.place_rows(row("mass balance ch"), row("wall heat cap"), row("mass balance EC"), row_if("tap EC pressure"));
    rod_side_.place_rows(row("mass balance A"), row("wall heat A"), row_if("mass balance ECr"),
                         row_if("tap EC_rod pressure"));
    force_row_ = row("force balance");
    lugre_row_ = row_if("bristle dynamics");
    if (2 + static_cast<int>(info().variables.size()) > kMemoKey)
      throw std::logic_error("cushioned_cylinder: the state memo's key is too short for its variables");
  }

  // Everything derived from the local variables, for equations and outputs.
  template <class T>
  struct State {
    T x, v, z;
    CylinderSide::Gas<T> cap;  // port B's channel ch, the cushion annulus EC at the piston
    CylinderSide::Gas<T> rod;  // port A's chamber (channel with rod cushioning), ECr at the piston
    T F_pressure, F_fric, F_stop;
  };

  // Everything derived from the local variables. It reads only the
  // position, the velocity and the chambers' masses and energies (not the
  // port pressures: p_A too comes from U_A / V_A, which the gas-law row
  // makes the port's pressure), so the framework can solve the ports'
  // pressures and the flange force from it in one pass. For double it is
  // memoised on those inputs (the contract's memoisation,
  // framework/model/component.hpp): one residual call evaluates the
  // cylinder twice at the same state (the explicitly solved unknowns first,
  // then IDA's rows), and outputs observe it at a point just evaluated.
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

  // The position, velocity and the chambers' pressures and temperatures:
  // all that the gas observables need.
  template <class T>
  void gas_state(const Eval<T>& e, State<T>& s) const {
    const auto fl = e.flange(kFlange);
    s.x = fl.s;
    s.v = fl.v;
    s.cap = cap_.chambers(e, T(stroke_ - s.x));
    s.rod = rod_side_.chambers(e, s.x);
  }
  // Observables read off gas_state() alone.
  static bool gas_observable(int k) {
    return (k >= kX && k <= kTcho) || k == kUgas || k == kPECr || k == kTECro;
  }

  template <class T>
  State<T> compute_state(const Eval<T>& e) const {
    const GasModel& gas = e.gas();
    const auto fl = e.flange(kFlange);
    State<T> s;
    s.x = fl.s;
    s.v = fl.v;
    // The cap side's travel left before its plug engages, (stroke - L) - x:
    // exactly minus the cushion-entry root, so the bore closes at the root.
    s.cap = cap_.gas(e, T(stroke_ - s.x), T(stroke_ - cap_.cushion_length() - s.x));
    s.rod = rod_side_.gas(e, s.x);
    s.z = friction_.has_state() ? e.var(z_var_) : T(0.0 * s.x);
    s.F_fric = friction(s, gas.p_ambient);
    if (friction_faults_.any())
      s.F_fric += friction_faults_.force(s.v, T(s.cap.p_piston - s.rod.p_piston), friction_.v_reg);
    s.F_stop = stops_.force(s.x, s.v, stroke_);
    s.F_pressure = rod_side_.force(s.rod) + gas.p_ambient * A_R_ - cap_.annulus_force(s.cap) - cap_.port_force(s.cap);
    return s;
  }

  // Friction on the piston (+x). The presets blend the main-stroke set and
  // the cushioning-zone set (at each cushioned end) by the bore openings; a
  // set whose weight is 0 (the opening clamped at 0 or 1, so its derivative
  // is 0 too) is not evaluated, except for the structural pattern.
  template <class T>
  T friction(const State<T>& s, double p_ambient) const {
    const T zero = 0.0 * s.x;
    if (friction_.model != FrictionModel::preset) return friction_.force(friction_.main, s.v, s.z, zero);
    const T& p_rod = s.rod.p_piston;
    const T& p_EC = s.cap.p_piston;
    auto set = [&](const FrictionCoefficients& c, const T& p_cushion) {
      return friction_force(c, s.v, p_rod, p_EC, p_cushion, p_ambient, friction_.v_reg, friction_.v_eps);
    };
    constexpr bool structural = std::is_same_v<T, Pattern>;
    const double open = value(s.cap.open), open_r = value(s.rod.open);
    const T F_main = structural || (open > 0.0 && open_r > 0.0) ? set(friction_.main, p_EC) : zero;
    const T F_cush = structural || open < 1.0 ? set(friction_.cushion, p_EC) : zero;
    if (!rod_side_.cushioned()) return friction_.scale * (s.cap.open * F_main + (1.0 - s.cap.open) * F_cush);
    const T F_cush_r = structural || open_r < 1.0 ? set(friction_.cushion, s.rod.p_piston) : zero;
    return friction_.scale *
           (s.cap.open * s.rod.open * F_main + (1.0 - s.cap.open) * F_cush + (1.0 - s.rod.open) * F_cush_r);
  }

  // Rows: the sides' (each where the constructor placed it), the force
  // balance, LuGre's z.
  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto& s = state(e);
    cap_.equations(e, e.gas_port(kB), e.heat_port(kHeatCap), s.cap, T(stroke_ - s.x), T(-s.v), wall_alpha_, r);
    rod_side_.equations(e, e.gas_port(kA), e.heat_port(kHeatA), s.rod, s.x, s.v, wall_alpha_, r);
    // The flange pulls on the cylinder with f = -F.
    const T F = s.F_pressure + s.F_fric + s.F_stop;
    r[force_row_] = e.flange(kFlange).f + F;
    if (friction_.has_state()) r[lugre_row_] = e.der(z_var_) - friction_.lugre_zdot(s.v, e.var(z_var_));
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
    auto inflow = [&](int port) {
      const auto g = e.gas_port(port);
      return enthalpy_inflow(g.m_flow, g.T_in, g.T_out, e.gas());
    };
    switch (k) {
      case kX: return s.x;
      case kV: return s.v;
      case kPA: return s.rod.p;
      case kPEC: return s.cap.p_piston;
      case kPch: return s.cap.p;
      case kTAo: return s.rod.T_gas;
      case kTECo: return s.cap.T_piston;
      case kTcho: return s.cap.T_gas;
      case kFfric: return s.F_fric;
      case kFstop: return s.F_stop;
      case kOpen: return s.cap.open;
      case kCushionFlow: return s.cap.m_x;
      case kZ: return s.z;
      case kFpressure: return s.F_pressure;
      case kHA: return inflow(kA);
      case kHB: return inflow(kB);
      case kHEC: return taps_ ? inflow(kTapEC) : 0.0;
      case kQA: return e.heat_port(kHeatA).Q;
      case kQcap: return e.heat_port(kHeatCap).Q;
      case kHcushion: return s.cap.H_x;
      case kPfric: return s.F_fric * s.v;
      case kPstop: return s.F_stop * s.v;
      case kEstop: return stops_.energy(s.x, stroke_);
      case kUgas: return rod_side_.internal_energy(e) + cap_.internal_energy(e);
      case kPECr: return s.rod.p_piston;
      case kTECro: return s.rod.T_piston;
      case kOpenR: return s.rod.open;
      case kCushionFlowR: return s.rod.m_x;
      case kHECr: return taps_ && rod_side_.cushioned() ? inflow(kTapECr) : 0.0;
      case kHcushionR: return s.rod.H_x;
    }
    return observe_work(k, s);
  }
  // p dV/dt of each chamber and their sum (the cap side moves at -v).
  double observe_work(int k, const State<double>& s) const {
    const double pdV_A = rod_side_.port_p_dV(s.rod, s.v), pdV_ECr = rod_side_.annulus_p_dV(s.rod, s.v);
    const double pdV_ch = cap_.port_p_dV(s.cap, -s.v), pdV_EC = cap_.annulus_p_dV(s.cap, -s.v);
    switch (k) {
      case kPdVA: return pdV_A;
      case kPdVEC: return pdV_EC;
      case kPdVch: return pdV_ch;
      case kPdVECr: return pdV_ECr;
      case kPdV: return pdV_A + pdV_EC + pdV_ch + pdV_ECr;
    }
    return 0.0;
  }

  void roots(const Eval<double>& e, double* g) const override {
    const double x = e.flange(kFlange).s;
    g[kRampStart] = x - (stroke_ - cap_.cushion_length() - cap_.ramp());
    g[kCushionEntry] = x - (stroke_ - cap_.cushion_length());
    g[kStopRod] = x;
    g[kStopCap] = x - stroke_;
    if (rod_side_.cushioned()) {
      g[kRodRampStart] = x - (rod_side_.cushion_length() + rod_side_.ramp());
      g[kRodCushionEntry] = x - rod_side_.cushion_length();
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
  // Walls that exchange heat (wall_alpha > 0) with nothing connected are at
  // the ambient temperature.
  bool unconnected_heat_port_at_ambient(int port) const override {
    return wall_alpha_ > 0 && (port == kHeatA || port == kHeatCap);
  }

  std::optional<EnergyAuditSpec> energy_audit(const GasModel& gas) const override {
    CushionAuditNames n;
    n.title = "cap-end cushioning";
    n.opens_at = "cushion_entry";
    n.open_description = "cushion entry";
    n.closes_when = "v";
    n.drive_description = "work of the rod-side gas and ambient on the piston";
    n.drive_changes = {{"x", gas.p_ambient * A_R_}};
    n.drive_integrals = {{"P_pdV_A", 1.0}};
    if (rod_side_.cushioned()) n.drive_integrals.push_back({"P_pdV_EC_rod", 1.0});
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
      const double F = p0_A_ * (A_B_ - A_R_) + gas.p_ambient * A_R_ - p0_cap_ * A_B_;
      x = F < 0 ? -stops_.rest_penetration_low(-F) : 0.0;
    }
    sv.fix_position(kFlange, x);
    rod_side_.start(sv, gas, kA, kHeatA, p0_A_, T0_, x);
    cap_.start(sv, gas, kB, kHeatCap, p0_cap_, T0_, stroke_ - x);
    if (friction_.has_state()) sv.fix_var(z_var_, 0.0);
  }

 private:
  // The cap end's bore opening, needle throttle and check valve.
  static std::vector<ParameterSpec> cap_cushion_parameters() {
    using P = ParameterSpec;
    return {
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
    };
  }
  // Rod-end cushioning: present when rod_plug_diameter is given. The
  // throttle/valve parameters default to their cap-end values.
  static std::vector<ParameterSpec> rod_cushion_parameters() {
    using P = ParameterSpec;
    return {
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
    };
  }
  // End stops, cushion taps, wall heat.
  static std::vector<ParameterSpec> wall_parameters() {
    using P = ParameterSpec;
    return {
        P::scalar("stop_stiffness", "N/m", "end stop stiffness", 1e7).positive(),
        P::scalar("stop_damping", "N*s/m", "end stop damping", 3000.0).non_negative(),
        P::text("cushion_taps", {"no", "yes"},
                "yes: ports EC (and EC_rod) tap the cushion volumes (sensors, leakage throttles); closed when "
                "unconnected, but each adds an algebraic pressure to the step-size control, so they are off by "
                "default",
                "no"),
        P::scalar("wall_alpha", "W/(m2*K)",
                  "gas-to-wall heat transfer coefficient; 0: heat ports at gas temperature (external convection); "
                  "> 0 with a heat port unconnected: that wall at the ambient temperature",
                  0.0)
            .non_negative(),
    };
  }
  static std::vector<ParameterSpec> initial_parameters() {
    using P = ParameterSpec;
    return {
        P::scalar("x0", "m", "initial position; default: at rest against the stop at x = 0 at force equilibrium",
                  kNaN),
        P::scalar("p0_A", "Pa", "initial rod-side pressure (with rod cushioning also ECr), absolute; default: ambient")
            .positive()
            .absolute()
            .ambient_pressure_by_default(),
        P::scalar("p0_cap", "Pa", "initial cap-side pressure (cushion volume and channel), absolute; default: ambient")
            .positive()
            .absolute()
            .ambient_pressure_by_default(),
        P::scalar("T0", "K", "initial gas temperature; default: ambient").positive().ambient_temperature_by_default(),
    };
  }

  // The ports, variables, observables, rows and roots every instance has.
  static InfoPart cylinder_part() {
    InfoPart c;
    c.ports = {{"A", Domain::pneumatic, Causality::acausal, "rod-side chamber port (closed if unconnected)", true},
               {"B", Domain::pneumatic, Causality::acausal, "cap-side outlet (outflow channel; closed if unconnected)",
                true},
               {"flange", Domain::translational, Causality::acausal, "rod end; position = x"},
               {"heat_A", Domain::thermal, Causality::acausal, "wall of the rod-side chamber (ECr with rod cushioning)",
                true},
               {"heat_cap", Domain::thermal, Causality::acausal, "wall of the cushion volume", true}};
    c.variables = {{"m_A", "kg", "gas mass, rod side"},       {"U_A", "J", "internal energy, rod side"},
                   {"m_EC", "kg", "gas mass, cushion volume"}, {"U_EC", "J", "internal energy, cushion volume"},
                   {"m_ch", "kg", "gas mass, channel"},        {"U_ch", "J", "internal energy, channel"}};
    c.observables = {{"x", "m", "piston position (0 extended, stroke at the cap)"},
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
                     {"U_gas", "J", "internal energy of the gas in all chambers"}};
    using S = CylinderSide;
    for (const auto& rows : {S::chamber_equation_names("A", "A"), S::annulus_equation_names("EC"),
                             S::chamber_equation_names("ch", "B"),
                             {"force balance", S::wall_equation_name("A"), S::wall_equation_name("cap")}})
      c.equations.insert(c.equations.end(), rows.begin(), rows.end());
    c.roots = 4;
    return c;
  }
  // The rod cushion annulus ECr: its state, observables, rows and roots.
  static InfoPart rod_cushion_part() {
    InfoPart r = CylinderSide::annulus_part("EC_rod", "ECr", "rod cushion volume");
    r.observables = {{"p_EC_rod", "Pa", "rod cushion volume pressure, absolute"},
                     {"T_EC_rod", "K", "rod cushion volume gas temperature"},
                     {"bore_open_rod", "1", "rod-end bore opening fraction"},
                     {"m_flow_cushion_rod", "kg/s", "flow rod cushion volume -> rod-side channel"},
                     {"H_EC_rod", "W", "enthalpy flow into the gas at the tapping port EC_rod"},
                     {"P_pdV_EC_rod", "W", "p dV/dt of the rod cushion volume"},
                     {"H_cushion_rod", "W", "enthalpy flow rod cushion volume -> rod-side channel"}};
    r.roots = 2;
    return r;
  }
  // The instance's parts in the order of its ports, variables, observables
  // and rows; the constructor places each side's rows where they are named.
  static void add_parts(ComponentInfo& i, bool taps, bool rod, bool lugre) {
    using S = CylinderSide;
    clear_parts(i);
    add_part(i, cylinder_part());
    if (taps)
      add_part(i, {.ports = {{"EC", Domain::pneumatic, Causality::acausal,
                              "tapping into the cushion volume EC (closed if unconnected)", true}},
                   .equations = S::tap_equation_names("EC")});
    if (rod) add_part(i, rod_cushion_part());
    if (rod && taps)
      add_part(i, {.ports = {{"EC_rod", Domain::pneumatic, Causality::acausal,
                              "tapping into the rod cushion volume (rod cushioning only; closed if unconnected)",
                              true}},
                   .equations = S::tap_equation_names("EC_rod")});
    if (lugre) add_part(i, lugre_part());
  }

  // The row named `name`; row_if: -1 if the instance has none.
  int row_if(const std::string& name) const {
    const auto& names = info().equations;
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
  }
  int row(const std::string& name) const {
    const int k = row_if(name);
    if (k < 0) throw std::logic_error("cushioned_cylinder: no row named '" + name + "'");
    return k;
  }

  // The rod end's sleeve, annulus and paths (rod_plug_diameter given).
  void add_rod_cushioning(const ParameterValues& p) {
    const double d = p["rod_plug_diameter"];
    if (!(d > p["rod"] && d < p["bore"]))
      throw ParameterError("rod_plug_diameter", "the rod-end sleeve diameter must lie between rod and bore");
    for (const char* name : {"rod_cushion_length", "rod_dead_volume_cushion"})
      if (!p.has(name))
        throw ParameterError(name, std::string("rod-end cushioning (rod_plug_diameter given) needs ") + name);
    rod_side_.cushion(
        {p["rod_cushion_length"], circle_area(d) - A_R_, p["rod_dead_volume_cushion"], read_cushion(p, "rod_")});
    if (cap_.cushion_length() + cap_.ramp() + rod_side_.cushion_length() + rod_side_.ramp() >= stroke_)
      throw ParameterError("rod_cushion_length",
                           "the cushioning zones (with their bore-opening ramps) at both ends overlap");
  }

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
    // The flow law's subsonic branch needs b below its laminar ratio.
    if (!(c.b_cushion >= 0 && c.b_cushion < kCushionLaminarRatio)) {
      char bound[32];
      std::snprintf(bound, sizeof bound, "%g", kCushionLaminarRatio);
      throw ParameterError(prefix + "cushion_b_slope",
                           "b of the cushion throttle leaves [0, " + std::string(bound) + ") at this opening");
    }
    c.C_check = get("check_C");
    c.b_check = get("check_b");
    c.crack = get("check_cracking");
    c.check_ramp = get("check_ramp");
    return c;
  }

  double A_B_, A_R_, stroke_;
  CylinderSide cap_, rod_side_;
  EndStops stops_;
  double wall_alpha_;
  FrictionLaw friction_;
  FrictionFaults friction_faults_;
  double x0_, p0_A_, p0_cap_, T0_;
  bool taps_;
  int z_var_ = 6, force_row_ = 0, lugre_row_ = -1;
  // state<double>() memo: its inputs (s, v, internal variables) and result.
  static constexpr int kMemoKey = 2 + 9;
  mutable bool memo_valid_ = false;
  mutable double memo_key_[kMemoKey] = {};
  mutable State<double> memo_state_{};
};

void register_cushioned_cylinder(Registry& r) { r.add<CushionedCylinder>(); }

}  // namespace pneumo::components
