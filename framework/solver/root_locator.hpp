// State events. The root functions are checked once per step at its end
// t_n, on the y(t_n) IDA returns; a sign change since the last check is
// located on IDA's interpolant (Illinois), and the event handled there. If
// the event re-initialises, IDA restarts from the event (the rest of the
// step is discarded); otherwise the search goes on to t_n. IDA's own root
// finding does the same but interpolates y(t_n) once more per step.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pneumo {

class RootLocator {
 public:
  explicit RootLocator(int n_roots)
      : n_(n_roots),
        root_info_(std::max(1, n_roots)),
        lo_(n_roots),
        hi_(n_roots),
        c_(n_roots),
        t_of_(n_roots),
        g_root_(n_roots),
        g_before_(n_roots) {}
  int size() const { return n_; }

  // Start an interval at t with the root functions g there (filled by the
  // caller into low()); `fired`: the roots just handled, which count as
  // crossed whatever rounding left at t.
  std::vector<double>& low() { return lo_; }
  // A handled root left on its old side counts as crossed only if g is
  // still what it was where the crossing was located (rounding, or exactly
  // 0); an event that re-armed it (a timer started again, due later) moved
  // g away, and its next crossing is a new event, however soon (issue 29: a
  // timer due 1 us after its previous event was lost, or fired at once).
  void start(double t, const std::vector<int>* fired) {
    t_lo_ = t;
    if (!fired) return;
    for (int i = 0; i < n_; ++i) {
      const int dir = (*fired)[i];
      if (dir == 0) continue;
      const double tol = 1e-9 * (std::abs(g_root_[i]) + std::abs(g_before_[i]));
      if (std::abs(lo_[i] - g_root_[i]) > tol) continue;  // re-armed: keep its side
      lo_[i] = dir > 0 ? std::max(lo_[i], 1e-300) : std::min(lo_[i], -1e-300);
    }
  }
  // The root functions at the step's end, filled by the caller.
  std::vector<double>& high() { return hi_; }

  // The earliest crossing in (t_lo, t_hi] of the interval; false if none.
  // g_at(t, g) fills the root functions at t on the interpolant. root_info()
  // then flags the roots crossing there (+1 rising, -1 falling, as IDA).
  template <class G>
  bool locate(double t_hi, double h_last, G&& g_at, double& t_root) {
    const double ttol = 100.0 * std::numeric_limits<double>::epsilon() * (std::abs(t_hi) + std::abs(h_last));
    bool any = false;
    t_root = t_hi;
    std::fill(root_info_.begin(), root_info_.end(), 0);
    std::fill(t_of_.begin(), t_of_.end(), std::numeric_limits<double>::infinity());
    for (int i = 0; i < n_; ++i) {
      if (lo_[i] == 0.0 || !crosses(lo_[i], hi_[i])) continue;
      t_of_[i] = illinois(i, t_hi, ttol, g_at);  // the first point where g has crossed
      if (t_of_[i] < t_root || !any) t_root = t_of_[i];
      any = true;
    }
    if (!any) return false;
    for (int i = 0; i < n_; ++i)
      if (t_of_[i] <= t_root + ttol) root_info_[i] = lo_[i] < 0 ? 1 : -1;
    return true;
  }
  const std::vector<int>& root_info() const { return root_info_; }

  // The events at t_root did not re-initialise: search on over (t_root,
  // t_hi] from the root functions at t_root (filled into low() by the
  // caller); the roots handled keep their new side.
  void passed(double t_root, const std::vector<int>& fired) {
    t_lo_ = t_root;
    for (int i = 0; i < n_; ++i)
      if (fired[i] != 0) lo_[i] = hi_[i];
  }
  // The step is done: its end starts the next interval.
  void step_done(double t_hi) {
    lo_ = hi_;
    t_lo_ = t_hi;
  }

 private:
  // A root function exactly 0 at the start of an interval has no side yet:
  // its first nonzero value sets it, without an event (as IDA does).
  static bool crosses(double a, double b) { return (a < 0 && b >= 0) || (a > 0 && b <= 0); }

  // Root i's crossing in (t_lo, t_hi] by the Illinois variant of regula falsi.
  template <class G>
  double illinois(int i, double t_hi, double ttol, G& g_at) {
    double a = t_lo_, fa = lo_[i], b = t_hi, fb = hi_[i];
    g_before_[i] = fa, g_root_[i] = fb;  // g at a and b, without Illinois' halving
    int side = 0;
    for (int it = 0; it < 60 && b - a > ttol && fb != 0.0; ++it) {
      double c = b - fb * (b - a) / (fb - fa);
      c = std::min(std::max(c, a + 0.5 * ttol), b - 0.5 * ttol);
      g_at(c, c_);
      const double fc = c_[i];
      if (crosses(fa, fc)) {  // the root lies in (a, c]
        b = c, fb = fc;
        g_root_[i] = fc;
        if (side == -1) fa *= 0.5;
        side = -1;
      } else {
        a = c, fa = fc;
        g_before_[i] = fc;
        if (side == 1) fb *= 0.5;
        side = 1;
      }
    }
    return b;
  }

  int n_;
  std::vector<int> root_info_;
  std::vector<double> lo_, hi_, c_, t_of_;
  std::vector<double> g_root_, g_before_;  // each root's g at its located crossing and just before
  double t_lo_ = 0.0;
};

}  // namespace pneumo
