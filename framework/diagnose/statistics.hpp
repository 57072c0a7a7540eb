// Numerical helpers of the diagnosis: interpolation of a sampled signal,
// the regularised incomplete gamma function (chi-square p-values), sums of
// squares, and the AR(p) whitening that makes a likelihood ratio honest for smooth,
// autocorrelated residuals.
#pragma once

#include <cstddef>
#include <vector>

namespace pneumo::diagnose {

// y(tq) by linear interpolation in (t, y), held constant outside.
double interp(const std::vector<double>& t, const std::vector<double>& y, double tq);
// Regularised upper incomplete gamma Q(a, x).
double gamma_q(double a, double x);
double ssr_of(const double* r, std::size_t n);

// Coefficients a_1..a_p of the autoregression r_t = sum_i a_i r_{t-i} + e_t,
// fitted to r[0..n) by least squares for p = 0..max_order (all on the samples
// t >= max_order, so that the orders compete on the same data) and p chosen
// by BIC. Empty: white (p = 0).
std::vector<double> fit_ar(const double* r, std::size_t n, int max_order);
// The whitened series e_t = r_t - sum_i a_i r_{t-i}, t >= p.
std::vector<double> whitened(const double* r, std::size_t n, const std::vector<double>& a);
// Its sum of squares.
double whitened_ssr(const double* r, std::size_t n, const std::vector<double>& a);
// Log-likelihood ratio of residual series r1 over r0 (both n long) after
// whitening both with r1's AR(p), p <= 5: (n - p) ln(SSR0_w / SSR1_w);
// `samples` gets n - p.
double whitened_log_ratio(const double* r0, const double* r1, std::size_t n, double* samples);

// Vuong's test of two non-nested models on one residual series each: the
// terms d_t = e1_t^2 - e0_t^2 (both whitened with r0's AR(p), p <= 5) added
// to `d` (their sum, sum of squares and count), so that several series
// make one statistic (vuong_z).
struct VuongSums {
  double sum = 0, sum_sq = 0, count = 0;
};
void add_vuong_terms(const double* r0, const double* r1, std::size_t n, VuongSums& d);
// The statistic: the mean of d_t over its standard error; above about 2,
// model 0 fits significantly better, below -2 model 1.
double vuong_z(const VuongSums& d);

}  // namespace pneumo::diagnose
