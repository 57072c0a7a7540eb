// The movement-time rig of seed paper 001 (netlists/movement_time_rig.yaml:
// SMC MY3B16-700 rodless, 16 mm bore, 700 mm stroke, 2 kg, 0.6 MPa, meter-out
// throttle 1.2 mm2, Table 2).
//   1. The paper's own throttle (1.2 mm2, C_q 0.95) drives the piston at about
//      1.1 m/s - the stroke takes well under a second, not the ~7 s of Table 4.
//   2. In the choked meter-out regime the uniform speed is the nozzle's
//      volumetric flow at the exhaust-side state over the piston area,
//        v = Cd A sqrt(kappa R T) (2/(kappa+1))^((kappa+1)/(2(kappa-1))) / S,
//      independent of the supply pressure (gauge or absolute reading).
//   3. The effective area Cd A = 0.1 mm2 (one twelfth of the paper's) with
//      the paper's 0.4 s reaction time reproduces Table 4 with R2 >= 0.95.
// Movement time at displacement d: first time x - x(0) >= d (d = 0: 0.1 mm,
// the start of motion; d = 700 mm: 699.5 mm, the bumper is reached).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kArea = kPi * 0.016 * 0.016 / 4;  // m2, both sides (rodless)
constexpr double kR = 287.0, kKappa = 1.4, kT = 296.15;  // netlist gas, 23 degC

// Table 4 of paper [2]: displacement (mm) and the measured ("Testing") time (s).
const std::vector<double> kTable4D = {0, 100, 200, 300, 400, 500, 600, 700};
const std::vector<double> kTable4T = {0.4, 1.21, 3, 4, 4.7, 5.4, 6.1, 7};

struct Trace {
  std::vector<double> t, x, v;
};

Trace run_rig(const std::vector<std::string>& overrides) {
  Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/movement_time_rig.yaml");
  for (const auto& o : overrides) apply_override(nl, o);
  const RunResult r = run_simulation(nl, builtin_registry());
  EXPECT_TRUE(r.solver.ok) << r.solver.message;
  Trace tr;
  const int cx = r.table.column("x"), cv = r.table.column("v");
  EXPECT_GE(cx, 0);
  EXPECT_GE(cv, 0);
  if (cx < 0 || cv < 0) return tr;
  for (const auto& row : r.table.rows) {
    tr.t.push_back(row[0]);
    tr.x.push_back(row[cx]);
    tr.v.push_back(row[cv]);
  }
  return tr;
}

// First time (interpolated) at which x - x(0) >= d; NaN if never.
double movement_time(const Trace& tr, double d) {
  const double level = tr.x.front() + d;
  for (std::size_t k = 1; k < tr.t.size(); ++k)
    if (tr.x[k] >= level && tr.x[k - 1] < level)
      return tr.t[k - 1] + (level - tr.x[k - 1]) / (tr.x[k] - tr.x[k - 1]) * (tr.t[k] - tr.t[k - 1]);
  return std::numeric_limits<double>::quiet_NaN();
}

// Movement times at Table 4's displacements.
std::vector<double> table4_times(const Trace& tr) {
  std::vector<double> out;
  for (double d_mm : kTable4D) {
    const double d = d_mm == 0 ? 1e-4 : d_mm == 700 ? 0.6995 : d_mm * 1e-3;
    out.push_back(movement_time(tr, d));
  }
  return out;
}

// Coefficient of determination of the model values f against the data y.
double r_squared(const std::vector<double>& y, const std::vector<double>& f) {
  double mean = 0;
  for (double v : y) mean += v / y.size();
  double ss_res = 0, ss_tot = 0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    ss_res += (y[k] - f[k]) * (y[k] - f[k]);
    ss_tot += (y[k] - mean) * (y[k] - mean);
  }
  return 1 - ss_res / ss_tot;
}

// Mean speed over the stroke section [x_lo, x_hi]: least-squares slope of
// x(t) there (the 2 kg load rides on two gas springs and oscillates about
// the uniform motion; the slope averages over the oscillation).
double section_speed(const Trace& tr, double x_lo, double x_hi) {
  double n = 0, st = 0, sx = 0, stt = 0, stx = 0;
  for (std::size_t k = 0; k < tr.t.size(); ++k) {
    if (tr.x[k] < x_lo || tr.x[k] > x_hi) continue;
    n += 1;
    st += tr.t[k];
    sx += tr.x[k];
    stt += tr.t[k] * tr.t[k];
    stx += tr.t[k] * tr.x[k];
  }
  return (n * stx - st * sx) / (n * stt - st * st);
}

// Choked meter-out nozzle: volumetric flow at the exhaust-side state / S.
double choked_meter_out_speed(double Cd_A) {
  const double psi = std::pow(2 / (kKappa + 1), (kKappa + 1) / (2 * (kKappa - 1)));
  return Cd_A * std::sqrt(kKappa * kR * kT) * psi / kArea;
}

void print_times(const char* label, const std::vector<double>& t) {
  std::cout << label << ":";
  for (std::size_t k = 0; k < t.size(); ++k) std::printf(" %g mm %.3f s;", kTable4D[k], t[k]);
  std::cout << std::endl;
}

TEST(MovementTimeRig, PaperThrottleAreaStrokesInUnderASecond) {
  const Trace tr = run_rig({});
  const double v = section_speed(tr, 0.2, 0.6);
  const double v_pred = choked_meter_out_speed(0.95 * 1.2e-6);
  const auto times = table4_times(tr);
  print_times("1.2 mm2, Cd 0.95", times);
  const double r2 = r_squared(kTable4T, times);
  std::cout << "mean speed 200-600 mm " << v << " m/s, choked-nozzle prediction " << v_pred << " m/s; R2 vs Table 4 "
            << r2 << std::endl;
  // A stroke of 0.7 s: a lightly damped gas-spring oscillation (period
  // ~0.4 s) rides on the uniform motion, so the section average is within
  // 10 % of the prediction rather than a few %.
  EXPECT_NEAR(v, v_pred, 0.10 * v_pred);
  EXPECT_LT(times.back(), 1.0);   // Table 4: 7 s
  EXPECT_LT(r2, 0.0);             // worse than Table 4's own mean
}

TEST(MovementTimeRig, UniformSpeedEqualsChokedNozzleFlowOverPistonArea) {
  // Effective area 0.105 mm2 x 0.95: a 5 s stroke, the oscillation averages out.
  const double v_pred = choked_meter_out_speed(0.95 * 0.105e-6);
  for (const char* p : {"p_supply=0.6 MPag", "p_supply=0.6 MPa"}) {
    const Trace tr = run_rig({"A_throttle=0.105 mm2", p});
    const double v = section_speed(tr, 0.2, 0.6);
    std::cout << p << ": uniform speed " << v << " m/s, prediction " << v_pred << " m/s (" << (v / v_pred - 1) * 100
              << " %)" << std::endl;
    EXPECT_NEAR(v, v_pred, 0.03 * v_pred) << p;
  }
}

TEST(MovementTimeRig, EffectiveAreaReproducesTable4) {
  // Cd A = 0.95 x 0.105 mm2 = 0.1 mm2, and the valve command at 0.36 s so
  // that motion starts at the paper's 0.4 s reaction time.
  const Trace tr = run_rig({"A_throttle=0.105 mm2", "t_valve=0.36 s"});
  const auto times = table4_times(tr);
  print_times("Cd A 0.1 mm2, t_valve 0.36 s", times);
  const double r2 = r_squared(kTable4T, times);
  std::cout << "R2 vs Table 4 (testing): " << r2 << std::endl;
  EXPECT_NEAR(times.front(), 0.4, 0.05);
  EXPECT_GE(r2, 0.95);
  // Without the extra delay (valve at 20 ms, start of motion at ~0.07 s) the
  // same area still explains most of Table 4's variance.
  const Trace quick = run_rig({"A_throttle=0.105 mm2"});
  const auto t_quick = table4_times(quick);
  print_times("Cd A 0.1 mm2, t_valve 20 ms", t_quick);
  const double r2_quick = r_squared(kTable4T, t_quick);
  std::cout << "R2 vs Table 4 (testing), valve at 20 ms: " << r2_quick << std::endl;
  EXPECT_LT(t_quick.front(), 0.1);
  EXPECT_GE(r2_quick, 0.90);
}

}  // namespace
}  // namespace pneumo
