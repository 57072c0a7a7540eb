// Ceres driver shared by the fitting tools (implementation header: include
// only from framework/fit/*.cpp). Each coefficient is its own parameter
// block, so that bounds and fixing are per coefficient.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Dense>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "framework/fit/least_squares.hpp"

namespace pneumo::fit::detail {

// Functor: template <class T> bool operator()(T const* const* p, T* r) const
// with one residual = (model - observed) / scale; observed() and scale given.
template <class Functor>
FitReport solve(std::vector<FitParameter> params, const std::vector<Functor>& residuals,
                const std::vector<double>& observed, double scale) {
  check_parameters(params);
  FitReport rep;
  const int k = static_cast<int>(params.size());
  std::vector<double> x(k);
  for (int i = 0; i < k; ++i) x[i] = params[i].initial;

  ceres::Problem problem;
  std::vector<double*> blocks;
  for (int i = 0; i < k; ++i) blocks.push_back(&x[i]);
  for (const auto& f : residuals) {
    // Stride 10: every model's coefficients (eq. 8 and an offset: 10) in one
    // pass of the automatic differentiation, not three.
    auto* cost = new ceres::DynamicAutoDiffCostFunction<Functor, 10>(new Functor(f));
    for (int i = 0; i < k; ++i) cost->AddParameterBlock(1);
    cost->SetNumResiduals(1);
    problem.AddResidualBlock(cost, nullptr, blocks);
  }
  int free = 0;
  for (int i = 0; i < k; ++i) {
    if (params[i].fixed) {
      problem.SetParameterBlockConstant(&x[i]);
      continue;
    }
    ++free;
    if (std::isfinite(params[i].lower)) problem.SetParameterLowerBound(&x[i], 0, params[i].lower);
    if (std::isfinite(params[i].upper)) problem.SetParameterUpperBound(&x[i], 0, params[i].upper);
  }
  const int n = static_cast<int>(residuals.size());
  if (n <= free)
    throw std::invalid_argument("too few points: " + std::to_string(n) + " data points for " +
                                std::to_string(free) + " free coefficients (need more points than coefficients)");

  ceres::Solver::Options opt;
  opt.linear_solver_type = ceres::DENSE_QR;
  // Converged when a step changes the cost by less than 1e-9 of itself:
  // far below the RSS's own sampling spread (relative sqrt(2/(n-k)), 1e-2
  // for 20 000 points). A tighter tolerance only made the solver crawl for
  // hundreds of iterations on real data whose optimum lies on a bound (the
  // exponent a) with nearly collinear coefficients (kv |v|^a and b), never
  // reporting convergence. Data without noise still converge tightly: there
  // the cost falls by orders of magnitude per step until the gradient test.
  opt.function_tolerance = 1e-9;
  opt.gradient_tolerance = 1e-14;
  opt.parameter_tolerance = 1e-10;
  opt.logging_type = ceres::SILENT;
  // A coefficient that ends on a bound is held there and the rest solved
  // again: with it free, every step the solver proposes leaves the box and
  // is cut back, so the trust region crawls along the bound (real friction
  // data: the exponent a at its lower bound) instead of converging.
  ceres::Solver::Summary summary;
  std::vector<bool> held(k, false);
  int iterations = 0;
  for (int pass = 0; pass < 3; ++pass) {
    opt.max_num_iterations = pass == 0 ? 100 : 400;
    ceres::Solve(opt, &problem, &summary);
    iterations += static_cast<int>(summary.iterations.size());
    bool newly_held = false;
    for (int i = 0; i < k; ++i)
      if (!params[i].fixed && !held[i] && (x[i] == params[i].lower || x[i] == params[i].upper)) {
        problem.SetParameterBlockConstant(&x[i]);
        held[i] = newly_held = true;
      }
    if (!newly_held && (summary.termination_type == ceres::CONVERGENCE || pass > 0)) break;
  }

  rep.points = n;
  rep.free_parameters = free;
  rep.converged = summary.termination_type == ceres::CONVERGENCE;
  rep.iterations = iterations;
  rep.solver_message = summary.message;
  rep.rss = 2.0 * summary.final_cost * scale * scale;  // Ceres' cost is 1/2 sum r^2
  double mean = 0;
  for (double o : observed) mean += o;
  mean /= n;
  for (double o : observed) rep.tss += (o - mean) * (o - mean);
  rep.r2 = rep.tss > 0 ? 1.0 - rep.rss / rep.tss : std::numeric_limits<double>::quiet_NaN();

  // Standard errors: (J^T J)^-1 sigma^2 with sigma^2 = RSS/(n - k), from the
  // Jacobian at the solution (columns scaled to unit norm for the rank test);
  // none for a coefficient on its bound (a one-sided estimate).
  // A singular problem (a coefficient the data do not determine, e.g. FS when
  // vS sits so low that exp(-|v|/vS) vanishes at every point) gives NaN.
  std::vector<double*> free_blocks;
  std::vector<int> free_index;
  for (int i = 0; i < k; ++i)
    if (!params[i].fixed && !held[i]) free_blocks.push_back(&x[i]), free_index.push_back(i);
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = free_blocks;
  ceres::CRSMatrix crs;
  if (!free_blocks.empty() && problem.Evaluate(eo, nullptr, nullptr, nullptr, &crs)) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
    for (int r = 0; r < crs.num_rows; ++r)
      for (int q = crs.rows[r]; q < crs.rows[r + 1]; ++q) J(r, crs.cols[q]) = crs.values[q];
    // A coefficient the residuals do not depend on at all (a zero column:
    // the exponent a once kv sits at 0) has no error; the others still do.
    std::vector<int> cols;
    for (int j = 0; j < static_cast<int>(J.cols()); ++j)
      if (J.col(j).norm() > 0) cols.push_back(j);
    Eigen::MatrixXd Jn(J.rows(), static_cast<Eigen::Index>(cols.size()));
    for (std::size_t c = 0; c < cols.size(); ++c) Jn.col(c) = J.col(cols[c]);
    const Eigen::VectorXd norms = Jn.colwise().norm();
    if (!cols.empty()) {
      const Eigen::MatrixXd Js = Jn * norms.cwiseInverse().asDiagonal();
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Js.transpose() * Js);
      const auto ev = es.eigenvalues();
      if (ev.minCoeff() > 1e-12 * ev.maxCoeff()) {
        const Eigen::MatrixXd inv_s = es.eigenvectors() * ev.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
        const double sigma2 = rep.rss / (scale * scale) / (n - free);
        for (std::size_t c = 0; c < cols.size(); ++c)
          params[free_index[cols[c]]].std_error = std::sqrt(inv_s(c, c) * sigma2) / norms(c);
      }
    }
  }
  for (int i = 0; i < k; ++i) params[i].value = x[i];
  rep.parameters = std::move(params);
  return rep;
}

}  // namespace pneumo::fit::detail
