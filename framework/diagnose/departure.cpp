#include "framework/diagnose/departure.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>

#include "framework/assembly/evaluator.hpp"

namespace pneumo::diagnose {

namespace {

// A residual difference that moves no unknown by more than this share of
// IDA's error weight over an output interval is no departure.
constexpr double kNegligible = 1e-2;

bool alike(const System& a, const System& b) {
  if (a.size() != b.size() || a.n_roots() != b.n_roots() || a.variable_names() != b.variable_names() ||
      a.differential() != b.differential() || a.col_ptr() != b.col_ptr() || a.row_idx() != b.row_idx())
    return false;
  std::vector<double> ya, ypa, yb, ypb;
  a.start_values(ya, ypa);
  b.start_values(yb, ypb);
  return ya == yb && ypa == ypb;
}

// The first time at which the two models' time events differ (infinity if
// they never do).
double first_other_time_event(const System& a, const System& b) {
  const auto ea = a.time_events(), eb = b.time_events();
  const std::size_t n = std::min(ea.size(), eb.size());
  for (std::size_t i = 0; i < n; ++i)
    if (ea[i] != eb[i]) return std::min(ea[i], eb[i]);
  if (ea.size() != eb.size()) return n < ea.size() ? ea[n] : eb[n];
  return INFINITY;
}

// The largest move of an unknown, in IDA's error weights, that a residual
// difference causes through the unpatched model's Newton matrix at
// cj = 1/dt. The matrix's pattern is the System's: its ordering is found
// once.
class WeightedMove {
 public:
  WeightedMove(const System& s, const Evaluator& eval, const SolverOptions& options)
      : s_(s), eval_(eval), options_(options) {}

  double operator()(const Checkpoint& c, const std::vector<double>& d, double dt) {
    const int n = s_.size();
    std::vector<double> values(static_cast<std::size_t>(s_.nnz()));
    if (eval_.jacobian(c.t, c.y.data(), c.yp.data(), 1.0 / dt, values.data()) != 0) return INFINITY;
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(values.size());
    for (int col = 0; col < n; ++col)
      for (long k = s_.col_ptr()[col]; k < s_.col_ptr()[col + 1]; ++k)
        entries.emplace_back(static_cast<int>(s_.row_idx()[k]), col, values[k]);
    Eigen::SparseMatrix<double> J(n, n);
    J.setFromTriplets(entries.begin(), entries.end());
    if (!analysed_) lu_.analyzePattern(J), analysed_ = true;
    lu_.factorize(J);
    if (lu_.info() != Eigen::Success) return INFINITY;
    const Eigen::VectorXd move = lu_.solve(Eigen::Map<const Eigen::VectorXd>(d.data(), n));
    if (lu_.info() != Eigen::Success) return INFINITY;
    double worst = 0;
    for (int i = 0; i < n; ++i) {
      const double weight = options_.rtol * std::abs(c.y[i]) + options_.atol * s_.nominal()[i];
      worst = std::max(worst, std::abs(move[i]) / weight);
    }
    return std::isfinite(worst) ? worst : INFINITY;
  }

 private:
  const System& s_;
  const Evaluator& eval_;
  const SolverOptions& options_;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu_;
  bool analysed_ = false;
};

int sign(double g) { return (g > 0) - (g < 0); }

// The two models side by side at the unpatched run's checkpoints, in order.
class SideBySide {
 public:
  SideBySide(const System& unpatched, const System& patched, const SolverOptions& options)
      : unpatched_(unpatched), options_(options), eu_(unpatched), ep_(patched),
        outputs_u_(unpatched.probe_set(integrands(unpatched))), outputs_p_(patched.probe_set(integrands(patched))),
        move_(unpatched, eu_, options) {}

  // Whether the patched model is the unpatched one at checkpoint c and,
  // for its events, since the one before.
  bool same_at(const Checkpoint& c) {
    if (c.modes.size() != eu_.modes().size() || c.modes.size() != ep_.modes().size()) return false;
    eu_.restore_modes(c.modes);
    ep_.restore_modes(c.modes);
    return same_events(c) && same_outputs(c) && same_residual(c);
  }

 private:
  // The circuit's outputs, an integral's integrand in its place.
  static std::vector<Probe> integrands(const System& s) {
    std::vector<Probe> probes = s.circuit().probes;
    for (auto& p : probes) p.integral = false;
    return probes;
  }

  // What is measured may read the patch directly (a force sensor's reading
  // of a friction law on a drive that replays its motion): the outputs,
  // bit for bit.
  bool same_outputs(const Checkpoint& c) const {
    const std::size_t n = unpatched_.circuit().probes.size();
    std::vector<double> ou(n), op(n);
    eu_.probe_all(outputs_u_, c.t, c.y.data(), c.yp.data(), ou.data());
    ep_.probe_all(outputs_p_, c.t, c.y.data(), c.yp.data(), op.data());
    return ou == op;
  }

  // A root function the patch moves (a switch set elsewhere) leaves the
  // run as it is while neither model's crosses zero: each keeps one sign,
  // the same in both, over the interval up to c.
  bool same_events(const Checkpoint& c) {
    std::vector<double> gu(static_cast<std::size_t>(unpatched_.n_roots())), gp(gu.size());
    eu_.roots(c.t, c.y.data(), c.yp.data(), gu.data());
    ep_.roots(c.t, c.y.data(), c.yp.data(), gp.data());
    bool same = true;
    for (std::size_t i = 0; i < gu.size() && same; ++i) {
      const bool moved = gu[i] != gp[i] || (!gu_.empty() && gu_[i] != gp_[i]);
      if (!moved) continue;
      const int s = sign(gu[i]);
      same = s != 0 && sign(gp[i]) == s && (gu_.empty() || (sign(gu_[i]) == s && sign(gp_[i]) == s));
    }
    gu_ = std::move(gu), gp_ = std::move(gp);
    return same;
  }

  bool same_residual(const Checkpoint& c) {
    const auto n = static_cast<std::size_t>(unpatched_.size());
    std::vector<double> Fu(n), Fp(n);
    if (eu_.residual(c.t, c.y.data(), c.yp.data(), Fu.data()) != 0 ||
        ep_.residual(c.t, c.y.data(), c.yp.data(), Fp.data()) != 0)
      return false;
    std::vector<double> d(n);
    bool differs = false;
    for (std::size_t i = 0; i < n; ++i) {
      d[i] = Fp[i] - Fu[i];
      differs = differs || d[i] != 0.0;
    }
    return !differs || move_(c, d, options_.output_interval) <= kNegligible;
  }

  const System& unpatched_;
  const SolverOptions& options_;
  Evaluator eu_, ep_;
  ProbeSet outputs_u_, outputs_p_;
  WeightedMove move_;
  std::vector<double> gu_, gp_;  // the roots at the checkpoint before
};

}  // namespace

long last_checkpoint_before_departure(const System& unpatched, const System& patched, const RunResult& kept,
                                      const SolverOptions& options) {
  if (!alike(unpatched, patched)) return -1;
  const double t_event = first_other_time_event(unpatched, patched);
  SideBySide models(unpatched, patched, options);
  long last = -1;
  for (std::size_t j = 0; j < kept.checkpoints.size(); ++j) {
    const RunCheckpoint& rc = kept.checkpoints[j];
    if (rc.parts.size() != 1 || rc.t >= t_event || !models.same_at(rc.parts[0])) break;
    last = static_cast<long>(j);
  }
  return last;
}

}  // namespace pneumo::diagnose
