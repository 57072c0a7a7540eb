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
        "dead_volume_cap_off", "dead_volume_rod_off"}},
      {"cushioned_cylinder",
       {"piston_seal_leak", "rod_seal_leak", "friction_running", "friction_breakaway", "wall_heat",
        "cushion_needle_misadjusted", "cushion_check_off"}},
      {"single_acting_cylinder", {"piston_seal_leak", "friction_breakaway", "spring_weak"}},
      {"directional_valve_32", {"delay_actuate", "delay_release", "slow_switching", "internal_leak"}},
      {"directional_valve_52", {"delay_actuate", "delay_release", "slow_switching", "internal_leak"}},
      {"directional_valve_53", {"delay_actuate", "delay_release", "slow_switching", "internal_leak"}},
      {"iso6358_throttle", {"misadjusted"}},
      {"one_way_flow_control", {"misadjusted", "check_leak"}},
      {"nozzle", {"clogged"}},
      {"check_valve", {"leak"}},
      {"pressure_source", {"supply_sag"}},
      {"pressure_regulator", {"supply_sag"}},
      {"volume", {"volume_off"}},
      {"hose", {"resistance"}},
      {"translational_mass", {"mass_off"}},
      {"pressure_sensor", {"offset", "gain", "lag"}},
      {"position_sensor", {"offset", "gain", "lag"}},
      {"temperature_sensor", {"offset", "gain", "lag"}},
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

// A source at p whose supply line throttles (restriction 1/C_line, b 0.3)
// feeding a throttle C (b 0.3) to atmosphere; both at one temperature.
double sagged_port_pressure(double p, double C_line, double C) {
  const RunResult r = run_text(
      "components:\n"
      "  supply: {type: pressure_source, p: " + num(p) + " Pa, fault_line_restriction: " + num(1.0 / C_line) + "}\n"
      "  thr: {type: iso6358_throttle, C: " + num(C) + ", b: 0.3}\n"
      "  air: {type: atmosphere}\n"
      "connections:\n  - [supply.port, thr.a]\n  - [thr.b, air.port]\n"
      "outputs: {p1: thr.a.p}\n"
      "simulation: {t_end: 0.1 s, output_interval: 10 ms}\n",
      "sag.yaml");
  return column(r.table, "p1").back();
}

// Line subsonic, throttle choked: C p1 = C_line p sqrt(1 - ((q - b)/(1 - b))^2)
// with q = p1/p, a quadratic in q. Both choked: C p1 = C_line p (within the
// few per cent the line's continuation past choking costs).
TEST(DeclaredFaults, SupplySagIsAThrottlingLineBetweenSourceAndPort) {
  const double b = 0.3, c2 = 1.0 / ((1 - b) * (1 - b)), C = 1e-8, p = 6e5;
  for (const double C_line : {4e-8, 1.5e-8}) {
    const double a2 = (C / C_line) * (C / C_line);
    const double q = (b * c2 + std::sqrt(b * b * c2 * c2 - (a2 + c2) * (b * b * c2 - 1))) / (a2 + c2);
    EXPECT_LT(rel_err(sagged_port_pressure(p, C_line, C), q * p), 1e-6) << C_line;
  }
  EXPECT_LT(rel_err(sagged_port_pressure(20e5, 2.25e-9, C), 4.5e5), 0.03);
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

// A mass pushed by a constant force F against friction reaches the speed
// where F = k_C F_C + k_v d v: the running-friction fault's two factors act
// on the dry and on the viscous part alone, in every law that has both.
TEST(DeclaredFaults, RunningFrictionScalesItsDryAndViscousPartsApart) {
  const double F = 50, FC = 20, d = 100, kc = 1.5, kv = 0.5;
  for (const std::string law : {"friction_model: coulomb_viscous, friction_FC: 20 N, friction_viscous: 100 N*s/m",
                                "friction: custom, friction_b0: 20 N, friction_kv0: 100 N, friction_a: 1"}) {
    const RunResult r = run_text(
        "components:\n"
        "  load: {type: translational_mass, m: 1 kg}\n"
        "  push: {type: force_source, F: " + num(F) + " N}\n"
        "  seal: {type: friction_element, " + law + ", friction_coulomb_scale: " + num(kc) +
            ", friction_viscous_scale: " + num(kv) + "}\n"
        "connections:\n  - [load.flange, push.flange, seal.flange]\n"
        "outputs: {v: load.v}\n"
        "simulation: {t_end: 1 s, output_interval: 10 ms}\n",
        "running_friction.yaml");
    EXPECT_LT(rel_err(column(r.table, "v").back(), (F - kc * FC) / (kv * d)), 1e-5) << law;
  }
}

const char* kMeterOut = PNEUMO_SOURCE_DIR "/netlists/meter_out_cylinder.yaml";

Netlist meter_out() {
  std::ifstream in(kMeterOut);
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_netlist(ss.str(), kMeterOut);
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

// The HTML verdict gives the values the verdict model was simulated with
// (the joint fit's), each beside its null.
TEST(DeclaredFaults, HtmlVerdictShowsJointValuesAgainstTheirNulls) {
  TempDir dir;
  diagnose::DiagnosisReport rep;
  rep.verdict = {"flow_cap.misadjusted"};
  rep.verdict_groups = {{"flow_cap.misadjusted"}};
  diagnose::EffectResult e;
  e.name = "flow_cap.misadjusted";
  e.parameter_names = {"k"};
  e.parameter_units = {"1"};
  e.parameter_nulls = {1.0};
  e.values = {1.1};  // the single fit's
  e.rank = 1;
  rep.effects = {e};
  rep.final_values = {{"flow_cap.misadjusted", {1.32}}};
  const std::string path = (dir.path() / "r.html").string();
  diagnose::write_report_html(rep, path);
  const std::string html = read_file(path);
  const auto verdict = html.find("id=\"verdict\"");
  ASSERT_NE(verdict, std::string::npos);
  EXPECT_NE(html.find("k = 1.32 (null 1.00, +32 %)", verdict), std::string::npos) << html.substr(verdict, 400);
}

}  // namespace
}  // namespace pneumo
