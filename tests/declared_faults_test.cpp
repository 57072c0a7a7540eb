// Fault modes declared through the component interface (issue #37): what
// each component type lists, and that each fault acts on the component's
// own equations as its physics says - a leak across the piston seal
// equalises the chambers, conserving their energy; a late valve switches
// late; a sagging supply falls by R times its flow; a sensor reads
// gain x + offset. And the catalogue side: the declared faults as
// candidates COMPONENT.FAULT, measurement offset and gain, bounds checked.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "components/builtin.hpp"
#include "framework/diagnose/catalogue.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "framework/diagnose/ranking.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

std::set<std::string> fault_names(const std::string& type) {
  const auto* entry = builtin_registry().find(type);
  EXPECT_NE(entry, nullptr) << type;
  std::set<std::string> out;
  if (entry)
    for (const auto& f : entry->info->faults) out.insert(f.name);
  return out;
}

TEST(DeclaredFaults, EachComponentTypeListsWhatCanFailInIt) {
  const std::map<std::string, std::vector<std::string>> want = {
      {"cylinder",
       {"piston_seal_leak", "rod_seal_leak", "friction_running", "friction_breakaway", "wall_heat",
        "dead_volume_cap_off", "dead_volume_rod_off", "friction_chamber_pressure"}},
      {"cushioned_cylinder",
       {"piston_seal_leak", "rod_seal_leak", "friction_running", "friction_breakaway", "wall_heat",
        "cushion_needle_misadjusted", "cushion_check_off", "cushion_seal_leak", "cushion_seal_friction",
        "cushion_screw_leak", "friction_chamber_pressure"}},
      {"single_acting_cylinder", {"piston_seal_leak", "friction_breakaway", "spring_weak"}},
      {"directional_valve_32", {"delay_actuate", "delay_release", "slow_switching", "internal_leak", "supply_restricted"}},
      {"directional_valve_52", {"delay_actuate", "delay_release", "slow_switching", "internal_leak", "supply_restricted"}},
      {"directional_valve_53", {"delay_actuate", "delay_release", "slow_switching", "internal_leak", "supply_restricted"}},
      {"iso6358_throttle", {"misadjusted", "opening_late"}},
      {"one_way_flow_control", {"misadjusted", "check_leak"}},
      {"nozzle", {"clogged"}},
      {"check_valve", {"leak"}},
      {"pressure_source", {"supply_sag"}},
      {"pressure_regulator", {"supply_sag", "misadjusted"}},
      {"volume", {"volume_off", "line_restriction"}},
      {"hose", {"resistance"}},
      {"translational_mass", {"mass_off"}},
      {"pressure_sensor", {"offset", "gain", "lag"}},
      {"position_sensor", {"offset", "gain", "lag"}},
      {"temperature_sensor", {"offset", "gain", "lag"}},
      {"relief_valve", {"misadjusted", "seat_leak"}},
      {"pressure_switch", {"misadjusted"}},
      {"limit_switch", {"misplaced"}},
      {"timer", {"misadjusted"}},
      {"shuttle_valve", {"restricted", "seat_leak"}},
      {"two_pressure_valve", {"restricted", "seat_leak"}},
      {"quick_exhaust_valve", {"exhaust_misadjusted", "disc_leak"}},
      {"spring_damper", {"spring_off"}},
      {"friction_element", {"friction_running"}},
  };
  for (const auto& [type, faults] : want) {
    const auto have = fault_names(type);
    for (const auto& f : faults) EXPECT_TRUE(have.count(f)) << type << " does not declare " << f;
  }
}

// Every declared fault parameter names a scalar parameter of its component;
// a fault-only parameter defaults to the fault's null (the sound model is
// the one without the fault), and the plausible range holds the null.
TEST(DeclaredFaults, EveryFaultParameterActsOnAParameterWhoseDefaultIsItsNull) {
  int n = 0;
  for (const auto& type : builtin_registry().types()) {
    const auto& info = *builtin_registry().find(type)->info;
    for (const auto& f : info.faults)
      for (const auto& fp : f.parameters) {
        ++n;
        const ParameterSpec* spec = info.parameter(fp.parameter);
        ASSERT_NE(spec, nullptr) << type << "." << f.name << " acts on unknown " << fp.parameter;
        EXPECT_EQ(spec->kind, ParameterKind::scalar) << type << "." << f.name;
        EXPECT_LE(fp.lower, fp.null_value) << type << "." << f.name;
        EXPECT_GE(fp.upper, fp.null_value) << type << "." << f.name;
        EXPECT_FALSE(f.description.empty()) << type << "." << f.name;
        if (fp.factor) {
          EXPECT_EQ(fp.null_value, 1.0) << type << "." << f.name;
        } else if (fp.parameter.rfind("fault_", 0) == 0) {
          ASSERT_TRUE(spec->default_value) << type << "." << fp.parameter;
          EXPECT_EQ(*spec->default_value, fp.null_value) << type << "." << fp.parameter;
        }
      }
  }
  EXPECT_GT(n, 40);
}

// A closed cylinder held at mid-stroke: cap side 6 bar, rod side 1 bar
// (absolute). Through a piston-seal leak the chambers reach one pressure;
// no work and no heat cross the walls, so their summed internal energy
// p V / (kappa - 1) is kept: p_end = (p_cap V_cap + p_rod V_rod) / (V_cap + V_rod).
TEST(DeclaredFaults, PistonSealLeakEqualisesTheChambersKeepingTheirEnergy) {
  auto model = [](const std::string& leak) {
    return "components:\n"
           "  cyl: {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, dead_volume_cap: 5 cm3,\n"
           "        dead_volume_rod: 5 cm3, x0: 50 mm, p0_cap: 6 bar, p0_rod: 1 bar" + leak + "}\n"
           "  hold: {type: fixed_position, s0: 50 mm}\n"
           "connections:\n  - [cyl.flange, hold.flange]\n"
           "outputs: {p_cap: cyl.p_cap, p_rod: cyl.p_rod}\n"
           "simulation: {t_end: 3 s, output_interval: 10 ms}\n";
  };
  const double A = M_PI / 4 * 0.032 * 0.032, Ar = M_PI / 4 * 0.012 * 0.012;
  const double V_cap = 5e-6 + A * 0.05, V_rod = 5e-6 + (A - Ar) * 0.05;
  const double p_end = (6e5 * V_cap + 1e5 * V_rod) / (V_cap + V_rod);
  const RunResult sound = run_text(model(""), "sound.yaml");
  EXPECT_NEAR(column(sound.table, "p_cap").back(), 6e5, 1.0);
  EXPECT_NEAR(column(sound.table, "p_rod").back(), 1e5, 1.0);
  const RunResult leaky = run_text(model(", fault_piston_leak_C: 0.1 dm3/(s*bar)"), "leaky.yaml");
  EXPECT_LT(rel_err(column(leaky.table, "p_cap").back(), p_end), 2e-3);
  EXPECT_LT(rel_err(column(leaky.table, "p_rod").back(), p_end), 2e-3);
}

// The cushioned cylinder (seed 000's rig) held at mid-stroke, closed: rod
// side 1 bar, cap side (channel and cushion volume, joined through the open
// bore) 6 bar. Through a piston-seal leak all three reach one pressure;
// nothing crosses the walls, so the gas's mass and internal energy are
// kept. A rod-seal leak vents the rod side alone.
TEST(DeclaredFaults, CushionedCylinderLeaksAcrossItsPistonAndPastItsRod) {
  auto run = [](const std::string& fault, const std::string& p0_A = "1 bar") {
    return run_text(
        "components:\n"
        "  cyl: {type: cushioned_cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, plug_diameter: 16 mm,\n"
        "        cushion_length: 20 mm, dead_volume_rod_side: 3 cm3, dead_volume_cushion: 2 cm3,\n"
        "        dead_volume_channel: 1 cm3, bore_opening_C: 5 dm3/(s*bar), z_EC: 1.5 rev,\n"
        "        cushion_C_of_z: [[0, 0], [6, 0.4 dm3/(s*bar)]],\n"
        "        friction: annexB_5.14, x0: 50 mm, p0_cap: 6 bar, p0_A: " + p0_A + fault + "}\n"
        "  hold: {type: fixed_position, s0: 50 mm}\n"
        "connections:\n  - [cyl.flange, hold.flange]\n"
        "outputs: {p_A: cyl.p_A, p_EC: cyl.p_EC, p_ch: cyl.p_ch, U: cyl.U_gas, m_A: cyl.m_A, m_EC: cyl.m_EC,\n"
        "          m_ch: cyl.m_ch}\n"
        "simulation: {t_end: 3 s, output_interval: 10 ms}\n",
        "cushioned.yaml");
  };
  const RunResult sound = run("");
  EXPECT_NEAR(column(sound.table, "p_A").back(), 1e5, 1.0);
  EXPECT_NEAR(column(sound.table, "p_ch").back(), 6e5, 1.0);
  const RunResult leaky = run(", fault_piston_leak_C: 0.1 dm3/(s*bar)");
  const double p_A = column(leaky.table, "p_A").back();
  EXPECT_GT(p_A, 2e5);
  EXPECT_LT(rel_err(column(leaky.table, "p_ch").back(), p_A), 2e-3);
  EXPECT_LT(rel_err(column(leaky.table, "p_EC").back(), p_A), 2e-3);
  auto mass = [&](std::size_t i) {
    return column(leaky.table, "m_A")[i] + column(leaky.table, "m_EC")[i] + column(leaky.table, "m_ch")[i];
  };
  const std::size_t last = leaky.table.rows.size() - 1;
  EXPECT_LT(rel_err(mass(last), mass(0)), 1e-6);
  EXPECT_LT(rel_err(column(leaky.table, "U").back(), column(leaky.table, "U").front()), 1e-5);
  const RunResult rod = run(", fault_rod_leak_C: 0.1 dm3/(s*bar)", "6 bar");
  EXPECT_LT(std::abs(column(rod.table, "p_A").back() - 101325.0), 500.0);
  EXPECT_NEAR(column(rod.table, "p_ch").back(), 6e5, 1.0);
}

// The rig's cushioned cylinder with the plug engaged (x = 95 mm of a 100 mm
// stroke, cushioning over the last 20 mm), cushion volume and channel at
// `p0`, port B vented through a throttle; `extra` adds parameters.
std::string cushion_held(const std::string& extra, const std::string& outputs, const std::string& p0 = "6 bar") {
  return "components:\n"
         "  cyl: {type: cushioned_cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, plug_diameter: 16 mm,\n"
         "        cushion_length: 20 mm, dead_volume_rod_side: 3 cm3, dead_volume_cushion: 2 cm3,\n"
         "        dead_volume_channel: 1 cm3, bore_opening_C: 5 dm3/(s*bar), cushion_b0: 0.3,\n"
         "        cushion_C_of_z: [[0, 0], [6, 0.6 dm3/(s*bar)]], friction: annexB_5.14, x0: 95 mm,\n"
         "        p0_cap: " + p0 + ", p0_A: 1 bar" + extra + "}\n"
         "  hold: {type: fixed_position, s0: 95 mm}\n"
         "  vent: {type: iso6358_throttle, C: 1 dm3/(s*bar), b: 0.3}\n"
         "  air: {type: atmosphere}\n"
         "connections:\n  - [cyl.flange, hold.flange]\n  - [cyl.B, vent.a]\n  - [vent.b, air.port]\n"
         "outputs: {" + outputs + "}\n"
         "simulation: {t_end: 1 s, output_interval: 10 ms}\n";
}

// A leak past the cushion seal is a conductance between the cushion volume
// and the channel beside the needle: with the needle shut, a leak of C
// (b 0.3) empties the cushion volume exactly as a needle of C at b 0.3
// does; without either, the cushion volume holds its pressure.
TEST(DeclaredFaults, CushionSealLeakIsAConductanceBesideTheNeedle) {
  const std::string out = "p_EC: cyl.p_EC, p_ch: cyl.p_ch";
  const RunResult shut = run_text(cushion_held(", z_EC: 0", out), "shut.yaml");
  EXPECT_NEAR(column(shut.table, "p_EC").back(), 6e5, 1.0);
  const RunResult needle = run_text(cushion_held(", z_EC: 1", out), "needle.yaml");
  const RunResult leak =
      run_text(cushion_held(", z_EC: 0, fault_cushion_seal_leak_C: 0.1 dm3/(s*bar)", out), "leak.yaml");
  const auto a = column(needle.table, "p_EC"), b = column(leak.table, "p_EC");
  ASSERT_EQ(a.size(), b.size());
  EXPECT_LT(b.back(), 2e5);
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LT(rel_err(b[i], a[i]), 1e-6) << i;
}

// A leak past the cushioning screw empties the cushion volume to the
// atmosphere: with the needle shut, a screw leak of C (b 0.3) empties it as
// a throttle of C at b 0.3 from a tap on the cushion volume to the
// atmosphere does, and leaves the channel as it is without the leak (to the
// solver's tolerance: the runs take their own steps).
TEST(DeclaredFaults, CushionScrewLeakVentsTheCushionVolumeToTheAtmosphere) {
  const std::string out = "p_EC: cyl.p_EC, T_EC: cyl.T_EC, p_ch: cyl.p_ch";
  const RunResult leak =
      run_text(cushion_held(", z_EC: 0, fault_cushion_screw_leak_C: 0.05 dm3/(s*bar)", out), "screw.yaml");
  std::string tapped = cushion_held(", z_EC: 0, cushion_taps: yes", out);
  tapped.replace(tapped.find("connections:"), 12,
                 "  screw: {type: iso6358_throttle, C: 0.05 dm3/(s*bar), b: 0.3}\n"
                 "  air_screw: {type: atmosphere}\n"
                 "connections:\n  - [cyl.EC, screw.a]\n  - [screw.b, air_screw.port]");
  const RunResult twin = run_text(tapped, "twin.yaml");
  const RunResult shut = run_text(cushion_held(", z_EC: 0", out), "shut.yaml");
  for (const char* col : {"p_EC", "T_EC", "p_ch"}) {
    const auto a = column(twin.table, col), b = column(leak.table, col);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LT(rel_err(b[i], a[i]), 1e-6) << col << " " << i;
  }
  EXPECT_LT(column(leak.table, "p_EC").back(), 1.5e5);
  const auto p_ch = column(leak.table, "p_ch"), p_ch0 = column(shut.table, "p_ch");
  for (std::size_t i = 0; i < p_ch.size(); ++i) EXPECT_LT(rel_err(p_ch[i], p_ch0[i]), 1e-6) << i;
}

// The cushion seal's drag acts on the plug only: a piston driven at 50 mm/s
// from mid-stroke into the cushioning zone meets the same friction as the
// sound cylinder's in the main stroke and F more (against the motion) once
// the plug is in; the gas is the same in both (the motion is imposed).
TEST(DeclaredFaults, CushionSealFrictionActsOnlyWhileThePlugIsIn) {
  auto run = [](const std::string& fault) {
    return run_text(
        "components:\n"
        "  cyl: {type: cushioned_cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, plug_diameter: 16 mm,\n"
        "        cushion_length: 20 mm, dead_volume_rod_side: 3 cm3, dead_volume_cushion: 2 cm3,\n"
        "        dead_volume_channel: 1 cm3, bore_opening_C: 5 dm3/(s*bar), z_EC: 1.5 rev,\n"
        "        cushion_C_of_z: [[0, 0], [6, 0.4 dm3/(s*bar)]], friction: annexB_5.14, x0: 50 mm" +
            fault + "}\n"
            "  drive: {type: velocity_source, v: 0.05, s0: 50 mm}\n"
            "  vent_A: {type: iso6358_throttle, C: 1 dm3/(s*bar), b: 0.3}\n"
            "  vent_B: {type: iso6358_throttle, C: 1 dm3/(s*bar), b: 0.3}\n"
            "  air: {type: atmosphere}\n"
            "connections:\n  - [cyl.flange, drive.flange]\n  - [cyl.A, vent_A.a]\n  - [cyl.B, vent_B.a]\n"
            "  - [vent_A.b, vent_B.b, air.port]\n"
            "outputs: {x: cyl.x, F: cyl.F_friction}\n"
            "simulation: {t_end: 0.9 s, output_interval: 10 ms}\n",
        "drag.yaml");
  };
  const RunResult sound = run(""), tight = run(", fault_cushion_seal_F: 15 N");
  const auto x = column(sound.table, "x"), F0 = column(sound.table, "F"), F1 = column(tight.table, "F");
  int main_stroke = 0, cushioning = 0;
  for (std::size_t i = 1; i < x.size(); ++i) {
    if (x[i] < 0.0795) {
      ++main_stroke;
      EXPECT_NEAR(F1[i] - F0[i], 0.0, 1e-9) << "x = " << x[i];
    } else if (x[i] > 0.0805) {
      ++cushioning;
      EXPECT_NEAR(F1[i] - F0[i], -15.0, 1e-6) << "x = " << x[i];
    }
  }
  EXPECT_GT(main_stroke, 50);
  EXPECT_GT(cushioning, 20);
}

// Wall heat of the cylinder's gas goes to the gas at the piston - with the
// plug in, the cushion volume, whose wall the heat port is - and not to the
// adiabatic channel, over that gas's wetted area: both end faces and the
// bore's wall over the length the gas would fill (5 mm of travel left to
// the cap, its 1 + 2 cm3 of dead volume spread over the bore). The cushion
// volume closed (needle and check valve shut) at 350 K cools at constant
// volume as T_amb + (T0 - T_amb) exp(-alpha A t / (m c_v)).
TEST(DeclaredFaults, WallHeatCoolsTheCushionVolumeNotTheChannel) {
  const std::string fault = ", z_EC: 0, check_C: 0, T0: 350 K, fault_wall_alpha: 8 W/(m2*K)";
  const RunResult r = run_text(cushion_held(fault, "T_EC: cyl.T_EC, m_EC: cyl.m_EC, T_ch: cyl.T_ch"), "wall.yaml");
  const double T0 = 350, T_amb = 293.15, cv = 287.05 / 0.4;  // the default gas
  const double bore = 0.032, A = M_PI * bore * bore / 4, kA = 8 * (2 * A + M_PI * bore * (0.005 + 3e-6 / A));
  const double m = column(r.table, "m_EC").front();
  EXPECT_LT(rel_err(column(r.table, "m_EC").back(), m), 1e-9);
  const auto t = column(r.table, "t"), T = column(r.table, "T_EC");
  for (std::size_t i = 10; i < t.size(); i += 30)
    EXPECT_LT(std::abs(T[i] - (T_amb + (T0 - T_amb) * std::exp(-kA * t[i] / (m * cv)))), 0.01) << t[i];
  EXPECT_LT(T.back(), T0 - 5);
  const RunResult adiabatic = run_text(cushion_held(", z_EC: 0, check_C: 0, T0: 350 K", "T_ch: cyl.T_ch"), "a.yaml");
  const auto T_ch = column(r.table, "T_ch"), T_ch0 = column(adiabatic.table, "T_ch");
  ASSERT_EQ(T_ch.size(), T_ch0.size());
  for (std::size_t i = 0; i < T_ch.size(); ++i) EXPECT_LT(rel_err(T_ch[i], T_ch0[i]), 1e-6) << i;
}

// A path whose opening is commanded opens late through four lags of d/4:
// a choked throttle's flow after a command step at t0 is its full flow
// times 1 - e^-s (1 + s + s^2/2 + s^3/6), s = 4 (t - t0) / d.
TEST(DeclaredFaults, ALateOpeningFollowsItsCommandThroughFourLags) {
  const RunResult r = run_text(
      "components:\n"
      "  supply: {type: pressure_source, p: 6 bar}\n"
      "  cmd: {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.1 s}\n"
      "  path: {type: iso6358_throttle, C: 0.5 dm3/(s*bar), b: 0.3, fault_opening_delay: 20 ms}\n"
      "  air: {type: atmosphere}\n"
      "connections:\n  - [supply.port, path.a]\n  - [path.b, air.port]\n  - [cmd.y, path.opening]\n"
      "outputs: {m: path.m_flow}\n"
      "simulation: {t_end: 0.3 s, output_interval: 1 ms}\n",
      "late.yaml");
  const auto t = column(r.table, "t"), m = column(r.table, "m");
  const double full = m.back(), d = 0.02;
  EXPECT_GT(full, 0.0);
  int checked = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double s = std::max(0.0, 4 * (t[i] - 0.1) / d);
    const double expected = full * (1 - std::exp(-s) * (1 + s + s * s / 2 + s * s * s / 6));
    EXPECT_NEAR(m[i], expected, 2e-4 * full) << "t = " << t[i];
    checked += s > 0 && s < 12;
  }
  EXPECT_GT(checked, 50);
}

// A fault of a part the instance lacks is no candidate: rod-end cushioning
// on a cushioned cylinder without it, cushioning on a plain cylinder's
// ends, a late opening on a throttle whose opening no signal drives, a
// valve delay with neither a schedule nor a command signal to delay.
TEST(DeclaredFaults, AFaultOfAnAbsentPartIsNoCandidate) {
  const Netlist nl = parse_netlist(
      "components:\n"
      "  rig: {type: cushioned_cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, plug_diameter: 16 mm,\n"
      "        cushion_length: 20 mm, dead_volume_rod_side: 3 cm3, dead_volume_cushion: 2 cm3,\n"
      "        dead_volume_channel: 1 cm3, bore_opening_C: 5 dm3/(s*bar), z_EC: 1.5 rev,\n"
      "        cushion_C_of_z: [[0, 0], [6, 0.4 dm3/(s*bar)]], friction: annexB_5.14}\n"
      "  cyl: {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, rod_cushion_length: 15 mm,\n"
      "        rod_plug_diameter: 20 mm, rod_cushion_C: 0.1 dm3/(s*bar)}\n"
      "  cmd: {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.1 s}\n"
      "  driven: {type: iso6358_throttle, C: 0.5 dm3/(s*bar)}\n"
      "  fixed: {type: iso6358_throttle, C: 0.5 dm3/(s*bar)}\n"
      "  valve: {type: directional_valve_32, C: 0.3 dm3/(s*bar)}\n"
      "  idle: {type: directional_valve_32, C: 0.3 dm3/(s*bar)}\n"
      "  supply: {type: pressure_source, p: 6 bar}\n"
      "  tank: {type: volume, V: 0.5 L}\n"
      "  tank2: {type: volume, V: 0.5 L}\n"
      "  air: {type: atmosphere}\n"
      "  load_rig: {type: translational_mass, m: 1 kg}\n"
      "  load_cyl: {type: translational_mass, m: 1 kg}\n"
      "connections:\n  - [cmd.y, driven.opening, valve.command]\n  - [supply.port, driven.a, fixed.a, valve.P, idle.P]\n"
      "  - [driven.b, fixed.b, valve.R, idle.R, air.port]\n  - [valve.A, tank.port]\n  - [idle.A, tank2.port]\n  - [rig.flange, load_rig.flange]\n"
      "  - [cyl.flange, load_cyl.flange]\n",
      "parts.yaml");
  const auto cat = diagnose::declared_faults(nl, builtin_registry(), {}, {});
  auto available = [&](const std::string& name) {
    const auto* e = cat.find(name);
    EXPECT_NE(e, nullptr) << name;
    return e && e->unavailable.empty();
  };
  for (const char* yes : {"rig.cushion_seal_leak", "rig.cushion_seal_friction", "rig.cushion_screw_leak",
                          "cyl.rod_cushion_seal_leak", "cyl.rod_cushion_screw_leak",
                          "cyl.rod_cushion_seal_friction", "driven.opening_late", "valve.slow_switching",
                          "valve.delay_actuate", "valve.delay_release"})
    EXPECT_TRUE(available(yes)) << yes;
  for (const char* no : {"rig.rod_cushion_seal_leak", "rig.rod_cushion_seal_friction", "rig.rod_cushion_screw_leak",
                         "cyl.cap_cushion_seal_leak", "cyl.cap_cushion_screw_leak", "tank.line_restriction",
                         "cyl.cap_cushion_seal_friction", "fixed.opening_late", "idle.delay_actuate",
                         "idle.delay_release"})
    EXPECT_FALSE(available(no)) << no;
}

// The rod-seal leak vents the rod side to the atmosphere (and only it).
TEST(DeclaredFaults, RodSealLeakVentsTheRodSideOnly) {
  const RunResult r = run_text(
      "components:\n"
      "  cyl: {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm, x0: 50 mm, p0_cap: 6 bar, p0_rod: 6 bar,\n"
      "        fault_rod_leak_C: 0.1 dm3/(s*bar)}\n"
      "  hold: {type: fixed_position, s0: 50 mm}\n"
      "connections:\n  - [cyl.flange, hold.flange]\n"
      "outputs: {p_cap: cyl.p_cap, p_rod: cyl.p_rod}\n"
      "simulation: {t_end: 3 s, output_interval: 10 ms}\n",
      "rod_leak.yaml");
  EXPECT_NEAR(column(r.table, "p_cap").back(), 6e5, 1.0);
  EXPECT_LT(std::abs(column(r.table, "p_rod").back() - 101325.0), 500.0);
}

// A valve's late switching moves its scheduled commands by the delay of
// their direction: actuated 20 ms late, released 100 ms late.
TEST(DeclaredFaults, ValveDelaysMoveEachCommandByItsDirectionsDelay) {
  const RunResult r = run_text(
      "components:\n"
      "  supply: {type: pressure_source, p: 6 bar}\n"
      "  valve: {type: directional_valve_32, C: 0.3 dm3/(s*bar), schedule: [[0.05, 1], [0.6, 0]],\n"
      "          fault_delay_actuate: 20 ms, fault_delay_release: 100 ms}\n"
      "  tank: {type: volume, V: 0.5 L}\n"
      "  air: {type: atmosphere}\n"
      "connections:\n  - [supply.port, valve.P]\n  - [valve.A, tank.port]\n  - [valve.R, air.port]\n"
      "outputs: {p: tank.p}\n"
      "simulation: {t_end: 1 s, output_interval: 5 ms}\n",
      "late_valve.yaml");
  std::map<std::string, double> first;
  for (const auto& e : r.solver.events)
    if (e.component == "valve" && !first.count(e.tag)) first[e.tag] = e.t;
  ASSERT_TRUE(first.count("command_on") && first.count("command_off"));
  EXPECT_NEAR(first["command_on"], 0.07, 1e-9);
  EXPECT_NEAR(first["command_off"], 0.70, 1e-9);
}

// The same valve commanded by a signal (a step at 0.05 s, as a sequencer
// or a switch would give it): 20 ms late, its spool and the tank's
// pressure are the sound run's 20 ms later, the command acting at 0.07 s.
// A command pulse shorter than the delay is lost: the spool never moves.
TEST(DeclaredFaults, ASignalDrivenValvesDelayShiftsItsResponseAndLosesAShorterPulse) {
  auto circuit = [](const std::string& command, const std::string& delay) {
    return "components:\n"
           "  supply: {type: pressure_source, p: 6 bar}\n"
           "  go: " + command + "\n"
           "  valve: {type: directional_valve_32, C: 0.3 dm3/(s*bar), fault_delay_actuate: " + delay + "}\n"
           "  tank: {type: volume, V: 0.5 L}\n"
           "  air: {type: atmosphere}\n"
           "connections:\n  - [supply.port, valve.P]\n  - [valve.A, tank.port]\n  - [valve.R, air.port]\n"
           "  - [go.y, valve.command]\n"
           "outputs: {p: tank.p, x: valve.x}\n"
           "simulation: {t_end: 0.3 s, output_interval: 1 ms}\n";
  };
  const std::string step = "{type: signal_source, kind: step, value: 0, height: 1, t_start: 0.05 s}";
  const RunResult sound = run_text(circuit(step, "0 s"), "sound.yaml");
  const RunResult late = run_text(circuit(step, "20 ms"), "late.yaml");
  ASSERT_TRUE(sound.solver.ok && late.solver.ok);
  double acted = NAN;
  for (const auto& e : late.solver.events)
    if (e.component == "valve" && e.tag == "command_on") acted = e.t;
  EXPECT_NEAR(acted, 0.07, 1e-9);
  const auto p0 = column(sound.table, "p"), p1 = column(late.table, "p");
  const auto x0 = column(sound.table, "x"), x1 = column(late.table, "x");
  ASSERT_EQ(p0.size(), p1.size());
  EXPECT_EQ(x1[69], 0.0);   // t = 69 ms: not moved yet
  EXPECT_GT(p0.back(), 1.5e5);  // the tank fills
  for (std::size_t k = 20; k < p0.size(); ++k) {
    EXPECT_NEAR(p1[k], p0[k - 20], 1e-4 * p0[k - 20]) << k;
    EXPECT_NEAR(x1[k], x0[k - 20], 1e-4) << k;
  }

  const std::string pulse =
      "{type: signal_source, kind: table, table: [[0, 0], [0.05, 0], [0.0501, 1], [0.06, 1], [0.0601, 0], [1, 0]]}";
  const RunResult lost = run_text(circuit(pulse, "20 ms"), "pulse.yaml");
  ASSERT_TRUE(lost.solver.ok) << lost.solver.message;
  for (const double x : column(lost.table, "x")) EXPECT_LT(std::abs(x), 1e-9);
  const auto x_sound_pulse = column(run_text(circuit(pulse, "0 s"), "p.yaml").table, "x");
  EXPECT_GT(*std::max_element(x_sound_pulse.begin(), x_sound_pulse.end()), 0.5);
}

// A command that rises continuously (a ramp from 0.05 s over 0.1 s, through
// two NOT gates, whose outputs are solved inside the residual) is taken at
// its half level, t = 0.1 s, and acts the delay later: at 0.12 s.
TEST(DeclaredFaults, ASignalDrivenValveTakesARisingCommandAtItsHalfLevel) {
  const RunResult r = run_text(
      "components:\n"
      "  supply: {type: pressure_source, p: 6 bar}\n"
      "  go: {type: signal_source, kind: ramp, value: 0, height: 1, t_start: 0.05 s, duration: 0.1 s}\n"
      "  inv1: {type: not}\n"
      "  inv2: {type: not}\n"
      "  valve: {type: directional_valve_32, C: 0.3 dm3/(s*bar), fault_delay_actuate: 20 ms}\n"
      "  tank: {type: volume, V: 0.5 L}\n"
      "  air: {type: atmosphere}\n"
      "connections:\n  - [supply.port, valve.P]\n  - [valve.A, tank.port]\n  - [valve.R, air.port]\n"
      "  - [go.y, inv1.in]\n  - [inv1.y, inv2.in]\n  - [inv2.y, valve.command]\n"
      "outputs: {p: tank.p, x: valve.x}\n"
      "simulation: {t_end: 0.3 s, output_interval: 1 ms}\n",
      "ramp.yaml");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  double due = NAN, acted = NAN;
  for (const auto& e : r.solver.events)
    if (e.component == "valve" && e.message.find("due") != std::string::npos) due = e.t;
    else if (e.component == "valve" && e.tag == "command_on") acted = e.t;
  EXPECT_NEAR(due, 0.10, 1e-6);
  EXPECT_NEAR(acted, 0.12, 1e-6);
  EXPECT_GT(column(r.table, "x").back(), 0.99);
}

// A source at p whose supply line throttles (restriction 1/C_line, b 0.3,
// and `volume` of gas behind it) feeding a throttle C (b 0.3) to
// atmosphere; all at one temperature. The port's pressure at the end.
double sagged_port_pressure(double p, double C_line, double C, const std::string& volume = "0") {
  const RunResult r = run_text(
      "components:\n"
      "  supply: {type: pressure_source, p: " + num(p) + " Pa, fault_line_restriction: " + num(1.0 / C_line) +
      ", fault_line_volume: " + volume + "}\n"
      "  thr: {type: iso6358_throttle, C: " + num(C) + ", b: 0.3}\n"
      "  air: {type: atmosphere}\n"
      "connections:\n  - [supply.port, thr.a]\n  - [thr.b, air.port]\n"
      "outputs: {p1: thr.a.p}\n"
      "simulation: {t_end: 0.3 s, output_interval: 10 ms}\n",
      "sag.yaml");
  return column(r.table, "p1").back();
}

// Line subsonic, throttle choked: C p1 = C_line p sqrt(1 - ((q - b)/(1 - b))^2)
// with q = p1/p, a quadratic in q. Both choked: C p1 = C_line p (within the
// few per cent the line's continuation past choking costs). The gas a line
// holds does not move the steady sag: with 20 cm3 behind the resistance
// the port settles where it does without.
TEST(DeclaredFaults, SupplySagIsAThrottlingLineBetweenSourceAndPort) {
  const double b = 0.3, c2 = 1.0 / ((1 - b) * (1 - b)), C = 1e-8, p = 6e5;
  for (const double C_line : {4e-8, 1.5e-8}) {
    const double a2 = (C / C_line) * (C / C_line);
    const double q = (b * c2 + std::sqrt(b * b * c2 * c2 - (a2 + c2) * (b * b * c2 - 1))) / (a2 + c2);
    EXPECT_LT(rel_err(sagged_port_pressure(p, C_line, C), q * p), 1e-6) << C_line;
    EXPECT_LT(rel_err(sagged_port_pressure(p, C_line, C, "20 cm3"), q * p), 1e-5) << C_line;
  }
  EXPECT_LT(rel_err(sagged_port_pressure(20e5, 2.25e-9, C), 4.5e5), 0.03);
}

// The gas a supply line holds is a volume behind its resistance: a tank
// filled from a 6 bar source through such a line (1/C = 2.5 s*bar/dm3,
// b 0.4, 50 cm3) and a valve, then vented back through the valve, fills
// and vents as through a sound source, a throttle of C = 0.4 dm3/(s*bar),
// b 0.4, and a 50 cm3 through-flow volume at 6 bar (the gas the line
// feeds mixes with what it holds before it leaves) - the line's gas first
// covering the valve's opening burst (the port sags less than without
// it), then refilled through the resistance.
TEST(DeclaredFaults, ASupplyLinesGasIsAVolumeBehindItsResistance) {
  auto circuit = [](const std::string& fault, const std::string& twin) {
    return "components:\n"
           "  supply: {type: pressure_source, p: 6 bar" + fault + "}\n"
           "  valve: {type: directional_valve_32, C: 1 dm3/(s*bar), schedule: [[0.05, 1], [0.6, 0]]}\n"
           "  air: {type: atmosphere}\n"
           "  tank: {type: volume, V: 0.1 L}\n" + twin +
           "connections:\n  - [valve.R, air.port]\n  - [valve.A, tank.port]\n" +
           (twin.empty() ? "  - [supply.port, valve.P]\n"
                         : "  - [supply.port, thr.a]\n  - [thr.b, line.port]\n  - [line.port_b, valve.P]\n") +
           "outputs: {p_tank: tank.p, p_port: valve.P.p}\n"
           "simulation: {t_end: 1.2 s, output_interval: 5 ms}\n";
  };
  const std::string line = ", fault_line_restriction: 2.5 s*bar/dm3, fault_line_b: 0.4";
  const RunResult fault = run_text(circuit(line + ", fault_line_volume: 50 cm3", ""), "fault.yaml");
  const RunResult twin = run_text(circuit("", "  thr: {type: iso6358_throttle, C: 0.4 dm3/(s*bar), b: 0.4}\n"
                                              "  line: {type: volume, V: 50 cm3, p0: 6 bar}\n"),
                                  "twin.yaml");
  const RunResult no_gas = run_text(circuit(line, ""), "no_gas.yaml");
  for (const char* col : {"p_tank", "p_port"}) {
    const auto a = column(twin.table, col), b = column(fault.table, col);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LT(rel_err(b[i], a[i]), 1e-5) << col << " " << i;
  }
  const auto with = column(fault.table, "p_port"), without = column(no_gas.table, "p_port");
  const auto lowest = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.begin() + 40); };
  EXPECT_GT(lowest(with), lowest(without) + 0.2e5);  // the burst of the first 0.2 s
  const auto p = column(fault.table, "p_tank");
  EXPECT_GT(p[110], 5.9e5);  // filled by 0.55 s
  EXPECT_LT(p.back(), 2e5);  // and vented back
}

// A line drawn as a volume that restricts the flow through it is a
// throttle between its gas and port_b: a tank filled from a 6 bar supply
// through a valve, the line and its restriction of 1/C (b 0.4) fills as it
// does through the sound line and a throttle of C, b 0.4 at port_b - in
// both directions (filled, then vented back through the valve).
TEST(DeclaredFaults, ARestrictingLineIsAThrottleBetweenItsGasAndPortB) {
  auto circuit = [](const std::string& line, const std::string& behind) {
    return "components:\n"
           "  supply: {type: pressure_source, p: 6 bar}\n"
           "  valve: {type: directional_valve_32, C: 1 dm3/(s*bar), schedule: [[0.05, 1], [0.6, 0]]}\n"
           "  air: {type: atmosphere}\n"
           "  line: {type: volume, V: 5 cm3" + line + "}\n"
           "  tank: {type: volume, V: 0.1 L}\n" + behind +
           "connections:\n  - [supply.port, valve.P]\n  - [valve.R, air.port]\n  - [valve.A, line.port]\n" +
           (behind.empty() ? "  - [line.port_b, tank.port]\n"
                           : "  - [line.port_b, extra.a]\n  - [extra.b, tank.port]\n") +
           "outputs: {p_tank: tank.p, p_line: line.p}\n"
           "simulation: {t_end: 1.2 s, output_interval: 10 ms}\n";
  };
  const RunResult fault =
      run_text(circuit(", fault_line_restriction: 5 s*bar/dm3, fault_line_b: 0.4", ""), "fault.yaml");
  const RunResult twin =
      run_text(circuit("", "  extra: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.4}\n"), "twin.yaml");
  for (const char* col : {"p_tank", "p_line"}) {
    const auto a = column(twin.table, col), b = column(fault.table, col);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LT(rel_err(b[i], a[i]), 1e-6) << col << " " << i;
  }
  const auto p = column(fault.table, "p_tank");
  EXPECT_GT(p[60], 5.5e5);  // filled by 0.6 s
  EXPECT_LT(p.back(), 2e5);  // and vented back
}

// A pressure sensor with a gain and a zero offset reads gain p + offset.
TEST(DeclaredFaults, SensorReadsGainTimesValuePlusOffset) {
  const RunResult r = run_text(
      "components:\n"
      "  tank: {type: volume, V: 1 L, p0: 2 bar}\n"
      "  sensor: {type: pressure_sensor, fault_gain: 1.1, fault_offset: 0.01 bar}\n"
      "connections:\n  - [tank.port, sensor.port]\n"
      "outputs: {p: sensor.p}\n"
      "simulation: {t_end: 0.1 s, output_interval: 10 ms}\n",
      "sensor.yaml");
  EXPECT_NEAR(column(r.table, "p").back(), 1.1 * 2e5 + 1e3, 1e-6);
}

// The run of netlist `text` with its declared fault `name` (COMPONENT.FAULT)
// at `values`, through the catalogue a diagnosis makes of the circuit.
RunResult run_with_fault(const std::string& text, const std::string& name, const std::vector<double>& values) {
  const Netlist nl = parse_netlist(text, "faulty.yaml");
  const auto cat = diagnose::declared_faults(nl, builtin_registry(), {}, {});
  const diagnose::Effect* e = cat.find(name);
  EXPECT_NE(e, nullptr) << name;
  if (!e) return {};
  EXPECT_TRUE(e->unavailable.empty()) << e->unavailable;
  diagnose::MeasurementModel mm;
  return run_simulation(diagnose::apply_effects(nl, {{e, values}}, &mm), builtin_registry());
}

// The first event of `component` tagged `tag`, as (time, value the message
// reports after " = ").
std::pair<double, double> first_event(const RunResult& r, const std::string& component, const std::string& tag) {
  for (const auto& ev : r.solver.events)
    if (ev.component == component && ev.tag == tag)
      return {ev.t, std::stod(ev.message.substr(ev.message.find(" = ") + 3))};
  ADD_FAILURE() << "no " << component << "." << tag;
  return {NAN, NAN};
}

const char* kMeterOut = PNEUMO_SOURCE_DIR "/netlists/meter_out_cylinder.yaml";

std::string meter_out_text() {
  std::ifstream in(kMeterOut);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Netlist meter_out() { return parse_netlist(meter_out_text(), kMeterOut); }

// The wall heat fault is the cylinder's own wall law: at alpha it is the
// meter-out cylinder with wall_alpha = alpha and both chamber walls held at
// the ambient temperature, row for row (to the solver's tolerance: the two
// runs take their own steps), over strokes that move the gas's temperature
// by tens of kelvin.
TEST(DeclaredFaults, WallHeatIsTheCylindersOwnWallLawWithWallsAtAmbient) {
  std::string text = meter_out_text();
  const std::string last_output = "  p_rod: cyl.p_rod\n";
  text.replace(text.find(last_output), last_output.size(), last_output + "  T_cap: cyl.T_cap\n  T_rod: cyl.T_rod\n");
  const RunResult fault = run_with_fault(text, "cyl.wall_heat", {40.0});
  std::string walls = text;
  const std::string law_end = "friction_viscous: 100 N*s/m}";
  walls.replace(walls.find(law_end), law_end.size(), "friction_viscous: 100 N*s/m, wall_alpha: 40 W/(m2*K)}");
  walls.replace(walls.find("connections:"), 12,
                "  walls: {type: fixed_temperature, T: 293.15 K}\n"
                "connections:\n  - [cyl.heat_cap, walls.port]\n  - [cyl.heat_rod, walls.port]");
  const RunResult own = run_text(walls, "walls.yaml");
  const RunResult adiabatic = run_text(text, "adiabatic.yaml");
  for (const char* col : {"x", "p_cap", "p_rod", "T_cap", "T_rod"}) {
    const auto a = column(fault.table, col), b = column(own.table, col), c = column(adiabatic.table, col);
    ASSERT_EQ(a.size(), b.size()) << col;
    double moved = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_NEAR(a[i], b[i], 1e-4 * std::max(std::abs(b[i]), 1e-2)) << col << " row " << i;
      moved = std::max(moved, std::abs(a[i] - c[i]));
    }
    if (col[0] == 'T') EXPECT_GT(moved, 5.0) << col;
  }
}

// A rod driven out at 0.1 m/s past a limit switch set at 50 mm (window
// 2 mm): sound, it switches on at 49 mm, t = 0.49 s; slipped 3 mm back
// along the travel, at 46 mm, t = 0.46 s.
TEST(DeclaredFaults, AMisplacedLimitSwitchSwitchesWhereItNowSits) {
  const std::string text =
      "components:\n"
      "  drive: {type: velocity_source, v: 0.1 m/s}\n"
      "  sw: {type: limit_switch, position: 50 mm}\n"
      "  watch: {type: not}\n"
      "connections:\n  - [drive.flange, sw.flange]\n  - [sw.y, watch.in]\n"
      "outputs: {s: sw.state}\n"
      "simulation: {t_end: 0.8 s, output_interval: 10 ms}\n";
  for (const double shift : {0.0, -3e-3, 2e-3}) {
    const RunResult r = run_with_fault(text, "sw.misplaced", {shift});
    ASSERT_TRUE(r.solver.ok) << r.solver.message;
    const auto [t, s] = first_event(r, "sw", "on");
    EXPECT_NEAR(s, 0.049 + shift, 1e-7) << shift;
    EXPECT_NEAR(t, (0.049 + shift) / 0.1, 1e-6) << shift;
  }
}

// A 1 L tank filled through a throttle: its pressure switch (set 4 bar
// abs) turned 0.3 bar up switches on where the tank's pressure reaches
// 4.3 bar, later than the sound switch.
TEST(DeclaredFaults, AMisadjustedPressureSwitchSwitchesAtItsShiftedPressure) {
  const std::string text =
      "components:\n"
      "  supply: {type: pressure_source, p: 7 bar}\n"
      "  fill: {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.3}\n"
      "  tank: {type: volume, V: 1 L, p0: 1 bar}\n"
      "  ps: {type: pressure_switch, p_on: 4 bar}\n"
      "  watch: {type: not}\n"
      "connections:\n  - [supply.port, fill.a]\n  - [fill.b, tank.port, ps.port]\n  - [ps.y, watch.in]\n"
      "outputs: {p: tank.p}\n"
      "simulation: {t_end: 3 s, output_interval: 10 ms}\n";
  const RunResult sound = run_with_fault(text, "ps.misadjusted", {0.0});
  const RunResult turned = run_with_fault(text, "ps.misadjusted", {0.3e5});
  ASSERT_TRUE(sound.solver.ok && turned.solver.ok);
  EXPECT_NEAR(first_event(sound, "ps", "on").second, 4e5, 1.0);
  EXPECT_NEAR(first_event(turned, "ps", "on").second, 4.3e5, 1.0);
  EXPECT_GT(first_event(turned, "ps", "on").first, first_event(sound, "ps", "on").first + 0.05);
}

// An on-delay timer set to 0.2 s, its dial 1.5 x off: the output rises
// 0.3 s after the input's step at 0.1 s.
TEST(DeclaredFaults, AMisadjustedTimerElapsesAfterItsDelayTimesTheFactor) {
  const std::string text =
      "components:\n"
      "  go: {type: signal_source, kind: step, value: 0, height: 1, t_start: 0.1 s}\n"
      "  tmr: {type: timer, delay: 0.2 s}\n"
      "  watch: {type: not}\n"
      "connections:\n  - [go.y, tmr.in]\n  - [tmr.y, watch.in]\n"
      "outputs: {y: tmr.state}\n"
      "simulation: {t_end: 1 s, output_interval: 10 ms}\n";
  for (const double k : {1.0, 1.5, 0.6}) {
    const RunResult r = run_with_fault(text, "tmr.misadjusted", {k});
    ASSERT_TRUE(r.solver.ok) << r.solver.message;
    double t_elapsed = NAN;
    for (const auto& ev : r.solver.events)
      if (ev.component == "tmr" && ev.tag == "elapsed") t_elapsed = ev.t;
    EXPECT_NEAR(t_elapsed, 0.1 + 0.2 * k, 1e-9) << k;
  }
}

// A relief valve (set 5 bar abs, band 0.5 bar) held at a source pressure:
// turned up by dp it is as open at p_set + dp + band / 2 as the sound valve
// at p_set + band / 2; with a seat leak, below its setting, it passes the
// flow of a throttle of that fraction of its conductance (same b).
TEST(DeclaredFaults, AReliefValveOffItsSettingOrLeakingAtItsSeat) {
  auto held = [](const std::string& p_in, const std::string& twin = "") {
    return "components:\n"
           "  src: {type: pressure_source, p: " + p_in + "}\n"
           "  relief: {type: relief_valve, p_set: 5 bar, band: 0.5 bar, C: 1 dm3/(s*bar), b: 0.3}\n"
           "  air: {type: atmosphere}\n" +
           (twin.empty() ? "" : "  twin: {type: iso6358_throttle, C: " + twin + ", b: 0.3}\n") +
           "connections:\n  - [src.port, relief.in" + (twin.empty() ? "" : ", twin.a") + "]\n"
           "  - [relief.out, air.port" + (twin.empty() ? "" : ", twin.b") + "]\n"
           "outputs: {open: relief.opening, m: relief.m_flow" + (twin.empty() ? "" : ", m_twin: twin.m_flow") + "}\n"
           "simulation: {t_end: 0.01 s, output_interval: 10 ms}\n";
  };
  const RunResult sound = run_with_fault(held("5.25 bar"), "relief.misadjusted", {0.0});
  const RunResult turned = run_with_fault(held("5.65 bar"), "relief.misadjusted", {0.4e5});
  ASSERT_TRUE(sound.solver.ok && turned.solver.ok);
  const double open = column(sound.table, "open").back();
  EXPECT_GT(open, 0.1);
  EXPECT_LT(open, 0.9);
  EXPECT_NEAR(column(turned.table, "open").back(), open, 1e-12);

  const RunResult leaking = run_with_fault(held("4 bar", "0.03 dm3/(s*bar)"), "relief.seat_leak", {0.03});
  ASSERT_TRUE(leaking.solver.ok) << leaking.solver.message;
  EXPECT_NEAR(column(leaking.table, "open").back(), 0.03, 1e-12);
  EXPECT_GT(column(leaking.table, "m").back(), 0.0);
  EXPECT_LT(rel_err(column(leaking.table, "m").back(), column(leaking.table, "m_twin").back()), 1e-9);
}

// A regulator set to 4 bar abs (droop 0.3 bar) between held pressures:
// turned down by 0.2 bar, its supply path is as open at 3.65 bar as the
// sound one at 3.85 bar - the whole law moved by the shift, the relief
// point with it.
TEST(DeclaredFaults, AMisadjustedRegulatorRegulatesAtItsShiftedSetting) {
  auto held = [](const std::string& p_out) {
    return "components:\n"
           "  src: {type: pressure_source, p: 8 bar}\n"
           "  reg: {type: pressure_regulator, p_set: 4 bar, droop: 0.3 bar, C: 1 dm3/(s*bar)}\n"
           "  load: {type: pressure_source, p: " + p_out + "}\n"
           "  air: {type: atmosphere}\n"
           "connections:\n  - [src.port, reg.in]\n  - [reg.out, load.port]\n  - [reg.exhaust, air.port]\n"
           "outputs: {open: reg.opening, relief: reg.opening_relief}\n"
           "simulation: {t_end: 0.01 s, output_interval: 10 ms}\n";
  };
  const RunResult sound = run_with_fault(held("3.85 bar"), "reg.misadjusted", {0.0});
  const RunResult turned = run_with_fault(held("3.65 bar"), "reg.misadjusted", {-0.2e5});
  ASSERT_TRUE(sound.solver.ok && turned.solver.ok);
  const double open = column(sound.table, "open").back();
  EXPECT_GT(open, 0.1);
  EXPECT_LT(open, 0.9);
  EXPECT_NEAR(column(turned.table, "open").back(), open, 1e-12);
  const RunResult relieving = run_with_fault(held("4.0 bar"), "reg.misadjusted", {-0.2e5});
  EXPECT_GT(column(relieving.table, "relief").back(), 0.0);  // above 3.8 + 0.1 bar: the relief path opens
  EXPECT_EQ(column(run_with_fault(held("4.0 bar"), "reg.misadjusted", {0.0}).table, "relief").back(), 0.0);
}

// A mass pushed by a constant force F against friction reaches the speed
// where F = k_C F_C + k_v d v: the running-friction fault's two factors act
// on the dry and on the viscous part alone, in every law that has both (a
// guide's friction element declares it as a cylinder's seal does).
TEST(DeclaredFaults, RunningFrictionScalesItsDryAndViscousPartsApart) {
  const double F = 50, FC = 20, d = 100, kc = 1.5, kv = 0.5;
  for (const std::string law : {"friction_model: coulomb_viscous, friction_FC: 20 N, friction_viscous: 100 N*s/m",
                                "friction: custom, friction_b0: 20 N, friction_kv0: 100 N, friction_a: 1"}) {
    const RunResult r = run_with_fault(
        "components:\n"
        "  load: {type: translational_mass, m: 1 kg}\n"
        "  push: {type: force_source, F: " + num(F) + " N}\n"
        "  seal: {type: friction_element, " + law + "}\n"
        "connections:\n  - [load.flange, push.flange, seal.flange]\n"
        "outputs: {v: load.v}\n"
        "simulation: {t_end: 1 s, output_interval: 10 ms}\n",
        "seal.friction_running", {kc, kv});
    ASSERT_TRUE(r.solver.ok) << r.solver.message;
    EXPECT_LT(rel_err(column(r.table, "v").back(), (F - kc * FC) / (kv * d)), 1e-5) << law;
  }
}

// Held pressures on a shuttle valve (OR) and a two-pressure valve (AND):
// the inlet that wins passes the flow of the whole conductance, the other
// none; with a seat leak the other passes the flow of a throttle of that
// fraction of C (same b), the winner's path still the whole C; restricted,
// the winner passes the flow of k C.
TEST(DeclaredFaults, ALogicValvesSeatLeakOpensAFractionTowardTheInletItSeals) {
  for (const std::string type : {"shuttle_valve", "two_pressure_valve"}) {
    // OR: in_1 (6 bar) wins against in_2 (2 bar); AND: in_2 (2 bar) wins.
    const bool or_valve = type == "shuttle_valve";
    const auto text = "components:\n"
                      "  in1: {type: pressure_source, p: 6 bar}\n"
                      "  in2: {type: pressure_source, p: 2 bar}\n"
                      "  out: {type: pressure_source, p: " + std::string(or_valve ? "4 bar" : "1.5 bar") + "}\n"
                      "  v: {type: " + type + ", C: 1 dm3/(s*bar), b: 0.3}\n"
                      "  twin: {type: iso6358_throttle, C: 0.04 dm3/(s*bar), b: 0.3}\n"
                      "  sound: {type: iso6358_throttle, C: 1 dm3/(s*bar), b: 0.3}\n"
                      "connections:\n"
                      "  - [in1.port, v.in_1" + std::string(or_valve ? ", sound.a" : ", twin.a") + "]\n"
                      "  - [in2.port, v.in_2" + std::string(or_valve ? ", twin.a" : ", sound.a") + "]\n"
                      "  - [out.port, v.out, twin.b, sound.b]\n"
                      "outputs: {m1: v.m_flow_1, m2: v.m_flow_2, m_twin: twin.m_flow, m_sound: sound.m_flow}\n"
                      "simulation: {t_end: 0.01 s, output_interval: 10 ms}\n";
    const std::string win = or_valve ? "m1" : "m2", lose = or_valve ? "m2" : "m1";
    const RunResult healthy = run_with_fault(text, "v.seat_leak", {0.0});
    const RunResult leaking = run_with_fault(text, "v.seat_leak", {0.04});
    const RunResult restricted = run_with_fault(text, "v.restricted", {0.5});
    ASSERT_TRUE(healthy.solver.ok && leaking.solver.ok && restricted.solver.ok) << type;
    const double m_sound = column(healthy.table, "m_sound").back();
    EXPECT_LT(rel_err(column(healthy.table, win).back(), m_sound), 1e-9) << type;
    EXPECT_EQ(column(healthy.table, lose).back(), 0.0) << type;
    EXPECT_LT(rel_err(column(leaking.table, win).back(), m_sound), 1e-9) << type;
    EXPECT_NE(column(leaking.table, lose).back(), 0.0) << type;
    EXPECT_LT(rel_err(column(leaking.table, lose).back(), column(leaking.table, "m_twin").back()), 1e-9) << type;
    EXPECT_LT(rel_err(column(restricted.table, win).back(), 0.5 * m_sound), 1e-9) << type;
  }
}

// A quick exhaust valve feeding a cylinder (P 6 bar above A 4 bar): the
// sound disc seals the exhaust; a leaking one passes from A to R the flow
// of a throttle of that fraction of C_AR, and P -> A is as it was.
TEST(DeclaredFaults, AQuickExhaustValvesLeakingDiscVentsItsWorkingPortWhileItFeeds) {
  const std::string text =
      "components:\n"
      "  p: {type: pressure_source, p: 6 bar}\n"
      "  a: {type: pressure_source, p: 4 bar}\n"
      "  air: {type: atmosphere}\n"
      "  qev: {type: quick_exhaust_valve, C_PA: 0.6 dm3/(s*bar), C_AR: 2 dm3/(s*bar), b: 0.3}\n"
      "  twin: {type: iso6358_throttle, C: 0.06 dm3/(s*bar), b: 0.3}\n"
      "connections:\n  - [p.port, qev.P]\n  - [a.port, qev.A, twin.a]\n  - [qev.R, air.port, twin.b]\n"
      "outputs: {m_PA: qev.m_flow_PA, m_AR: qev.m_flow_AR, m_twin: twin.m_flow}\n"
      "simulation: {t_end: 0.01 s, output_interval: 10 ms}\n";
  const RunResult sound = run_with_fault(text, "qev.disc_leak", {0.0});
  const RunResult worn = run_with_fault(text, "qev.disc_leak", {0.03});
  ASSERT_TRUE(sound.solver.ok && worn.solver.ok);
  EXPECT_EQ(column(sound.table, "m_AR").back(), 0.0);
  EXPECT_GT(column(worn.table, "m_AR").back(), 0.0);
  EXPECT_LT(rel_err(column(worn.table, "m_AR").back(), column(worn.table, "m_twin").back()), 1e-9);
  EXPECT_LT(rel_err(column(worn.table, "m_PA").back(), column(sound.table, "m_PA").back()), 1e-12);
}

// A spring loaded by a constant force settles at F / (k k_f): the spring's
// fault is a factor on its stiffness.
TEST(DeclaredFaults, AWeakSpringSettlesFurtherUnderItsLoad) {
  const double F = 40, k = 2000, kf = 0.6;
  const RunResult r = run_with_fault(
      "components:\n"
      "  frame: {type: fixed_position}\n"
      "  spring: {type: spring_damper, k: " + num(k) + " N/m, d: 200 N*s/m}\n"
      "  load: {type: translational_mass, m: 1 kg}\n"
      "  push: {type: force_source, F: " + num(F) + " N}\n"
      "connections:\n  - [frame.flange, spring.a]\n  - [spring.b, load.flange, push.flange]\n"
      "outputs: {s: load.s}\n"
      "simulation: {t_end: 3 s, output_interval: 10 ms}\n",
      "spring.spring_off", {kf});
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_LT(rel_err(column(r.table, "s").back(), F / (kf * k)), 1e-5);
}

// A load written as the top-level m_load, which the runs set: its mass
// fault is a factor on each run's own mass, applied on the run's netlist
// after its operating point (1.3 x 4 kg = 5.2 kg where the netlist says
// 2 kg). A run that sets the load's mass itself (load.m) would replace the
// factor's value: then the fault is unavailable, saying why.
TEST(DeclaredFaults, AFactorOnAValueTheRunsSetActsOnEachRunsOwnValue) {
  const std::string text =
      "parameters:\n  m_load: 2 kg\n"
      "components:\n  load: {type: translational_mass, m: m_load}\n  push: {type: force_source, F: 10 N}\n"
      "connections:\n  - [load.flange, push.flange]\n"
      "outputs: {x: load.s}\n"
      "simulation: {t_end: 0.1 s, output_interval: 10 ms}\n";
  const Netlist nl = parse_netlist(text, "load.yaml");
  const auto cat = diagnose::declared_faults(nl, builtin_registry(), {}, {"m_load"});
  const diagnose::Effect* mass = cat.find("load.mass_off");
  ASSERT_NE(mass, nullptr);
  EXPECT_TRUE(mass->unavailable.empty()) << mass->unavailable;
  std::vector<diagnose::RunFactor> per_run;
  diagnose::MeasurementModel mm;
  Netlist run = diagnose::apply_effects(nl, {{mass, {1.3}}}, &mm, &per_run);
  ASSERT_EQ(per_run.size(), 1u);
  apply_override(run, "m_load=4 kg");  // the run's operating point
  diagnose::apply_run_factors(run, per_run);
  const ValueDecl* m = value_of(run, ParameterPath::parse("load.m"));
  ASSERT_NE(m, nullptr);
  ASSERT_TRUE(m->si.has_value());
  EXPECT_NEAR(*m->si, 5.2, 1e-12);

  const auto set_by_run = diagnose::declared_faults(nl, builtin_registry(), {}, {"load.m"});
  const std::string why = set_by_run.find("load.mass_off")->unavailable;
  EXPECT_NE(why.find("load.m is set by the runs' operating points"), std::string::npos) << why;
}

// The meter-out cylinder's candidates without any catalogue: its
// components' faults as COMPONENT.FAULT and each measured signal's
// measurement faults; a factor fault sets its product with the netlist's
// value.
TEST(DeclaredFaults, CircuitCandidatesAreItsComponentsFaultsAndMeasurementFaults) {
  const Netlist nl = meter_out();
  const auto cat = diagnose::declared_faults(nl, builtin_registry(), {{"x", 0.1, "m"}, {"p_cap", 6e5, "Pa"}}, {});
  for (const char* name : {"cyl.piston_seal_leak", "cyl.rod_seal_leak", "cyl.friction_breakaway", "flow_cap.misadjusted",
                           "silencer.misadjusted", "valve.delay_actuate", "supply.supply_sag", "load.mass_off",
                           "line_A.volume_off", "x.offset", "x.gain", "x.lag", "p_cap.offset"}) {
    const auto* e = cat.find(name);
    ASSERT_NE(e, nullptr) << name;
    EXPECT_TRUE(e->unavailable.empty()) << name << ": " << e->unavailable;
  }
  const auto* needle = cat.find("flow_cap.misadjusted");
  EXPECT_EQ(needle->component, "flow_cap");
  EXPECT_EQ(needle->fault, "misadjusted");
  diagnose::MeasurementModel mm;
  const Netlist patched = diagnose::apply_effects(nl, {{needle, {2.0}}}, &mm);
  for (const auto& c : patched.components)
    if (c.name == "flow_cap")
      for (const auto& [k, v] : c.parameters)
        if (k == "C") {
          ASSERT_TRUE(v.si);
          EXPECT_NEAR(*v.si, 2 * 0.1e-3 / 1e5, 1e-20);
        }
  const auto* offset = cat.find("x.offset");
  (void)diagnose::apply_effects(nl, {{offset, {0.004}}}, &mm);
  EXPECT_EQ(mm.offset.at("x"), 0.004);
  EXPECT_EQ(diagnose::narrow_catalogue(cat, {"cyl"}).effects.size(), fault_names("cylinder").size());
  EXPECT_THROW(diagnose::narrow_catalogue(cat, {"cly"}), InputError);
}

// A fault at its null is the sound component: every declared fault of the
// meter-out cylinder, set at its null, leaves every number of the run as it
// was - which is what lets a diagnosis take the unpatched model's runs for
// each candidate at its null (vanishes_at_null). A null that is not the
// netlist's value, or a patch that adds a component, does not vanish.
TEST(DeclaredFaults, AFaultAtItsNullLeavesEveryBitOfTheRun) {
  Netlist nl = meter_out();
  nl.simulation.t_end = 1.0;
  const auto cat = diagnose::declared_faults(nl, builtin_registry(), {{"x", 0.1, "m"}, {"p_cap", 6e5, "Pa"}}, {});
  const RunResult sound = run_simulation(nl, builtin_registry());
  ASSERT_TRUE(sound.solver.ok);
  int patched = 0;
  for (const auto& e : cat.effects) {
    if (!e.unavailable.empty()) continue;
    EXPECT_TRUE(diagnose::vanishes_at_null(e, nl, builtin_registry())) << e.name;
    if (!e.patches_netlist()) continue;
    diagnose::MeasurementModel mm;
    const RunResult at_null =
        run_simulation(diagnose::apply_effects(nl, {{&e, e.null_values()}}, &mm), builtin_registry());
    EXPECT_TRUE(at_null.solver.ok) << e.name;
    EXPECT_EQ(at_null.table.rows, sound.table.rows) << e.name;
    ++patched;
  }
  EXPECT_GT(patched, 20);

  diagnose::Effect needle = *cat.find("flow_cap.misadjusted");
  needle.parameters[0].null_value = 1.5;
  EXPECT_FALSE(diagnose::vanishes_at_null(needle, nl, builtin_registry()));
  diagnose::Effect leak = *cat.find("cyl.piston_seal_leak");
  leak.add_components.push_back(*nl.component("flow_cap"));
  leak.add_components.back().name = "extra";
  EXPECT_FALSE(diagnose::vanishes_at_null(leak, nl, builtin_registry()));
  const auto* offset = cat.find("x.offset");
  diagnose::Effect shifted = *offset;
  shifted.parameters[0].null_value = 1e-3;
  EXPECT_FALSE(diagnose::vanishes_at_null(shifted, nl, builtin_registry()));
}

// `measure:` takes an offset and a gain besides the lag.
TEST(DeclaredFaults, CatalogueMeasureTakesOffsetAndGain) {
  TempDir dir;
  const std::string cat = dir.write("c.yaml",
                                    "effects:\n  transducer:\n    parameters:\n"
                                    "      o: {initial: 0.001, lower: -0.01, upper: 0.01, null: 0, unit: m}\n"
                                    "      g: {initial: 1.01, lower: 0.9, upper: 1.1, null: 1, unit: \"1\"}\n"
                                    "    measure:\n      x: {offset: \"${o}\", gain: \"${g}\"}\n");
  const Netlist nl = meter_out();
  const auto c = diagnose::load_catalogue(cat, nl, builtin_registry());
  diagnose::MeasurementModel mm;
  (void)diagnose::apply_effects(nl, {{&c.effects[0], {0.002, 1.05}}}, &mm);
  EXPECT_EQ(mm.offset.at("x"), 0.002);
  EXPECT_EQ(mm.gain.at("x"), 1.05);
}

// A bound the component refuses is found when the catalogue is read, at the
// effect's line, naming the bound: b's upper bound 1.2 lies outside the
// throttle's [0, 0.999].
TEST(DeclaredFaults, CatalogueBoundsAreCheckedAtLoad) {
  TempDir dir;
  const std::string cat = dir.write("c.yaml",
                                    "effects:\n  silencer_b:\n    parameters:\n"
                                    "      b: {initial: 0.3, lower: 0.1, upper: 1.2, null: 0.3, unit: \"1\"}\n"
                                    "    set: {silencer.b: \"${b}\"}\n");
  try {
    (void)diagnose::load_catalogue(cat, meter_out(), builtin_registry());
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("upper bound of b"), std::string::npos) << e.what();
    EXPECT_EQ(e.where().line, 2) << e.what();
  }
}

// A fit whose model the solver could not run on a validation run is ranked
// after every fit that ran, whatever its sentinel gap says.
TEST(DeclaredFaults, AFailedFitIsNeverRankedAboveAFitThatRan) {
  std::vector<diagnose::EffectResult> r(2);
  r[0].name = "failed";
  r[0].significant = true;
  r[0].gap_before = 10;
  r[0].gap_after = 1.5;
  r[0].failed_validation_runs = 1;
  r[1].name = "ran";
  r[1].significant = true;
  r[1].gap_before = 10;
  r[1].gap_after = 3;
  const auto order = diagnose::rank_effects(r);
  EXPECT_EQ(r[order[0]].name, "ran");
}

// An effect fitted at `value` (one parameter of `unit`, null `null`).
diagnose::EffectResult fitted_effect(const std::string& name, const std::string& parameter, const std::string& unit,
                                     double null, double value) {
  diagnose::EffectResult e;
  e.name = name;
  e.parameter_names = {parameter};
  e.parameter_units = {unit};
  e.parameter_nulls = {null};
  e.values = {value};
  e.rank = 1;
  return e;
}

// The HTML report whose verdict names each of `effects` in a slot of its
// own, at the joint value `joint` (the verdict model's; each effect's own
// `values` are its single fit's).
std::string verdict_html(const std::vector<diagnose::EffectResult>& effects, const std::vector<double>& joint) {
  TempDir dir;
  diagnose::DiagnosisReport rep;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    rep.verdict.push_back(effects[i].name);
    rep.verdict_groups.push_back({effects[i].name});
    rep.effects.push_back(effects[i]);
    rep.final_values.push_back({effects[i].name, {joint[i]}});
  }
  const std::string path = (dir.path() / "r.html").string();
  diagnose::write_report_html(rep, path);
  return read_file(path);
}

// The HTML verdict gives the values the verdict model was simulated with
// (the joint fit's), each beside its null.
TEST(DeclaredFaults, HtmlVerdictShowsJointValuesAgainstTheirNulls) {
  const std::string html = verdict_html({fitted_effect("flow_cap.misadjusted", "k", "1", 1.0, 1.1)}, {1.32});
  const auto verdict = html.find("id=\"verdict\"");
  ASSERT_NE(verdict, std::string::npos);
  EXPECT_NE(html.find("k = 1.32 (null 1.00, +32 %)", verdict), std::string::npos) << html.substr(verdict, 400);
}

// A transducer's offset is a difference: 0.2 bar on a pressure reading
// (not "bar abs"), 2 K on a temperature reading (not -271 degC), in the
// verdict and in the ranking.
TEST(DeclaredFaults, HtmlShowsAnOffsetAsADifferenceOfItsQuantity) {
  const std::string html = verdict_html(
      {fitted_effect("p.offset", "offset", "Pa", 0.0, 2e4), fitted_effect("T.offset", "offset", "K", 0.0, 2.0)},
      {2e4, 2.0});
  const auto verdict = html.find("id=\"verdict\"");
  ASSERT_NE(verdict, std::string::npos);
  const std::string shown = html.substr(verdict, 600);
  EXPECT_NE(shown.find("offset = 0.200 bar (null 0)"), std::string::npos) << shown;
  EXPECT_NE(shown.find("offset = 2.00 K (null 0)"), std::string::npos) << shown;
  EXPECT_EQ(html.find("bar abs"), std::string::npos);
  EXPECT_EQ(html.find("degC"), std::string::npos);
}

// A re-calibrated pressure is shown as what the component means by it: a
// check valve's cracking pressure is a difference (bar), a supply's
// pressure absolute (bar abs).
TEST(DeclaredFaults, ARecalibratedPressureIsShownAsADifferenceOrAbsoluteAsTheComponentMeansIt) {
  const Netlist nl = meter_out();
  const auto cracking =
      diagnose::recalibration("flow_cap.check_cracking", "", "", nl, builtin_registry(), "--test");
  const auto supply = diagnose::recalibration("supply.p", "", "", nl, builtin_registry(), "--test");
  EXPECT_TRUE(cracking.parameters[0].difference);
  EXPECT_FALSE(supply.parameters[0].difference);
  auto e = fitted_effect("flow_cap.check_cracking", "check_cracking", "Pa", 1e4, 1.2e4);
  e.parameter_differences = {true};
  e.netlist_value = 1e4;
  const std::string html = verdict_html({e}, {1.2e4});
  EXPECT_NE(html.find("= 0.120 bar (netlist 0.100 bar, +20 %)"), std::string::npos);
  EXPECT_EQ(html.find("bar abs"), std::string::npos);
}

}  // namespace
}  // namespace pneumo
