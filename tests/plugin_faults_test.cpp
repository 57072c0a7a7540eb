// A fault a plugin's component declares (issue #37): the example plugin's
// seal declares "worn" (its gap wider than built); diagnosing a tank that
// leaks through that seal, without a catalogue, names it among the
// pressure signal's measurement faults.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "components/builtin.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "framework/plugin/plugin.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

std::string tank(const std::string& plugin, const std::string& h) {
  return "plugins:\n  - " + plugin +
         "\nparameters:\n  p0: 6 bar\n"
         "components:\n"
         "  tank: {type: volume, V: 0.1 L, p0: p0}\n"
         "  seal: {type: seal_leakage, d: 20 mm, h: " + h + ", L: 5 mm}\n"
         "  air:  {type: atmosphere}\n"
         "connections:\n  - [tank.port, seal.a]\n  - [seal.b, air.port]\n"
         "outputs: {p: tank.p}\n"
         "simulation: {t_end: 2 s, output_interval: 4 ms}\n";
}

TEST(PluginFaults, AWornPluginSealIsNamedWithoutACatalogue) {
  TempDir dir;
  const std::string plugin = (fs::path(PNEUMO_TEST_PLUGIN_DIR) / "seal_leakage.so").string();
  const std::string model = dir.write("tank.yaml", tank(plugin, "15 um"));
  const Netlist truth = parse_netlist(tank(plugin, "19 um"), "truth.yaml");
  const Registry registry = registry_with_plugins(builtin_registry(), truth);
  ASSERT_FALSE(registry.find("seal_leakage")->info->faults.empty());
  fs::create_directories(dir.path() / "runs");
  std::mt19937 rng(5);
  for (const auto& [name, role, p0] : {std::tuple{"cal", "calibration", 6e5}, {"val", "validation", 4e5}}) {
    Netlist nl = truth;
    apply_override(nl, "p0=" + num(p0));
    const RunResult res = run_simulation(nl, registry);
    ASSERT_TRUE(res.solver.ok) << res.solver.message;
    std::ofstream csv(dir.path() / "runs" / (std::string(name) + ".csv"));
    csv << "t,p\n";
    csv.precision(10);
    std::normal_distribution<double> noise(0, 1e3);
    for (const auto& row : res.table.rows) csv << row[0] << "," << row[res.table.column("p")] + noise(rng) << "\n";
    std::ofstream(dir.path() / "runs" / (std::string(name) + ".yaml"))
        << "data: " << name << ".csv\nrole: " << role << "\noperating_point:\n  p0: " << p0 << "\n";
  }
  diagnose::DiagnoseOptions opt;
  opt.progress = false;
  opt.declared_faults = true;
  // The tank's volume would be the seal's double: the decay's time constant
  // goes with V / h^3, which no pressure trace separates.
  opt.faults = {"seal", "p"};
  const auto rep = diagnose::diagnose(model, (dir.path() / "runs").string(), "", builtin_registry(), opt);
  ASSERT_FALSE(rep.verdict.empty());
  EXPECT_EQ(rep.verdict[0], "seal.worn");
  for (const auto& [name, values] : rep.final_values)
    if (name == "seal.worn") {
      EXPECT_NEAR(values[0], 19.0 / 15.0, 0.05);
    }
}

}  // namespace
}  // namespace pneumo
