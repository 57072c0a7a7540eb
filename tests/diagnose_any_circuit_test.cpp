// `pneumo diagnose` on a circuit without a cylinder (issue #16): a tank
// filled and vented through a 3/2 valve on a schedule. The measured runs are
// generated here with a withheld leak from the tank to the atmosphere (a
// near-laminar one, b = 0.1, another form than the candidate's b = 0.3)
// plus sensor noise; the catalogue offers the leak, wall heat transfer and
// a lagging pressure sensor. The diagnosis must name the leak, and the gap
// report's phases come from the model's own events (the valve's switching),
// since the catalogue declares none.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>

#include "components/builtin.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

const std::string kModel = R"(
parameters:
  p_supply: 6 bar
components:
  supply: {type: pressure_source, p: p_supply, T: 293.15 K}
  valve:
    type: directional_valve_32
    C: 0.3 dm3/(s*bar)
    b: 0.3
    C_AR: 0.2 dm3/(s*bar)
    t_switch_time: 5 ms
    schedule: [[0.05, 1], [0.6, 0]]
  tank: {type: volume, V: 0.5 L, p0: 1 atm, T0: 293.15 K}
  air: {type: atmosphere}
connections:
  - [supply.port, valve.P]
  - [valve.A, tank.port]
  - [valve.R, air.port]
outputs: {p: tank.p, T: tank.T}
simulation: {t_end: 1.2 s, output_interval: 2 ms}
)";

const std::string kCatalogue = R"(
effects:
  leak:
    description: leak from the tank to the atmosphere
    parameters:
      C: {initial: 2.0e-10, lower: 0, upper: 5.0e-9, null: 0, unit: m3/(s*Pa)}
    add_components:
      leak_path: {type: iso6358_throttle, C: "${C}", b: 0.3}
      leak_air: {type: atmosphere}
    connect:
      - [tank.port, leak_path.a]
      - [leak_path.b, leak_air.port]
  wall_heat:
    description: heat exchange of the tank gas with a wall at room temperature
    parameters:
      kA: {initial: 0.5, lower: 0, upper: 20, null: 0, unit: W/K}
    add_components:
      film: {type: heat_convection, alpha: "${kA}", A: 1}
      wall: {type: fixed_temperature, T: 293.15}
    connect:
      - [tank.heat, film.a]
      - [film.b, wall.port]
  sensor_lag_p:
    description: first-order lag of the pressure sensor
    parameters:
      tau: {initial: 0.005, lower: 0, upper: 0.1, null: 0, unit: s}
    measure:
      p: {lag: "${tau}"}
)";

// Two runs of the model with the true leak, sampled at 500 Hz with noise.
void make_runs(const std::filesystem::path& dir) {
  std::string truth = kModel;
  truth.replace(truth.find("connections:"), 12,
                "  true_leak: {type: iso6358_throttle, C: 0.03 dm3/(s*bar), b: 0.1}\n"
                "  true_air: {type: atmosphere}\nconnections:\n  - [tank.port, true_leak.a]\n"
                "  - [true_leak.b, true_air.port]");
  std::mt19937 rng(11);
  const struct {
    const char* name;
    const char* role;
    double p;
  } runs[] = {{"cal", "calibration", 5e5}, {"val", "validation", 7e5}};
  for (const auto& r : runs) {
    Netlist nl = parse_netlist(truth, "truth.yaml");
    apply_override(nl, "p_supply=" + num(r.p));
    const RunResult res = run_simulation(nl, builtin_registry());
    ASSERT_TRUE(res.solver.ok) << res.solver.message;
    std::ofstream csv(dir / (std::string(r.name) + ".csv"));
    csv << "t,p,T\n";
    csv.precision(10);
    std::normal_distribution<double> np(0, 2e3), nT(0, 0.3);
    for (const auto& row : res.table.rows)
      csv << row[0] << "," << row[res.table.column("p")] + np(rng) << "," << row[res.table.column("T")] + nT(rng)
          << "\n";
    std::ofstream(dir / (std::string(r.name) + ".yaml"))
        << "data: " << r.name << ".csv\nrole: " << r.role << "\noperating_point:\n  p_supply: " << r.p << "\n";
  }
}

TEST(DiagnoseAnyCircuit, WithheldLeakOfATankIsNamed) {
  TempDir dir;
  const std::string model = dir.write("tank.yaml", kModel), catalogue = dir.write("catalogue.yaml", kCatalogue);
  std::filesystem::create_directories(dir.path() / "runs");
  make_runs(dir.path() / "runs");
  diagnose::DiagnoseOptions opt;
  opt.progress = false;
  const auto rep = diagnose::diagnose(model, (dir.path() / "runs").string(), catalogue, builtin_registry(), opt);
  std::cout << "validation gap " << rep.validation_before.total.rms << " -> " << rep.validation_after.total.rms
            << ", verdict:";
  for (const auto& v : rep.verdict) std::cout << " " << v;
  std::cout << "\n";
  ASSERT_FALSE(rep.verdict.empty());
  EXPECT_EQ(rep.verdict[0], "leak");
  EXPECT_GT(rep.validation_before.total.rms, 5.0);  // the leak is far above the noise
  EXPECT_LT(rep.validation_after.total.rms, 2.0);
  // Phases from the valve's tagged events, in time order.
  const auto& ph = rep.phase_names;
  ASSERT_GE(ph.size(), 3u);
  EXPECT_EQ(ph[0], "start");
  const auto on = std::find(ph.begin(), ph.end(), "valve.command_on");
  const auto off = std::find(ph.begin(), ph.end(), "valve.command_off");
  ASSERT_NE(on, ph.end());
  ASSERT_NE(off, ph.end());
  EXPECT_LT(on, off);
}

}  // namespace
}  // namespace pneumo
