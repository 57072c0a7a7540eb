// Global sensitivity analysis of scalar run metrics over parameter ranges.
//
// Both methods work on the unit hypercube u in [0, 1]^k (parameter j =
// lo_j + u_j (hi_j - lo_j)); the designs are plain point lists that a sweep
// runs, and the estimators take the metric values back (NaN = failed run).
//
// Morris screening (Morris 1991, mu* of Campolongo et al. 2007): r random
// one-at-a-time trajectories on a p-level grid, step Delta = p / (2 (p - 1)).
// Elementary effect EE_j = (f(u + Delta e_j) - f(u)) / Delta, i.e. the
// change of f per full range of parameter j. Reported: mu = mean EE,
// mu* = mean |EE| (importance), sigma = standard deviation of EE
// (non-linearity and interactions). An effect whose two runs did not both
// succeed is left out (n says how many were used).
//
// Sobol indices (Saltelli et al. 2010): matrices A and B of N random points,
// and AB_j = A with column j from B; N (k + 2) runs. With V the variance of
// f over A and B,
//   first order  S_j  = mean( (f(B) - f0) (f(AB_j) - f(A)) ) / V   (Saltelli 2010;
//                f0 = mean of f over A and B: centring leaves the expectation
//                unchanged and removes the variance a large mean would add)
//   total        ST_j = mean( (f(A) - f(AB_j))^2 ) / (2 V)    (Jansen 1999)
// Rows j of the design with a failed run are left out. Confidence
// intervals: percentile bootstrap over the rows.
#pragma once

#include <cstdint>
#include <vector>

namespace pneumo::study {

using UnitPoint = std::vector<double>;

struct MorrisPlan {
  int k = 0, trajectories = 0, levels = 4;
  std::vector<UnitPoint> points;  // trajectories * (k + 1), trajectory by trajectory
  std::vector<int> moved;         // per point: the factor changed from the previous point (-1 at a start)
};
MorrisPlan morris_plan(int k, int trajectories, int levels, std::uint64_t seed);

struct MorrisIndices {
  std::vector<double> mu, mu_star, sigma;
  std::vector<int> effects;  // elementary effects used per factor
};
MorrisIndices morris_indices(const MorrisPlan& plan, const std::vector<double>& f);

struct SobolPlan {
  int k = 0, base = 0;
  // base rows of A, then of B, then of AB_0, ..., AB_{k-1}: base * (k + 2)
  std::vector<UnitPoint> points;
};
SobolPlan sobol_plan(int k, int base, std::uint64_t seed);

struct SobolIndices {
  std::vector<double> first, total;
  std::vector<double> first_lo, first_hi, total_lo, total_hi;  // 95 % bootstrap intervals
  double variance = 0.0;
  int rows_used = 0;
};
SobolIndices sobol_indices(const SobolPlan& plan, const std::vector<double>& f, int bootstrap = 200,
                           std::uint64_t seed = 1);

}  // namespace pneumo::study
