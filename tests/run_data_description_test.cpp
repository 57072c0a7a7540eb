// A run file's `data:` may describe a lab file as it comes (no header,
// semicolons, '.' as thousands separator and decimal mark, ms and bar
// gauge): the diagnosis reads the same samples as from an SI CSV.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "components/builtin.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

const std::string kTank = R"(
ambient: {p: 0.95 bar}
components:
  supply: {type: pressure_source, p: 6 bar, T: 293.15 K}
  valve: {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.3}
  tank: {type: volume, V: 0.5 L, p0: 1 atm, T0: 293.15 K}
connections:
  - [supply.port, valve.a]
  - [valve.b, tank.port]
outputs: {p: tank.p, T: tank.T}
simulation: {t_end: 2.5 s, output_interval: 2 ms}
)";

double p_of(double t) { return 1e5 + 4e5 * (1 - std::exp(-t / 0.2)); }

// "1.234.500" for 1234.5 ms: three decimals, '.' grouping the thousands.
std::string lab_ms(double ms) {
  char buf[64];
  const long long whole = static_cast<long long>(ms), thousandths = std::llround((ms - whole) * 1000);
  if (whole >= 1000)
    std::snprintf(buf, sizeof buf, "%lld.%03lld.%03lld", whole / 1000, whole % 1000, thousandths);
  else
    std::snprintf(buf, sizeof buf, "%lld.%03lld", whole, thousandths);
  return buf;
}

struct Folder {
  TempDir dir;
  fs::path runs() const { return dir.path() / "runs"; }
  Folder(const std::string& description) {
    fs::create_directories(runs());
    std::ofstream lab(runs() / "lab.csv"), si(runs() / "val.csv");
    si << "t,p,T\n";
    for (int i = 0; i <= 200; ++i) {
      const double t = 0.01 * i;
      char row[128];
      // raw volts (unused), bar gauge against the model's 0.95 bar ambient
      std::snprintf(row, sizeof row, "%s;%.3f;%.5f\n", lab_ms(1e3 * t).c_str(), 1.7, (p_of(t) - 0.95e5) / 1e5);
      lab << row;
      si << t << "," << p_of(t) << ",293.15\n";
    }
    std::ofstream(runs() / "cal.yaml") << description;
    std::ofstream(runs() / "val.yaml") << "data: val.csv\nrole: validation\n";
  }
  std::vector<diagnose::MeasuredRun> load() const {
    const Netlist nl = parse_netlist(kTank, "tank.yaml");
    return diagnose::load_runs(runs().string(), nl, elaborate(nl, builtin_registry()).probes, builtin_registry());
  }
};

const std::string kDescription = R"(role: calibration
data:
  file: lab.csv
  separator: semicolon
  header: no
  thousands: "."
  columns:
    t: {column: 1, unit: ms}
    p: {column: 3, unit: bar g}
)";

TEST(RunDataDescription, ALabFileIsReadAsItComesIntoSi) {
  const Folder f(kDescription);
  const auto runs = f.load();
  const auto& cal = runs[0].name == "cal" ? runs[0] : runs[1];
  ASSERT_EQ(cal.signals, std::vector<std::string>{"p"});
  ASSERT_EQ(cal.t.size(), 201u);
  EXPECT_DOUBLE_EQ(cal.t[150], 1.5);  // "1.500.000" ms
  for (std::size_t i = 0; i < cal.t.size(); ++i) EXPECT_NEAR(cal.y[0][i], p_of(cal.t[i]), 0.51);  // 5 decimals of bar
}

TEST(RunDataDescription, AnUnknownKeyOrAColumnThatIsNoOutputIsRefusedInTheRunFile) {
  std::string bad = kDescription;
  bad.replace(bad.find("header: no"), 10, "headers: no");
  try {
    (void)Folder(bad).load();
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("cal.yaml:5"), std::string::npos) << m;
    EXPECT_NE(m.find("unknown key 'headers'"), std::string::npos) << m;
  }
  std::string other = kDescription;
  other.replace(other.find("p: {column: 3"), 2, "q:");
  try {
    (void)Folder(other).load();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("column 'q' is no output of the model"), std::string::npos) << e.what();
  }
}

// A column read through a running median and line: the median leaves the
// monotone rise as it is, and the line through five 10 ms samples bends it
// by half its curvature times the window's mean square time offset,
// p'' x 2e-4 s^2 / 2 (9 mbar at the start), to the file's rounding; a
// window of an even number of samples is refused at its line.
TEST(RunDataDescription, AColumnsMedianAndLineAreReadAndAnEvenWindowIsRefusedAtItsLine) {
  std::string cleaned = kDescription;
  cleaned.replace(cleaned.find("unit: bar g}"), 12, "unit: bar g, median: 5, average: 5}");
  const auto runs = Folder(cleaned).load();
  const auto& cal = runs[0].name == "cal" ? runs[0] : runs[1];
  ASSERT_EQ(cal.t.size(), 201u);
  for (std::size_t i = 2; i + 2 < cal.t.size(); ++i) {
    const double curvature = -4e5 / 0.04 * std::exp(-cal.t[i] / 0.2);
    EXPECT_NEAR(cal.y[0][i], p_of(cal.t[i]) + curvature * 1e-4, 2.0) << "t = " << cal.t[i];
  }
  std::string even = kDescription;
  even.replace(even.find("unit: bar g}"), 12, "unit: bar g, median: 4}");
  try {
    (void)Folder(even).load();
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("cal.yaml:9"), std::string::npos) << m;
    EXPECT_NE(m.find("median: an odd number of samples"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace pneumo
