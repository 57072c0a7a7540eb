// The AD Jacobian against finite differences, for every built-in component.
//
// What is checked (testkit::check_jacobian), per circuit, at the consistent
// initial point and at a point after a short simulation (flows, heat and
// motion under way):
//  * Evaluator::jacobian_parts (forward-mode AD: dF/dy and dF/dy') equals
//    central finite differences of Evaluator::residual;
//  * Evaluator::jacobian(cj), the matrix IDA factorises, equals
//    dF/dy + cj dF/dy' on the structural pattern, has nothing outside it,
//    and reports no pattern misses.
// Every registered component type must appear in some circuit below: a new
// component without a snippet fails RegistryIsCovered.
//
// Tolerance. Entries are compared scaled by their variable's magnitude,
// S_ij = J_ij * max(|y_j|, nominal_j) (the change of F_i for a relative change
// of y_j), so that rows mixing Pa, kg and K compare like with like. A central
// difference with relative step 1e-6 has truncation error ~1e-12 and
// rounding error ~1e-10 of the row's largest scaled entry; asserted
// |S_ad - S_fd| <= 1e-5 max(|S_ad|, 1e-3 max_j |S_ij|), i.e. relative 1e-5
// for every entry that matters in its row. Where the residual has a kink
// inside the stencil (choked/subsonic switch, end stop contact) the forward
// and backward differences disagree and the entry is skipped; such entries
// are counted and must stay rare.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "framework/testkit/testkit.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

struct Snippet {
  std::string name;
  std::string netlist;          // YAML text
  double t_short = 0.05;        // s, second check point
  std::set<std::string> types;  // component types the snippet is there to cover
};
void PrintTo(const Snippet& s, std::ostream* os) { *os << s.name; }

using test_support::read_file;

const std::vector<Snippet>& snippets() {
  static const std::vector<Snippet> list = {
      {"tank_with_wall",
       // Filling from a source and venting to the atmosphere at once, the gas
       // exchanging heat with a wall that starts warmer than the gas.
       test_support::kTankWithWallCircuit,
       0.05,
       {"pressure_source", "iso6358_throttle", "volume", "atmosphere", "heat_convection", "thermal_mass"}},
      {"tank_to_reservoir",
       R"(
components:
  tank:      {type: volume, V: 1 L, p0: 8 bar, T0: 310 K}
  orifice:   {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.4}
  air:       {type: atmosphere}
  film:      {type: heat_convection, alpha: 20 W/(m2*K), A: 0.05 m2}
  reservoir: {type: fixed_temperature, T: 290 K}
connections:
  - [tank.port, orifice.a]
  - [orifice.b, air.port]
  - [tank.heat, film.a]
  - [film.b, reservoir.port]
)",
       0.1,
       {"fixed_temperature"}},
      {"signals",
       // Every kind of signal source, each driving an input: a ramp opening a
       // throttle, a table setting a supply pressure, a step and a constant
       // forces (the step switches a discrete mode before the second point);
       // an external input (an FMU's) at its start value as the drag.
       R"(
components:
  supply_p: {type: signal_source, kind: table, table: [[0, 4e5], [0.02, 5e5], [1, 6e5]]}
  supply:   {type: pressure_source, p: 5 bar, T: 293.15 K}
  opening:  {type: signal_source, kind: ramp, value: 0.2, height: 0.7, t_start: 0, duration: 0.1}
  valve:    {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.3}
  tank:     {type: volume, V: 0.2 L, p0: 1.5 bar}
  push_cmd: {type: signal_source, kind: step, value: 5, height: 20, t_start: 0.01}
  push:     {type: force_source}
  body:     {type: translational_mass, m: 1.5 kg, s0: 0.01 m, v0: 0.2 m/s}
  drag_cmd: {type: external_input, start: -3, unit: N}
  drag:     {type: force_source}
connections:
  - [supply_p.y, supply.p_in]
  - [opening.y, valve.opening]
  - [supply.port, valve.a]
  - [valve.b, tank.port]
  - [push_cmd.y, push.F_in]
  - [push.flange, body.flange, drag.flange]
  - [drag_cmd.y, drag.F_in]
)",
       0.03,
       {"signal_source", "external_input", "force_source", "translational_mass"}},
      {"frame",
       // The frame carrying a load force (nothing else can connect to it
       // without a spring).
       R"(
components:
  frame: {type: fixed_position, s0: 0.02 m}
  load:  {type: force_source, F: 40 N}
connections:
  - [frame.flange, load.flange]
)",
       0.05,
       {"fixed_position"}},
      {"three_port_node",
       // Not a component: the framework's stream mixing at a node of three
       // pneumatic ports, with flows in both directions.
       test_support::kThreePortMixingCircuit,
       0.2,
       {}},
      {"cushion_rig",
       // The paper's end-cushioning rig; the second point is in mid-stroke.
       read_file(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml"),
       0.05,
       {"cushioned_cylinder"}},
      {"friction_laws",
       // A signal-driven velocity source pulling a LuGre body through a
       // spring-damper (stick-slip under way at the second point), a body on
       // Coulomb + viscous friction and a pressure-dependent eq. 8 preset.
       R"(
components:
  speed:  {type: signal_source, kind: ramp, value: 0.05, height: 0.1, t_start: 0, duration: 0.5}
  drive:  {type: velocity_source, s0: 0.01 m}
  spring: {type: spring_damper, k: 200 N/m, d: 0.5 N*s/m, L0: 0.01 m}
  body:   {type: translational_mass, m: 0.5 kg, s0: 0, v0: 0}
  lugre:  {type: friction_element, friction_model: lugre, friction_FC: 1 N, friction_FS: 1.5 N,
           friction_vS: 0.01 m/s, friction_sigma0: 1e4 N/m, friction_sigma1: 50 N*s/m, friction_viscous: 0.4 N*s/m}
  push:   {type: force_source, F: 3 N}
  slider: {type: translational_mass, m: 0.2 kg, s0: 0, v0: 0.1 m/s}
  visc:   {type: friction_element, friction_model: coulomb_viscous, friction_FC: 1 N, friction_viscous: 5 N*s/m,
           friction_v_reg: 1e-3 m/s}
  drag:   {type: force_source, F: 30 N}
  sled:   {type: translational_mass, m: 1 kg, s0: 0, v0: 0.05 m/s}
  eq8:    {type: friction_element, friction: annexC_pAB+, pressure: 4 bar}
connections:
  - [speed.y, drive.v_in]
  - [drive.flange, spring.b]
  - [spring.a, body.flange, lugre.flange]
  - [push.flange, slider.flange, visc.flange]
  - [drag.flange, sled.flange, eq8.flange]
)",
       0.3,
       {"friction_element", "spring_damper", "velocity_source"}},
      {"replayed_position",
       // A measured position (TU Delft excerpt) replayed through a servo
       // that pulls a mass on a spring-damper (second point mid-stroke).
       R"(
components:
  pos:    {type: data_signal, file: )" + std::string(PNEUMO_SOURCE_DIR) + R"(/tests/data/tudelft/O-ring_3bar_head.csv,
           separator: whitespace, header: no, time_column: "1", time_unit: ms, column: "5", unit: mm}
  servo:  {type: position_source, tau: 2 ms}
  spring: {type: spring_damper, k: 2000 N/m, d: 5 N*s/m, L0: 0.01 m}
  body:   {type: translational_mass, m: 0.5 kg, s0: 0.01 m, v0: 0}
connections:
  - [pos.y, servo.s_in]
  - [pos.dy, servo.v_in]
  - [servo.flange, spring.a]
  - [spring.b, body.flange]
)",
       3.0,
       {"data_signal", "position_source"}},
      {"cylinder_rod_cushion_lugre",
       // The rig mirrored: an extending stroke into the rod-end cushion
       // (second point inside it), LuGre friction, gas-to-wall heat with
       // wall masses, and a leakage throttle on the cap-side cushion tap.
       R"(
components:
  supply:    {type: pressure_source, p: 5 bar, T: 293.15 K}
  valve_cmd: {type: signal_source, kind: step, value: 0, height: 1, t_start: 10 ms}
  valve_PB:  {type: iso6358_throttle, C: 1.0 dm3/(s*bar), b: 0.30}
  valve_AR:  {type: iso6358_throttle, C: 1.0 dm3/(s*bar), b: 0.30}
  meter_out: {type: iso6358_throttle, C: 0.35 dm3/(s*bar), b: 0.45}
  line_A:    {type: volume, V: 1.0e-6 m3, p0: 5 bar, T0: 293.15 K}
  exhaust:   {type: atmosphere}
  leak:      {type: iso6358_throttle, C: 0.002 dm3/(s*bar), b: 0.3}
  leak_out:  {type: atmosphere}
  load:      {type: translational_mass, m: 3.7 kg}
  wall_A:    {type: thermal_mass, C: 30 J/K, T0: 300 K}
  wall_cap:  {type: thermal_mass, C: 30 J/K, T0: 300 K}
  cylinder:
    type: cushioned_cylinder
    bore: 32 mm
    rod: 12 mm
    stroke: 100 mm
    plug_diameter: 16 mm
    cushion_length: 20 mm
    dead_volume_rod_side: 1.0e-6 m3
    dead_volume_cushion: 2.0e-6 m3
    dead_volume_channel: 1.0e-6 m3
    bore_opening_C: 5.0 dm3/(s*bar)
    cushion_C_of_z: [[0, 0], [1.5, 0.12 dm3/(s*bar)], [6, 0.4 dm3/(s*bar)]]
    cushion_b_slope: 0.45
    z_EC: 1.5
    rod_plug_diameter: 18 mm
    rod_cushion_length: 20 mm
    rod_dead_volume_cushion: 2.0e-6 m3
    z_EC_rod: 2
    cushion_taps: yes
    wall_alpha: 200 W/(m2*K)
    friction_model: lugre
    friction_FC: 20 N
    friction_FS: 30 N
    friction_vS: 0.004 m/s
    friction_sigma0: 1e6 N/m
    friction_sigma1: 1000 N*s/m
    friction_viscous: 100 N*s/m
    x0: 99.5 mm
    p0_A: 5 bar
    p0_cap: 101325 Pa
connections:
  - [supply.port, valve_PB.a]
  - [valve_PB.b, cylinder.B]
  - [cylinder.A, meter_out.a]
  - [meter_out.b, line_A.port]
  - [line_A.port_b, valve_AR.a]
  - [valve_AR.b, exhaust.port]
  - [valve_cmd.y, valve_PB.opening, valve_AR.opening]
  - [cylinder.flange, load.flange]
  - [cylinder.EC, leak.a]
  - [leak.b, leak_out.port]
  - [cylinder.heat_A, wall_A.port]
  - [cylinder.heat_cap, wall_cap.port]
)",
       0.25,
       {"cushioned_cylinder"}},
      {"orifices",
       // A nozzle opening by a ramp fills a tank that a check valve relieves
       // (partly open: the smoothstep) and that exchanges gas with a second
       // tank through a one-way flow control (throttled, later free through
       // its check valve).
       R"(
components:
  source: {type: pressure_source, p: 6 bar, T: 300 K}
  open:   {type: signal_source, kind: ramp, value: 0.5, height: 0.5, t_start: 0, duration: 0.1}
  jet:    {type: nozzle, d: 0.5 mm, Cd: 0.9}
  tank:   {type: volume, V: 0.2 L, p0: 2 bar}
  relief: {type: check_valve, C: 0.2 dm3/(s*bar), cracking: 0.5 bar, ramp: 1 bar}
  air:    {type: atmosphere}
  owfc:   {type: one_way_flow_control, C: 0.05 dm3/(s*bar), check_C: 0.5 dm3/(s*bar)}
  tank2:  {type: volume, V: 0.1 L, p0: 4 bar, T0: 320 K}
connections:
  - [source.port, jet.a]
  - [open.y, jet.opening]
  - [jet.b, tank.port, relief.in, owfc.b]
  - [relief.out, air.port]
  - [owfc.a, tank2.port]
)",
       0.05,
       {"nozzle", "check_valve", "one_way_flow_control"}},
      {"directional_valves",
       // A 5/2 valve on a schedule, checked mid-stroke (all four paths partly
       // open), a 3/2 valve driven by a command signal, and a position sensor.
       R"(
components:
  supply: {type: pressure_source, p: 6 bar}
  v52:    {type: directional_valve_52, C: 0.3 dm3/(s*bar), t_switch_time: 20 ms, schedule: [[0.01, 1]]}
  ca:     {type: volume, V: 0.1 L, p0: 1.5 bar}
  cb:     {type: volume, V: 0.1 L, p0: 3 bar}
  air:    {type: atmosphere}
  cmd:    {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.005}
  v32:    {type: directional_valve_32, C: 0.2 dm3/(s*bar), t_switch_time: 10 ms}
  air2:   {type: atmosphere}
  cc:     {type: volume, V: 0.1 L, p0: 2 bar}
  body:   {type: translational_mass, m: 1 kg, s0: 0 m, v0: 0.5 m/s}
  push:   {type: force_source, F: 2 N}
  pos:    {type: position_sensor, tau: 10 ms}
connections:
  - [supply.port, v52.P, v32.P]
  - [v52.A, ca.port]
  - [v52.B, cb.port]
  - [v52.R, air.port]
  - [v32.R, air2.port]
  - [cmd.y, v32.command]
  - [v32.A, cc.port]
  - [body.flange, push.flange, pos.flange]
)",
       0.02,
       {"directional_valve_52", "directional_valve_32", "position_sensor"}},
      {"hoses",
       // A hose with inertia (4 segments) filling a tank that vents through a
       // hose without inertia; dead-end stubs, each fed by its own source,
       // with a temperature and a pressure sensor at their closed ends (all
       // two-port nodes: the framework's stream mixing at a port with nearly
       // zero flow has a curvature on the scale m_flow_small that central
       // differences cannot follow, and the stubs' flows die out).
       R"(
components:
  source: {type: pressure_source, p: 3 bar}
  feed1:  {type: pressure_source, p: 2 bar, T: 320 K}
  feed2:  {type: pressure_source, p: 4 bar, T: 300 K}
  stub:   {type: hose, D: 4 mm, L: 0.5 m, segments: 2}
  ts:     {type: temperature_sensor, tau: 15 ms, T0: 293.15 K}
  stub2:  {type: hose, D: 3 mm, L: 0.3 m, segments: 1}
  ps:     {type: pressure_sensor, tau: 5 ms, p0: 1 bar}
  line:   {type: hose, D: 4 mm, L: 3 m, segments: 4, inertia: true}
  tank:   {type: volume, V: 0.1 L}
  vent:   {type: hose, D: 2 mm, L: 1 m, segments: 2}
  air:    {type: atmosphere}
connections:
  - [source.port, line.a]
  - [feed1.port, stub.a]
  - [feed2.port, stub2.a]
  - [stub.b, ts.port]
  - [stub2.b, ps.port]
  - [line.b, tank.port, vent.a]
  - [vent.b, air.port]
)",
       0.02,
       {"hose", "temperature_sensor", "pressure_sensor"}},
      {"switching",
       // Switches on a moving flange and a filling tank, gates, a timer, a
       // flip-flop and a step chain, checked with the chain mid-cycle (the
       // gates' inputs are variables, so their products have slopes).
       R"yaml(
components:
  supply: {type: pressure_source, p: 4 bar}
  fill:   {type: iso6358_throttle, C: 0.5 dm3/(s*bar)}
  tank:   {type: volume, V: 0.2 L, p0: 1 bar}
  ps:     {type: pressure_switch, p_on: 2 bar}
  body:   {type: translational_mass, m: 1 kg, s0: 0 m, v0: 0.5 m/s}
  home:   {type: limit_switch, position: 0, window: 10 mm}
  far:    {type: limit_switch, position: 20 mm, window: 10 mm}
  go:     {type: signal_source, kind: step, value: 0, height: 1, t_start: 1 ms}
  seq:    {type: sequencer, steps: "A+ (A- B+)", transitions: "X1 P1"}
  both:   {type: and}
  either: {type: or}
  inv:    {type: not}
  delay:  {type: timer, delay: 2 ms}
  mem:    {type: flip_flop}
connections:
  - [supply.port, fill.a]
  - [fill.b, tank.port, ps.port]
  - [body.flange, home.flange, far.flange]
  - [go.y, seq.start, both.in1]
  - [far.y, seq.X1, inv.in]
  - [ps.y, either.in1, delay.in]
  - [seq.A, both.in2]
  - [seq.B, either.in2]
  - [delay.y, seq.P1, mem.S]
  - [inv.y, mem.R, both.in3]
)yaml",
       0.02,
       {"pressure_switch", "limit_switch", "sequencer", "and", "or", "not", "timer", "flip_flop"}},
      {"cylinders",
       // A cylinder cushioned at both ends with LuGre friction and wall heat,
       // extending into its rod-end cushion (second point inside it); a
       // rodless one with closed ports (a gas spring) and eq. 8 friction;
       // single-acting cylinders with a closed (vented through a throttle)
       // and a vented spring chamber.
       R"(
components:
  supply: {type: pressure_source, p: 6 bar}
  valve:  {type: iso6358_throttle, C: 1 dm3/(s*bar), b: 0.3}
  out:    {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.4}
  air:    {type: atmosphere}
  load:   {type: translational_mass, m: 1 kg}
  wall:   {type: thermal_mass, C: 20 J/K, T0: 300 K}
  cyl:    {type: cylinder, bore: 25 mm, rod: 10 mm, stroke: 50 mm, cap_cushion_length: 10 mm, cap_plug_diameter: 12 mm,
           cap_cushion_C: 0.05 dm3/(s*bar), rod_cushion_length: 10 mm, rod_plug_diameter: 14 mm,
           rod_cushion_C: 0.05 dm3/(s*bar), wall_alpha: 100 W/(m2*K), friction_model: lugre, friction_FC: 10 N,
           friction_FS: 15 N, friction_sigma0: 1e5 N/m, x0: 30 mm, p0_cap: 3 bar, p0_rod: 3 bar}
  gasspr: {type: cylinder, bore: 20 mm, rod: 0, stroke: 40 mm, friction: annexC_pAB+, x0: 20 mm, p0_cap: 3 bar}
  mass2:  {type: translational_mass, m: 0.5 kg}
  sac_in: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  sac:    {type: single_acting_cylinder, bore: 16 mm, rod: 6 mm, stroke: 30 mm, spring_preload: 5 N,
           spring_rate: 300 N/m, spring_chamber: closed, x0: 10 mm, p0_cap: 2 bar, friction_model: coulomb_viscous,
           friction_FC: 3 N, friction_viscous: 10 N*s/m}
  sac_out: {type: iso6358_throttle, C: 0.05 dm3/(s*bar), b: 0.3}
  air2:   {type: atmosphere}
  mass3:  {type: translational_mass, m: 0.2 kg}
  sac2_in: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  sac2:   {type: single_acting_cylinder, bore: 16 mm, rod: 6 mm, stroke: 30 mm, spring_rate: 300 N/m, x0: 5 mm}
  mass4:  {type: translational_mass, m: 0.2 kg}
connections:
  - [supply.port, valve.a]
  - [valve.b, cyl.cap]
  - [cyl.rod, out.a]
  - [out.b, air.port]
  - [cyl.flange, load.flange]
  - [cyl.heat_rod, wall.port]
  - [gasspr.flange, mass2.flange]
  - [supply.port, sac_in.a, sac2_in.a]
  - [sac_in.b, sac.cap]
  - [sac.rod, sac_out.a]
  - [sac_out.b, air2.port]
  - [sac.flange, mass3.flange]
  - [sac2_in.b, sac2.cap]
  - [sac2.flange, mass4.flange]
)",
       0.03,
       {"cylinder", "single_acting_cylinder"}},
      {"pressure_valves",
       // A relief valve opening on a tank being filled (partly open at the
       // second point), a regulator feeding a load, and a regulator whose
       // outlet is back-driven into its relief (every node of two ports:
       // see the hoses snippet on nodes with nearly zero flow).
       R"(
components:
  source: {type: pressure_source, p: 8 bar, T: 300 K}
  feed:   {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 0.1 L, p0: 5.9 bar}
  relief: {type: relief_valve, p_set: 5 barg, band: 0.5 bar, C: 1 dm3/(s*bar)}
  air:    {type: atmosphere}
  reg:    {type: pressure_regulator, p_set: 4 barg, C: 1 dm3/(s*bar)}
  line:   {type: volume, V: 0.05 L, p0: 4.5 bar}
  load:   {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.3}
  air2:   {type: atmosphere}
  reg2:   {type: pressure_regulator, p_set: 3 barg, C: 0.5 dm3/(s*bar), relief_C: 0.3 dm3/(s*bar)}
  line2:  {type: volume, V: 0.05 L, p0: 4.2 bar, T0: 310 K}
  push:   {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.3}
  high:   {type: pressure_source, p: 7 bar, T: 320 K}
  air3:   {type: atmosphere}
  air4:   {type: atmosphere}
  src2:   {type: pressure_source, p: 7.5 bar, T: 290 K}
  src3:   {type: pressure_source, p: 6 bar, T: 300 K}
connections:
  - [source.port, feed.a]
  - [src2.port, reg.in]
  - [src3.port, reg2.in]
  - [feed.b, tank.port, relief.in]
  - [relief.out, air.port]
  - [reg.out, line.port]
  - [line.port_b, load.a]
  - [load.b, air2.port]
  - [reg.exhaust, air3.port]
  - [reg2.out, line2.port]
  - [line2.port_b, push.a]
  - [push.b, high.port]
  - [reg2.exhaust, air4.port]
)",
       0.02,
       {"relief_valve", "pressure_regulator"}},
      {"directional_valve_53",
       // 5/3 valves: one on a schedule from solenoid 14 towards 12 (second
       // point mid-ramp just past the centre's overlap: the 12 paths
       // opening), one with an exhausted centre driven by its solenoid
       // signals, one with a pressurised centre at rest.
       R"(
components:
  supply: {type: pressure_source, p: 6 bar}
  v1:     {type: directional_valve_53, C: 0.3 dm3/(s*bar), t_switch_time: 20 ms, initial: 1, centre: exhausted,
           schedule: [[0.005, -1]]}
  a1:     {type: volume, V: 0.1 L, p0: 1.5 bar}
  b1:     {type: volume, V: 0.1 L, p0: 3 bar}
  air1:   {type: atmosphere}
  s2:     {type: pressure_source, p: 5 bar}
  sol14:  {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.004}
  sol12:  {type: signal_source, kind: constant, value: 0}
  v2:     {type: directional_valve_53, C: 0.2 dm3/(s*bar), t_switch_time: 10 ms, centre: exhausted}
  a2:     {type: volume, V: 0.1 L, p0: 2 bar}
  b2:     {type: volume, V: 0.1 L, p0: 4 bar}
  air2:   {type: atmosphere}
  s3:     {type: pressure_source, p: 4 bar}
  v3:     {type: directional_valve_53, C: 0.2 dm3/(s*bar), centre: pressurised}
  a3:     {type: volume, V: 0.1 L, p0: 2 bar}
  b3:     {type: volume, V: 0.1 L, p0: 3 bar}
  air3:   {type: atmosphere}
connections:
  - [supply.port, v1.P]
  - [v1.A, a1.port]
  - [v1.B, b1.port]
  - [v1.R, air1.port]
  - [s2.port, v2.P]
  - [v2.A, a2.port]
  - [v2.B, b2.port]
  - [v2.R, air2.port]
  - [sol14.y, v2.command_14]
  - [sol12.y, v2.command_12]
  - [s3.port, v3.P]
  - [v3.A, a3.port]
  - [v3.B, b3.port]
  - [v3.R, air3.port]
)",
       0.03,
       {"directional_valve_53"}},
      {"logic_valves",
       // A shuttle and a two-pressure valve, each with inlets crossing over
       // (a ramped inlet pressure passes the other's inside the run), and a
       // quick exhaust valve venting a tank through R while its line fills.
       R"(
components:
  ramp:   {type: signal_source, kind: ramp, value: 2e5, height: 4e5, t_start: 0, duration: 0.04}
  s1:     {type: pressure_source, p: 2 bar}
  s2:     {type: pressure_source, p: 3 bar, T: 310 K}
  or:     {type: shuttle_valve, C: 0.2 dm3/(s*bar)}
  t1:     {type: volume, V: 0.1 L, p0: 2.5 bar}
  s3:     {type: pressure_source, p: 2 bar}
  s4:     {type: pressure_source, p: 3 bar, T: 310 K}
  and:    {type: two_pressure_valve, C: 0.2 dm3/(s*bar), ramp: 0.5 bar}
  t2:     {type: volume, V: 0.1 L, p0: 2.5 bar}
  line:   {type: volume, V: 0.02 L, p0: 1.5 bar}
  feed:   {type: iso6358_throttle, C: 0.05 dm3/(s*bar), b: 0.3}
  s5:     {type: pressure_source, p: 6 bar}
  qev:    {type: quick_exhaust_valve, C_PA: 0.5 dm3/(s*bar), C_AR: 1 dm3/(s*bar)}
  t3:     {type: volume, V: 0.1 L, p0: 5 bar}
  air:    {type: atmosphere}
connections:
  - [ramp.y, s1.p_in, s3.p_in]
  - [s1.port, or.in_1]
  - [s2.port, or.in_2]
  - [or.out, t1.port]
  - [s3.port, and.in_1]
  - [s4.port, and.in_2]
  - [and.out, t2.port]
  - [s5.port, feed.a]
  - [feed.b, line.port]
  - [line.port_b, qev.P]
  - [qev.A, t3.port]
  - [qev.R, air.port]
)",
       0.02,
       {"shuttle_valve", "two_pressure_valve", "quick_exhaust_valve"}},
  };
  return list;
}

TEST(Jacobian, RegistryIsCovered) {
  std::set<std::string> covered;
  for (const auto& s : snippets()) covered.insert(s.types.begin(), s.types.end());
  for (const auto& type : builtin_registry().types())
    EXPECT_TRUE(covered.count(type)) << "component type '" << type
                                     << "' has no Jacobian test circuit; add a snippet to tests/jacobian_test.cpp";
}

class JacobianOf : public ::testing::TestWithParam<Snippet> {};

// The comparison itself is the component authors' test kit
// (framework/testkit), so that out-of-tree components get the same check.
TEST_P(JacobianOf, MatchesFiniteDifferencesAndPattern) {
  const Snippet& snippet = GetParam();
  const Netlist netlist = parse_netlist(snippet.netlist, snippet.name + ".yaml");
  Circuit circuit = elaborate(netlist, builtin_registry());
  for (const auto& type : snippet.types) {
    bool present = false;
    for (const auto& c : circuit.components) present |= c->info().type == type;
    EXPECT_TRUE(present) << "snippet " << snippet.name << " claims to cover '" << type << "' but has none";
  }
  AssemblyOptions all_unknowns;  // each component's rows as written, no alias elimination
  all_unknowns.eliminate_aliases = false;
  System sys(std::move(circuit), all_unknowns);
  for (const auto& check : testkit::check_jacobian(sys, solver_options(netlist.simulation), snippet.t_short))
    EXPECT_TRUE(check.passed(1e-5)) << check.report();
}

// The solver keeps dF/dy and dF/dy' of its last Newton matrix and answers a
// request after a change of cj with dF/dy + cj dF/dy' (ida_solver.cpp,
// NewtonMatrixParts). That is exact only if the matrix of the assembled
// system - aliases substituted, algebraic unknowns solved inside the
// residual - is linear in cj: the explicit unknowns must have no y'. Checked
// on the rig netlists, at their start and at points with their y' set to
// rates of the size of a stroke (so that any cj term would show), for cj
// from 1/(10 s) to 1/(10 ns).
TEST(Jacobian, AssembledNewtonMatrixIsLinearInCj) {
  for (const char* name : {"cushion_rig", "cushion_rig_full", "movement_time_rig", "bracha_cylinder"}) {
    const Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/" + name + ".yaml");
    const System sys(elaborate(nl, builtin_registry()));
    const Evaluator eval(sys);
    std::vector<double> y, yp;
    sys.start_values(y, yp);
    for (int point = 0; point < 2; ++point) {
      if (point == 1)
        for (std::size_t i = 0; i < yp.size(); ++i) yp[i] = 10.0 * (std::abs(y[i]) + 1e-6) * (i % 2 ? 1.0 : -1.0);
      const std::size_t nz = static_cast<std::size_t>(sys.nnz());
      std::vector<double> j0(nz), j1(nz), jc(nz);
      eval.jacobian(0.0, y.data(), yp.data(), 0.0, j0.data());
      eval.jacobian(0.0, y.data(), yp.data(), 1.0, j1.data());
      for (const double cj : {0.1, 1e3, 1e8}) {
        eval.jacobian(0.0, y.data(), yp.data(), cj, jc.data());
        for (std::size_t k = 0; k < nz; ++k) {
          const double recombined = j0[k] + cj * (j1[k] - j0[k]);
          const double scale = std::abs(j0[k]) + cj * std::abs(j1[k] - j0[k]);
          // Rounding: the Schur complement forms cj products in another
          // order (measured 3e-12 relative at cj = 1e8); a y' of an explicit
          // unknown would be an error of order one.
          EXPECT_LE(std::abs(jc[k] - recombined), 1e-10 * scale + 1e-300)
              << name << ", point " << point << ", cj " << cj << ", entry " << k << ": J(cj) = " << jc[k]
              << ", J(0) + cj (J(1) - J(0)) = " << recombined;
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Builtin, JacobianOf, ::testing::ValuesIn(snippets()),
                         [](const ::testing::TestParamInfo<Snippet>& info) { return info.param.name; });

}  // namespace
}  // namespace pneumo
