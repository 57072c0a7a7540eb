// The actuator of seed paper 002 (netlists/bracha_cylinder.yaml: 20/8 mm,
// 200 mm stroke, 1 kg, meter-in nozzle from 6 bar gauge, LuGre friction
// F_C 15 N, F_S 25 N, v_S 10 mm/s, sigma2 20 N s/m, wall heat eq. 2).
//   1. Low supply flow (A_in 0.003 mm2): stick-slip - the velocity returns
//      to ~0 again and again, and each slip starts when the pressure force
//      reaches the break-away force F_S.
//   2. High supply flow (A_in 0.1 mm2): no stick once the piston moves; the
//      steady speed is the choked inlet nozzle's flow swept at the drive
//      chamber's density, the friction is the LuGre sliding force
//      F_C + sigma2 v, and the drive chamber gas settles at the supply
//      temperature (isobaric filling with walls at room temperature).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kAreaA = kPi * (0.020 * 0.020 - 0.008 * 0.008) / 4;  // m2, drive (rod) side
constexpr double kR = 287.05, kKappa = 1.4, kTSupply = 293.15, kPAmb = 101325;
constexpr double kFC = 15, kFS = 25, kSigma2 = 20, kStroke = 0.2;

struct RigRun {
  RunResult r;
  std::vector<double> col(const std::string& name) const { return test_support::column(r.table, name); }
};

RigRun run_rig(const std::string& A_in) {
  Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/bracha_cylinder.yaml");
  apply_override(nl, "A_in=" + A_in);
  RigRun out;
  out.r = run_simulation(nl, builtin_registry());
  EXPECT_TRUE(out.r.solver.ok) << out.r.solver.message;
  return out;
}

// Stick phases before the cap end: the velocity falls below 1 mm/s after
// the piston has slid faster than 10 mm/s. (While stuck, LuGre's bristles
// let it creep at ~1e-4 m/s as the load grows: presliding, dF/dt / sigma0.)
struct Sticks {
  int count = 0;
  std::vector<double> breakaway_force;  // |F_friction| peak before each slip, N
};

Sticks count_sticks(const RigRun& run) {
  const auto x = run.col("x"), v = run.col("v"), F = run.col("F_friction");
  Sticks s;
  bool sliding = false;
  double F_peak = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (x[k] > kStroke - 2e-3) break;
    if (!sliding) F_peak = std::max(F_peak, std::abs(F[k]));
    if (!sliding && v[k] > 0.01) {
      sliding = true;
      s.breakaway_force.push_back(F_peak);
      F_peak = 0;
    }
    if (sliding && std::abs(v[k]) < 1e-3) {
      sliding = false;
      ++s.count;
    }
  }
  return s;
}

TEST(BrachaCylinder, StickSlipAtLowSupplyFlow) {
  const RigRun run = run_rig("0.003 mm2");
  const Sticks s = count_sticks(run);
  std::cout << "A_in 0.003 mm2: " << s.count << " stick phases in 4 s, break-away friction";
  for (double F : s.breakaway_force) std::cout << " " << F;
  std::cout << " N (F_S = " << kFS << " N), travel " << run.col("x").back() * 1e3 << " mm" << std::endl;
  EXPECT_GE(s.count, 4);
  ASSERT_GE(s.breakaway_force.size(), 4u);
  // The bristles carry the growing pressure force up to the Stribeck peak.
  for (double F : s.breakaway_force) EXPECT_NEAR(F, kFS, 0.05 * kFS);
}

TEST(BrachaCylinder, SmoothMotionAtHighSupplyFlow) {
  const RigRun run = run_rig("0.1 mm2");
  const Sticks s = count_sticks(run);
  EXPECT_EQ(s.count, 0);
  EXPECT_EQ(s.breakaway_force.size(), 1u);  // one break-away at the start
  const auto x = run.col("x"), v = run.col("v"), p_A = run.col("p_A"), T_A = run.col("T_A"),
             F = run.col("F_friction");
  // Steady sliding between 100 and 190 mm.
  std::size_t k = 0;
  while (x[k] < 0.19) ++k;
  const double psi = std::pow(2 / (kKappa + 1), (kKappa + 1) / (2 * (kKappa - 1)));
  const double p_supply = kPAmb + 6e5;
  const double m_in = 0.8 * 0.1e-6 * p_supply * std::sqrt(kKappa / (kR * kTSupply)) * psi;  // choked inlet
  const double v_pred = m_in * kR * T_A[k] / (p_A[k] * kAreaA);
  const double F_pred = kFC + kSigma2 * v[k];
  std::cout << "A_in 0.1 mm2: speed at 190 mm " << v[k] << " m/s (inlet flow / (rho_A A_A) = " << v_pred
            << "), friction " << F[k] << " N (F_C + sigma2 v = " << F_pred << "), T_A " << T_A[k] << " K" << std::endl;
  EXPECT_NEAR(v[k], v_pred, 0.01 * v_pred);
  EXPECT_NEAR(-F[k], F_pred, 0.01 * F_pred);
  EXPECT_NEAR(T_A[k], kTSupply, 0.5);
  for (std::size_t j = 0; j < x.size() && x[j] < 0.19; ++j)
    if (x[j] > 0.1) EXPECT_NEAR(v[j], v[k], 0.02 * v[k]) << "at x = " << x[j];
}

}  // namespace
}  // namespace pneumo
