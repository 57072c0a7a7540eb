// The bounded Levenberg-Marquardt of framework/fit/bounded_lm.hpp (the
// diagnosis's fits) on closed forms: noise-free samples of y = a exp(-b t)
// give back a and b; with b's range ending below the b that made the data,
// the fit sits on that bound and a is the least-squares amplitude there,
// a = sum(y exp(-b t)) / sum(exp(-2 b t)).
#include <gtest/gtest.h>

#include <cmath>

#include "framework/fit/bounded_lm.hpp"

namespace pneumo {
namespace {

struct Decay {
  fit::ScaledBound a, b;
  std::vector<double> t, y;

  Decay(double a_true, double b_true, fit::ScaledBound a_range, fit::ScaledBound b_range) : a(a_range), b(b_range) {
    for (int i = 0; i <= 40; ++i) {
      t.push_back(0.05 * i);
      y.push_back(a_true * std::exp(-b_true * t.back()));
    }
  }
  std::vector<double> residual(const Eigen::VectorXd& u) const {
    std::vector<double> r;
    for (std::size_t i = 0; i < t.size(); ++i) r.push_back(y[i] - a.from_u(u[0]) * std::exp(-b.from_u(u[1]) * t[i]));
    return r;
  }
  fit::BatchResiduals batch() const {
    return [this](const std::vector<Eigen::VectorXd>& points) {
      std::vector<std::vector<double>> out;
      for (const auto& p : points) out.push_back(residual(p));
      return out;
    };
  }
  Eigen::VectorXd u(double a0, double b0) const { return Eigen::Vector2d(a.to_u(a0), b.to_u(b0)); }
};

fit::BoundedLmOptions iterations(int n) {
  fit::BoundedLmOptions o;
  o.max_iterations = n;
  return o;
}

TEST(BoundedLm, ScaledBoundsMapTheRangeOntoTheUnitInterval) {
  const fit::ScaledBound lin{2.0, 6.0, false}, log{0.1, 10.0, true};
  EXPECT_DOUBLE_EQ(lin.to_u(3.0), 0.25);
  EXPECT_DOUBLE_EQ(log.to_u(1.0), 0.5);  // the geometric middle
  EXPECT_DOUBLE_EQ(log.from_u(0.5), 1.0);
  EXPECT_EQ(lin.from_u(1.7), 6.0);  // clamped onto the bound
  EXPECT_EQ(lin.from_u(-0.3), 2.0);
}

TEST(BoundedLm, InteriorOptimumOfAnExponentialDecayIsFound) {
  const Decay d(2.0, 1.3, {0.5, 5.0, false}, {0.1, 10.0, true});
  const auto res = fit::bounded_lm(d.batch(), d.u(1.0, 0.5), {}, {}, iterations(60));
  EXPECT_NEAR(d.a.from_u(res.u[0]), 2.0, 2e-6);
  EXPECT_NEAR(d.b.from_u(res.u[1]), 1.3, 2e-6);
  EXPECT_LT(res.cost, 1e-10);
  EXPECT_GT(res.evaluations, 3);
}

TEST(BoundedLm, OptimumBeyondABoundSitsOnIt) {
  const Decay d(2.0, 2.0, {0.5, 5.0, false}, {0.1, 1.5, false});
  const auto res = fit::bounded_lm(d.batch(), d.u(1.0, 0.5), {}, {}, iterations(60));
  EXPECT_EQ(res.u[1], 1.0);  // on the upper bound of b, not near it
  double num = 0, den = 0;
  for (std::size_t i = 0; i < d.t.size(); ++i) {
    num += d.y[i] * std::exp(-1.5 * d.t[i]);
    den += std::exp(-3.0 * d.t[i]);
  }
  EXPECT_NEAR(d.a.from_u(res.u[0]), num / den, 1e-3 * num / den);
  double cost = 0;
  for (double r : d.residual(res.u)) cost += r * r;
  EXPECT_DOUBLE_EQ(res.cost, cost);
}

// A start far down the wrong slope: among the further starting points the
// one with the least cost replaces it, and the fit goes on from there.
TEST(BoundedLm, BestOfTheFurtherStartsReplacesAWorseStart) {
  const Decay d(2.0, 1.3, {0.5, 5.0, false}, {0.1, 10.0, true});
  const Eigen::VectorXd far = d.u(4.9, 9.5), near = d.u(2.2, 1.2), mid = d.u(1.0, 3.0);
  const auto one = fit::bounded_lm(d.batch(), far, {}, {mid, near}, iterations(0));
  EXPECT_EQ(one.u, near);
  EXPECT_EQ(one.evaluations, 3);
  const auto res = fit::bounded_lm(d.batch(), far, {}, {mid, near}, iterations(60));
  EXPECT_NEAR(d.b.from_u(res.u[1]), 1.3, 2e-6);
}

// A front - a pressure rising at t = 1/k over 20 ms, as at a stroke's end -
// sampled over 4 s, k on a log range 0.1-4. Far from the data's front the
// residuals' linearisation sees only the front's width, so Gauss-Newton
// steps stay short; striding along a direction taken twice reaches the
// data's k within the diagnosis's budget of 12 iterations (without it the
// fit stops at k = 0.89 from 0.63, at 1.30 from 2.3 toward 0.7).
TEST(BoundedLm, AFarStartOnAMovingFrontIsLeftWithinTwelveIterations) {
  const fit::ScaledBound k{0.1, 4.0, true};
  for (const auto& [start, truth] : {std::pair{0.63, 1.3}, std::pair{2.3, 0.7}}) {
    auto front = [](double kk, double t) { return std::tanh((t - 1.0 / kk) / 0.02); };
    const fit::BatchResiduals batch = [&](const std::vector<Eigen::VectorXd>& points) {
      std::vector<std::vector<double>> out;
      for (const auto& p : points) {
        std::vector<double> r;
        for (int i = 0; i <= 400; ++i) r.push_back(front(k.from_u(p[0]), 0.01 * i) - front(truth, 0.01 * i));
        out.push_back(r);
      }
      return out;
    };
    Eigen::VectorXd u0(1);
    u0[0] = k.to_u(start);
    const auto res = fit::bounded_lm(batch, u0, {}, {}, iterations(12));
    EXPECT_NEAR(k.from_u(res.u[0]), truth, 1e-3 * truth) << "from " << start;
  }
}

// A screen's arithmetic on residuals linear in u, r = A u - b: forward
// differences are A's columns (a step backwards at the upper face), and the
// Gauss-Newton share is the closed form 1 - min|r|^2 / |r(u)|^2, with the
// minimum over the columns taken free (the least-squares projection).
TEST(BoundedLm, ScreenOfALinearResidualIsItsLeastSquaresProjection) {
  Eigen::MatrixXd A(4, 3);
  A << 1, 2, 0, 0, 1, -1, 3, 0, 1, 1, 1, 1;
  const Eigen::Vector4d b(1, -2, 0.5, 3);
  const fit::BatchResiduals batch = [&](const std::vector<Eigen::VectorXd>& points) {
    std::vector<std::vector<double>> out;
    for (const auto& p : points) {
      const Eigen::VectorXd r = A * p - b;
      out.emplace_back(r.data(), r.data() + r.size());
    }
    return out;
  };
  const Eigen::Vector3d u(0.2, 1.0, 0.5);  // the second on its upper face
  const auto r = batch({u})[0];
  const Eigen::MatrixXd J = fit::forward_differences(batch, u, r, {1, 2});
  ASSERT_EQ(J.cols(), 2);
  EXPECT_TRUE(J.isApprox(A.rightCols(2), 1e-9));
  // Free along columns 1 and 2, u[0] held: the least-squares step.
  const Eigen::Map<const Eigen::VectorXd> rv(r.data(), 4);
  const Eigen::VectorXd step = A.rightCols(2).colPivHouseholderQr().solve(-rv);
  const double left = (rv + A.rightCols(2) * step).squaredNorm();
  EXPECT_NEAR(fit::gauss_newton_share(J, r), 1 - left / rv.squaredNorm(), 1e-9);
  EXPECT_EQ(fit::gauss_newton_share(Eigen::MatrixXd(4, 0), r), 0.0);
}

}  // namespace
}  // namespace pneumo
