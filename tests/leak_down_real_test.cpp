// netlists/real/tudelft_leak_down.yaml with its fitted leak (ISO 6358 C, b,
// a linear part above r_lam, the wall's heat conductance; C per litre)
// reproduces the measured leak-down of the printed chamber Ultimaker_015
// (tests/data/tudelft/Ultimaker_015.csv, CC0): 7.66 -> 0.08 bar gauge.
//
// Bound 0.04 bar RMS: the fit reaches 0.027 bar; the sensor's resolution is
// 1 mbar and its noise a few mbar, so what remains is model error (one lumped
// gap law, one wall conductance). An isothermal chamber (the wall's
// conductance 1000x) gives 0.27 bar and a gap conductance 20 % low 0.32 bar: the
// bound tells the fitted law from those.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "framework/io/data_file.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using test_support::run_cli;
using test_support::TempDir;

const std::string kSrc = PNEUMO_SOURCE_DIR;
const double kValveClosed = 7.15;  // s in the file: the last full-pressure sample 6.78 s, falling by 7.35 s

// RMS (bar) between the netlist, run with `sets`, and the measured curve.
double rms_against_measured(const std::string& sets) {
  TempDir dir;
  const auto out = (dir.path() / "leak.csv").string();
  const auto [rc, text] = run_cli("simulate '" + kSrc + "/netlists/real/tudelft_leak_down.yaml' -q -o '" + out +
                                  "' " + sets);
  EXPECT_EQ(rc, 0) << text;
  std::vector<double> ts, ps;
  std::ifstream f(out);
  std::string line;
  std::getline(f, line);  // header "t [s],p [UNIT]": the netlist's display unit
  const auto open = line.rfind('['), close = line.rfind(']');
  const std::string unit = open < close && close != std::string::npos ? line.substr(open + 1, close - open - 1) : "";
  while (std::getline(f, line)) {
    double t, p;
    if (std::sscanf(line.c_str(), "%lf,%lf", &t, &p) == 2) ts.push_back(t), ps.push_back(test_support::to_si(p, unit));
  }
  if (ts.size() < 2) return INFINITY;
  DataFileSpec spec;
  spec.file = kSrc + "/tests/data/tudelft/Ultimaker_015.csv";
  spec.separator = DataSeparator::semicolon;
  spec.header = false;
  spec.thousands = '.';
  spec.columns = {DataColumnSpec{"t", 1, "", "ms"}, DataColumnSpec{"p", 3, "", "bar g"}};
  const auto d = read_data_file(spec);
  double sum = 0;
  int n = 0;
  std::size_t j = 1;
  for (std::size_t i = 0; i < d.rows(); ++i) {
    const double t = d.values[0][i] - kValveClosed;
    if (t < 0.15 || t > ts.back()) continue;
    while (ts[j] < t) ++j;
    const double f = (t - ts[j - 1]) / (ts[j] - ts[j - 1]);
    const double sim = ps[j - 1] + f * (ps[j] - ps[j - 1]);
    sum += std::pow((sim - d.values[1][i]) / 1e5, 2);
    ++n;
  }
  EXPECT_GT(n, 1300);
  return std::sqrt(sum / n);
}

TEST(LeakDownReal, TheFittedLeakReproducesTheMeasuredDecayOfThePrintedChamber) {
  const double fitted = rms_against_measured("");
  std::printf("leak-down Ultimaker_015: RMS %.4f bar\n", fitted);
  EXPECT_LT(fitted, 0.04);
  // The bound can fail: the same netlist with the conductance 20 % off, or
  // an isothermal chamber, does not reproduce the curve.
  EXPECT_GT(rms_against_measured("--set 'C_leak=0.0324 dm3/(s*bar)'"), 0.04);
  EXPECT_GT(rms_against_measured("--set 'hA=77 W/(m2*K)'"), 0.04);
}

}  // namespace
}  // namespace pneumo
