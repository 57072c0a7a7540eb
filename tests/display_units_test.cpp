// What people read is in the units they think in, and a label never differs
// from its value (issue #30): a netlist-wide `display:` shows outputs,
// metrics and plots in bar g, mm and degC while the solver stays SI; a
// metric that is undefined says why; several runs overlay in one plot; a
// cylinder's wall heat with nothing connected to its heat ports is a wall at
// the ambient temperature, not a silent no-op.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "framework/io/results.hpp"
#include "test_support.hpp"

namespace pneumo {
namespace {

using test_support::column;
using test_support::read_file;
using test_support::replace_once;
using test_support::run_cli;
using test_support::run_text;
using test_support::TempDir;

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

constexpr double kAmbient = 101325.0;

// A cylinder extending against a load from a 6 bar g supply, the rod side
// vented; the ambient is not the standard one, so that a gauge display that
// used 1.01325 bar would show.
const std::string kCylinder = R"(ambient: {p: 0.98 bar, T: 293.15 K}
components:
  supply: {type: pressure_source, p: 6 bar g, T: 293.15 K}
  inlet:  {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  cyl:    {type: cylinder, bore: 32 mm, rod: 12 mm, stroke: 100 mm}
  outlet: {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.3}
  air:    {type: atmosphere}
  load:   {type: translational_mass, m: 2 kg}
connections:
  - [supply.port, inlet.a]
  - [inlet.b, cyl.cap]
  - [cyl.rod, outlet.a]
  - [outlet.b, air.port]
  - [cyl.flange, load.flange]
outputs:
  x: cyl.x
  p: cyl.p_cap
  p_abs: {var: cyl.p_cap, unit: bar}
  T: cyl.T_cap
metrics:
  p_peak: {max: p}
  p_low: {min: p}
  swing: {expr: "p_peak - p_low"}
  t_out: {event: cyl.extended}
simulation: {t_end: 1 s, output_interval: 1 ms}
)";
constexpr double kLocalAmbient = 0.98e5;

const std::string kDisplay = "display: {pressure: barg, length: mm, temperature: degC, time: ms}\n";

// The number printed after "metric NAME = " and the unit after it.
std::pair<double, std::string> printed_metric(const std::string& out, const std::string& name) {
  const std::string key = "metric " + name + " = ";
  const auto at = out.find(key);
  if (at == std::string::npos) return {NAN, "missing"};
  const auto end = out.find('\n', at);
  const std::string rest = out.substr(at + key.size(), end - at - key.size());
  std::size_t used = 0;
  const double v = std::stod(rest, &used);
  const auto unit_end = rest.find(' ', used + 1);
  return {v, rest.substr(used + 1, unit_end == std::string::npos ? std::string::npos : unit_end - used - 1)};
}

TEST(DisplayUnits, ANetlistWideDisplayShowsOutputsInBarGaugeMillimetresAndDegreesCelsius) {
  TempDir dir;
  const std::string si = dir.write("si.yaml", kCylinder), shown = dir.write("shown.yaml", kDisplay + kCylinder);
  const auto [s1, out_si] = run_cli("simulate '" + si + "' -o '" + (dir.path() / "si.csv").string() + "'");
  const auto [s2, out] = run_cli("simulate '" + shown + "' -o '" + (dir.path() / "shown.csv").string() + "'");
  ASSERT_EQ(s1, 0) << out_si;
  ASSERT_EQ(s2, 0) << out;
  const ResultsTable a = read_csv((dir.path() / "si.csv").string());
  const ResultsTable b = read_csv((dir.path() / "shown.csv").string());
  ASSERT_EQ(a.rows.size(), b.rows.size());
  const std::vector<std::pair<std::string, std::string>> expected_units{
      {"t", "s"}, {"x", "mm"}, {"p", "barg"}, {"p_abs", "bar"}, {"T", "degC"}};
  for (const auto& [name, unit] : expected_units) EXPECT_EQ(b.units[b.column(name)], unit) << name;
  const auto x = column(a, "x"), p = column(a, "p"), T = column(a, "T");
  const auto x_mm = column(b, "x"), p_g = column(b, "p"), p_bar = column(b, "p_abs"), T_c = column(b, "T");
  double stroke_mm = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    // Within the 10 significant digits a results file holds.
    EXPECT_NEAR(x_mm[i], 1e3 * x[i], 1e-6) << i;
    EXPECT_NEAR(p_g[i], (p[i] - kLocalAmbient) / 1e5, 1e-8) << i;  // gauge on the netlist's ambient
    EXPECT_NEAR(p_bar[i], p[i] / 1e5, 1e-8) << i;
    EXPECT_NEAR(T_c[i], T[i] - 273.15, 1e-6) << i;
    stroke_mm = std::max(stroke_mm, x_mm[i]);
  }
  EXPECT_NEAR(stroke_mm, 100.0, 0.5);  // the piston reached its stop: the values are those of a real stroke

  // An output's extreme is shown as the output; a difference of pressures
  // is not a gauge pressure, so it is shown in bar, and an event time in ms.
  double hi = -1e300, lo = 1e300;
  for (double v : p) hi = std::max(hi, v), lo = std::min(lo, v);
  const auto [peak, peak_unit] = printed_metric(out, "p_peak");
  EXPECT_EQ(peak_unit, "barg") << out;
  EXPECT_NEAR(peak, (hi - kLocalAmbient) / 1e5, 1e-5) << out;
  const auto [swing, swing_unit] = printed_metric(out, "swing");
  EXPECT_EQ(swing_unit, "bar") << out;
  EXPECT_NEAR(swing, (hi - lo) / 1e5, 1e-5) << out;
  const auto [t_si, t_si_unit] = printed_metric(out_si, "t_out");
  const auto [t_ms, t_ms_unit] = printed_metric(out, "t_out");
  EXPECT_EQ(t_si_unit, "s") << out_si;
  EXPECT_EQ(t_ms_unit, "ms") << out;
  EXPECT_NEAR(t_ms, 1e3 * t_si, 1e-3 * t_ms) << out;
}

// The README's main command (the first picture a newcomer sees) plots the
// rig in bar g, mm and degC.
TEST(DisplayUnits, TheMainCommandOfTheReadmePlotsInBarGaugeMillimetresAndDegreesCelsius) {
  const std::string src = PNEUMO_SOURCE_DIR;
  const std::string readme = read_file(src + "/README.md");
  const auto block = readme.find("<!-- main-command -->");
  ASSERT_NE(block, std::string::npos);
  const auto start = readme.find("./build/pneumo simulate", block);
  ASSERT_NE(start, std::string::npos);
  std::string args = readme.substr(start + std::string("./build/pneumo ").size());
  args = args.substr(0, args.find('\n'));
  TempDir dir;
  for (std::string::size_type at; (at = args.find("out/")) != std::string::npos;)
    args.replace(at, 4, dir.path().string() + "/");
  args = replace_once(args, "netlists/", src + "/netlists/");
  const auto [status, out] = run_cli(args);
  ASSERT_EQ(status, 0) << args << "\n" << out;
  const ResultsTable table = read_csv((dir.path() / "cushion_rig.csv").string());
  EXPECT_EQ(table.units[table.column("x")], "mm");
  EXPECT_EQ(table.units[table.column("p_A")], "barg");
  EXPECT_EQ(table.units[table.column("T_EC")], "degC");
  const std::string svg = read_file(dir.path() / "cushion_rig.svg");
  for (const char* label : {"x [mm]", "p_A [barg]", "p_EC [barg]", "T_EC [degC]"}) EXPECT_TRUE(has(svg, label)) << label;
  // The rig's 100 mm stroke, travelled, in millimetres.
  double x_max = 0;
  for (double x : column(table, "x")) x_max = std::max(x_max, x);
  EXPECT_NEAR(x_max, 100.0, 1.0);
}

TEST(DisplayUnits, AnUnknownQuantityOrAUnitOfAnotherQuantityIsRefusedAtItsLine) {
  TempDir dir;
  const std::string wrong_unit = dir.write("a.yaml", "display: {pressure: barg,\n          length: bar}\n" + kCylinder);
  const auto [s1, out1] = run_cli("simulate '" + wrong_unit + "' -o '" + (dir.path() / "a.csv").string() + "'");
  EXPECT_EQ(s1, 2) << out1;
  EXPECT_TRUE(has(out1, "a.yaml:2:")) << out1;
  EXPECT_TRUE(has(out1, "display: length")) << out1;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "a.csv"));

  const std::string unknown = dir.write("b.yaml", "display:\n  presure: barg\n" + kCylinder);
  const auto [s2, out2] = run_cli("simulate '" + unknown + "' -o '" + (dir.path() / "b.csv").string() + "'");
  EXPECT_EQ(s2, 2) << out2;
  EXPECT_TRUE(has(out2, "b.yaml:2:")) << out2;
  EXPECT_TRUE(has(out2, "did you mean 'pressure'")) << out2;
}

TEST(UndefinedMetrics, ANanMetricSaysWhatTheRunDidNotDo) {
  TempDir dir;
  std::string text = kDisplay + kCylinder;
  text = replace_once(text, "  t_out: {event: cyl.extended}\n",
                      "  t_out: {event: cyl.extended}\n"
                      "  t_9bar: {of: p, crosses: 9 bar g, direction: rising}\n"
                      "  t_back: {event: cyl.extended, n: 9}\n"
                      "  late: {expr: \"t_back - t_out\"}\n");
  const std::string path = dir.write("nan.yaml", text);
  const auto [status, out] = run_cli("simulate '" + path + "' -o '" + (dir.path() / "nan.csv").string() + "'");
  ASSERT_EQ(status, 0) << out;
  EXPECT_TRUE(has(out, "metric t_9bar = nan ms (undefined: p never rose through 9 barg)")) << out;
  EXPECT_TRUE(has(out, "metric t_back = nan ms (undefined: event cyl.extended happened ")) << out;
  EXPECT_TRUE(has(out, ", not 9)")) << out;
  EXPECT_TRUE(has(out, "metric late = nan ms (undefined: it uses t_back, which is undefined)")) << out;
  EXPECT_FALSE(has(printed_metric(out, "t_out").second, "undefined")) << out;
}

TEST(PlotOverlay, TwoRunsShareOnePlotEachCurveNamedByItsFile) {
  TempDir dir;
  const std::string six = dir.write("six_bar.yaml", kDisplay + kCylinder);
  const std::string four = dir.write("four_bar.yaml", kDisplay + replace_once(kCylinder, "p: 6 bar g", "p: 4 bar g"));
  const std::string si = dir.write("in_si.yaml", kCylinder);
  for (const std::string& n : {six, four, si}) {
    const std::string csv = std::filesystem::path(n).replace_extension(".csv").string();
    const auto [status, out] = run_cli("simulate '" + n + "' -q -o '" + csv + "'");
    ASSERT_EQ(status, 0) << out;
  }
  const std::string a = (dir.path() / "six_bar.csv").string(), b = (dir.path() / "four_bar.csv").string();
  const std::string prefix = (dir.path() / "compare").string();
  const auto [status, out] = run_cli("plot '" + a + "' '" + b + "' -o '" + prefix + "' --columns x,p");
  ASSERT_EQ(status, 0) << out;
  const std::string svg = read_file(prefix + ".svg");
  EXPECT_TRUE(has(svg, "six_bar")) << "legend of the first file";
  EXPECT_TRUE(has(svg, "four_bar")) << "legend of the second file";
  EXPECT_TRUE(has(svg, "p [barg]"));

  // Millimetres beside metres are converted; a gauge pressure beside an
  // absolute one cannot be without the ambient pressure, which a file does
  // not hold: refused, nothing written.
  const std::string c = (dir.path() / "in_si.csv").string();
  const auto [s2, out2] = run_cli("plot '" + a + "' '" + c + "' -o '" + prefix + "_x' --columns x");
  EXPECT_EQ(s2, 0) << out2;
  const auto [s3, out3] = run_cli("plot '" + a + "' '" + c + "' -o '" + prefix + "_p' --columns p");
  EXPECT_EQ(s3, 2) << out3;
  EXPECT_TRUE(has(out3, "gauge")) << out3;
  EXPECT_FALSE(std::filesystem::exists(prefix + "_p.svg"));
  // Several files need a name for the one plot they make.
  const auto [s4, out4] = run_cli("plot '" + a + "' '" + b + "'");
  EXPECT_EQ(s4, 2) << out4;
  EXPECT_TRUE(has(out4, "-o PREFIX")) << out4;
}

// A cylinder given a gas-to-wall heat transfer coefficient with its heat
// ports unconnected exchanges heat with walls at the ambient temperature:
// the same run as with both ports connected to a fixed ambient temperature,
// and not the adiabatic run (where the compressed gas stays hot).
TEST(WallHeat, UnconnectedHeatPortsOfACylinderWithWallAlphaAreWallsAtTheAmbientTemperature) {
  const std::string walls = replace_once(kCylinder, "stroke: 100 mm}", "stroke: 100 mm, wall_alpha: 200 W/(m2*K)}");
  std::string fixed = replace_once(walls, "  load:", "  wall_cap: {type: fixed_temperature}\n"
                                                    "  wall_rod: {type: fixed_temperature}\n  load:");
  fixed = replace_once(fixed, "  - [cyl.flange, load.flange]\n",
                       "  - [cyl.flange, load.flange]\n  - [cyl.heat_cap, wall_cap.port]\n"
                       "  - [cyl.heat_rod, wall_rod.port]\n");
  const RunResult open = run_text(walls, "open.yaml");
  const RunResult held = run_text(fixed, "held.yaml");
  const RunResult adiabatic = run_text(kCylinder, "adiabatic.yaml");
  const auto T_open = column(open.table, "T"), T_held = column(held.table, "T"), T_adiabatic = column(adiabatic.table, "T");
  ASSERT_EQ(T_open.size(), T_held.size());
  double apart = 0;
  for (std::size_t i = 0; i < T_open.size(); ++i) {
    EXPECT_NEAR(T_open[i], T_held[i], 1e-6) << i;
    apart = std::max(apart, std::abs(T_open[i] - T_adiabatic[std::min(i, T_adiabatic.size() - 1)]));
  }
  EXPECT_GT(apart, 1.0) << "wall heat made no difference";
}

}  // namespace
}  // namespace pneumo
