// The full end-cushioning rig (netlists/cushion_rig_full.yaml): the basic rig
// plus wall heat transfer, Annex C eq. 8 friction (p_AB+ main stroke, p_EC
// cushioning zone), a 5/2 valve with a 15 ms spool stroke, hoses, and the
// measurement chain (pressure sensor, 15 ms PT1 thermocouple) of paper [1].
//   1. every operating point of the paper (5, 7 bar abs; z_EC 0.1, 1.5, 6 rev)
//      runs to t_end with physical pressures, temperatures and walls;
//   2. the three cushioning regimes of paper [1] section 4 hold;
//   3. what the full model changes against the basic rig: the stroke starts
//      later (valve ramp, hoses) at the same speed, and the cushion gas no
//      longer stays at the adiabatic expansion temperature;
//   4. the thermocouple lags the gas: smaller, later extremes, each one where
//      the gas temperature crosses the reading (dT_s/dt = 0 <=> T_s = T_gas);
//   5. heat flows to and from the walls are non-zero, point from hot to
//      cold, and each wall's temperature change is the heat it received;
//   6. the command line of the issue works.
// Figures are printed so that the margins are visible in the test log.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/io/results.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;

constexpr double kStroke = 0.100;                 // m
constexpr double kEntry = kStroke - 0.020;        // m: the plug engages
constexpr double kHead = 0.0999;                  // m: "reached the head"
constexpr double kTEnd = 1.2;                     // s
constexpr double kT0 = 293.15;                    // K: ambient, initial gas and walls
constexpr double kTau = 0.015;                    // s: thermocouple
constexpr double kCwallA = 250.0, kCwallCap = 100.0;  // J/K: the netlist's wall capacities

std::string num(double v, int prec = 4) {
  std::ostringstream s;
  s << std::setprecision(prec) << v;
  return s.str();
}

struct Trace {
  std::map<std::string, std::vector<double>> c;  // column name -> values
  const std::vector<double>& operator[](const std::string& name) const {
    auto it = c.find(name);
    if (it == c.end()) throw std::runtime_error("no output column " + name);
    return it->second;
  }
  std::size_t size() const { return (*this)["t"].size(); }
};

const Trace& run(const std::string& netlist, double p_supply, double z_EC) {
  static std::map<std::tuple<std::string, double, double>, Trace> cache;
  const auto key = std::make_tuple(netlist, p_supply, z_EC);
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/" + netlist);
  char buf[64];
  std::snprintf(buf, sizeof buf, "p_supply=%.17g", p_supply);
  apply_override(nl, buf);
  std::snprintf(buf, sizeof buf, "z_EC=%.17g", z_EC);
  apply_override(nl, buf);
  const RunResult r = run_simulation(nl, builtin_registry());
  if (!r.solver.ok)
    throw std::runtime_error(netlist + " failed at t = " + num(r.solver.t_reached) + ": " + r.solver.message);
  Trace tr;
  for (std::size_t j = 0; j < r.table.names.size(); ++j) {
    std::vector<double> col;
    for (const auto& row : r.table.rows) col.push_back(row[j]);
    tr.c[j == 0 ? "t" : r.table.names[j]] = std::move(col);
  }
  return cache.emplace(key, std::move(tr)).first->second;
}

const Trace& full(double p, double z) { return run("cushion_rig_full.yaml", p, z); }
const Trace& basic(double p, double z) { return run("cushion_rig.yaml", p, z); }

double interp(const std::vector<double>& t, const std::vector<double>& y, double tq) {
  if (tq <= t.front()) return y.front();
  if (tq >= t.back()) return y.back();
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), tq) - t.begin());
  if (t[k] <= t[k - 1]) return y[k];
  return y[k - 1] + (tq - t[k - 1]) / (t[k] - t[k - 1]) * (y[k] - y[k - 1]);
}

// First time at or after sample `from` with x >= level (interpolated); NaN if never.
std::pair<double, std::size_t> first_crossing(const Trace& tr, double level, std::size_t from = 0) {
  const auto& t = tr["t"];
  const auto& x = tr["x"];
  for (std::size_t k = std::max<std::size_t>(from, 1); k < t.size(); ++k)
    if (x[k] >= level && x[k - 1] < level)
      return {t[k - 1] + (level - x[k - 1]) / (x[k] - x[k - 1]) * (t[k] - t[k - 1]), k};
  return {std::numeric_limits<double>::quiet_NaN(), t.size()};
}

struct Regime {
  double t_entry = NAN, v_entry = NAN, t_head = NAN, time_in_zone = NAN;
  double rebound = 0;           // largest drop of x below its running maximum between entry and head, m
  double v_impact = 0;          // v at the first x >= stroke (0 if never)
  double x_rest = NAN;          // x where the piston first comes to rest (|v| < 1 mm/s) after entry
  double p_EC_peak = 0;         // Pa, gas
};

Regime regime(const Trace& tr) {
  Regime g;
  const auto& t = tr["t"];
  const auto& x = tr["x"];
  const auto& v = tr["v"];
  const auto [te, ke] = first_crossing(tr, kEntry);
  g.t_entry = te;
  if (std::isnan(te)) return g;
  g.v_entry = interp(t, v, te);
  const auto [th, kh] = first_crossing(tr, kHead, ke);
  g.t_head = th;
  g.time_in_zone = th - te;
  double xmax = x[ke];
  for (std::size_t k = ke; k < std::min(kh, t.size()); ++k) {
    xmax = std::max(xmax, x[k]);
    g.rebound = std::max(g.rebound, xmax - x[k]);
    if (std::isnan(g.x_rest) && std::abs(v[k]) < 1e-3) g.x_rest = x[k];
  }
  const auto [ti, ki] = first_crossing(tr, kStroke, ke);
  if (!std::isnan(ti)) g.v_impact = interp(t, v, ti);
  // The gas pressure (the basic rig has no sensor: its p_EC is the gas's).
  for (double p : tr[tr.c.count("p_EC_gas") ? "p_EC_gas" : "p_EC"]) g.p_EC_peak = std::max(g.p_EC_peak, p);
  return g;
}

std::string case_name(double p, double z) { return num(p / 1e5, 2) + " bar, z_EC " + num(z, 2) + " rev"; }

void print(const char* label, double p, double z, const Regime& g) {
  std::cout << "[full-rig] " << label << " " << case_name(p, z) << ": entry " << num(g.t_entry, 4) << " s at "
            << num(g.v_entry, 4) << " m/s, time in zone " << num(g.time_in_zone, 4) << " s, rebound "
            << num(g.rebound * 1e3, 3) << " mm, at rest first at x = " << num(g.x_rest * 1e3, 4)
            << " mm, v_impact " << num(g.v_impact, 4) << " m/s, peak p_EC " << num(g.p_EC_peak / 1e5, 4) << " bar\n";
}

// ---------------------------------------------------------------------------
// 1. Every operating point runs to t_end and stays physical.
// ---------------------------------------------------------------------------

struct Case {
  double p, z;
};

// Test name of a case, e.g. p5bar_z1_5.
std::string case_label(const ::testing::TestParamInfo<Case>& info) {
  std::ostringstream s;
  s << "p" << std::lround(info.param.p / 1e5) << "bar_z" << info.param.z;
  std::string n = s.str();
  std::replace(n.begin(), n.end(), '.', '_');
  return n;
}

class FullRigRuns : public ::testing::TestWithParam<Case> {};

TEST_P(FullRigRuns, CompletesWithPhysicalStates) {
  const auto [p, z] = GetParam();
  const Trace& tr = full(p, z);
  ASSERT_GE(tr["t"].back(), kTEnd - 1e-9);
  const auto mm = [&](const std::string& name) {
    const auto& c = tr[name];
    return std::make_pair(*std::min_element(c.begin(), c.end()), *std::max_element(c.begin(), c.end()));
  };
  const auto [pEC_lo, pEC_hi] = mm("p_EC_gas");
  const auto [TEC_lo, TEC_hi] = mm("T_EC_gas");
  const auto [TwA_lo, TwA_hi] = mm("T_wall_A");
  const auto [Twc_lo, Twc_hi] = mm("T_wall_cap");
  std::cout << "[full-rig] " << case_name(p, z) << ": p_EC in [" << num(pEC_lo / 1e5) << ", " << num(pEC_hi / 1e5)
            << "] bar, T_EC gas in [" << num(TEC_lo) << ", " << num(TEC_hi) << "] K, walls in [" << num(TwA_lo, 6)
            << ", " << num(TwA_hi, 6) << "] / [" << num(Twc_lo, 6) << ", " << num(Twc_hi, 6) << "] K; x(t_end) "
            << num(tr["x"].back() * 1e3, 5) << " mm\n";
  // The stroke ends at the cap (within the stop's elastic penetration), at rest.
  EXPECT_NEAR(tr["x"].back(), kStroke, 1e-4);
  EXPECT_LT(std::abs(tr["v"].back()), 1e-3);
  // Cushion pressure: above ambient minus a blow-down undershoot, below the
  // basic rig's 2.5 p_supply bound (cushion_rig_test: quasi-static balance
  // 1.15 p_supply plus the entry's kinetic energy).
  EXPECT_GT(pEC_lo, 0.9e5);
  EXPECT_LE(pEC_hi, 2.5 * p);
  // Gas temperature: never below the adiabatic expansion from p_supply to
  // ambient (the walls only warm it), 293.15 (1.01325e5/p)^(2/7) K.
  EXPECT_GE(TEC_lo, kT0 * std::pow(101325.0 / p, 0.4 / 1.4) - 0.5);
  EXPECT_LE(TEC_hi, 400.0);
  // Walls of 100-250 J/K exchange a few J over the stroke: they stay within
  // 1 K of the room and between the coldest and the hottest gas.
  for (double T : {TwA_lo, TwA_hi, Twc_lo, Twc_hi}) {
    EXPECT_NEAR(T, kT0, 1.0);
    EXPECT_GE(T, TEC_lo);
  }
}

INSTANTIATE_TEST_SUITE_P(PaperOperatingPoints, FullRigRuns,
                         ::testing::Values(Case{5e5, 0.1}, Case{5e5, 1.5}, Case{5e5, 6.0}, Case{7e5, 0.1},
                                           Case{7e5, 1.5}, Case{7e5, 6.0}),
                         case_label);

// ---------------------------------------------------------------------------
// 2. The three regimes of paper [1] section 4, 3.7 kg.
// ---------------------------------------------------------------------------

class FullRigRegimes : public ::testing::TestWithParam<double> {};

// z_EC 0.1 rev, overdamped: the cushion pressure rises well above supply,
// the piston is stopped well short of the head and creeps in for about half
// a second (paper: 0.48 s and twice that). The paper's piston springs back;
// here it does at 5 bar (0.2 mm), while at 7 bar the Annex C cushion-zone
// friction (27 N at rest at p_EC = 7 bar_rel) holds it for ~40 ms instead
// (printed; with the Annex B friction of the basic rig it springs back
// 0.75 mm) - so the rebound itself is not asserted.
TEST_P(FullRigRegimes, OverdampedAtSmallOpening) {
  const double p = GetParam();
  const Regime g = regime(full(p, 0.1));
  print("overdamped", p, 0.1, g);
  ASSERT_FALSE(std::isnan(g.t_entry));
  ASSERT_FALSE(std::isnan(g.t_head)) << "never reaches the head";
  EXPECT_GE(g.p_EC_peak, 1.1 * p);
  ASSERT_FALSE(std::isnan(g.x_rest)) << "never comes to rest in the cushioning zone";
  EXPECT_LE(g.x_rest, kStroke - 0.005);
  EXPECT_GE(g.time_in_zone, 0.3);
  EXPECT_LE(g.time_in_zone, 1.0);
  EXPECT_LE(g.v_impact, 0.1 * g.v_entry);
}

// z_EC 1.5 rev, well adjusted: no rebound, entry to head in 0.07-0.10 s
// (paper 0.08-0.09 s), a soft knock: it arrives with well under the entry
// speed (v_impact <= 0.6 v_entry: <= 36 % of the entry's kinetic energy).
TEST_P(FullRigRegimes, WellAdjustedAtMediumOpening) {
  const double p = GetParam();
  const Regime g = regime(full(p, 1.5));
  print("adjusted", p, 1.5, g);
  ASSERT_FALSE(std::isnan(g.t_head));
  EXPECT_LE(g.rebound, 0.01e-3);
  EXPECT_GE(g.time_in_zone, 0.07);
  EXPECT_LE(g.time_in_zone, 0.10);
  EXPECT_LE(g.v_impact, 0.6 * g.v_entry);
  EXPECT_GT(g.v_impact, 0.0);
}

// z_EC 6 rev, wide open: no braking pressure, impact at >= 90 % of the entry speed.
TEST_P(FullRigRegimes, HardImpactWideOpen) {
  const double p = GetParam();
  const Regime g = regime(full(p, 6.0));
  print("impact", p, 6.0, g);
  ASSERT_GT(g.v_entry, 0.0);
  EXPECT_GE(g.v_impact, 0.9 * g.v_entry);
  EXPECT_LE(g.p_EC_peak, 1.01 * p);  // never pressurised above the supply it started at
}

INSTANTIATE_TEST_SUITE_P(FiveAndSevenBar, FullRigRegimes, ::testing::Values(5e5, 7e5), [](const auto& info) {
  return "p" + std::to_string(std::lround(info.param / 1e5)) + "bar";
});

// ---------------------------------------------------------------------------
// 3. Full against basic at the default point (5 bar, 1.5 rev).
// ---------------------------------------------------------------------------

// The stroke starts later - the spool opens over 15 ms instead of at once
// and the 0.5 m hose to A must fill - but the travel speed is set by the
// same meter-out throttle, so the entry speed agrees within 5 %.
// The full rig leaves algebraic unknowns to IDA (flows and forces of the
// hose, sensor and wall couplings): their rows of the Newton matrix are
// dF/dy alone, which an old matrix gets wrong, so the solver evaluates every
// Newton matrix afresh (ida_solver.cpp, NewtonMatrixParts) even though reuse
// is asked for.
TEST(FullRigSolver, AlgebraicUnknownsKeepEveryNewtonMatrixFresh) {
  const Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig_full.yaml");
  ASSERT_TRUE(nl.simulation.jacobian_reuse);
  System system(elaborate(nl, builtin_registry()));
  const auto& id = system.differential();
  ASSERT_TRUE(std::count(id.begin(), id.end(), 0.0) > 0) << "the full rig has no algebraic unknown left";
  const RunResult r = run_system(system, solver_options(nl.simulation));
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_EQ(r.solver.stats.jacobian_recombinations, 0);
  EXPECT_GT(r.solver.stats.jacobian_evals, 0);
}

TEST(FullRigVsBasic, LaterStartSameSpeed) {
  const Regime f = regime(full(5e5, 1.5)), b = regime(basic(5e5, 1.5));
  std::cout << "[full-vs-basic] entry " << num(f.t_entry, 4) << " s vs " << num(b.t_entry, 4) << " s, at "
            << num(f.v_entry, 4) << " vs " << num(b.v_entry, 4) << " m/s; time in zone " << num(f.time_in_zone, 4)
            << " vs " << num(b.time_in_zone, 4) << " s; v_impact " << num(f.v_impact, 4) << " vs "
            << num(b.v_impact, 4) << " m/s\n";
  EXPECT_GT(f.t_entry - b.t_entry, 0.0);
  EXPECT_LT(f.t_entry - b.t_entry, 0.03);
  EXPECT_NEAR(f.v_entry, b.v_entry, 0.05 * b.v_entry);
}

// The basic rig is adiabatic: after arrival the cushion volume blows down
// to ambient and its gas stays near the isentropic 185.8 K to the end. With
// wall heat it is warmed while blowing down and returns to the wall's
// temperature once at rest (its thermal time constant there is m c_v /
// (alpha A) ~ 20 ms).
TEST(FullRigVsBasic, WallsWarmTheBlownDownCushionGas) {
  const Trace& f = full(5e5, 1.5);
  const Trace& b = basic(5e5, 1.5);
  const double f_min = *std::min_element(f["T_EC_gas"].begin(), f["T_EC_gas"].end());
  const double b_min = *std::min_element(b["T_EC"].begin(), b["T_EC"].end());
  const double isentropic = kT0 * std::pow(101325.0 / 5e5, 0.4 / 1.4);
  std::cout << "[full-vs-basic] T_EC gas min " << num(f_min) << " K (basic " << num(b_min) << " K, isentropic "
            << num(isentropic) << " K); at t_end " << num(f["T_EC_gas"].back(), 6) << " K, wall "
            << num(f["T_wall_cap"].back(), 6) << " K (basic " << num(b["T_EC"].back()) << " K)\n";
  EXPECT_NEAR(b_min, isentropic, 1.0);  // the basic rig: adiabatic blow-down
  EXPECT_GT(f_min, isentropic + 10.0);
  EXPECT_NEAR(f["T_EC_gas"].back(), f["T_wall_cap"].back(), 0.5);
  EXPECT_LT(b["T_EC"].back(), isentropic + 5.0);
}

// ---------------------------------------------------------------------------
// 4. The thermocouple (PT1, 15 ms) against the gas temperature.
// ---------------------------------------------------------------------------

struct Extreme {
  double t, T;
  std::size_t k;
};

Extreme extreme(const Trace& tr, const std::string& col, bool maximum, double t_from) {
  const auto& t = tr["t"];
  const auto& y = tr[col];
  Extreme e{NAN, maximum ? -1e9 : 1e9, 0};
  for (std::size_t k = 0; k < t.size(); ++k)
    if (t[k] >= t_from && (maximum ? y[k] > e.T : y[k] < e.T)) e = {t[k], y[k], k};
  return e;
}

struct LagCase {
  double p, z;
  bool maximum;
};

class ThermocoupleLag : public ::testing::TestWithParam<LagCase> {};

// Its extreme is smaller (closer to the start value) and later, by at most
// a few time constants; and it sits where the gas curve crosses the
// reading, within one output interval (a PT1 is stationary exactly when
// its input equals its output).
TEST_P(ThermocoupleLag, ReadingLagsTheGas) {
  const auto [p, z, maximum] = GetParam();
  const Trace& tr = full(p, z);
  const double t_from = 0.2;  // the cushioning, not the start of the stroke
  const Extreme gas = extreme(tr, "T_EC_gas", maximum, t_from);
  const Extreme tc = extreme(tr, "T_EC", maximum, t_from);
  const auto& t = tr["t"];
  const auto& Tg = tr["T_EC_gas"];
  const auto& Ts = tr["T_EC"];
  // The crossing of gas and reading nearest to the reading's extreme.
  double t_cross = NAN;
  for (std::size_t k = 1; k < t.size(); ++k) {
    const double d0 = Tg[k - 1] - Ts[k - 1], d1 = Tg[k] - Ts[k];
    if (d0 * d1 > 0 || d0 == d1) continue;
    const double tc_k = t[k - 1] + d0 / (d0 - d1) * (t[k] - t[k - 1]);
    if (std::isnan(t_cross) || std::abs(tc_k - tc.t) < std::abs(t_cross - tc.t)) t_cross = tc_k;
  }
  std::cout << "[thermocouple] " << case_name(p, z) << (maximum ? " max" : " min") << ": gas " << num(gas.T)
            << " K at " << num(gas.t) << " s, reading " << num(tc.T) << " K at " << num(tc.t)
            << " s (lag " << num((tc.t - gas.t) * 1e3, 3) << " ms); gas crosses the reading at " << num(t_cross)
            << " s\n";
  EXPECT_GT(std::abs(gas.T - kT0), 3.0) << "no temperature excursion to compare";
  EXPECT_LT(std::abs(tc.T - kT0), std::abs(gas.T - kT0));
  EXPECT_GT(tc.t, gas.t);
  EXPECT_LE(tc.t - gas.t, 3 * kTau);
  EXPECT_NEAR(t_cross, tc.t, 1.0e-3);
}

INSTANTIATE_TEST_SUITE_P(Extremes, ThermocoupleLag,
                         ::testing::Values(LagCase{5e5, 0.1, true}, LagCase{5e5, 1.5, true}, LagCase{5e5, 1.5, false},
                                           LagCase{5e5, 6.0, false}, LagCase{7e5, 0.1, true},
                                           LagCase{7e5, 1.5, false}),
                         [](const auto& info) {
                           std::ostringstream s;
                           s << "p" << std::lround(info.param.p / 1e5) << "bar_z" << info.param.z
                             << (info.param.maximum ? "_max" : "_min");
                           std::string n = s.str();
                           std::replace(n.begin(), n.end(), '.', '_');
                           return n;
                         });

// ---------------------------------------------------------------------------
// 5. Heat to and from the walls.
// ---------------------------------------------------------------------------

// Trapezoid integral of y over t (event rows repeat a time: zero width).
double integral(const std::vector<double>& t, const std::vector<double>& y) {
  double s = 0;
  for (std::size_t k = 1; k < t.size(); ++k) s += 0.5 * (y[k - 1] + y[k]) * (t[k] - t[k - 1]);
  return s;
}

class WallHeat : public ::testing::TestWithParam<Case> {};

// Non-zero both ways; from hot to cold (paper [1] eq. 13: into the gas while
// the gas is colder than its wall, out of it while hotter); and each wall's
// temperature change is what it received, C dT = -int(Q_gas + Q_out) dt
// (Q_gas into the gas, Q_out to the room), within 2 % of the heat exchanged
// with the gas (trapezoid over 1 ms rows).
TEST_P(WallHeat, FlowsBothWaysAndWallsKeepTheBalance) {
  const auto [p, z] = GetParam();
  const Trace& tr = full(p, z);
  const auto& t = tr["t"];
  const auto& Qc = tr["Q_cap"];
  const auto& QA = tr["Q_A"];
  const auto& Tg = tr["T_EC_gas"];
  const auto& Tw = tr["T_wall_cap"];
  double Qc_in = 0, Qc_out = 0, QA_max = 0;
  bool direction_ok = true;
  for (std::size_t k = 0; k < t.size(); ++k) {
    Qc_in = std::max(Qc_in, Qc[k]);
    Qc_out = std::min(Qc_out, Qc[k]);
    QA_max = std::max(QA_max, std::abs(QA[k]));
    if (std::abs(Tw[k] - Tg[k]) > 0.1 && Qc[k] * (Tw[k] - Tg[k]) < 0) direction_ok = false;
  }
  const double gas_cap = integral(t, Qc), out_cap = integral(t, tr["Q_out_cap"]);
  const double gas_A = integral(t, QA), out_A = integral(t, tr["Q_out_A"]);
  const double dU_cap = kCwallCap * (Tw.back() - Tw.front());
  const double dU_A = kCwallA * (tr["T_wall_A"].back() - tr["T_wall_A"].front());
  std::cout << "[wall-heat] " << case_name(p, z) << ": Q_cap in [" << num(Qc_out, 3) << ", " << num(Qc_in, 3)
            << "] W, max |Q_A| " << num(QA_max, 3) << " W; cap wall: C dT = " << num(dU_cap, 4)
            << " J, -int(Q_gas + Q_out) = " << num(-(gas_cap + out_cap), 4) << " J; rod-side wall: " << num(dU_A, 4)
            << " J vs " << num(-(gas_A + out_A), 4) << " J\n";
  EXPECT_GT(Qc_in, 1.0);    // W, into the cushion gas (cold after expanding)
  if (z < 1.0) EXPECT_LT(Qc_out, -1.0);  // W, out of it (hot after compression; only the overdamped case heats it)
  EXPECT_GT(QA_max, 1.0);
  EXPECT_TRUE(direction_ok) << "heat flows from the colder to the hotter side";
  double abs_cap = 0, abs_A = 0;
  for (std::size_t k = 1; k < t.size(); ++k) {
    abs_cap += 0.5 * (std::abs(Qc[k - 1]) + std::abs(Qc[k])) * (t[k] - t[k - 1]);
    abs_A += 0.5 * (std::abs(QA[k - 1]) + std::abs(QA[k])) * (t[k] - t[k - 1]);
  }
  EXPECT_NEAR(dU_cap, -(gas_cap + out_cap), 0.02 * abs_cap);
  EXPECT_NEAR(dU_A, -(gas_A + out_A), 0.02 * abs_A);
}

INSTANTIATE_TEST_SUITE_P(ThreeOpenings, WallHeat, ::testing::Values(Case{5e5, 0.1}, Case{5e5, 1.5}, Case{7e5, 6.0}),
                         case_label);

// ---------------------------------------------------------------------------
// 6. The command line.
// ---------------------------------------------------------------------------

TEST(FullRigCli, SimulateWithOverridesWritesTheRigColumns) {
  const fs::path dir = fs::temp_directory_path() / ("pneumo_full_rig_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path out = dir / "out.csv";
  const std::string cmd = std::string("cd '") + PNEUMO_SOURCE_DIR + "' && '" + PNEUMO_BINARY +
                          "' simulate netlists/cushion_rig_full.yaml --set p_supply=7e5 --set z_EC=0.1 -o '" +
                          out.string() + "' > '" + (dir / "log.txt").string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << cmd;
  ASSERT_EQ(WEXITSTATUS(status), 0) << cmd;
  const ResultsTable table = read_csv(out.string());
  fs::remove_all(dir);
  ASSERT_FALSE(table.rows.empty());
  EXPECT_NEAR(table.rows.back()[0], kTEnd, 1e-9);
  for (const char* name : {"x", "v", "p_A", "p_EC", "T_EC", "T_EC_gas"}) EXPECT_GE(table.column(name), 0) << name;
  // The netlist's display: what an engineer reads, converted from SI.
  EXPECT_EQ(table.units[table.column("p_EC")], "barg");
  EXPECT_EQ(table.units[table.column("T_EC")], "degC");
  EXPECT_EQ(table.units[table.column("x")], "mm");
  // The run of the CLI is the run of the library (same netlist, same overrides).
  const Trace& lib = full(7e5, 0.1);
  EXPECT_NEAR(table.rows.back()[table.column("x")], 1e3 * lib["x"].back(), 1e-6);
  EXPECT_NEAR(table.rows.back()[table.column("p_EC")], (lib["p_EC"].back() - 101325.0) / 1e5, 1e-6);
}

}  // namespace
}  // namespace pneumo
