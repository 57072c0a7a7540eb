#include "framework/diagnose/next_run.hpp"

#include <algorithm>
#include <cmath>

#include "framework/core/parallel.hpp"

namespace pneumo::diagnose {

namespace {

using Scaled = std::vector<double>;  // a point with each parameter mapped onto [0, 1] over its range
using Traces = std::vector<std::vector<double>>;  // per signal, per sample

struct Score {
  bool ok = false;  // every member ran
  double separation = 0;
  int a = 0, b = 1, signal = -1;
};

// RMS over the samples of (a - b) / sigma.
double separation_of(const std::vector<double>& a, const std::vector<double>& b, double sigma) {
  double ssr = 0;
  for (std::size_t i = 0; i < a.size(); ++i) ssr += (a[i] - b[i]) * (a[i] - b[i]);
  return a.empty() ? 0.0 : std::sqrt(ssr / static_cast<double>(a.size())) / sigma;
}

// The group's smallest pairwise separation, each pair by its best signal.
Score score(const std::vector<const Traces*>& members, const std::vector<double>& sigma) {
  Score sc;
  for (const Traces* t : members)
    if (t->empty()) return sc;
  sc.ok = true;
  sc.separation = INFINITY;
  for (int a = 0; a < static_cast<int>(members.size()); ++a)
    for (int b = a + 1; b < static_cast<int>(members.size()); ++b) {
      double best = -1;
      int best_signal = 0;
      for (int s = 0; s < static_cast<int>(sigma.size()); ++s)
        if (const double sep = separation_of((*members[a])[s], (*members[b])[s], sigma[s]); sep > best)
          best = sep, best_signal = s;
      if (best < sc.separation) sc.separation = best, sc.a = a, sc.b = b, sc.signal = best_signal;
    }
  return sc;
}

class Search {
 public:
  explicit Search(const NextRunSearch& s) : s_(s) {}

  std::vector<double> si(const Scaled& u) const {
    std::vector<double> x(u.size());
    for (std::size_t k = 0; k < u.size(); ++k) x[k] = s_.axes[k].lower + u[k] * (s_.axes[k].upper - s_.axes[k].lower);
    return x;
  }
  Scaled scaled(const std::vector<double>& x) const {
    Scaled u(x.size());
    for (std::size_t k = 0; k < x.size(); ++k)
      u[k] = (x[k] - s_.axes[k].lower) / (s_.axes[k].upper - s_.axes[k].lower);
    return u;
  }

  // Every member simulated once at each point, all in parallel; the best
  // scored point among the `proposable` ones (all when empty) becomes the
  // proposal if it separates more than the one found so far.
  std::vector<Score> evaluate(const std::vector<Scaled>& points, const std::vector<bool>& proposable = {}) {
    const long m = static_cast<long>(s_.members.size());
    std::vector<Traces> out(points.size() * m);
    parallel_for(static_cast<long>(points.size()) * m, s_.threads,
                 [&](int, long j) { out[j] = s_.simulate(static_cast<int>(j % m), si(points[j / m])); });
    std::vector<Score> scores;
    for (std::size_t p = 0; p < points.size(); ++p) {
      std::vector<const Traces*> members;
      for (long k = 0; k < m; ++k) {
        members.push_back(&out[p * m + k]);
        found_.failed += out[p * m + k].empty() ? 1 : 0;
      }
      found_.simulations += m;
      found_.points += 1;
      scores.push_back(score(members, s_.sigma));
      const Score& sc = scores.back();
      if (!sc.ok || (!proposable.empty() && !proposable[p])) continue;
      if (found_.found && !(sc.separation > found_.separation)) continue;
      found_.found = true;
      found_.point = si(points[p]);
      best_u_ = points[p];
      found_.separation = sc.separation;
      found_.member_a = sc.a;
      found_.member_b = sc.b;
      found_.signal = sc.signal;
      const auto &a = out[p * m + sc.a][sc.signal], &b = out[p * m + sc.b][sc.signal];
      const double var = s_.sigma[sc.signal] * s_.sigma[sc.signal];
      found_.d2.assign(a.size(), 0.0);
      for (std::size_t i = 0; i < a.size(); ++i) found_.d2[i] = (a[i] - b[i]) * (a[i] - b[i]) / var;
    }
    return scores;
  }

  // The measured runs' points: what the data already have (and candidates
  // too where they lie inside the ranges searched).
  void measured() {
    std::vector<Scaled> points;
    std::vector<bool> inside;
    for (const auto& x : s_.measured_points) {
      const Scaled u = scaled(x);
      if (std::find(points.begin(), points.end(), u) != points.end()) continue;
      points.push_back(u);
      inside.push_back(std::all_of(u.begin(), u.end(), [](double v) { return v >= 0 && v <= 1; }));
    }
    if (points.empty()) return;
    for (const auto& sc : evaluate(points, inside))
      if (sc.ok) found_.separation_measured = std::max(found_.separation_measured, sc.separation);
  }

  // The coarse grid: as many levels per parameter (3 to 9) as keep it within kGridPoints.
  void grid() {
    const int d = static_cast<int>(s_.axes.size());
    int n = 9;
    while (n > 2 && std::pow(n, d) > kGridPoints) --n;
    long total = 1;
    for (int k = 0; k < d; ++k) total *= n;
    std::vector<Scaled> points;
    for (long j = 0; j < total; ++j) {
      Scaled u(d);
      long rest = j;
      for (int k = d; k-- > 0;) {
        u[k] = static_cast<double>(rest % n) / (n - 1);
        rest /= n;
      }
      points.push_back(u);
    }
    evaluate(points);
    step_ = 0.5 / (n - 1);
  }

  // A local pattern search from the best point: each parameter a step up and
  // down; move when a neighbour separates more, else halve the step.
  void refine() {
    for (int round = 0; round < 4 && found_.found && step_ > 1.0 / 128; ++round) {
      std::vector<Scaled> points;
      for (std::size_t k = 0; k < best_u_.size(); ++k)
        for (double dir : {-1.0, 1.0}) {
          Scaled u = best_u_;
          u[k] = std::clamp(u[k] + dir * step_, 0.0, 1.0);
          if (u != best_u_) points.push_back(u);
        }
      const double before = found_.separation;
      if (!points.empty()) evaluate(points);
      if (!(found_.separation > before)) step_ /= 2;
    }
  }

  NextRunFound result() const { return found_; }

 private:
  const NextRunSearch& s_;
  NextRunFound found_;
  Scaled best_u_;
  double step_ = 0.25;
};

}  // namespace

NextRunFound search_next_run(const NextRunSearch& s) {
  if (s.axes.empty() || s.members.size() < 2 || !s.simulate) return {};
  Search search(s);
  search.measured();
  search.grid();
  search.refine();
  return search.result();
}

}  // namespace pneumo::diagnose
