// Bounded Levenberg-Marquardt in scaled coordinates: every parameter mapped
// onto u in [0, 1] between its bounds (logarithmically for a log-scale one),
// so that one finite-difference step and one damping suit them all, and a
// bound is a face of the unit box the iterate is clamped onto. For residuals
// that only a simulation gives (no derivatives, failures possible): the
// Jacobian by forward differences, the points of each stage handed to the
// caller together so that it may evaluate them in parallel. pneumo fit's
// Ceres fits (least_squares.hpp) have automatic derivatives instead.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <vector>

namespace pneumo::fit {

// One parameter's range and its map onto [0, 1].
struct ScaledBound {
  double lower = 0, upper = 1;
  bool log_scale = false;  // needs 0 < lower < upper

  double to_u(double value) const;
  double from_u(double u) const;  // u clamped to [0, 1]
};

// The residual vectors at several points of the unit box (all of one length).
using BatchResiduals = std::function<std::vector<std::vector<double>>(const std::vector<Eigen::VectorXd>& points)>;

struct BoundedLmOptions {
  int max_iterations = 12;
};

struct BoundedLmResult {
  Eigen::VectorXd u;
  std::vector<double> r;  // the residuals at u
  double cost = 0;        // their sum of squares
  int evaluations = 0;    // points evaluated
};

// Minimises |r(u)|^2 over the unit box from `u0` (its residuals `r0`, or
// empty to evaluate them). `starts`: further starting points against local
// minima, evaluated together; the best, if better than u0, replaces it.
// After two accepted steps in about one direction it strides on along it
// (1, 2, 4, 8 steps more, each while the cost falls): far from the fit of a
// moving front the linearisation predicts steps of the front's width.
// Stops after max_iterations, when an accepted step lowers the cost by less
// than 1e-4 of it, when a step moves u by less than 1e-7, or when six
// damped steps in a row fail to lower the cost.
BoundedLmResult bounded_lm(const BatchResiduals& residuals, const Eigen::VectorXd& u0, std::vector<double> r0,
                           const std::vector<Eigen::VectorXd>& starts, const BoundedLmOptions& options);

// The forward differences bounded_lm takes, of the residuals `r` at `u`
// along the coordinates `columns` (a step of 3e-3, backwards where a
// forward one would leave the box), the probes evaluated together.
Eigen::MatrixXd forward_differences(const BatchResiduals& residuals, const Eigen::VectorXd& u,
                                    const std::vector<double>& r, const std::vector<long>& columns);

// The share of |r|^2 that the undamped Gauss-Newton step of the Jacobian
// `J` removes in the linearisation, in [0, 1] (0 without a column): what a
// screen of a candidate's parameters predicts before any fit.
double gauss_newton_share(const Eigen::MatrixXd& J, const std::vector<double>& r);

}  // namespace pneumo::fit
