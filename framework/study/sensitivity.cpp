#include "framework/study/sensitivity.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

namespace pneumo::study {

MorrisPlan morris_plan(int k, int trajectories, int levels, std::uint64_t seed) {
  if (k < 1 || trajectories < 1 || levels < 2 || levels % 2 != 0)
    throw std::invalid_argument("Morris: need k >= 1, trajectories >= 1 and an even number of levels >= 2");
  MorrisPlan plan;
  plan.k = k;
  plan.trajectories = trajectories;
  plan.levels = levels;
  const double delta = levels / (2.0 * (levels - 1));
  const int half = levels / 2;  // base levels 0..half-1 step up, half..levels-1 step down
  std::mt19937_64 rng(seed);
  for (int t = 0; t < trajectories; ++t) {
    UnitPoint x(k);
    std::vector<int> up(k);
    for (int j = 0; j < k; ++j) {
      up[j] = static_cast<int>(rng() % 2);
      const int level = static_cast<int>(rng() % half) + (up[j] ? 0 : half);
      x[j] = static_cast<double>(level) / (levels - 1);
    }
    std::vector<int> order(k);
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), rng);
    plan.points.push_back(x);
    plan.moved.push_back(-1);
    for (int j : order) {
      x[j] += up[j] ? delta : -delta;
      x[j] = std::clamp(x[j], 0.0, 1.0);
      plan.points.push_back(x);
      plan.moved.push_back(j);
    }
  }
  return plan;
}

MorrisIndices morris_indices(const MorrisPlan& plan, const std::vector<double>& f) {
  if (f.size() != plan.points.size()) throw std::invalid_argument("Morris: one value per design point expected");
  const int k = plan.k;
  std::vector<std::vector<double>> ee(k);
  for (std::size_t i = 1; i < plan.points.size(); ++i) {
    const int j = plan.moved[i];
    if (j < 0) continue;
    if (!std::isfinite(f[i]) || !std::isfinite(f[i - 1])) continue;
    const double du = plan.points[i][j] - plan.points[i - 1][j];
    ee[j].push_back((f[i] - f[i - 1]) / du);
  }
  MorrisIndices out;
  for (int j = 0; j < k; ++j) {
    const auto& e = ee[j];
    const double n = static_cast<double>(e.size());
    double mu = 0, mu_star = 0;
    for (double v : e) mu += v, mu_star += std::abs(v);
    mu = n > 0 ? mu / n : NAN;
    mu_star = n > 0 ? mu_star / n : NAN;
    double ss = 0;
    for (double v : e) ss += (v - mu) * (v - mu);
    out.mu.push_back(mu);
    out.mu_star.push_back(mu_star);
    out.sigma.push_back(n > 1 ? std::sqrt(ss / (n - 1)) : NAN);
    out.effects.push_back(static_cast<int>(e.size()));
  }
  return out;
}

SobolPlan sobol_plan(int k, int base, std::uint64_t seed) {
  if (k < 1 || base < 2) throw std::invalid_argument("Sobol: need k >= 1 and at least 2 base samples");
  SobolPlan plan;
  plan.k = k;
  plan.base = base;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<UnitPoint> A(base, UnitPoint(k)), B(base, UnitPoint(k));
  for (auto& row : A)
    for (auto& v : row) v = u(rng);
  for (auto& row : B)
    for (auto& v : row) v = u(rng);
  plan.points = A;
  plan.points.insert(plan.points.end(), B.begin(), B.end());
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < base; ++i) {
      UnitPoint x = A[i];
      x[j] = B[i][j];
      plan.points.push_back(std::move(x));
    }
  return plan;
}

namespace {

struct SobolEstimate {
  std::vector<double> first, total;
  double variance = 0.0;
};

SobolEstimate estimate(const std::vector<int>& rows, int k, int base, const std::vector<double>& f) {
  SobolEstimate e;
  const double n = static_cast<double>(rows.size());
  double mean = 0, sq = 0;
  for (int i : rows) {
    mean += f[i] + f[base + i];
    sq += f[i] * f[i] + f[base + i] * f[base + i];
  }
  mean /= 2 * n;
  e.variance = sq / (2 * n) - mean * mean;
  for (int j = 0; j < k; ++j) {
    double s = 0, t = 0;
    const std::size_t ab = static_cast<std::size_t>(2 + j) * base;
    for (int i : rows) {
      const double fa = f[i], fb = f[base + i], fab = f[ab + i];
      s += (fb - mean) * (fab - fa);  // centred: same expectation, far less variance when |mean| >> sd
      t += (fa - fab) * (fa - fab);
    }
    e.first.push_back(s / n / e.variance);
    e.total.push_back(t / (2 * n) / e.variance);
  }
  return e;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(pos);
  const double w = pos - i;
  return i + 1 < v.size() ? v[i] * (1 - w) + v[i + 1] * w : v[i];
}

}  // namespace

SobolIndices sobol_indices(const SobolPlan& plan, const std::vector<double>& f, int bootstrap, std::uint64_t seed) {
  const int k = plan.k, base = plan.base;
  if (f.size() != plan.points.size()) throw std::invalid_argument("Sobol: one value per design point expected");
  std::vector<int> rows;
  for (int i = 0; i < base; ++i) {
    bool ok = std::isfinite(f[i]) && std::isfinite(f[base + i]);
    for (int j = 0; j < k; ++j) ok &= std::isfinite(f[static_cast<std::size_t>(2 + j) * base + i]);
    if (ok) rows.push_back(i);
  }
  SobolIndices out;
  out.rows_used = static_cast<int>(rows.size());
  if (rows.size() < 2) {
    out.first.assign(k, NAN), out.total.assign(k, NAN);
    out.first_lo = out.first_hi = out.total_lo = out.total_hi = out.first;
    return out;
  }
  const SobolEstimate e = estimate(rows, k, base, f);
  out.first = e.first;
  out.total = e.total;
  out.variance = e.variance;
  std::vector<std::vector<double>> bs_first(k), bs_total(k);
  std::mt19937_64 rng(seed);
  std::vector<int> resample(rows.size());
  for (int b = 0; b < bootstrap; ++b) {
    for (auto& r : resample) r = rows[rng() % rows.size()];
    const SobolEstimate eb = estimate(resample, k, base, f);
    for (int j = 0; j < k; ++j) bs_first[j].push_back(eb.first[j]), bs_total[j].push_back(eb.total[j]);
  }
  for (int j = 0; j < k; ++j) {
    out.first_lo.push_back(percentile(bs_first[j], 0.025));
    out.first_hi.push_back(percentile(bs_first[j], 0.975));
    out.total_lo.push_back(percentile(bs_total[j], 0.025));
    out.total_hi.push_back(percentile(bs_total[j], 0.975));
  }
  return out;
}

}  // namespace pneumo::study
