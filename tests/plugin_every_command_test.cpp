// A netlist whose component comes from a plugin (the README's example seal,
// tests/plugins/plugins.cmake builds it) runs under every command that
// runs netlists, not only `pneumo simulate` (issue #31): sweep, sensitivity,
// optimize and diagnose each run every point, with finite results that
// follow the seal's physics (a wider gap leaks faster: the tank's pressure
// after 1 s falls as the gap widens). And a sweep whose every run fails
// exits non-zero: 2, with the netlist's own error, when the netlist as
// written is refused; 1 when only the runs fail.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "framework/study/sweep.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

const std::string kPlugin = (fs::path(PNEUMO_TEST_PLUGIN_DIR) / "seal_leakage.so").string();

// examples/custom_component/seal_leakage.yaml, shortened to 1 s, with
// metrics unless `metrics` is false.
std::string seal_tank(const std::string& h_gap, const std::string& seal_type = "seal_leakage", bool metrics = true) {
  return "plugins: [" + kPlugin + "]\n"
         "parameters:\n"
         "  V_tank: 0.1 L\n"
         "  p_start: 6 bar\n"
         "  h_gap: " + h_gap + "\n"
         "components:\n"
         "  tank: {type: volume, V: V_tank, p0: p_start, T0: 293.15 K}\n"
         "  seal: {type: " + seal_type + ", d: 20 mm, h: h_gap, L: 5 mm}\n"
         "  air:  {type: atmosphere}\n"
         "  film: {type: heat_convection, alpha: 1e5 W/(m2*K), A: 0.1 m2}\n"
         "  wall: {type: fixed_temperature, T: 293.15 K}\n"
         "connections:\n"
         "  - [tank.port, seal.a]\n"
         "  - [seal.b, air.port]\n"
         "  - [tank.heat, film.a]\n"
         "  - [film.b, wall.port]\n"
         "outputs: {p: tank.p, m_leak: seal.m_flow}\n" +
         std::string(metrics ? "metrics:\n  p_end: {final: p}\n  m_leak_max: {max: m_leak}\n" : "") +
         "simulation: {t_end: 1 s, output_interval: 10 ms}\n";
}

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

double number(const std::string& cell) {
  std::size_t used = 0;
  const double v = std::stod(cell, &used);
  return used == cell.size() ? v : NAN;
}

// The column whose header starts with `name`.
int column_of(const study::SweepTable& t, const std::string& name) {
  for (std::size_t j = 0; j < t.columns.size(); ++j)
    if (t.columns[j].rfind(name, 0) == 0) return static_cast<int>(j);
  return -1;
}

// Every run of a sweep's results ok, its metrics finite; the final pressure
// per run, in run order.
std::vector<double> final_pressures(const std::string& csv, std::size_t runs) {
  const study::SweepTable t = study::read_sweep_csv(csv);
  const int p_end = column_of(t, "p_end"), m_leak = column_of(t, "m_leak_max");
  EXPECT_GE(p_end, 0);
  EXPECT_GE(m_leak, 0);
  EXPECT_EQ(t.rows.size(), runs);
  std::vector<double> p;
  for (const auto& row : t.rows) {
    EXPECT_EQ(row[1], "ok") << row.back();
    if (p_end < 0 || m_leak < 0 || row[1] != "ok") continue;
    EXPECT_TRUE(std::isfinite(number(row[m_leak])) && number(row[m_leak]) > 0) << row[m_leak];
    p.push_back(number(row[p_end]));
    EXPECT_TRUE(std::isfinite(p.back())) << row[p_end];
  }
  return p;
}

TEST(PluginEveryCommand, SweepRunsEveryPointAndAWiderGapLeavesLessPressure) {
  TempDir dir;
  const std::string net = dir.write("seal.yaml", seal_tank("15 um"));
  const std::string out = (dir.path() / "s.csv").string();
  const auto [rc, text] = run_cli("sweep '" + net + "' --grid h_gap=10um:20um:3 -q -o '" + out + "'");
  ASSERT_EQ(rc, 0) << text;
  const std::vector<double> p = final_pressures(out, 3);
  ASSERT_EQ(p.size(), 3u);
  // Below the start (6 bar), above the atmosphere, and falling as the gap widens.
  EXPECT_LT(p[0], 6e5);
  EXPECT_GT(p[2], 101325.0);
  EXPECT_GT(p[0], p[1]);
  EXPECT_GT(p[1], p[2]);
}

TEST(PluginEveryCommand, SensitivityRunsEveryPointAndThePressureFallsWithTheGap) {
  TempDir dir;
  const std::string net = dir.write("seal.yaml", seal_tank("15 um"));
  const std::string out = (dir.path() / "i.csv").string();
  const auto [rc, text] = run_cli("sensitivity '" + net + "' --param h_gap=10um:20um --param V_tank=0.08L:0.12L "
                                  "--trajectories 2 --metrics p_end,m_leak_max -q -o '" + out + "'");
  ASSERT_EQ(rc, 0) << text;
  (void)final_pressures((dir.path() / "i.runs.csv").string(), 2 * (2 + 1));
  // metric,parameter,mu_star,mu,sigma,effects: the final pressure's mean
  // effect of the gap is negative (a wider gap leaks more), of the volume
  // positive (a larger tank empties slower).
  std::ifstream in(out);
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (cells.size() != 6 || cells[0] == "metric") continue;
    ++rows;
    for (int k = 2; k <= 4; ++k) EXPECT_TRUE(std::isfinite(number(cells[k]))) << line;
    if (cells[0] == "p_end" && cells[1] == "h_gap") {
      EXPECT_LT(number(cells[3]), 0) << line;
    }
    if (cells[0] == "p_end" && cells[1] == "V_tank") {
      EXPECT_GT(number(cells[3]), 0) << line;
    }
  }
  EXPECT_EQ(rows, 4) << "two metrics times two parameters";
}

// The numbers in the `values: [...]` list of metric `name` in an optimize result.
std::vector<double> values_of(const std::string& yaml, const std::string& name) {
  std::vector<double> out;
  const auto at = yaml.find("  " + name + ": {");
  if (at == std::string::npos) return out;
  const auto open = yaml.find("values: [", at), close = yaml.find(']', open);
  if (open == std::string::npos || close == std::string::npos) return out;
  std::stringstream ss(yaml.substr(open + 9, close - open - 9));
  for (std::string c; std::getline(ss, c, ',');) out.push_back(number(c.substr(c.find_first_not_of(' '))));
  return out;
}

TEST(PluginEveryCommand, OptimizeRunsEverySampleAndWidensTheGapToEmptyTheTank) {
  TempDir dir;
  const std::string net = dir.write("seal.yaml", seal_tank("15 um"));
  const std::string out = (dir.path() / "o.yaml").string();
  const auto [rc, text] = run_cli("optimize '" + net + "' --design h_gap=10um:20um --minimize p_end "
                                  "--uncertain p_start=uniform:5bar:6bar --samples 3 --max-evaluations 6 -q -o '" +
                                  out + "'");
  ASSERT_EQ(rc, 0) << text;
  const std::string yaml = read_file(out);
  EXPECT_TRUE(has(yaml, "found: true")) << yaml;
  const std::vector<double> p = values_of(yaml, "p_end");
  ASSERT_EQ(p.size(), 3u) << yaml;
  for (double v : p) EXPECT_TRUE(std::isfinite(v) && v > 101325.0 && v < 6e5) << yaml;
  // The final pressure falls as the gap widens: the optimum lies in the
  // upper half of the range (DIRECT's first points are its centre and thirds).
  const auto at = yaml.find("h_gap: {value: ");
  ASSERT_NE(at, std::string::npos) << yaml;
  EXPECT_GT(number(yaml.substr(at + 15, yaml.find(',', at) - at - 15)), 15e-6) << yaml;
}

// Runs measured on the tank whose seal is worn to 19 um (the model says 15):
// a calibration run from 6 bar and a validation run from 4 bar, with noise.
void measured_runs(const fs::path& dir) {
  fs::create_directories(dir);
  TempDir truth_dir;
  std::mt19937 rng(5);
  for (const auto& [name, role, p0] : {std::tuple{"cal", "calibration", "6bar"}, {"val", "validation", "4bar"}}) {
    const std::string truth = truth_dir.write(std::string(name) + ".yaml", seal_tank("19 um"));
    const std::string csv = (truth_dir.path() / (std::string(name) + ".csv")).string();
    const auto [rc, text] = run_cli("simulate '" + truth + "' --set p_start=" + p0 + " -q -o '" + csv + "'");
    ASSERT_EQ(rc, 0) << text;
    std::ifstream in(csv);
    std::ofstream data(dir / (std::string(name) + ".csv"));
    data << "t,p\n";
    data.precision(10);
    std::normal_distribution<double> noise(0, 1e3);
    std::string line;
    std::getline(in, line);  // t,p,m_leak
    while (std::getline(in, line)) {
      std::stringstream ss(line);
      std::string t, p;
      std::getline(ss, t, ',');
      std::getline(ss, p, ',');
      data << t << "," << number(p) + noise(rng) << "\n";
    }
    std::ofstream(dir / (std::string(name) + ".yaml"))
        << "data: " << name << ".csv\nrole: " << role << "\noperating_point:\n  p_start: " << p0 << "\n";
  }
}

TEST(PluginEveryCommand, DiagnoseRunsThePluginModelAndNamesTheWornSeal) {
  TempDir dir;
  const std::string net = dir.write("seal.yaml", seal_tank("15 um"));
  measured_runs(dir.path() / "runs");
  const auto [rc, text] = run_cli("diagnose '" + net + "' --runs '" + (dir.path() / "runs").string() + "' --out '" +
                                  (dir.path() / "report").string() + "' --faults seal,p --max-effects 1 -q");
  ASSERT_EQ(rc, 0) << text;
  EXPECT_TRUE(has(text, "seal.worn")) << text;
  // "validation gap BEFORE -> AFTER (noise = 1)": both finite, the worn seal
  // brings it down.
  const auto at = text.find("\nvalidation gap ");
  ASSERT_NE(at, std::string::npos) << text;
  std::stringstream ss(text.substr(at + 16));
  double before = NAN, after = NAN;
  std::string arrow;
  ss >> before >> arrow >> after;
  EXPECT_TRUE(std::isfinite(before) && std::isfinite(after)) << text;
  EXPECT_LT(after, before) << text;
  EXPECT_TRUE(fs::exists(dir.path() / "report" / "report.json"));
}

TEST(PluginEveryCommand, ASweepWhoseEveryRunFailsExitsNonZero) {
  TempDir dir;
  // A type no registry has (and no metrics, which would find it before
  // the runs): every run fails, and the netlist itself is refused, status
  // 2, with the line that names the type.
  const std::string bad = dir.write("bad.yaml", seal_tank("15 um", "seal_leakagee", false));
  const auto [rc, text] = run_cli("sweep '" + bad + "' --grid h_gap=10um:20um:2 -q -o '" +
                                  (dir.path() / "b.csv").string() + "'");
  EXPECT_EQ(rc, 2) << text;
  EXPECT_TRUE(has(text, "every run failed")) << text;
  EXPECT_TRUE(has(text, "unknown component type 'seal_leakagee'")) << text;
  EXPECT_TRUE(has(text, "bad.yaml:")) << text;
  // A netlist that is fine whose every grid point is not (a negative gap):
  // the runs fail, status 1, with their reason.
  const std::string good = dir.write("good.yaml", seal_tank("15 um"));
  const auto [rc2, text2] = run_cli("sweep '" + good + "' --grid h_gap=-2um:-1um:2 --metrics p_end -q -o '" +
                                    (dir.path() / "g.csv").string() + "'");
  EXPECT_EQ(rc2, 1) << text2;
  EXPECT_TRUE(has(text2, "every run failed")) << text2;
}

}  // namespace
}  // namespace pneumo
