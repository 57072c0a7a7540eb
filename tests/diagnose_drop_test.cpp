// Issue #37, "near-null effects named, often first": with a leak planted,
// the verdict was "needle at k = 1.00002; leak". A tank filled and vented
// through a 3/2 valve leaks to the atmosphere. Candidates: the leak,
// written by its hole's diameter (conductance ~ d^2, no slope at its null),
// and the vent path's conductance (a re-calibration of valve.C_AR), which
// mimics the faster venting and screens a little better; with one full fit
// after the screen (screen_keep 1, as a long catalogue leaves the right
// effect outside the few fitted) the vent conductance is named first. When the leak joins in the second round, the joint
// fit takes the vent conductance back to about its setting: re-tested at
// its null beside the leak, it adds nothing significant and is dropped.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>

#include "components/builtin.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
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
outputs: {p: tank.p}
simulation: {t_end: 1.2 s, output_interval: 2 ms}
)";

// The leak as a hole of diameter d (mm): C = 0.1 d^2 dm3/(s*bar).
const std::string kCatalogue = R"CAT(
recalibrate:
  valve.C_AR: {}
effects:
  leak:
    description: leak from the tank to the atmosphere through a hole of diameter d (mm)
    parameters:
      d: {initial: 1.5, lower: 0, upper: 2, null: 0, unit: "1", scale: linear}
    add_components:
      leak_path: {type: iso6358_throttle, C: "${0.1 * d * d} dm3/(s*bar)", b: 0.3}
      leak_air: {type: atmosphere}
    connect:
      - [tank.port, leak_path.a]
      - [leak_path.b, leak_air.port]
)CAT";

constexpr double kHole = 0.55;  // mm: C = 0.03025 dm3/(s*bar)

void make_runs(const fs::path& dir) {
  fs::create_directories(dir);
  std::string truth = kModel;
  truth.replace(truth.find("connections:"), 12,
                "  true_leak: {type: iso6358_throttle, C: " + num(0.1 * kHole * kHole) +
                    " dm3/(s*bar), b: 0.3}\n  true_air: {type: atmosphere}\nconnections:\n"
                    "  - [tank.port, true_leak.a]\n  - [true_leak.b, true_air.port]");
  std::mt19937 rng(37);
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
    csv << "t,p\n";
    csv.precision(10);
    std::normal_distribution<double> np(0, 2e3);
    for (const auto& row : res.table.rows) csv << row[0] << "," << row[res.table.column("p")] + np(rng) << "\n";
    std::ofstream(dir / (std::string(r.name) + ".yaml"))
        << "data: " << r.name << ".csv\nrole: " << r.role << "\noperating_point:\n  p_supply: " << r.p << "\n";
  }
}

TEST(DiagnoseDrop, NearNullFirstPickIsDroppedOnceTheLeakJoins) {
  TempDir dir;
  const std::string model = dir.write("tank.yaml", kModel), catalogue = dir.write("catalogue.yaml", kCatalogue);
  make_runs(dir.path() / "runs");
  diagnose::DiagnoseOptions opt;
  opt.screen_keep = 1;
  std::string log;
  opt.log = [&](const std::string& line) { log += line + "\n"; };
  const auto rep = diagnose::diagnose(model, (dir.path() / "runs").string(), catalogue, builtin_registry(), opt);
  std::cout << "validation gap " << rep.validation_before.total.rms << " -> " << rep.validation_after.total.rms
            << ", verdict:";
  for (const auto& v : rep.verdict) std::cout << " " << v;
  std::cout << "\n";
  // The vent conductance was named first, then re-tested and dropped.
  EXPECT_NE(log.find("polishing valve.C_AR"), std::string::npos) << log;
  EXPECT_NE(log.find("re-test: valve.C_AR"), std::string::npos) << log;
  ASSERT_EQ(rep.verdict, std::vector<std::string>{"leak"}) << log;
  ASSERT_EQ(rep.final_values.size(), 1u);
  EXPECT_EQ(rep.final_values[0].first, "leak");
  EXPECT_NEAR(rep.final_values[0].second[0], kHole, 0.03 * kHole);
  EXPECT_LT(rep.validation_after.total.rms, 1.3);
}

}  // namespace
}  // namespace pneumo
