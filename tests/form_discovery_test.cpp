// The missing term's form (issue #32): (a) the solver's state-dependent
// disturbance terms against closed forms; (b) on measured runs of a
// meter-out cylinder made with an effect the model lacks - a return spring,
// a heavier load, a leak out of the cap chamber, a friction bump - the form
// found on the right balance is that effect, with its size, and the model
// with the form added leaves a gap within 1.5 x noise.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <random>

#include "components/builtin.hpp"
#include "framework/diagnose/engine.hpp"
#include "framework/diagnose/form.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;
using Of = DisturbanceFactor::Of;

// A free mass whose velocity balance gets -(k/m) s: a spring it does not
// have, so s = (v0 / w) sin(w t) with w = sqrt(k / m).
TEST(DisturbanceTerms, ASpringTermMakesAFreeMassOscillate) {
  const Netlist nl = parse_netlist(R"(
components:
  load: {type: translational_mass, m: 2 kg, s0: 0 m, v0: 0.1 m/s}
  free: {type: force_source, F: 0 N}
connections: [[free.flange, load.flange]]
outputs: {s: load.s}
simulation: {t_end: 1 s, output_interval: 10 ms, rtol: 1e-8}
)",
                                   "mass.yaml");
  const double k = 200, m = 2, w = std::sqrt(k / m);
  SolverOptions opt = solver_options(nl.simulation);
  opt.disturbances = {Disturbance{"v at {free.flange, load.flange}", {}, {}, {{-k / m, {{Of::value, "load.s"}}}}}};
  const RunResult r = run_circuit(elaborate(nl, builtin_registry()), opt);
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  for (double t : {0.1, 0.37, 0.8}) EXPECT_NEAR(at(r.table, "s", t), 0.1 / w * std::sin(w * t), 2e-6) << "t = " << t;
}

// A term in the acceleration is extra inertia: with c d[v]/dt added, a
// constant force F accelerates the mass at F / (m (1 - c)).
TEST(DisturbanceTerms, AnAccelerationTermIsInertia) {
  const Netlist nl = parse_netlist(R"(
components:
  load: {type: translational_mass, m: 2 kg, s0: 0 m}
  push: {type: force_source, F: 10 N}
connections: [[push.flange, load.flange]]
outputs: {v: load.v}
simulation: {t_end: 1 s, output_interval: 10 ms}
)",
                                   "push.yaml");
  SolverOptions opt = solver_options(nl.simulation);
  opt.disturbances = {Disturbance{"v at {push.flange, load.flange}", {}, {}, {{-0.25, {{Of::rate, "v at {push.flange, load.flange}"}}}}}};
  const RunResult r = run_circuit(elaborate(nl, builtin_registry()), opt);
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_NEAR(at(r.table, "v", 1.0), 10.0 / (2 * 1.25), 1e-6);
}

// The meter-out cylinder of netlists/meter_out_cylinder.yaml with the
// supply pressure as the runs' operating point, a 10 kg load and a shorter
// schedule (extend at 0.05 s, retract at 1 s), measured at 500 Hz.
std::string meter_out() {
  std::string text = read_file(std::filesystem::path(PNEUMO_SOURCE_DIR) / "netlists/meter_out_cylinder.yaml");
  const auto edit = [&](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    if (at == std::string::npos) throw std::logic_error("meter_out_cylinder.yaml has no '" + from + "'");
    text.replace(at, from.size(), to);
  };
  edit("components:", "parameters:\n  p_s: 6 bar g\ncomponents:");
  edit("{type: pressure_source, p: 6 bar g", "{type: pressure_source, p: p_s");
  edit("schedule: [[0.1, 1], [2.0, 0]]", "schedule: [[0.05, 1], [1.0, 0]]");
  edit("flow_cap: {type: one_way_flow_control, C: 0.1 dm3", "flow_cap: {type: one_way_flow_control, C: 0.15 dm3");
  edit("flow_rod: {type: one_way_flow_control, C: 0.1 dm3", "flow_rod: {type: one_way_flow_control, C: 0.15 dm3");
  edit("{type: translational_mass, m: 2 kg}", "{type: translational_mass, m: 10 kg}");
  text.erase(text.find("outputs:"));
  return text + "outputs: {x: cyl.x, p_cap: cyl.p_cap, p_rod: cyl.p_rod}\n"
                "simulation: {t_end: 1.8 s, output_interval: 2 ms}\n";
}
const std::string kMeterOut = meter_out();

const char* const kVelocity = "v at {cyl.flange, load.flange}";
const char* const kPosition = "s at {cyl.flange, load.flange}";
constexpr double kMass = 10;  // kg: the load; the cylinder's piston has no mass of its own

// A measured output of the runs and the standard deviation of its noise.
struct Reading {
  std::string column;
  double noise;
};

// Runs of the netlist `truth` at the supply pressures `gauge` (p_s, gauge;
// the highest one the validation run) with `disturbances`, each reading
// sampled every `dt` from `from` on with Gaussian noise.
std::filesystem::path write_runs(const TempDir& dir, const std::string& truth,
                                 const std::vector<std::pair<std::string, double>>& gauge,
                                 const std::vector<Reading>& readings, double dt, double from, unsigned seed,
                                 const std::vector<Disturbance>& disturbances = {}) {
  const auto runs = dir.path() / "runs";
  std::filesystem::create_directories(runs);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 1);
  for (const auto& [name, p] : gauge) {
    Netlist nl = parse_netlist(truth, "truth.yaml");
    set_si_value(nl, ParameterPath::parse("p_s"), p + 101325);
    SolverOptions opt = solver_options(nl.simulation);
    opt.disturbances = disturbances;
    const RunResult res = run_circuit(elaborate(nl, builtin_registry()), opt);
    EXPECT_TRUE(res.solver.ok) << res.solver.message;
    std::ofstream csv(runs / (name + ".csv"));
    csv << "t";
    for (const auto& r : readings) csv << "," << r.column;
    csv << "\n";
    csv.precision(12);
    double last = -1;
    for (const auto& row : res.table.rows) {
      // The sampling grid only: the rows written at events are not samples.
      if (std::abs(row[0] / dt - std::round(row[0] / dt)) > 1e-6 || row[0] <= last || row[0] < from) continue;
      last = row[0];
      csv << row[0];
      for (const auto& r : readings) csv << "," << row[res.table.column(r.column)] + r.noise * noise(rng);
      csv << "\n";
    }
    std::ofstream(runs / (name + ".yaml")) << "data: " << name << ".csv\nrole: "
                                           << (p == gauge.back().second ? "validation" : "calibration")
                                           << "\noperating_point:\n  p_s: " << num(p + 101325) << "\n";
  }
  return runs;
}

// Runs at three supply pressures of the model edited by `edit` (the truth),
// with `truth` disturbances, and sensor noise: x 0.02 mm, pressures 3 mbar.
std::filesystem::path measured(const TempDir& dir, const std::function<void(std::string&)>& edit,
                               const std::vector<Disturbance>& truth = {}) {
  std::string text = kMeterOut;
  edit(text);
  return write_runs(dir, text, {{"low", 4e5}, {"mid", 5.5e5}, {"high", 7e5}}, {{"x", 2e-5}, {"p_cap", 300}, {"p_rod", 300}},
                    2e-3, 0.0, 11, truth);
}

using Discover = std::function<std::optional<diagnose::FormFinding>(const diagnose::FormInput&)>;

// The form `discover` finds in the runs in `runs`, the model being the netlist file `netlist`.
diagnose::FormFinding form_found(const std::filesystem::path& runs, const Discover& discover,
                                 const std::filesystem::path& netlist) {
  diagnose::DiagnoseOptions opt;
  opt.progress = false;
  diagnose::engine::Engine eng(netlist.string(), builtin_registry(), opt);
  eng.runs = diagnose::load_runs(runs.string(), eng.base(), eng.base_probes(), eng.registry());
  const auto model = eng.model({});
  const auto residual = [&](int k, const std::vector<std::vector<double>>& sim) {
    const auto& run = eng.runs[k];
    Eigen::VectorXd r(run.signals.size() * run.t.size());
    for (std::size_t s = 0; s < run.signals.size(); ++s)
      for (std::size_t i = 0; i < run.t.size(); ++i) r[s * run.t.size() + i] = (run.y[s][i] - sim[s][i]) / run.sigma[s];
    return r;
  };
  diagnose::FormInput in;
  in.runs = &eng.runs;
  for (int k = 0; k < static_cast<int>(eng.runs.size()); ++k) {
    const auto sim = eng.simulate(model, k);
    EXPECT_FALSE(sim.empty());
    in.used.push_back(k);
    in.r0.push_back(residual(k, sim));
  }
  in.netlist_of = [&](int k) { return eng.netlist_of(model, k); };
  in.registry = &eng.registry();
  in.simulate = [&](int k, const std::vector<Disturbance>& d, std::string* why) {
    return eng.simulate(model, k, d, {}, why);
  };
  in.residual = residual;
  const auto f = discover(in);
  EXPECT_TRUE(f.has_value());
  if (f) std::cout << f->sentence << "\n";
  return f.value_or(diagnose::FormFinding{});
}

// The form on `balance` that the runs in `runs` call for, the model being kMeterOut.
diagnose::FormFinding form_on(const TempDir& dir, const std::filesystem::path& runs, const std::string& balance,
                              const std::string& unit, const std::string& model_text = kMeterOut) {
  return form_found(runs, [&](const diagnose::FormInput& in) { return diagnose::discover_form(in, balance, unit, INFINITY); },
                    dir.write("model.yaml", model_text));
}

void insert(std::string& text, const std::string& before, const std::string& what) {
  text.insert(text.find(before), what);
}

// The terms of a form that read exactly these factor kinds, in order.
std::vector<diagnose::FormTermFinding> terms_of(const diagnose::FormFinding& f, const std::string& prefix) {
  std::vector<diagnose::FormTermFinding> out;
  for (const auto& t : f.terms)
    if (t.text.rfind(prefix, 0) == 0) out.push_back(t);
  return out;
}

double constant_of(const diagnose::FormFinding& f) {
  double c = 0;
  for (const auto& t : f.terms)
    if (t.text == "1") c += t.coefficient;
  return c;
}

// A return spring the model lacks, F = -F0 - k s with k = 300 N/m and
// F0 = 15 N (a wall 50 mm behind the retracted piston): the form on the
// load's momentum balance is affine in the position, k and F0 within 20 %.
TEST(FormDiscovery, AReturnSpringIsFoundWithItsStiffnessAndPreload) {
  TempDir dir;
  const auto runs = measured(dir, [](std::string& t) {
    insert(t, "connections:", "  spring: {type: spring_damper, k: 300 N/m}\n  wall: {type: fixed_position, s0: -50 mm}\n");
    insert(t, "outputs:", "  - [load.flange, spring.a]\n  - [spring.b, wall.flange]\n");
  });
  const auto f = form_on(dir, runs, kVelocity, "m/s2");
  ASSERT_TRUE(f.confirmed) << f.sentence;
  const auto linear = terms_of(f, std::string("[") + kPosition + "]");
  ASSERT_EQ(linear.size(), 1u) << f.formula;
  EXPECT_NEAR(-linear[0].coefficient * kMass, 300.0, 60.0) << f.formula;
  EXPECT_NEAR(-constant_of(f) * kMass, 15.0, 3.0) << f.formula;
  EXPECT_LT(f.gap_after, 1.5);
  EXPECT_GT(f.gap_before, 50.0);
}

// A load 2.5 kg heavier than the model's 10 kg: (m + dm) a = F is the
// model's balance with -(dm / m) a added, so the form is a term in the
// acceleration whose coefficient gives dm within 15 %.
TEST(FormDiscovery, AHeavierLoadIsATermInTheAcceleration) {
  TempDir dir;
  const auto runs = measured(dir, [](std::string& t) { t.replace(t.find("m: 10 kg"), 8, "m: 12.5 kg"); });
  const auto f = form_on(dir, runs, kVelocity, "m/s2");
  ASSERT_TRUE(f.confirmed) << f.sentence;
  const auto inertia = terms_of(f, std::string("d[") + kVelocity + "]/dt");
  ASSERT_EQ(inertia.size(), 1u) << f.formula;
  EXPECT_NEAR(-inertia[0].coefficient * kMass, 2.5, 0.375) << f.formula;
  EXPECT_EQ(inertia[0].unit, "") << "m/s2 per m/s2";
  EXPECT_LT(f.gap_after, 1.5);
}

// Friction of 25 N concentrated around s = 45 mm (a misaligned guide: a
// Gaussian bump of 4 mm against the motion). The runs are made with the
// solver's own state-dependent term (checked against closed forms above);
// the bump's centre and width are found off the candidates' grid.
TEST(FormDiscovery, AFrictionBumpIsFoundWhereItIs) {
  TempDir dir;
  const DisturbanceTerm bump{-25.0 / kMass, {{Of::sign, kVelocity, "", 0, 0.005}, {Of::bump, kPosition, "", 0.045, 0.004}}};
  const auto runs = measured(dir, [](std::string&) {}, {Disturbance{kVelocity, {}, {}, {bump}}});
  const auto f = form_on(dir, runs, kVelocity, "m/s2");
  ASSERT_TRUE(f.confirmed) << f.sentence;
  const auto found = terms_of(f, std::string("sgn([") + kVelocity + "]) * bump(");
  ASSERT_GE(found.size(), 1u) << f.formula;
  EXPECT_NEAR(-found[0].coefficient * kMass, 25.0, 6.25) << f.formula;
  const auto at = found[0].text.find("centre ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_NEAR(std::stod(found[0].text.substr(at + 7)), 45.0, 3.0) << found[0].text;
  EXPECT_LT(f.gap_after, 1.5);
}

// A leak from the cap port to the atmosphere (an ISO 6358 throttle of
// C 0.005 dm3/(s*bar), b 0.3, 3 % of the flow control's): the form on the
// cap chamber's mass balance is a term growing with the chamber's pressure,
// mass leaving at about C rho0 p while choked (ISO 6358, rho0 1.185 kg/m3:
// 5.93e-11 kg/(s*Pa)), within 25 %; the escaping gas takes its enthalpy
// from the energy balance with it, and the model with the form is within
// 1.5 x noise.
TEST(FormDiscovery, ALeakOutOfTheCapChamberIsATermInItsPressureOnItsMassBalance) {
  TempDir dir;
  const auto runs = measured(dir, [](std::string& t) {
    insert(t, "connections:", "  leak: {type: iso6358_throttle, C: 0.005 dm3/(s*bar), b: 0.3}\n  leak_air: {type: atmosphere}\n");
    t.replace(t.find("[flow_cap.a, cyl.cap]"), 21, "[flow_cap.a, cyl.cap, leak.a]");
    insert(t, "outputs:", "  - [leak.b, leak_air.port]\n");
  });
  const auto f = form_on(dir, runs, "cyl.m_cap", "kg/s");
  ASSERT_TRUE(f.confirmed) << f.sentence;
  EXPECT_LT(f.gap_after, 1.5) << f.formula;
  EXPECT_GT(f.gap_before, 20.0);
  // The cap chamber's pressure under any of its names (the node's, a port's,
  // the chamber's), as a factor alone or as either side of a difference.
  double per_pa = 0;
  int found = 0;
  for (const auto& t : f.terms)
    for (const std::string cap : {"[flow_cap.a.p]", "[cyl.cap.p]", "[cyl.p_cap]", "[p at {flow_cap.a, cyl.cap}]"}) {
      if (t.text == cap) per_pa += t.coefficient, ++found;
      else if (t.text.front() == '(' && t.text.find(" - " + cap + ")") != std::string::npos) per_pa -= t.coefficient, ++found;
      else if (t.text.rfind("(" + cap + " - ", 0) == 0) per_pa += t.coefficient, ++found;
    }
  ASSERT_EQ(found, 1) << f.formula;
  EXPECT_NEAR(-per_pa, 5.93e-11, 0.25 * 5.93e-11) << f.formula;
  for (const auto& t : f.terms) EXPECT_EQ(t.unit.rfind("kg/s", 0), 0u) << t.unit;
}

// The meter-out cylinder beside a drive of its own: a valve, lines, flow
// controls, a smaller cylinder and load, switching at other times, on a
// second supply or (`shared_supply`) on the first cylinder's.
std::string with_second_drive(bool shared_supply = false) {
  std::string t = kMeterOut;
  insert(t, "connections:",
         std::string(shared_supply ? "" : "  supply2: {type: pressure_source, p: 5 bar g}\n") +
         "  valve2: {type: directional_valve_52, C: 1 dm3/(s*bar), b: 0.3, t_switch_time: 10 ms,"
         " schedule: [[0.3, 1], [1.3, 0]]}\n"
         "  silencer2: {type: iso6358_throttle, C: 2 dm3/(s*bar), b: 0.3}\n  air2: {type: atmosphere}\n"
         "  line_A2: {type: volume, V: 5 cm3, p0: 0 bar g}\n  line_B2: {type: volume, V: 5 cm3, p0: 6 bar g}\n"
         "  flow_cap2: {type: one_way_flow_control, C: 0.1 dm3/(s*bar), check_C: 1 dm3/(s*bar)}\n"
         "  flow_rod2: {type: one_way_flow_control, C: 0.1 dm3/(s*bar), check_C: 1 dm3/(s*bar)}\n"
         "  cyl2: {type: cylinder, bore: 25 mm, rod: 10 mm, stroke: 80 mm, p0_rod: 6 bar g,"
         " friction_model: coulomb_viscous, friction_FC: 15 N, friction_viscous: 80 N*s/m}\n"
         "  load2: {type: translational_mass, m: 3 kg}\n\n");
  insert(t, "outputs:",
         std::string(shared_supply ? "  - [supply.port, valve2.P]\n" : "  - [supply2.port, valve2.P]\n") +
         "  - [valve2.A, line_A2.port]\n  - [line_A2.port_b, flow_cap2.b]\n"
         "  - [flow_cap2.a, cyl2.cap]\n  - [valve2.B, line_B2.port]\n  - [line_B2.port_b, flow_rod2.b]\n"
         "  - [flow_rod2.a, cyl2.rod]\n  - [valve2.R, silencer2.a]\n  - [silencer2.b, air2.port]\n"
         "  - [cyl2.flange, load2.flange]\n\n");
  return t;
}

// A missing term in one cylinder's balance reads that cylinder's part of
// the circuit (form.hpp): beside a second drive that moves on its own, the
// dictionary on the first cylinder's cap mass balance is the one it has
// alone - none of the second drive's pressures, positions, velocities,
// temperatures or their products enter it.
TEST(FormDiscovery, ABalanceOfOneCylinderReadsNothingOfAnotherDrive) {
  TempDir dir;
  const auto runs = measured(dir, [](std::string&) {});
  const auto alone = form_on(dir, runs, "cyl.m_cap", "kg/s");
  const auto beside = form_on(dir, runs, "cyl.m_cap", "kg/s", with_second_drive());
  EXPECT_GT(alone.dictionary, 50);
  EXPECT_EQ(beside.dictionary, alone.dictionary);
}

// A source holds its node's pressure whatever flows through it, so a drive
// on the same supply is as far from a balance as one on a supply of its
// own: the line to the first valve's A port reads what it reads alone and
// nothing of the second drive's components. (What the first valve reads of
// the supply node may now move - the stream temperature its three ports
// share, and the valve's outlet temperatures with it - and is read.) Its
// valve is one node from it, the supply two: without the stop at a held
// node, the second drive's valve and lines would be read (249 terms against
// 153).
TEST(FormDiscovery, ASharedSupplyDoesNotJoinTwoDrives) {
  TempDir dir;
  const auto runs = measured(dir, [](std::string&) {});
  const auto alone = form_on(dir, runs, "line_A.m", "kg/s");
  const auto beside = form_on(dir, runs, "line_A.m", "kg/s", with_second_drive(true));
  EXPECT_GT(alone.dictionary, 50);
  for (const auto& name : alone.read)
    EXPECT_NE(std::find(beside.read.begin(), beside.read.end(), name), beside.read.end()) << name;
  const std::string shared = "{supply.port, valve.P, valve2.P}";
  for (std::string name : beside.read) {
    if (const auto at = name.find(shared); at != std::string::npos) name.erase(at, shared.size());
    for (const char* other : {"valve2", "silencer2", "line_A2", "line_B2", "flow_cap2", "flow_rod2", "cyl2", "load2"})
      EXPECT_EQ(name.find(other), std::string::npos) << name;
  }
}

// A rod moved by a position servo over 30 mm and back at 15 mm/s, the
// chamber held at the runs' pressure, the force the drive holds the rod
// with measured (the TU Delft friction rig's arrangement,
// netlists/real/tudelft_friction.yaml).
const char* const kDrivenRod = R"(
parameters:
  p_s: 4 bar g
components:
  motion: {type: signal_source, kind: table, table: [[0, 0.010], [0.5, 0.010], [2.5, 0.040], [3.0, 0.040], [5.0, 0.010], [5.5, 0.010], [7.5, 0.040]]}
  supply: {type: pressure_source, p: p_s}
  line: {type: iso6358_throttle, C: 5 dm3/(s*bar), b: 0.3}
  actuator:
    {type: single_acting_cylinder, bore: 25 mm, rod: 8 mm, stroke: 50 mm, spring_rate: 0 N/m, friction_model: coulomb_viscous,
     friction_FC: 5 N, friction_viscous: 100 N*s/m, friction_v_reg: 1 mm/s, x0: 10 mm}
  drive: {type: position_source, s0: 10 mm, tau: 2 ms}
connections:
  - [motion.y, drive.s_in]
  - [supply.port, line.a]
  - [line.b, actuator.cap]
  - [drive.flange, actuator.flange]
outputs: {F: drive.F}
simulation: {t_end: 7.5 s, output_interval: 10 ms}
)";

// Runs of `truth` at 2, 4 and 6 bar g, the force read with 0.03 N of noise at 100 Hz.
std::filesystem::path driven_runs(const TempDir& dir, const std::string& truth) {
  return write_runs(dir, truth, {{"p2", 2e5}, {"p4", 4e5}, {"p6", 6e5}}, {{"F", 0.03}}, 1e-2, 0.1, 5);
}

// The seal's friction grows by 0.5 N/bar of the chamber's gauge pressure
// (5e-6 N/Pa), which the model lacks. On a rod whose motion is imposed no
// balance holds that force - it is in the force the drive reads: the form
// on the reading is the friction's sign times an affine law of the chamber
// pressure (the slope within 10 %), and it leaves the noise.
TEST(FormDiscovery, APressureDependentFrictionIsFoundInTheReadingOfADrivenRod) {
  TempDir dir;
  std::string truth = kDrivenRod;
  insert(truth, "friction_v_reg:", "fault_friction_per_pressure: 5e-6 N/Pa, ");
  const auto runs = driven_runs(dir, truth);
  const auto f = form_found(runs, [](const diagnose::FormInput& in) {
    return diagnose::discover_reading_form(in, "F", INFINITY);
  }, dir.write("model.yaml", kDrivenRod));
  ASSERT_TRUE(f.confirmed) << f.sentence;
  EXPECT_TRUE(f.reading);
  EXPECT_EQ(f.unit, "N");
  std::vector<diagnose::FormTermFinding> slope;
  for (const auto& t : f.terms)
    if (t.text.rfind("sgn([", 0) == 0 && t.text.find(".p]") != std::string::npos) slope.push_back(t);
  ASSERT_EQ(slope.size(), 1u) << f.formula;
  EXPECT_NEAR(std::abs(slope[0].coefficient), 5e-6, 5e-7) << f.formula;
  EXPECT_GT(f.gap_before, 20.0);
  EXPECT_LT(f.gap_after, 1.5) << f.formula;
}

// Real data (tests/data/tudelft, CC0): the O-ring seal's first ten seconds
// at 1, 3, 5 and 7 bar gauge, the nominal constant friction of
// netlists/real/tudelft_friction.yaml. The reading's form must say what the
// seal does - its friction grows with the chamber pressure (3.9 N at 1 bar,
// 6.9 N at 7 bar, half the difference of the two directions' forces): a term
// with the motion (its sign or speed) times the chamber pressure, whose
// coefficient makes the force against the motion grow with the pressure,
// and the form lowers the gap of all runs by at least a third.
TEST(FormDiscovery, TheORingsFrictionGrowsWithThePressureInTheReadingsForm) {
  const std::string data = std::string(PNEUMO_SOURCE_DIR) + "/tests/data/tudelft";
  // The netlist replays the shared data beside the repository by default;
  // here its excerpt (each run file sets its own).
  std::string netlist = read_file(std::filesystem::path(PNEUMO_SOURCE_DIR) / "netlists/real/tudelft_friction.yaml");
  const std::string shared = "../../../shared/real-data/tudelft-actuator/friction/O-ring_3bar.csv";
  for (auto at = netlist.find(shared); at != std::string::npos; at = netlist.find(shared))
    netlist.replace(at, shared.size(), data + "/O-ring_3bar_head1000.csv");
  TempDir dir;
  const auto f = form_found(data, [](const diagnose::FormInput& in) {
    return diagnose::discover_reading_form(in, "F", INFINITY);
  }, dir.write("model.yaml", netlist));
  ASSERT_TRUE(f.confirmed) << f.sentence;
  // F is the force the drive holds the rod with (+ extends): a friction
  // against the motion raises it while the rod moves out (v > 0).
  double slope = 0;
  for (const auto& t : f.terms)
    if ((t.text.rfind("sgn([actuator.flange.v])", 0) == 0 || t.text.rfind("[actuator.flange.v]", 0) == 0) &&
        t.text.find(".p]") != std::string::npos)
      slope += t.coefficient;
  EXPECT_GT(slope, 0.0) << f.formula;
  EXPECT_LT(f.gap_after, 0.67 * f.gap_before) << f.formula;
}

// Runs of the model itself: nothing is left to explain, no form is proposed.
TEST(FormDiscovery, NoFormIsProposedForNoise) {
  TempDir dir;
  const auto runs = measured(dir, [](std::string&) {});
  const auto f = form_on(dir, runs, kVelocity, "m/s2");
  EXPECT_TRUE(f.terms.empty()) << f.formula;
  EXPECT_LT(f.gap_before, 1.1);
  EXPECT_NE(f.sentence.find("Nothing is left"), std::string::npos) << f.sentence;
}

}  // namespace
}  // namespace pneumo
