// A metric's unit converts (issue #30): `unit: ms` on a time shows 1000 x its
// seconds, `unit: barg` on a pressure shows gauge bar, a metric of an output
// declared in barg is shown in barg, and a unit of another dimension is an
// error (exit 2) naming the metric. The same numbers reach the printed
// metrics, --metrics-out and a sweep's results, and the `final:` line shows
// the outputs' display units.
//
// The circuit: a 1 L tank filled adiabatically from 3 bar (absolute) through
// a throttle for 2 s; it ends at the supply pressure, 3 bar = 1.98675 barg
// with the ambient 101325 Pa. Event-free, so the times are plain numbers.
#include <gtest/gtest.h>

#include <map>
#include <sstream>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

const std::string kTank = R"(
parameters:
  p_supply: 3 bar
components:
  source: {type: pressure_source, p: p_supply, T: 293.15 K}
  valve:  {type: iso6358_throttle, C: 0.4 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 1 L, p0: 1 bar, T0: 293.15 K}
connections:
  - [source.port, valve.a]
  - [valve.b, tank.port]
outputs:
  p: tank.p
  p_g: {var: tank.p, unit: barg}
metrics:
  t_half: {of: p, crosses: 2 bar, direction: rising}
  t_half_ms: {expr: "t_half", unit: ms}
  p_end_barg: {final: p, unit: barg}
  p_end_shown: {final: p_g}
  PLACEHOLDER
simulation: {t_end: 2 s, rtol: 1e-8, atol: 1e-8, output_interval: 10 ms}
)";

std::string netlist(const std::string& extra = "") {
  std::string s = kTank;
  s.replace(s.find("PLACEHOLDER"), 11, extra.empty() ? "p_end: {final: p}" : extra);
  return s;
}

// "metric NAME = VALUE UNIT" lines of the printed output.
std::map<std::string, std::pair<double, std::string>> printed_metrics(const std::string& out) {
  std::map<std::string, std::pair<double, std::string>> m;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("metric ", 0) != 0) continue;
    std::istringstream l(line.substr(7));
    std::string name, eq, unit;
    double v = 0;
    l >> name >> eq >> v >> unit;
    m[name] = {v, unit};
  }
  return m;
}

constexpr double kBarg = (3e5 - 101325.0) / 1e5;  // the supply, gauge

TEST(MetricUnits, PrintedMetricsAreConvertedToTheirUnit) {
  TempDir dir;
  const std::string nl = dir.write("tank.yaml", netlist());
  const auto [status, out] = run_cli("simulate '" + nl + "' -o '" + dir.path().string() + "/r.csv' --metrics-out '" +
                                     dir.path().string() + "/m.csv'");
  ASSERT_EQ(status, 0) << out;
  const auto m = printed_metrics(out);
  ASSERT_TRUE(m.count("t_half") && m.count("t_half_ms")) << out;
  EXPECT_EQ(m.at("t_half").second, "s");
  EXPECT_EQ(m.at("t_half_ms").second, "ms");
  EXPECT_NEAR(m.at("t_half_ms").first, 1000.0 * m.at("t_half").first, 1e-3 * m.at("t_half").first) << out;
  EXPECT_GT(m.at("t_half").first, 0.001);
  EXPECT_LT(m.at("t_half").first, 2.0);
  EXPECT_EQ(m.at("p_end_barg").second, "barg");
  EXPECT_NEAR(m.at("p_end_barg").first, kBarg, 1e-4) << out;
  EXPECT_EQ(m.at("p_end_shown").second, "barg");  // the output's unit
  EXPECT_NEAR(m.at("p_end_shown").first, kBarg, 1e-4) << out;
  EXPECT_EQ(m.at("p_end").second, "Pa");
  EXPECT_NEAR(m.at("p_end").first, 3e5, 10.0);

  // --metrics-out holds the same numbers under the same labels.
  const std::string csv = read_file(dir.path() / "m.csv");
  std::istringstream in(csv);
  std::map<std::string, std::pair<double, std::string>> written;
  for (std::string line; std::getline(in, line);) {
    const auto a = line.find(','), b = line.rfind(',');
    if (a == std::string::npos || line.rfind("metric,", 0) == 0) continue;
    written[line.substr(0, a)] = {std::stod(line.substr(a + 1, b - a - 1)), line.substr(b + 1)};
  }
  EXPECT_EQ(written.at("t_half_ms").second, "ms");
  EXPECT_NEAR(written.at("t_half_ms").first, m.at("t_half_ms").first, 1e-4 * m.at("t_half_ms").first);
  EXPECT_EQ(written.at("p_end_barg").second, "barg");
  EXPECT_NEAR(written.at("p_end_barg").first, kBarg, 1e-4);

  // The final: line shows p_g in barg, p in Pa.
  const auto f = out.find("final:");
  ASSERT_NE(f, std::string::npos) << out;
  const std::string final_line = out.substr(f, out.find('\n', f) - f);
  const auto g = final_line.find("p_g=");
  ASSERT_NE(g, std::string::npos) << final_line;
  EXPECT_NEAR(std::stod(final_line.substr(g + 4)), kBarg, 1e-4) << final_line;
  EXPECT_NE(final_line.find(" barg"), std::string::npos) << final_line;
}

TEST(MetricUnits, AUnitOfAnotherDimensionIsRefusedNamingTheMetric) {
  TempDir dir;
  for (const std::string bad : {"wrong: {expr: \"t_half\", unit: bar}", "wrong: {final: p, unit: ms}"}) {
    const std::string nl = dir.write("tank.yaml", netlist(bad));
    const auto [status, out] = run_cli("simulate '" + nl + "' -o '" + dir.path().string() + "/r.csv'");
    EXPECT_EQ(status, 2) << bad << "\n" << out;
    EXPECT_NE(out.find("metric 'wrong'"), std::string::npos) << out;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "r.csv")) << "nothing half-written";
  }
}

TEST(MetricUnits, SweepResultsShowTheSameConvertedValues) {
  TempDir dir;
  const std::string nl = dir.write("tank.yaml", netlist());
  const std::string res = dir.path().string() + "/s.csv";
  const auto [status, out] = run_cli("sweep '" + nl + "' --grid 'p_supply=3 bar:3.5 bar:2' --metrics t_half,t_half_ms,p_end_barg -o '" +
                                     res + "'");
  ASSERT_EQ(status, 0) << out;
  std::istringstream in(read_file(res));
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_NE(header.find("t_half_ms [ms]"), std::string::npos) << header;
  EXPECT_NE(header.find("p_end_barg [barg]"), std::string::npos) << header;
  // run,status,p_supply,t_half,t_half_ms,p_end_barg,...
  std::vector<std::string> cells;
  std::istringstream r(row);
  for (std::string c; std::getline(r, c, ',');) cells.push_back(c);
  ASSERT_GE(cells.size(), 6u) << row;
  EXPECT_NEAR(std::stod(cells[4]), 1000.0 * std::stod(cells[3]), 1e-6 * std::stod(cells[4])) << row;
  EXPECT_NEAR(std::stod(cells[5]), kBarg, 1e-4) << row;
}

}  // namespace
}  // namespace pneumo
