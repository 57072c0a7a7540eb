// pneumo fit friction on real rig data (TU Delft O-ring seal at 1, 3, 5 and
// 7 bar gauge, tests/data/tudelft/O-ring_*bar_head1000.csv: the first 1000
// lines of each shared file) and with a force offset.
//
// The friction points are made from the files as a user would: speed by a
// central difference of the laser position over +-2 samples (40 ms), the
// seal's force as load cell - p A (bore 25 mm), signed along the motion.
// On these data eq. 8's optimum puts the exponent a on its lower bound with
// kv |v|^a nearly collinear with b: the fit used to crawl along that bound
// for 500 iterations (52 s) and report NOT CONVERGED.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include "components/friction.hpp"
#include "components/fit/friction_fit.hpp"
#include "framework/io/data_file.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace pneumo::fit;
using test_support::run_cli;
using test_support::TempDir;

const std::string kDir = std::string(PNEUMO_SOURCE_DIR) + "/tests/data/tudelft/";
const double kPi = 3.14159265358979323846;
const double kArea = kPi * 0.0125 * 0.0125;  // bore 25 mm, m^2

// Signed points (v along the stroke, F = load cell - p A), pressure in bar gauge.
std::vector<FrictionPoint> oring_points() {
  std::vector<FrictionPoint> pts;
  for (int bar : {1, 3, 5, 7}) {
    DataFileSpec spec;
    spec.file = kDir + "O-ring_" + std::to_string(bar) + "bar_head1000.csv";
    spec.separator = DataSeparator::whitespace;
    spec.header = false;
    spec.skip_rows = 15;  // the start-up transient (README)
    spec.columns = {DataColumnSpec{"t", 1, "", "ms"}, DataColumnSpec{"s", 5, "", "mm"},
                    DataColumnSpec{"p", 6, "", "bar g"}, DataColumnSpec{"F", 7, "", "N"}};
    const auto d = read_data_file(spec);
    const auto &t = d.values[0], &s = d.values[1], &p = d.values[2], &F = d.values[3];
    for (std::size_t i = 2; i + 2 < d.rows(); ++i) {
      const double v = (s[i + 2] - s[i - 2]) / (t[i + 2] - t[i - 2]);
      const double p_gauge = p[i] - 101325.0;
      if (v != 0) pts.push_back({v, p_gauge / 1e5, F[i] - p_gauge * kArea, d.lines[i]});
    }
  }
  return pts;
}

std::string points_csv(const std::vector<FrictionPoint>& pts) {
  std::ostringstream o;
  o.precision(9);
  o << "v [m/s], F [N], p_A [bar_rel], p_B [bar_rel]\n";
  for (const auto& p : pts) o << p.v << ", " << p.F << ", " << p.p_bar << ", 0\n";
  return o.str();
}

TEST(FitFrictionReal, Eq4AndEq8ConvergeOnTheORingSealAndEq8FitsAtLeastAsWell) {
  const auto pts = oring_points();
  ASSERT_GT(pts.size(), 3800u);
  const auto r4 = fit_friction(FrictionModel::eq4, pts, default_friction_parameters(FrictionModel::eq4));
  const auto r8 = fit_friction(FrictionModel::eq8, pts, default_friction_parameters(FrictionModel::eq8));
  std::printf("O-ring 1-7 bar, %zu points: eq4 R2 %.4f (%d iterations), eq8 R2 %.4f (%d iterations)\n", pts.size(),
              r4.r2, r4.iterations, r8.r2, r8.iterations);
  EXPECT_TRUE(r4.converged) << r4.solver_message;
  EXPECT_TRUE(r8.converged) << r8.solver_message;
  EXPECT_LE(r4.iterations, 200);
  EXPECT_LE(r8.iterations, 200);
  // Eq. 8 contains eq. 4 up to FS - FC (kv1 = FS1 = 0, b0 = FC, b1 = kp),
  // so at its optimum it cannot fit worse; less means a local minimum.
  EXPECT_GE(r8.r2, r4.r2);
}

TEST(FitFrictionReal, TheCommandConvergesAndReportsTheLoadCellOffset) {
  TempDir dir;
  const auto csv = dir.write("oring.csv", points_csv(oring_points()));
  const auto [rc, out] = run_cli("fit friction '" + csv + "' --model eq8");
  EXPECT_EQ(rc, 0) << out;
  EXPECT_EQ(out.find("NOT CONVERGED"), std::string::npos) << out;
  const auto [rc2, out2] = run_cli("fit friction '" + csv + "' --model eq8 --offset");
  EXPECT_EQ(rc2, 0) << out2;
  // The band of the load cell is not centred on p A (README): about +2 N.
  std::istringstream lines(out2);
  std::string line;
  double F0 = NAN, se = NAN;
  while (std::getline(lines, line))
    if (line.rfind("  F0 ", 0) == 0) std::sscanf(line.c_str(), "  F0 N %lf %lf", &F0, &se);
  EXPECT_GT(F0, 1.0) << out2;
  EXPECT_LT(F0, 3.5) << out2;
  EXPECT_GT(se, 0.0) << out2;
  EXPECT_LT(se, 0.2) << out2;
}

// Generalisation across pressure: eq. 8 with the load-cell offset, fitted
// at 1, 3 and 5 bar, predicts the 7 bar force. The load cell's noise is
// 0.035 N (sd of the second difference of the 7 bar file), so the error
// is the law's own. The bound: extrapolating 2 bar beyond the fitted range
// costs at most half again the law's error at the nearest fitted pressure
// (5 bar). Printed beside it, as measured: eq. 7 (one pressure's law)
// fitted to the 7 bar points themselves, and the 5 bar eq. 7 fit held at
// 7 bar - on these excerpts both do better than eq. 8's extrapolation.
TEST(FitFrictionReal, FittedAtOneThreeAndFiveBarEq8PredictsTheSevenBarForce) {
  std::vector<FrictionPoint> fitted, at5, at7;
  for (const auto& p : oring_points()) {
    (p.p_bar < 6 ? fitted : at7).push_back(p);
    if (p.p_bar > 4 && p.p_bar < 6) at5.push_back(p);
  }
  ASSERT_GT(at7.size(), 900u);
  const auto r = fit_friction(FrictionModel::eq8, fitted, default_friction_parameters(FrictionModel::eq8, true));
  EXPECT_TRUE(r.converged) << r.solver_message;
  const auto own = fit_friction(FrictionModel::eq7, at7, default_friction_parameters(FrictionModel::eq7, true));
  EXPECT_TRUE(own.converged) << own.solver_message;
  const double rms5 = friction_rms(FrictionModel::eq8, r, at5), rms7 = friction_rms(FrictionModel::eq8, r, at7);
  const double best7 = friction_rms(FrictionModel::eq7, own, at7);
  const auto frozen = fit_friction(FrictionModel::eq7, at5, default_friction_parameters(FrictionModel::eq7, true));
  const double frozen7 = friction_rms(FrictionModel::eq7, frozen, at7);
  std::printf("eq8 + offset fitted at 1, 3, 5 bar: RMS %.3f N at 5 bar, %.3f N predicted at 7 bar; "
              "eq7 fitted at 7 bar: %.3f N; eq7 fitted at 5 bar on 7 bar: %.3f N\n",
              rms5, rms7, best7, frozen7);
  EXPECT_LT(rms7, 1.5 * rms5);
}

TEST(FitFrictionReal, TheCommandReportsTheRmsOnEachValidationFile) {
  std::vector<FrictionPoint> low, high;
  for (const auto& p : oring_points()) (p.p_bar < 6 ? low : high).push_back(p);
  TempDir dir;
  const auto fit_csv = dir.write("oring135.csv", points_csv(low));
  const auto val_csv = dir.write("oring7.csv", points_csv(high));
  const auto [rc, out] = run_cli("fit friction '" + fit_csv + "' --model eq8 --offset --validate '" + val_csv + "'");
  ASSERT_EQ(rc, 0) << out;
  const auto r = fit_friction(FrictionModel::eq8, low, default_friction_parameters(FrictionModel::eq8, true));
  char expected[64];
  std::snprintf(expected, sizeof expected, "%.3g N on %s", friction_rms(FrictionModel::eq8, r, high), val_csv.c_str());
  EXPECT_NE(out.find(expected), std::string::npos) << out;
  const auto [rc2, out2] = run_cli("fit friction '" + fit_csv + "' --model eq8 --validate '" + dir.path().string() + "/none.csv'");
  EXPECT_EQ(rc2, 2) << out2;
  // A validation file without points is refused, not reported as an RMS of nan.
  const auto empty_csv = dir.write("empty.csv", "v [m/s], F [N], p_A [bar_rel], p_B [bar_rel]\n");
  const auto [rc3, out3] = run_cli("fit friction '" + fit_csv + "' --model eq8 --validate '" + empty_csv + "'");
  EXPECT_EQ(rc3, 2) << out3;
  EXPECT_NE(out3.find("no friction points"), std::string::npos) << out3;
}

TEST(FitFrictionReal, AnOffsetFitRefusesForcesSignedAgainstTheMotion) {
  auto pts = oring_points();
  for (auto& p : pts) p.F = -p.F;
  TempDir dir;
  const auto csv = dir.write("against.csv", points_csv(pts));
  const auto [rc, out] = run_cli("fit friction '" + csv + "' --model eq4 --offset");
  EXPECT_EQ(rc, 2) << out;
  EXPECT_NE(out.find("negate the F column"), std::string::npos) << out;
}

// Synthetic signed data: F = sign(v) |law| + F0 with the law written by
// components/friction.hpp (not the fitting code), Gaussian noise of 0.3 N
// (fixed seed), speeds and pressures like the rig's. The truth is known in
// closed form: each coefficient must come back within 4 of its reported
// standard errors and within a stated absolute tolerance.
TEST(FitFrictionOffset, RecoversAKnownOffsetAndEq8CoefficientsFromNoisySignedData) {
  const components::FrictionCoefficients c{3.0, 1.5, 9.0, 0.8, 5.0, 0.004, 60.0, 12.0, 0.8,
                                           components::FrictionPressure::ab_minus};
  const double F0 = 2.2, sigma = 0.3;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<FrictionPoint> pts;
  for (double p : {1.0, 3.0, 5.0, 7.0})
    for (int i = 0; i < 40; ++i) {
      const double speed = 0.0005 * std::pow(0.04 / 0.0005, i / 39.0);
      for (double sign : {1.0, -1.0})
        pts.push_back({sign * speed, p, sign * components::friction_magnitude(c, speed, p) + F0 + noise(rng), 0});
    }
  auto params = default_friction_parameters(FrictionModel::eq8, true);
  set_parameter(params, "FC=5", ParameterField::fixed);
  const auto r = fit_friction(FrictionModel::eq8, pts, params);
  EXPECT_TRUE(r.converged) << r.solver_message;
  EXPECT_LE(r.iterations, 200);
  auto expect = [&](const std::string& name, double truth, double tol) {
    SCOPED_TRACE(name);
    const auto& p = r.parameter(name);
    EXPECT_NEAR(p.value, truth, tol);
    ASSERT_TRUE(std::isfinite(p.std_error));
    EXPECT_LT(std::abs(p.value - truth), 4 * p.std_error) << "std error " << p.std_error;
  };
  expect("F0", F0, 0.05);  // sigma / sqrt(320) = 0.017 N
  expect("b0", c.b0, 1.0);
  expect("b1", c.b1, 0.3);
  expect("FS0", c.FS0, 1.5);
  expect("FS1", c.FS1, 0.4);
  expect("vS", c.vS, 0.001);
  expect("kv0", c.kv0, 15.0);
  expect("kv1", c.kv1, 4.0);
  expect("a", c.a, 0.06);
  const double s2 = r.rss / (r.points - r.free_parameters);
  EXPECT_NEAR(s2 / (sigma * sigma), 1.0, 0.3);
}

}  // namespace
}  // namespace pneumo
