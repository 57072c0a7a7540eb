#include "framework/fit/bounded_lm.hpp"

#include <algorithm>
#include <cmath>

namespace pneumo::fit {

double ScaledBound::to_u(double v) const {
  return log_scale ? std::log(v / lower) / std::log(upper / lower) : (v - lower) / (upper - lower);
}

double ScaledBound::from_u(double u) const {
  u = std::clamp(u, 0.0, 1.0);
  return log_scale ? lower * std::pow(upper / lower, u) : lower + u * (upper - lower);
}

namespace {

double sum_of_squares(const std::vector<double>& r) {
  double s = 0;
  for (double x : r) s += x * x;
  return s;
}

// The iterate: point, residuals, cost, damping, the last step taken.
struct State {
  Eigen::VectorXd u;
  std::vector<double> r;
  double cost = 0, lambda = 1e-2;
  Eigen::VectorXd last_step;
};

std::vector<long> every_column(long n) {
  std::vector<long> all(n);
  for (long k = 0; k < n; ++k) all[k] = k;
  return all;
}

// Evaluates `un` and moves there if its cost is lower; false: it is not.
bool move_if_lower(const BatchResiduals& residuals, State& s, BoundedLmResult& out, const Eigen::VectorXd& un) {
  auto rn = residuals({un})[0];
  out.evaluations += 1;
  const double cn = sum_of_squares(rn);
  if (!(cn < s.cost)) return false;  // a NaN cost (a failed run) is never lower
  s.u = un;
  s.r = std::move(rn);
  s.cost = cn;
  return true;
}

// Two steps in a row the same way: the linearisation underestimates how far
// the minimum lies (far from a fit whose residuals are a moving front - a
// stroke's end - it sees only the front's width), and one step an iteration
// crawls. Strides of 1, 2, 4 and 8 more such steps, each taken while it
// lowers the cost.
void stride(const BatchResiduals& residuals, State& s, BoundedLmResult& out, Eigen::VectorXd step) {
  for (int k = 0; k < 4; ++k) {
    const Eigen::VectorXd un = (s.u + step).cwiseMax(0.0).cwiseMin(1.0);
    if ((un - s.u).norm() < 1e-7 || !move_if_lower(residuals, s, out, un)) return;
    step *= 2;
  }
}

// One iteration: up to six damped steps, the first that lowers the cost is
// taken. Returns false when the fit stops: converged, or no step lowered
// the cost.
bool lm_step(const BatchResiduals& residuals, State& s, BoundedLmResult& out) {
  const long np = s.u.size();
  const Eigen::MatrixXd J = forward_differences(residuals, s.u, s.r, every_column(np));
  out.evaluations += static_cast<int>(np);
  const Eigen::Map<const Eigen::VectorXd> rv(s.r.data(), static_cast<long>(s.r.size()));
  Eigen::MatrixXd A = J.transpose() * J;
  Eigen::VectorXd g = J.transpose() * rv;
  // A parameter on a bound whose descent points out of the box is held
  // there: the others' step is then the one of the problem without it, not
  // a coupled step cut off at the bound.
  for (long k = 0; k < np; ++k)
    if ((s.u[k] <= 0.0 && g[k] > 0) || (s.u[k] >= 1.0 && g[k] < 0)) {
      A.row(k).setZero();
      A.col(k).setZero();
      g[k] = 0;
    }
  for (int tries = 0; tries < 6; ++tries) {
    Eigen::MatrixXd M = A;
    for (long k = 0; k < np; ++k) M(k, k) += s.lambda * std::max(A(k, k), 1e-12) + 1e-12;
    const Eigen::VectorXd d = M.ldlt().solve(-g);
    const Eigen::VectorXd un = (s.u + d).cwiseMax(0.0).cwiseMin(1.0);
    if ((un - s.u).norm() < 1e-7) return false;
    const Eigen::VectorXd step = un - s.u;
    const double cost = s.cost;
    if (move_if_lower(residuals, s, out, un)) {
      const double gain = (cost - s.cost) / cost;
      const bool crawling = s.last_step.size() == np && step.dot(s.last_step) > 0.9 * step.norm() * s.last_step.norm();
      s.lambda = std::max(s.lambda / 4, 1e-7);
      s.last_step = step;
      if (crawling) stride(residuals, s, out, step);
      return gain >= 1e-4;  // below: converged
    }
    s.lambda *= 8;
  }
  return false;
}

}  // namespace

BoundedLmResult bounded_lm(const BatchResiduals& residuals, const Eigen::VectorXd& u0, std::vector<double> r0,
                           const std::vector<Eigen::VectorXd>& starts, const BoundedLmOptions& options) {
  BoundedLmResult out;
  State s;
  s.u = u0;
  if (r0.empty()) {
    s.r = residuals({u0})[0];
    out.evaluations += 1;
  } else {
    s.r = std::move(r0);
  }
  if (!starts.empty()) {
    const auto rs = residuals(starts);
    out.evaluations += static_cast<int>(starts.size());
    double best = sum_of_squares(s.r);
    for (std::size_t k = 0; k < starts.size(); ++k)
      if (const double c = sum_of_squares(rs[k]); c < best) {
        best = c;
        s.u = starts[k];
        s.r = rs[k];
      }
  }
  s.cost = sum_of_squares(s.r);
  for (int it = 0; it < options.max_iterations && s.u.size() > 0; ++it)
    if (!lm_step(residuals, s, out)) break;
  out.u = std::move(s.u);
  out.r = std::move(s.r);
  out.cost = s.cost;
  return out;
}

Eigen::MatrixXd forward_differences(const BatchResiduals& residuals, const Eigen::VectorXd& u,
                                    const std::vector<double>& r, const std::vector<long>& columns) {
  constexpr double h = 3e-3;
  std::vector<Eigen::VectorXd> probes;
  std::vector<double> steps;
  for (long k : columns) {
    Eigen::VectorXd up = u;
    steps.push_back(u[k] + h <= 1.0 ? h : -h);
    up[k] += steps.back();
    probes.push_back(up);
  }
  const auto rp = residuals(probes);
  Eigen::MatrixXd J(r.size(), static_cast<long>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c)
    for (std::size_t i = 0; i < r.size(); ++i) J(i, c) = (rp[c][i] - r[i]) / steps[c];
  return J;
}

double gauss_newton_share(const Eigen::MatrixXd& J, const std::vector<double>& r) {
  if (J.cols() == 0) return 0;
  const Eigen::Map<const Eigen::VectorXd> rv(r.data(), static_cast<long>(r.size()));
  const Eigen::VectorXd g = J.transpose() * rv;
  const Eigen::VectorXd d = (J.transpose() * J).ldlt().solve(-g);
  return std::clamp(-(g.dot(d)) / std::max(sum_of_squares(r), 1e-300), 0.0, 1.0);
}

}  // namespace pneumo::fit
