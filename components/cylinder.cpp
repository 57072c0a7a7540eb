// Double-acting cylinder as FluidSIM and Automation Studio draw it, a preset
// of the one double-acting cylinder (components/cylinder.hpp): x = 0
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
// "rod_cushion_entry" and their "_exit" where the plug engages,
// "cap_bore_closing" / "cap_bore_open" (and the rod end's) at the ends of
// the bore opening's ramp.
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "components/cylinder.hpp"
#include "components/faults.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

namespace {
using End = CylinderEnd;
using Q = CylinderQuantity;

const CylinderLayout& layout();

ComponentInfo describe() {
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
  for (const std::string end : {"cap", "rod"}) {
    for (auto& s : CylinderSide::cushion_parameters(end)) i.parameters.push_back(std::move(s));
    for (auto& s : CushionFaults::parameters(end + "_")) i.parameters.push_back(std::move(s));
  }
  for (auto& s : Piston::parameters("rod-side")) i.parameters.push_back(std::move(s));
  DoubleActingCylinder::add_parts(layout(), i, true, true, true, FrictionState::lugre);
  i.faults = Piston::faults({"dead_volume_cap", "dead_volume_rod"});
  i.faults.push_back(FrictionFaults::chamber_pressure_fault());
  i.events = Piston::stop_events();
  for (const std::string end : {"cap", "rod"}) {
    i.events.push_back({end + "_cushion_entry", "enters the " + end + "-end cushioning zone (cushioned ends)"});
    i.events.push_back({end + "_cushion_exit", "leaves the " + end + "-end cushioning zone (cushioned ends)"});
    i.events.push_back({end + "_bore_closing", "the " + end + "-end bore opening starts to close (cushioned ends)"});
    i.events.push_back({end + "_bore_open", "the " + end + "-end bore opening is fully open (cushioned ends)"});
  }
  for (const char* end : {"cap", "rod"})
    i.faults.push_back(setting_fault(std::string(end) + "_cushion_misadjusted",
                                     std::string("cushion needle at the ") + end + " end off its setting (turned, clogged)",
                                     {{"k", std::string(end) + "_cushion_C", "1", true, 1.0, 0.1, 10.0, 1.5, true}}));
  for (const std::string end : {"cap", "rod"})
    for (auto& f : CushionFaults::faults(end + "_", end + "_cushion_length")) i.faults.push_back(std::move(f));
  return i;
}

std::string name(End end) { return end == End::cap ? "cap" : "rod"; }

bool cushioned(const ParameterValues& p, End end) { return CylinderSide::has_cushion(p, name(end)); }
bool no_taps(const ParameterValues&) { return false; }
std::optional<CylinderSide::Cushioning> cushioning(const ParameterValues& p, End end, double A, double A_rod,
                                                   double stroke) {
  return CylinderSide::read_cushioning(p, name(end), A, A_rod, stroke);
}

// The energy balance of the cushioned end (the cap end's if both are;
// cylinder_parts.hpp), from its cushion entry to the piston's first
// standstill or reversal.
std::optional<EnergyAuditSpec> audit(const CylinderShape& shape, const GasModel& gas) {
  if (!shape.cap_cushioned && !shape.rod_cushioned) return std::nullopt;
  const std::string end = shape.cap_cushioned ? "cap" : "rod", other = shape.cap_cushioned ? "rod" : "cap";
  CushionAuditNames n;
  n.title = end + "-end cushioning";
  n.opens_at = end + "_cushion_entry";
  n.open_description = end + "-end cushion entry";
  n.closes_when = shape.cap_cushioned ? "v_retract" : "v";  // the speed into the cushioned end
  n.drive_description = "work of the " + other + "-side gas and ambient on the piston";
  n.drive_changes = {{"x", -gas.p_ambient * shape.A_rod}};
  n.drive_integrals = {{"P_pdV_" + other, 1.0}};
  n.U_cushion = "U_" + end + "_cushion";
  n.Q_wall = "Q_" + end;
  n.P_pdV_channel = "P_pdV_" + end + "_channel";
  n.channel_port = end;
  n.outflows = {{"H_" + end + "_cushion", 1.0}};
  return cushion_energy_audit(n, gas);
}

CylinderEndLayout end_layout(End e) {
  using S = CylinderSide;
  const std::string end = name(e);
  const InfoPart annulus = S::annulus_part(end + "_cushion", end + " cushion", end + " cushion annulus");
  return {.chamber_variables = {{"m_" + end, "kg", "gas mass, " + end + " side (channel with " + end + " cushioning)", 0.0, "U_" + end},
                                {"U_" + end, "J", "internal energy, " + end + " side"}},
          .annulus_variables = annulus.variables,
          .chamber_rows = S::chamber_equation_names(end, end),
          .annulus_rows = annulus.equations,
          .wall_row = S::wall_equation_name(end),
          .entry = {end + "_cushion_entry", "enters the " + end + "-end cushioning zone"},
          .exit = {end + "_cushion_exit", "leaves the " + end + "-end cushioning zone"},
          .closing = {end + "_bore_closing", "the " + end + "-end bore opening starts to close"},
          .open = {end + "_bore_open", "the " + end + "-end bore opening is fully open"}};
}

std::vector<CylinderObservable> observables() {
  return {{{"x", "m", "piston position (0 retracted, stroke extended)"}, {Q::x}},
          {{"v", "m/s", "piston velocity (> 0 extending)"}, {Q::v}},
          {{"p_cap", "Pa", "cap-side pressure at the port, absolute"}, {Q::p_port, End::cap}},
          {{"p_rod", "Pa", "rod-side pressure at the port, absolute"}, {Q::p_port, End::rod}},
          {{"T_cap", "K", "cap-side gas temperature at the port"}, {Q::T_port, End::cap}},
          {{"T_rod", "K", "rod-side gas temperature at the port"}, {Q::T_port, End::rod}},
          {{"F_pressure", "N", "pressure force on the piston (+x), ambient on the rod included"}, {Q::F_pressure}},
          {{"F_friction", "N", "friction force on the piston (+x)"}, {Q::F_friction}},
          {{"F_stop", "N", "end stop force on the piston (+x)"}, {Q::F_stop}},
          {{"z", "m", "LuGre bristle deflection (0 for other friction models)"}, {Q::z}},
          {{"H_cap", "W", "enthalpy flow into the gas at port cap"}, {Q::H_port, End::cap}},
          {{"H_rod", "W", "enthalpy flow into the gas at port rod"}, {Q::H_port, End::rod}},
          {{"P_pdV", "W", "p dV/dt summed over the chambers: power from the gas to the piston"}, {Q::pdV_total}},
          {{"Q_cap", "W", "heat flow into the gas through heat_cap"}, {Q::Q_heat, End::cap}},
          {{"Q_rod", "W", "heat flow into the gas through heat_rod"}, {Q::Q_heat, End::rod}},
          {{"P_friction", "W", "friction power F_friction v (<= 0)"}, {Q::P_friction}},
          {{"P_stop", "W", "end stop power F_stop v"}, {Q::P_stop}},
          {{"E_stop", "J", "elastic energy stored in the end stops"}, {Q::E_stop}},
          {{"U_gas", "J", "internal energy of the gas in all chambers"}, {Q::U_gas}},
          {{"p_cap_cushion", "Pa", "cap cushion annulus pressure (p_cap without cap cushioning)"},
           {Q::p_piston, End::cap}},
          {{"T_cap_cushion", "K", "cap cushion annulus temperature (T_cap without cap cushioning)"},
           {Q::T_piston, End::cap}},
          {{"p_rod_cushion", "Pa", "rod cushion annulus pressure (p_rod without rod cushioning)"},
           {Q::p_piston, End::rod}},
          {{"T_rod_cushion", "K", "rod cushion annulus temperature (T_rod without rod cushioning)"},
           {Q::T_piston, End::rod}},
          {{"m_flow_cap_cushion", "kg/s", "flow cap cushion annulus -> channel (0 without)"}, {Q::m_cushion, End::cap}},
          {{"m_flow_rod_cushion", "kg/s", "flow rod cushion annulus -> channel (0 without)"}, {Q::m_cushion, End::rod}},
          {{"v_retract", "m/s", "retracting speed -v"}, {Q::v_negative}},
          {{"P_pdV_cap", "W", "p dV/dt of the cap-side gas (power to the piston)"}, {Q::pdV_side, End::cap}},
          {{"P_pdV_rod", "W", "p dV/dt of the rod-side gas (power to the piston)"}, {Q::pdV_side, End::rod}},
          {{"U_cap_cushion", "J", "internal energy of the cap cushion annulus gas (0 without)"},
           {Q::U_cushion, End::cap}},
          {{"U_rod_cushion", "J", "internal energy of the rod cushion annulus gas (0 without)"},
           {Q::U_cushion, End::rod}},
          {{"H_cap_cushion", "W", "enthalpy flow cap cushion annulus -> channel (0 without)"},
           {Q::H_cushion, End::cap}},
          {{"H_rod_cushion", "W", "enthalpy flow rod cushion annulus -> channel (0 without)"},
           {Q::H_cushion, End::rod}},
          {{"P_pdV_cap_channel", "W", "p dV/dt of the cap-side channel gas (0 without cushioning)"},
           {Q::pdV_channel, End::cap}},
          {{"P_pdV_rod_channel", "W", "p dV/dt of the rod-side channel gas (0 without cushioning)"},
           {Q::pdV_channel, End::rod}}};
}

const CylinderLayout& layout() {
  static const CylinderLayout l{
      .at_zero = End::cap,
      .ports = {{"cap", Domain::pneumatic, Causality::acausal,
                 "cap-side port: pressure extends (closed if unconnected)", true},
                {"rod", Domain::pneumatic, Causality::acausal,
                 "rod-side port: pressure retracts (closed if unconnected)", true},
                {"flange", Domain::translational, Causality::acausal, "rod end; position = x (0 retracted)"},
                {"heat_cap", Domain::thermal, Causality::acausal, "wall of the cap-side chamber", true},
                {"heat_rod", Domain::thermal, Causality::acausal, "wall of the rod-side chamber", true}},
      .observables = observables(),
      .cap = end_layout(End::cap),
      .rod = end_layout(End::rod),
      .stops = Piston::stop_texts(),
      .dead_volume_cap = "dead_volume_cap",
      .dead_volume_rod = "dead_volume_rod",
      .p0_cap = "p0_cap",
      .p0_rod = "p0_rod",
      .cushion_friction = false,
      .cushioned = cushioned,
      .taps = no_taps,
      .cushioning = cushioning,
      .audit = audit};
  return l;
}

}  // namespace

void register_cylinder(Registry& r) { DoubleActingCylinder::add_preset(r, layout(), describe()); }

}  // namespace pneumo::components
