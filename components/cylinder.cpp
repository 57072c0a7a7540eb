// Double-acting cylinder as FluidSIM and Automation Studio draw it: x = 0
// fully retracted, x = stroke fully extended; port `cap` feeds the cap-side
// chamber (pressure there extends), port `rod` the rod-side chamber (pressure
// there retracts). Both ports are closed when unconnected.
//
//   V_cap = dead_volume_cap + A x,   V_rod = dead_volume_rod + (A - A_rod)(stroke - x)
//   F = p_cap A - p_rod (A - A_rod) - p_amb A_rod + F_friction + F_stops   (+x)
//
// Each chamber has its own mass and energy balance (state m, U); rod: 0
// makes it rodless (both faces full bore). Friction: the friction_model of
// components/friction.hpp (paper [1] presets with the chamber pressures at
// the piston - the presets' p_A is the rod side, p_B and p_EC the cap side -
// Coulomb + viscous, LuGre); elastic end stops at x = 0 and x = stroke.
// Heat: with wall_alpha = 0 the heat ports are at the gas temperature
// (insulated if unconnected); with wall_alpha > 0 they are the walls and the
// gas exchanges Q = wall_alpha A_wall(x) (T_wall - T_gas) with them - walls
// at the ambient temperature where nothing is connected to the heat port.
//
// End-position cushioning at either end is optional: giving
// cap_cushion_length (or rod_cushion_length) splits that chamber into the
// cushion annulus at the piston and the channel behind the port, joined by
// the bore opening, the needle throttle <end>_cushion_C and a check valve
// (components/cylinder_parts.hpp; the geometry of cushioned_cylinder).
//
// Events, tagged for metrics and audits: "retracted" / "extended" at the
// stop contacts (the stop force jumps: the solver re-initialises),
// "left_retracted" / "left_extended" leaving them, "cap_cushion_entry" /
// "rod_cushion_entry" and their "_exit" where the plug engages.
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "components/builtin.hpp"
#include "components/cylinder_parts.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class Cylinder final : public ComponentT<Cylinder> {
 public:
  enum Port { kCap, kRod, kFlange, kHeatCap, kHeatRod };
  enum Obs {
    kX, kV, kPcap, kProd, kTcap, kTrod, kFpressure, kFfric, kFstop, kZ, kHcap, kHrod, kPdV, kQcap, kQrod, kPfric,
    kPstop, kEstop, kUgas, kPcapC, kTcapC, kProdC, kTrodC, kMcapC, kMrodC,
    // energy audit of a cushioned end
    kVretract, kPdVcap, kPdVrod, kUcapC, kUrodC, kHcapC, kHrodC, kPdVcapCh, kPdVrodCh
  };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "cylinder";
    i.description =
        "Double-acting cylinder: x = 0 retracted, x = stroke extended; ports cap (extends) and rod (retracts), closed "
        "if unconnected; mass and energy balance per chamber, friction (presets, Coulomb + viscous, LuGre), elastic "
        "end stops, optional wall heat and optional end-position cushioning at either end.";
    i.symbol = symbols::cylinder("cap", "rod");
    using P = ParameterSpec;
    i.parameters = {
        P::scalar("bore", "m", "piston diameter").positive(),
        P::scalar("rod", "m", "rod diameter; 0: rodless (both faces full bore area)").non_negative(),
        P::scalar("stroke", "m", "stroke").positive(),
        P::scalar("dead_volume_cap", "m3", "cap-side volume at x = 0 (with cap cushioning: the channel's)", 1e-6)
            .positive(),
        P::scalar("dead_volume_rod", "m3", "rod-side volume at x = stroke (with rod cushioning: the channel's)",
                  1e-6)
            .positive(),
    };
    for (const char* end : {"cap", "rod"})
      for (auto& s : CylinderSide::cushion_parameters(end)) i.parameters.push_back(std::move(s));
    for (auto& s : Piston::parameters("rod-side")) i.parameters.push_back(std::move(s));
    i.ports = {{"cap", Domain::pneumatic, Causality::acausal, "cap-side port: pressure extends (closed if unconnected)",
                true},
               {"rod", Domain::pneumatic, Causality::acausal, "rod-side port: pressure retracts (closed if unconnected)",
                true},
               {"flange", Domain::translational, Causality::acausal, "rod end; position = x (0 retracted)"},
               {"heat_cap", Domain::thermal, Causality::acausal, "wall of the cap-side chamber", true},
               {"heat_rod", Domain::thermal, Causality::acausal, "wall of the rod-side chamber", true}};
    i.observables = {{"x", "m", "piston position (0 retracted, stroke extended)"},
                     {"v", "m/s", "piston velocity (> 0 extending)"},
                     {"p_cap", "Pa", "cap-side pressure at the port, absolute"},
                     {"p_rod", "Pa", "rod-side pressure at the port, absolute"},
                     {"T_cap", "K", "cap-side gas temperature at the port"},
                     {"T_rod", "K", "rod-side gas temperature at the port"},
                     {"F_pressure", "N", "pressure force on the piston (+x), ambient on the rod included"},
                     {"F_friction", "N", "friction force on the piston (+x)"},
                     {"F_stop", "N", "end stop force on the piston (+x)"},
                     {"z", "m", "LuGre bristle deflection (0 for other friction models)"},
                     {"H_cap", "W", "enthalpy flow into the gas at port cap"},
                     {"H_rod", "W", "enthalpy flow into the gas at port rod"},
                     {"P_pdV", "W", "p dV/dt summed over the chambers: power from the gas to the piston"},
                     {"Q_cap", "W", "heat flow into the gas through heat_cap"},
                     {"Q_rod", "W", "heat flow into the gas through heat_rod"},
                     {"P_friction", "W", "friction power F_friction v (<= 0)"},
                     {"P_stop", "W", "end stop power F_stop v"},
                     {"E_stop", "J", "elastic energy stored in the end stops"},
                     {"U_gas", "J", "internal energy of the gas in all chambers"},
                     {"p_cap_cushion", "Pa", "cap cushion annulus pressure (p_cap without cap cushioning)"},
                     {"T_cap_cushion", "K", "cap cushion annulus temperature (T_cap without cap cushioning)"},
                     {"p_rod_cushion", "Pa", "rod cushion annulus pressure (p_rod without rod cushioning)"},
                     {"T_rod_cushion", "K", "rod cushion annulus temperature (T_rod without rod cushioning)"},
                     {"m_flow_cap_cushion", "kg/s", "flow cap cushion annulus -> channel (0 without)"},
                     {"m_flow_rod_cushion", "kg/s", "flow rod cushion annulus -> channel (0 without)"},
                     {"v_retract", "m/s", "retracting speed -v"},
                     {"P_pdV_cap", "W", "p dV/dt of the cap-side gas (power to the piston)"},
                     {"P_pdV_rod", "W", "p dV/dt of the rod-side gas (power to the piston)"},
                     {"U_cap_cushion", "J", "internal energy of the cap cushion annulus gas (0 without)"},
                     {"U_rod_cushion", "J", "internal energy of the rod cushion annulus gas (0 without)"},
                     {"H_cap_cushion", "W", "enthalpy flow cap cushion annulus -> channel (0 without)"},
                     {"H_rod_cushion", "W", "enthalpy flow rod cushion annulus -> channel (0 without)"},
                     {"P_pdV_cap_channel", "W", "p dV/dt of the cap-side channel gas (0 without cushioning)"},
                     {"P_pdV_rod_channel", "W", "p dV/dt of the rod-side channel gas (0 without cushioning)"}};
    add_parts(i, true, true, true);
    i.faults = Piston::faults({"dead_volume_cap", "dead_volume_rod"});
    i.events = Piston::stop_events();
    for (const std::string end : {"cap", "rod"}) {
      i.events.push_back({end + "_cushion_entry", "enters the " + end + "-end cushioning zone (cushioned ends)"});
      i.events.push_back({end + "_cushion_exit", "leaves the " + end + "-end cushioning zone (cushioned ends)"});
    }
    for (const char* end : {"cap", "rod"})
      i.faults.push_back({std::string(end) + "_cushion_misadjusted",
                          std::string("cushion needle at the ") + end + " end off its setting (turned, clogged)",
                          {{"k", std::string(end) + "_cushion_C", "1", true, 1.0, 0.1, 10.0, 1.5, true}}});
    return i;
  }

  // The parts this instance has: an end's cushion annulus, the LuGre state.
  static ComponentInfo instance_info(ComponentInfo i, const ParameterValues& p) {
    add_parts(i, CylinderSide::has_cushion(p, "cap"), CylinderSide::has_cushion(p, "rod"),
              p.text("friction_model") == "lugre");
    return i;
  }
  // In the order of the rows: each side's (its annulus' with cushioning, a
  // root each), the force balance, LuGre's z.
  static void add_parts(ComponentInfo& i, bool cap_cushion, bool rod_cushion, bool lugre) {
    // Every instance has describe()'s ports and observables, and the stops' roots.
    InfoPart cylinder{.ports = i.ports, .observables = i.observables, .roots = 2};
    clear_parts(i);
    add_part(i, cylinder);
    for (const auto& [end, cushioned] : {std::pair<std::string, bool>{"cap", cap_cushion}, {"rod", rod_cushion}}) {
      add_part(i, {.variables = {{"m_" + end, "kg", "gas mass, " + end + " side (channel with " + end + " cushioning)"},
                                 {"U_" + end, "J", "internal energy, " + end + " side"}},
                   .equations = CylinderSide::equation_names(end, end, end)});
      if (!cushioned) continue;
      InfoPart annulus = CylinderSide::annulus_part(end + "_cushion", end + " cushion", end + " cushion annulus");
      annulus.roots = 1;  // the cushion entry
      add_part(i, annulus);
    }
    add_part(i, {.equations = {"force balance"}});
    if (lugre) add_part(i, lugre_part());
  }

  explicit Cylinder(const Construction& c) : ComponentT(c), p_(c.params) {
    if (p_.cap.cushioned() && p_.rod.cushioned() &&
        p_.cap.cushion_length() + p_.rod.cushion_length() >= p_.stroke)
      throw ParameterError("rod_cushion_length", "the cushioning zones at both ends overlap");
    p_.cap.set_first_variable(0);
    p_.rod.set_first_variable(p_.cap.variables());
    z_var_ = p_.cap.variables() + p_.rod.variables();
  }

  template <class T>
  struct State {
    T x, v, z;
    CylinderSide::Gas<T> cap, rod;
    T F_pressure, F_fric, F_stop;
  };

  template <class T>
  State<T> state(const Eval<T>& e) const {
    const auto fl = e.flange(kFlange);
    const double p_amb = e.gas().p_ambient;
    State<T> s{fl.s, fl.v, p_.friction.has_state() ? e.var(z_var_) : T(0.0 * fl.v), p_.cap.gas(e, fl.s),
               p_.rod.gas(e, T(p_.stroke - fl.s)), T(0.0), T(0.0), T(0.0)};
    s.F_pressure = p_.cap.force(s.cap) - p_.rod.force(s.rod) - p_amb * p_.A_rod;
    s.F_fric = piston_friction(p_.friction, s.v, s.z, s.rod.p_piston, s.cap.p_piston, s.cap.p_piston, p_amb);
    if (p_.friction_faults.any()) s.F_fric += p_.friction_faults.force(s.v, T(s.cap.p - s.rod.p), p_.friction.v_reg);
    s.F_stop = p_.stops.force(s.x, s.v, p_.stroke);
    return s;
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const State<T> s = state(e);
    const bool faulty = p_.has_fault_flows();
    const auto ff = faulty ? p_.fault_flows(s.cap, &s.rod, e.gas()) : Piston::FaultFlows<T>{};
    p_.cap.equations(e, e.gas_port(kCap), e.heat_port(kHeatCap), s.cap, s.x, s.v, p_.wall_alpha, r,
                     faulty ? &ff.cap : nullptr);
    r += p_.cap.rows();
    p_.rod.equations(e, e.gas_port(kRod), e.heat_port(kHeatRod), s.rod, T(p_.stroke - s.x), T(-s.v), p_.wall_alpha, r,
                     faulty ? &ff.rod : nullptr);
    r += p_.rod.rows();
    // The flange pulls on the cylinder with f = -F.
    r[0] = e.flange(kFlange).f + s.F_pressure + s.F_fric + s.F_stop;
    if (p_.friction.has_state()) r[1] = e.der(z_var_) - p_.friction.lugre_zdot(s.v, e.var(z_var_));
  }

  double observe(int k, const Eval<double>& e) const override { return observe(k, state(e), e); }
  // Outputs ask for several observables at one point: the state once.
  void observe_all(const int* ks, int n, const Eval<double>& e, double* out) const override {
    const State<double> s = state(e);
    for (int i = 0; i < n; ++i) out[i] = observe(ks[i], s, e);
  }
  double observe(int k, const State<double>& s, const Eval<double>& e) const {
    auto inflow = [&](int port) {
      const auto g = e.gas_port(port);
      return enthalpy_inflow(g.m_flow, g.T_in, g.T_out, e.gas());
    };
    switch (k) {
      case kX: return s.x;
      case kV: return s.v;
      case kPcap: return s.cap.p;
      case kProd: return s.rod.p;
      case kTcap: return s.cap.T_gas;
      case kTrod: return s.rod.T_gas;
      case kFpressure: return s.F_pressure;
      case kFfric: return s.F_fric;
      case kFstop: return s.F_stop;
      case kZ: return s.z;
      case kHcap: return inflow(kCap);
      case kHrod: return inflow(kRod);
      case kPdV: return p_.cap.p_dV(s.cap, s.v) + p_.rod.p_dV(s.rod, -s.v);
      case kQcap: return e.heat_port(kHeatCap).Q;
      case kQrod: return e.heat_port(kHeatRod).Q;
      case kPfric: return s.F_fric * s.v;
      case kPstop: return s.F_stop * s.v;
      case kEstop: return p_.stops.energy(s.x, p_.stroke);
      case kUgas: return p_.cap.internal_energy(e) + p_.rod.internal_energy(e);
      case kPcapC: return s.cap.p_piston;
      case kTcapC: return s.cap.T_piston;
      case kProdC: return s.rod.p_piston;
      case kTrodC: return s.rod.T_piston;
      case kMcapC: return s.cap.m_x;
      case kMrodC: return s.rod.m_x;
      case kVretract: return -s.v;
      case kPdVcap: return p_.cap.p_dV(s.cap, s.v);
      case kPdVrod: return p_.rod.p_dV(s.rod, -s.v);
      case kUcapC: return p_.cap.cushion_internal_energy(e);
      case kUrodC: return p_.rod.cushion_internal_energy(e);
      case kHcapC: return s.cap.H_x;
      case kHrodC: return s.rod.H_x;
      case kPdVcapCh: return p_.cap.channel_p_dV(s.cap, s.v);
      case kPdVrodCh: return p_.rod.channel_p_dV(s.rod, -s.v);
    }
    return 0.0;
  }

  void roots(const Eval<double>& e, double* g) const override {
    const double x = e.flange(kFlange).s;
    p_.stop_roots(x, g);
    int k = 2;
    if (p_.cap.cushioned()) g[k++] = x - p_.cap.cushion_length();
    if (p_.rod.cushioned()) g[k++] = (p_.stroke - x) - p_.rod.cushion_length();
  }

  EventResult on_event(const Eval<double>& e, double*, EventKind, int root, int dir) const override {
    const std::string at = " at v = " + std::to_string(e.flange(kFlange).v) + " m/s";
    if (root < 2) return Piston::stop_event(root, dir, at);
    // Cushion roots: the cap end's first; g falls on entry at both ends.
    const std::string end = root == 2 && p_.cap.cushioned() ? "cap" : "rod";
    return dir > 0 ? EventResult{false, "leaves the " + end + "-end cushioning zone" + at, end + "_cushion_exit"}
                   : EventResult{false, "enters the " + end + "-end cushioning zone" + at, end + "_cushion_entry"};
  }

  // The energy balance of the cushioned end (the cap end's if both are;
  // cylinder_parts.hpp), from its cushion entry to the piston's first
  // standstill or reversal.
  // Walls that exchange heat (wall_alpha > 0) with nothing connected are at
  // the ambient temperature.
  bool unconnected_heat_port_at_ambient(int port) const override {
    return p_.wall_alpha > 0 && (port == kHeatCap || port == kHeatRod);
  }

  std::optional<EnergyAuditSpec> energy_audit(const GasModel& gas) const override {
    if (!p_.cap.cushioned() && !p_.rod.cushioned()) return std::nullopt;
    const std::string end = p_.cap.cushioned() ? "cap" : "rod", other = p_.cap.cushioned() ? "rod" : "cap";
    CushionAuditNames n;
    n.title = end + "-end cushioning";
    n.opens_at = end + "_cushion_entry";
    n.open_description = end + "-end cushion entry";
    n.closes_when = p_.cap.cushioned() ? "v_retract" : "v";  // the speed into the cushioned end
    n.drive_description = "work of the " + other + "-side gas and ambient on the piston";
    n.drive_changes = {{"x", -gas.p_ambient * p_.A_rod}};
    n.drive_integrals = {{"P_pdV_" + other, 1.0}};
    n.U_cushion = "U_" + end + "_cushion";
    n.Q_wall = "Q_" + end;
    n.P_pdV_channel = "P_pdV_" + end + "_channel";
    n.channel_port = end;
    n.outflows = {{"H_" + end + "_cushion", 1.0}};
    return cushion_energy_audit(n, gas);
  }

  void start(StartValues& sv, const GasModel& gas) const override {
    double x = p_.x0;
    if (std::isnan(x)) {
      // At rest against the stop at x = 0: the stop carries the net pressure
      // force (friction is zero at rest).
      const double F = p_.p0_cap * p_.A - p_.p0_rod * (p_.A - p_.A_rod) - gas.p_ambient * p_.A_rod;
      x = F < 0 ? -p_.stops.rest_penetration_low(-F) : 0.0;
    }
    sv.fix_position(kFlange, x);
    p_.cap.start(sv, gas, kCap, kHeatCap, p_.p0_cap, p_.T0, x);
    p_.rod.start(sv, gas, kRod, kHeatRod, p_.p0_rod, p_.T0, p_.stroke - x);
    if (p_.friction.has_state()) sv.fix_var(z_var_, 0.0);
  }

 private:
  Piston p_;
  int z_var_ = 4;
};

void register_cylinder(Registry& r) { r.add<Cylinder>(); }

}  // namespace pneumo::components
