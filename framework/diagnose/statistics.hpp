// Numerical helpers of the diagnosis: interpolation of a sampled signal,
// the regularised incomplete gamma function (chi-square p-values), the
// effective sample size of an autocorrelated residual series, sums of squares.
#pragma once

#include <cstddef>
#include <vector>

namespace pneumo::diagnose {

// y(tq) by linear interpolation in (t, y), held constant outside.
double interp(const std::vector<double>& t, const std::vector<double>& y, double tq);
// Regularised upper incomplete gamma Q(a, x).
double gamma_q(double a, double x);
// Effective number of independent samples of r[0..n) (lag-1 autocorrelation).
double effective_n(const double* r, std::size_t n);
double ssr_of(const double* r, std::size_t n);

}  // namespace pneumo::diagnose
