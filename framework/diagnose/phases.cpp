#include "framework/diagnose/phases.hpp"

#include <algorithm>
#include <cmath>

namespace pneumo::diagnose {

namespace {

// Without a declared list: "start" and every tagged event, by the median of
// its first times over the runs where it happened.
std::vector<std::string> event_phases(const std::vector<PhaseStarts>& starts) {
  std::map<std::string, std::vector<double>> seen;
  for (const auto& s : starts)
    for (const auto& [ref, t] : s)
      if (ref.find('.') != std::string::npos && !std::isnan(t)) seen[ref].push_back(t);
  std::vector<std::pair<double, std::string>> order;
  for (auto& [ref, times] : seen) {
    std::sort(times.begin(), times.end());
    order.emplace_back(times[times.size() / 2], ref);
  }
  std::sort(order.begin(), order.end());
  std::vector<std::string> out = {"start"};
  for (const auto& [t, ref] : order) out.push_back(ref);
  return out;
}

}  // namespace

Phases assign_phases(const std::vector<PhaseDecl>& declared, const std::vector<std::vector<double>>& run_times,
                     const std::vector<PhaseStarts>& starts) {
  Phases ph;
  std::vector<std::string> from;
  for (const auto& p : declared) ph.names.push_back(p.name), from.push_back(p.from);
  if (declared.empty()) ph.names = from = event_phases(starts);
  for (std::size_t k = 0; k < run_times.size(); ++k) {
    const auto& t = run_times[k];
    // A phase whose start never came is empty; starts never go back in time.
    std::vector<double> pt;
    for (const auto& f : from) {
      const auto it = starts[k].find(f);
      const double s0 =
          f == "start" ? t.front() : it == starts[k].end() || std::isnan(it->second) ? t.back() : it->second;
      pt.push_back(std::clamp(std::max(s0, pt.empty() ? t.front() : pt.back()), t.front(), t.back()));
    }
    pt.push_back(t.back());
    std::vector<int> of(t.size(), 0);
    for (std::size_t i = 0, p = 0; i < t.size(); ++i) {
      while (p + 1 < from.size() && t[i] >= pt[p + 1]) ++p;
      of[i] = static_cast<int>(p);
    }
    ph.times.push_back(std::move(pt));
    ph.of_sample.push_back(std::move(of));
  }
  return ph;
}

}  // namespace pneumo::diagnose
