#include "framework/diagnose/statistics.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace pneumo::diagnose {

double interp(const std::vector<double>& t, const std::vector<double>& y, double tq) {
  if (tq <= t.front()) return y.front();
  if (tq >= t.back()) return y.back();
  const auto it = std::upper_bound(t.begin(), t.end(), tq);
  const std::size_t i = static_cast<std::size_t>(it - t.begin());
  const double w = (tq - t[i - 1]) / (t[i] - t[i - 1]);
  return y[i - 1] + w * (y[i] - y[i - 1]);
}

// Regularised upper incomplete gamma Q(a, x) (Numerical Recipes series / continued fraction).
double gamma_q(double a, double x) {
  if (x <= 0) return 1.0;
  const double gln = std::lgamma(a);
  if (x < a + 1) {
    double ap = a, sum = 1.0 / a, del = sum;
    for (int n = 0; n < 500; ++n) {
      ap += 1;
      del *= x / ap;
      sum += del;
      if (std::abs(del) < std::abs(sum) * 1e-14) break;
    }
    return std::max(0.0, 1.0 - sum * std::exp(-x + a * std::log(x) - gln));
  }
  double b = x + 1 - a, c = 1e300, d = 1 / b, h = d;
  for (int i = 1; i < 500; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < 1e-300) d = 1e-300;
    c = b + an / c;
    if (std::abs(c) < 1e-300) c = 1e-300;
    d = 1 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1) < 1e-14) break;
  }
  return std::exp(-x + a * std::log(x) - gln) * h;
}

double whitened_log_ratio(const double* r0, const double* r1, std::size_t n, double* samples) {
  const auto a = fit_ar(r1, n, 5);
  const double s0 = whitened_ssr(r0, n, a), s1 = whitened_ssr(r1, n, a);
  *samples = static_cast<double>(n - a.size());
  return s0 > 0 && s1 > 0 ? *samples * std::log(s0 / s1) : 0.0;
}

void add_vuong_terms(const double* r0, const double* r1, std::size_t n, VuongSums& d) {
  const auto a = fit_ar(r0, n, 5);
  const auto e0 = whitened(r0, n, a), e1 = whitened(r1, n, a);
  for (std::size_t t = 0; t < e0.size(); ++t) {
    const double v = e1[t] * e1[t] - e0[t] * e0[t];
    d.sum += v, d.sum_sq += v * v, d.count += 1;
  }
}

double vuong_z(const VuongSums& d) {
  if (d.count < 2) return 0.0;
  const double mean = d.sum / d.count, var = d.sum_sq / d.count - mean * mean;
  return var > 0 ? mean / std::sqrt(var / d.count) : 0.0;
}

double ssr_of(const double* r, std::size_t n) {
  double s = 0;
  for (std::size_t i = 0; i < n; ++i) s += r[i] * r[i];
  return s;
}

std::vector<double> fit_ar(const double* r, std::size_t n, int max_order) {
  const int pmax = std::clamp<int>(max_order, 0, static_cast<int>(n / 4));
  const std::size_t m = n - pmax;  // samples every order is fitted on
  if (pmax == 0 || m < 8) return {};
  const Eigen::Map<const Eigen::VectorXd> y(r + pmax, m);
  Eigen::MatrixXd X(m, pmax);
  for (int i = 0; i < pmax; ++i) X.col(i) = Eigen::Map<const Eigen::VectorXd>(r + pmax - 1 - i, m);
  auto bic = [&](double ssr, int p) { return m * std::log(std::max(ssr / m, 1e-300)) + p * std::log(double(m)); };
  std::vector<double> best;
  double best_bic = bic(y.squaredNorm(), 0);
  for (int p = 1; p <= pmax; ++p) {
    const auto Xp = X.leftCols(p);
    const Eigen::VectorXd a = (Xp.transpose() * Xp).ldlt().solve(Xp.transpose() * y);
    if (!a.allFinite()) continue;
    if (const double b = bic((y - Xp * a).squaredNorm(), p); b < best_bic) {
      best_bic = b;
      best.assign(a.data(), a.data() + p);
    }
  }
  return best;
}

std::vector<double> whitened(const double* r, std::size_t n, const std::vector<double>& a) {
  std::vector<double> e;
  for (std::size_t t = a.size(); t < n; ++t) {
    double v = r[t];
    for (std::size_t i = 0; i < a.size(); ++i) v -= a[i] * r[t - 1 - i];
    e.push_back(v);
  }
  return e;
}

double whitened_ssr(const double* r, std::size_t n, const std::vector<double>& a) {
  double s = 0;
  for (double e : whitened(r, n, a)) s += e * e;
  return s;
}

}  // namespace pneumo::diagnose
