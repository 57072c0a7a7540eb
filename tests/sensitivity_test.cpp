// Sensitivity estimators (framework/study/sensitivity) on functions with
// known indices, and a Morris screening of the cushion rig whose ranking must
// be the physical one.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <unistd.h>

#include "components/builtin.hpp"
#include "framework/study/sensitivity.hpp"
#include "framework/study/sweep.hpp"

namespace pneumo::study {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Ishigami function, x_j uniform on [-pi, pi], a = 7, b = 0.1. Analytic
// indices (Saltelli et al., Global Sensitivity Analysis: The Primer, 2008):
//   V = a^2/8 + b pi^4/5 + b^2 pi^8/18 + 1/2
//   S1 = (1/2)(1 + b pi^4/5)^2 / V,  S2 = (a^2/8) / V,  S3 = 0
//   ST1 = S1 + (8 b^2 pi^8/225) / V,  ST2 = S2,  ST3 = (8 b^2 pi^8/225) / V
double ishigami(const UnitPoint& u) {
  const double x1 = -kPi + 2 * kPi * u[0], x2 = -kPi + 2 * kPi * u[1], x3 = -kPi + 2 * kPi * u[2];
  return std::sin(x1) + 7.0 * std::sin(x2) * std::sin(x2) + 0.1 * std::pow(x3, 4) * std::sin(x1);
}

TEST(Sobol, IshigamiIndicesMatchTheAnalyticValues) {
  const double a = 7, b = 0.1, pi4 = std::pow(kPi, 4), pi8 = std::pow(kPi, 8);
  const double V = a * a / 8 + b * pi4 / 5 + b * b * pi8 / 18 + 0.5;
  const double S1 = 0.5 * (1 + b * pi4 / 5) * (1 + b * pi4 / 5) / V, S2 = a * a / 8 / V;
  const double S13 = 8 * b * b * pi8 / 225 / V;
  const double first[3] = {S1, S2, 0.0}, total[3] = {S1 + S13, S2, S13};

  const SobolPlan plan = sobol_plan(3, 40000, 7);
  ASSERT_EQ(plan.points.size(), 40000u * 5);
  std::vector<double> f;
  for (const auto& u : plan.points) f.push_back(ishigami(u));
  const SobolIndices ix = sobol_indices(plan, f, 100);
  EXPECT_NEAR(ix.variance, V, 0.03 * V);
  for (int j = 0; j < 3; ++j) {
    std::cout << "x" << j + 1 << ": S1 " << ix.first[j] << " (exact " << first[j] << ") [" << ix.first_lo[j] << ", "
              << ix.first_hi[j] << "], ST " << ix.total[j] << " (exact " << total[j] << ") [" << ix.total_lo[j]
              << ", " << ix.total_hi[j] << "]\n";
    // Monte Carlo error at N = 40000 is about 0.01 for these estimators.
    EXPECT_NEAR(ix.first[j], first[j], 0.03) << "S1 of x" << j + 1;
    EXPECT_NEAR(ix.total[j], total[j], 0.03) << "ST of x" << j + 1;
    EXPECT_LE(ix.first_lo[j], ix.first[j]);
    EXPECT_GE(ix.first_hi[j], ix.first[j]);
  }
}

TEST(Sobol, FailedRunsDropTheirRowsOnly) {
  const SobolPlan plan = sobol_plan(2, 20000, 3);
  std::vector<double> f;
  for (const auto& u : plan.points) f.push_back(3 * u[0] + u[1]);  // S = 0.9, 0.1 (additive)
  for (int i = 0; i < 100; ++i) f[static_cast<std::size_t>(2 + i % 2) * plan.base + 7 * i] = NAN;
  const SobolIndices ix = sobol_indices(plan, f, 0);
  EXPECT_EQ(ix.rows_used, 20000 - 100);
  EXPECT_NEAR(ix.first[0], 0.9, 0.03);
  EXPECT_NEAR(ix.first[1], 0.1, 0.03);
  EXPECT_NEAR(ix.total[0], 0.9, 0.03);
  EXPECT_NEAR(ix.total[1], 0.1, 0.03);
}

// For f = sum c_j u_j every elementary effect is exactly c_j: mu* = |c_j|,
// sigma = 0. For f = u0 u1 the effects depend on the other factor: sigma > 0.
TEST(Morris, LinearFunctionHasExactEffectsAndInteractionShowsInSigma) {
  const double c[4] = {2.0, -0.5, 0.0, 10.0};
  const MorrisPlan plan = morris_plan(4, 12, 4, 11);
  ASSERT_EQ(plan.points.size(), 12u * 5);
  std::vector<double> lin, prod;
  for (const auto& u : plan.points) {
    double s = 0;
    for (int j = 0; j < 4; ++j) s += c[j] * u[j];
    lin.push_back(s);
    prod.push_back(u[0] * u[1]);
  }
  const MorrisIndices m = morris_indices(plan, lin);
  for (int j = 0; j < 4; ++j) {
    EXPECT_EQ(m.effects[j], 12);
    EXPECT_NEAR(m.mu_star[j], std::abs(c[j]), 1e-12);
    EXPECT_NEAR(m.mu[j], c[j], 1e-12);
    EXPECT_NEAR(m.sigma[j], 0.0, 1e-12);
  }
  const MorrisIndices p = morris_indices(plan, prod);
  EXPECT_GT(p.sigma[0], 0.05);
  EXPECT_GT(p.sigma[1], 0.05);
  EXPECT_NEAR(p.mu_star[2], 0.0, 1e-15);
}

// Morris screening of the rig (5 trajectories, 20 runs): the cushion throttle
// opening must dominate the time in the cushioning zone and the impact
// velocity (it sets the outflow from the cushion volume), and supply pressure
// must dominate the lowest cushion temperature (the expansion of the cap-side
// gas in the main stroke scales with the pressure ratio).
TEST(Morris, RigRankingIsPhysical) {
  namespace fs = std::filesystem;
  const std::string rig = std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml";
  const Netlist nl = load_netlist(rig);
  const auto ranges = parse_ranges(nl, builtin_registry(),
                                   {"z_EC=1:6", "p_supply=5bar:7bar", "m_load=2kg:5kg", "cylinder.friction_scale=0.5:1.5"});
  const MorrisPlan plan = morris_plan(4, 5, 4, 5);
  Design d;
  for (const auto& r : ranges) d.parameters.push_back(r.parameter);
  for (const auto& u : plan.points) {
    Sample s;
    for (int j = 0; j < 4; ++j) s.push_back(ranges[j].lo + u[j] * (ranges[j].hi - ranges[j].lo));
    d.samples.push_back(s);
  }
  const fs::path dir = fs::temp_directory_path() / ("pneumo_sensitivity_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  SweepOptions opt;
  opt.threads = 2;
  opt.progress = false;
  opt.metrics = {"t_cushion", "v_impact", "T_EC_min"};
  const SweepSummary s = run_sweep(load_model(rig, builtin_registry()), d, (dir / "runs.csv").string(), opt, process_communicator());
  ASSERT_TRUE(s.complete);
  EXPECT_EQ(s.failed, 0);
  auto mu_star = [&](int metric) {
    std::vector<double> f;
    for (const auto& r : s.records) f.push_back(r.ok ? r.metrics[metric] : NAN);
    return morris_indices(plan, f).mu_star;
  };
  const auto t_cushion = mu_star(0), v_impact = mu_star(1), T_min = mu_star(2);
  for (int j = 0; j < 4; ++j)
    std::cout << d.parameters[j].name << ": mu*(t_cushion) " << t_cushion[j] << " s, mu*(v_impact) " << v_impact[j]
              << " m/s, mu*(T_EC_min) " << T_min[j] << " K\n";
  for (int j = 1; j < 4; ++j) {
    EXPECT_GT(t_cushion[0], 3 * t_cushion[j]) << d.parameters[j].name;
    EXPECT_GT(v_impact[0], 3 * v_impact[j]) << d.parameters[j].name;
  }
  for (int j : {0, 2, 3}) EXPECT_GT(T_min[1], 3 * T_min[j]) << d.parameters[j].name;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pneumo::study
