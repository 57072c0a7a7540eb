#include "framework/diagnose/ranking.hpp"

#include <algorithm>

namespace pneumo::diagnose {

double excess_reduction(double gap_before, double gap_after) {
  const double e0 = std::max(gap_before - 1.0, 1e-12), e1 = std::max(gap_after - 1.0, 0.0);
  return (e0 - e1) / e0;
}

namespace {

bool removes_enough(const Gap& before, const Gap& after, double noise_uncertainty) {
  const double ms0 = before.rms * before.rms, removed = ms0 - after.rms * after.rms;
  const double u = noise_uncertainty;
  return removed >= 1.0 && removed >= ((1 + u) * (1 + u) - 1) * ms0;
}

}  // namespace

bool explains_the_data(const GapTable& gap, const DiagnoseOptions& opt) {
  if (gap.total.rms > opt.adequate_gap) return false;
  return std::none_of(gap.by_signal.begin(), gap.by_signal.end(),
                      [&](const Gap& g) { return g.rms > opt.adequate_gap; });
}

bool practically_significant(const GapTable& before, const GapTable& after, const DiagnoseOptions& opt,
                             std::string* why) {
  if (removes_enough(before.total, after.total, opt.noise_uncertainty)) {
    if (why) *why = "total";
    return true;
  }
  for (std::size_t s = 0; s < before.by_signal.size() && s < after.by_signal.size(); ++s)
    if (before.by_signal[s].rms > opt.adequate_gap &&
        removes_enough(before.by_signal[s], after.by_signal[s], opt.noise_uncertainty)) {
      if (why) *why = before.signals[s];
      return true;
    }
  return false;
}

std::vector<int> rank_effects(std::vector<EffectResult>& results) {
  std::vector<int> order;
  for (std::size_t k = 0; k < results.size(); ++k)
    if (results[k].unavailable.empty()) order.push_back(static_cast<int>(k));
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    const auto &A = results[a], &B = results[b];
    if (A.screened_out != B.screened_out) return !A.screened_out;
    if (A.screened_out) return A.screening_improvement > B.screening_improvement;
    // A fit whose model the solver could not run on every validation run is
    // no fit: its gap is a sentinel's, ranked after every fit that ran.
    if ((A.failed_validation_runs > 0) != (B.failed_validation_runs > 0)) return A.failed_validation_runs == 0;
    if (A.significant != B.significant) return A.significant;
    const double ra = excess_reduction(A.gap_before, A.gap_after), rb = excess_reduction(B.gap_before, B.gap_after);
    // Two that each bring the gap within the noise remove all of its excess:
    // the likelihood, not the order the candidates were declared in, decides.
    if (ra != rb) return ra > rb;
    return A.delta_bic > B.delta_bic;
  });
  for (std::size_t q = 0; q < order.size(); ++q) results[order[q]].rank = static_cast<int>(q) + 1;
  return order;
}

}  // namespace pneumo::diagnose
