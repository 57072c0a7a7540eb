// Double-acting cylinder with integrated end-position cushioning at the cap
// end and optionally at the rod end (seed paper 000, fig. 1;
// ../shared/rigs/cushion-rig.yaml).
//
// The seed-000 preset of the one double-acting cylinder (components/
// cylinder.hpp): x = 0 fully extended, x = stroke at the cap. The cap side is
// a CylinderSide (components/cylinder_parts.hpp) at travel stroke - x, split into
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
// instance then has the extra chamber, port and roots; rod_cushion_length
// without it is an error): the rod side splits
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
#include <cstdio>
#include <limits>

#include "components/builtin.hpp"
#include "components/cylinder.hpp"
#include "components/faults.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using End = CylinderEnd;
using Q = CylinderQuantity;

const CylinderLayout& layout();

// The cap end's bore opening, needle throttle and check valve.
std::vector<ParameterSpec> cap_cushion_parameters() {
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
std::vector<ParameterSpec> rod_cushion_parameters() {
  using P = ParameterSpec;
  return {
      P::scalar("rod_plug_diameter", "m", "rod-end cushion sleeve diameter (> rod); enables rod-end cushioning")
          .positive()
          .optional(),
      P::scalar("rod_cushion_length", "m",
              "rod-end cushioning length (engages at x = rod_cushion_length); needs rod_plug_diameter")
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
std::vector<ParameterSpec> wall_parameters() {
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
std::vector<ParameterSpec> initial_parameters() {
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

// The throttle/valve parameters of one end; the rod end's default to the
// cap end's.
Cushion read_cushion(const ParameterValues& p, const std::string& prefix) {
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
  CushionFaults::read(p, prefix, c);
  return c;
}

ComponentInfo describe() {
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
  for (auto& f : SealPresliding::parameters()) i.parameters.push_back(std::move(f));
  for (auto& s : initial_parameters()) i.parameters.push_back(std::move(s));
  for (auto& f : FrictionFaults::parameters()) i.parameters.push_back(std::move(f));
  for (auto& f : ChamberFaults::parameters()) i.parameters.push_back(std::move(f));
  for (const char* end : {"", "rod_"})
    for (auto& f : CushionFaults::parameters(end)) i.parameters.push_back(std::move(f));
  DoubleActingCylinder::add_parts(layout(), i, true, true, true, FrictionState::lugre);
  i.faults = {
      FrictionLaw::running_fault(),
      setting_fault("cushion_needle_misadjusted", "cushion needle opening off its setting (turned, clogged)",
                    {{"k", "z_EC", "1", true, 1.0, 0.2, 5.0, 1.3, true}}),
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
  i.faults.push_back(FrictionFaults::chamber_pressure_fault());
  for (auto& f : ChamberFaults::faults()) i.faults.push_back(std::move(f));
  for (auto& f : CushionFaults::faults("", "")) i.faults.push_back(std::move(f));
  for (auto& f : CushionFaults::faults("rod_", "rod_plug_diameter")) i.faults.push_back(std::move(f));
  // The rod side's and the channel's gas are at the ports; the cushion
  // volume is inside the end cap.
  for (const char* v : {"dead_volume_rod_side", "dead_volume_cushion", "dead_volume_channel"})
    i.faults.push_back(Piston::dead_volume_fault(v, std::string(v) != "dead_volume_cushion"));
  return i;
}

// The cap end is always cushioned; the rod end when rod_plug_diameter is
// given.
bool cushioned(const ParameterValues& p, End end) { return end == End::cap || p.has("rod_plug_diameter"); }
bool taps(const ParameterValues& p) { return p.text("cushion_taps") == "yes"; }

std::optional<CylinderSide::Cushioning> cushioning(const ParameterValues& p, End end, double, double A_rod,
                                                   double stroke) {
  if (end == End::cap) {
    if (p["plug_diameter"] >= p["bore"])
      throw ParameterError("plug_diameter", "plug diameter must be smaller than the bore");
    if (p["cushion_length"] >= stroke)
      throw ParameterError("cushion_length", "cushion length must be shorter than the stroke");
    return CylinderSide::Cushioning{p["cushion_length"], circle_area(p["plug_diameter"]), p["dead_volume_cushion"],
                                    read_cushion(p, "")};
  }
  if (!p.has("rod_plug_diameter")) {
    if (p.has("rod_cushion_length"))
      throw ParameterError("rod_plug_diameter",
                           "rod_cushion_length is given but rod-end cushioning needs rod_plug_diameter too");
    return std::nullopt;
  }
  const double d = p["rod_plug_diameter"];
  if (!(d > p["rod"] && d < p["bore"]))
    throw ParameterError("rod_plug_diameter", "the rod-end sleeve diameter must lie between rod and bore");
  for (const char* name : {"rod_cushion_length", "rod_dead_volume_cushion"})
    if (!p.has(name))
      throw ParameterError(name, std::string("rod-end cushioning (rod_plug_diameter given) needs ") + name);
  return CylinderSide::Cushioning{p["rod_cushion_length"], circle_area(d) - A_rod, p["rod_dead_volume_cushion"],
                                  read_cushion(p, "rod_")};
}

// The cap-end cushioning's energy balance (cylinder_parts.hpp), from the
// cushion entry to the piston's first standstill or reversal.
std::optional<EnergyAuditSpec> audit(const CylinderShape& shape, const GasModel& gas) {
  CushionAuditNames n;
  n.title = "cap-end cushioning";
  n.opens_at = "cushion_entry";
  n.open_description = "cushion entry";
  n.closes_when = "v";
  n.drive_description = "work of the rod-side gas and ambient on the piston";
  n.drive_changes = {{"x", gas.p_ambient * shape.A_rod}};
  n.drive_integrals = {{"P_pdV_A", 1.0}};
  if (shape.rod_cushioned) n.drive_integrals.push_back({"P_pdV_EC_rod", 1.0});
  n.U_cushion = "U_EC";
  n.Q_wall = "Q_cap";
  n.P_pdV_channel = "P_pdV_ch";
  n.channel_port = "B";
  n.outflows = {{"H_cushion", 1.0}};
  if (shape.taps) n.outflows.push_back({"H_EC", -1.0});  // the tap's gas leaves too, not through the throttle
  return cushion_energy_audit(n, gas);
}

CylinderEndLayout cap_end() {
  using S = CylinderSide;
  return {.chamber_variables = {{"m_ch", "kg", "gas mass, channel", 0.0, "U_ch"}, {"U_ch", "J", "internal energy, channel"}},
          .annulus_variables = {{"m_EC", "kg", "gas mass, cushion volume", 0.0, "U_EC"},
                                {"U_EC", "J", "internal energy, cushion volume"}},
          .chamber_rows = S::chamber_equation_names("ch", "B"),
          .annulus_rows = S::annulus_equation_names("EC"),
          .wall_row = S::wall_equation_name("cap"),
          .tap = PortSpec{"EC", Domain::pneumatic, Causality::acausal,
                          "tapping into the cushion volume EC (closed if unconnected)", true},
          .tap_rows = S::tap_equation_names("EC"),
          .entry = {"cushion_entry", "enters the cushioning zone"},
          .exit = {"cushion_exit", "leaves the cushioning zone"},
          .closing = {"bore_closing", "bore opening starts to close"},
          .open = {"bore_open", "bore opening fully open"}};
}

CylinderEndLayout rod_end() {
  using S = CylinderSide;
  const InfoPart annulus = S::annulus_part("EC_rod", "ECr", "rod cushion volume");
  return {
      .chamber_variables = {{"m_A", "kg", "gas mass, rod side", 0.0, "U_A"}, {"U_A", "J", "internal energy, rod side"}},
      .annulus_variables = annulus.variables,
      .chamber_rows = S::chamber_equation_names("A", "A"),
      .annulus_rows = annulus.equations,
      .wall_row = S::wall_equation_name("A"),
      .cushion_observables = {{{"p_EC_rod", "Pa", "rod cushion volume pressure, absolute"}, {Q::p_piston, End::rod}},
                              {{"T_EC_rod", "K", "rod cushion volume gas temperature"}, {Q::T_piston, End::rod}},
                              {{"bore_open_rod", "1", "rod-end bore opening fraction"}, {Q::bore_open, End::rod}},
                              {{"m_flow_cushion_rod", "kg/s", "flow rod cushion volume -> rod-side channel"},
                               {Q::m_cushion, End::rod}},
                              {{"H_EC_rod", "W", "enthalpy flow into the gas at the tapping port EC_rod"},
                               {Q::H_tap, End::rod}},
                              {{"P_pdV_EC_rod", "W", "p dV/dt of the rod cushion volume"}, {Q::pdV_annulus, End::rod}},
                              {{"H_cushion_rod", "W", "enthalpy flow rod cushion volume -> rod-side channel"},
                               {Q::H_cushion, End::rod}}},
      .tap = PortSpec{"EC_rod", Domain::pneumatic, Causality::acausal,
                      "tapping into the rod cushion volume (rod cushioning only; closed if unconnected)", true},
      .tap_rows = S::tap_equation_names("EC_rod"),
      .entry = {"rod_cushion_entry", "enters the rod-end cushioning zone"},
      .exit = {"rod_cushion_exit", "leaves the rod-end cushioning zone"},
      .closing = {"rod_bore_closing", "rod-end bore opening starts to close"},
      .open = {"rod_bore_open", "rod-end bore opening fully open"}};
}

std::vector<CylinderObservable> observables() {
  return {{{"x", "m", "piston position (0 extended, stroke at the cap)"}, {Q::x}},
          {{"v", "m/s", "piston velocity"}, {Q::v}},
          {{"p_A", "Pa", "rod-side pressure, absolute"}, {Q::p_port, End::rod}},
          {{"p_EC", "Pa", "cushion volume pressure, absolute"}, {Q::p_piston, End::cap}},
          {{"p_ch", "Pa", "channel pressure, absolute"}, {Q::p_port, End::cap}},
          {{"T_A", "K", "rod-side gas temperature"}, {Q::T_port, End::rod}},
          {{"T_EC", "K", "cushion volume gas temperature"}, {Q::T_piston, End::cap}},
          {{"T_ch", "K", "channel gas temperature"}, {Q::T_port, End::cap}},
          {{"F_friction", "N", "friction force on the piston (+x)"}, {Q::F_friction}},
          {{"F_stop", "N", "end stop force on the piston (+x)"}, {Q::F_stop}},
          {{"bore_open", "1", "bore opening fraction"}, {Q::bore_open, End::cap}},
          {{"m_flow_cushion", "kg/s", "flow cushion volume -> channel (bore, throttle, check valve)"},
           {Q::m_cushion, End::cap}},
          {{"z", "m", "LuGre bristle deflection (0 for other friction models)"}, {Q::z}},
          {{"F_pressure", "N", "pressure force on the piston (+x), ambient on the rod included"}, {Q::F_pressure}},
          {{"H_A", "W", "enthalpy flow into the gas at port A"}, {Q::H_port, End::rod}},
          {{"H_B", "W", "enthalpy flow into the gas at port B"}, {Q::H_port, End::cap}},
          {{"H_EC", "W", "enthalpy flow into the gas at the tapping port EC"}, {Q::H_tap, End::cap}},
          {{"P_pdV_A", "W", "p dV/dt of the rod-side chamber (port A's volume)"}, {Q::pdV_port, End::rod}},
          {{"P_pdV_EC", "W", "p dV/dt of the cushion volume"}, {Q::pdV_annulus, End::cap}},
          {{"P_pdV_ch", "W", "p dV/dt of the channel"}, {Q::pdV_port, End::cap}},
          {{"P_pdV", "W", "sum of p dV/dt over all chambers: power from the gas to the piston"}, {Q::pdV_total}},
          {{"Q_A", "W", "heat flow into the gas through heat_A"}, {Q::Q_heat, End::rod}},
          {{"Q_cap", "W", "heat flow into the gas through heat_cap"}, {Q::Q_heat, End::cap}},
          {{"H_cushion", "W", "enthalpy flow cushion volume -> channel"}, {Q::H_cushion, End::cap}},
          {{"P_friction", "W", "friction power F_friction v (<= 0)"}, {Q::P_friction}},
          {{"P_stop", "W", "end stop power F_stop v"}, {Q::P_stop}},
          {{"E_stop", "J", "elastic energy stored in the end stops, k pen^2 / 2"}, {Q::E_stop}},
          {{"U_gas", "J", "internal energy of the gas in all chambers"}, {Q::U_gas}}};
}

const CylinderLayout& layout() {
  static const CylinderLayout l{
      .at_zero = End::rod,
      .ports = {{"A", Domain::pneumatic, Causality::acausal, "rod-side chamber port (closed if unconnected)", true},
                {"B", Domain::pneumatic, Causality::acausal, "cap-side outlet (outflow channel; closed if unconnected)",
                 true},
                {"flange", Domain::translational, Causality::acausal, "rod end; position = x"},
                {"heat_A", Domain::thermal, Causality::acausal,
                 "wall of the rod-side chamber (ECr with rod cushioning)", true},
                {"heat_cap", Domain::thermal, Causality::acausal, "wall of the cushion volume", true}},
      .observables = observables(),
      .cap = cap_end(),
      .rod = rod_end(),
      .stops = {{"rod_stop_contact", "contact with the rod-end stop"},
                {"rod_stop_left", "leaves the rod-end stop"},
                {"cap_impact", "impact on the cap-end stop"},
                {"cap_stop_left", "leaves the cap-end stop"}},
      .dead_volume_cap = "dead_volume_channel",
      .dead_volume_rod = "dead_volume_rod_side",
      .p0_cap = "p0_cap",
      .p0_rod = "p0_A",
      .cushion_friction = true,
      .cushioned = cushioned,
      .taps = taps,
      .cushioning = cushioning,
      .audit = audit};
  return l;
}

}  // namespace

void register_cushioned_cylinder(Registry& r) { DoubleActingCylinder::add_preset(r, layout(), describe()); }

}  // namespace pneumo::components
