#include "framework/diagnose/unexplained.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>

#include "framework/assembly/system.hpp"
#include "framework/core/parallel.hpp"
#include "framework/core/text.hpp"
#include "framework/diagnose/form.hpp"
#include "framework/run/run.hpp"

namespace pneumo::diagnose {

namespace {

// A balance is named only when its disturbance removes at least half of the
// excess gap: less, and the "correction" is as much noise fitting as finding.
constexpr double kMinExplained = 0.5;
constexpr int kConfirm = 3;  // candidates confirmed by simulation, best predicted first
constexpr int kTrials = 8, kSteps = 3;  // simulated steps of one confirmation: tried, accepted at most
constexpr double kShortestStep = 1.0 / 64;  // of the distance to the linearised optimum
// Many states are screened on coarse hats first (Search::balances()).
constexpr int kCoarseHats = 4;
constexpr std::size_t kFineStates = 8;
static_assert((kDisturbanceKnots - 1) % (kCoarseHats - 1) == 0, "coarse knots are fine knots");
static_assert(kFineStates > static_cast<std::size_t>(kConfirm), "the confirmed balances have the fine hats");

struct State {
  std::string name, unit;
  double nominal = 1;
};

std::vector<State> model_states(const Netlist& model, const Registry& registry) {
  const System sys(elaborate(model, registry));
  std::vector<State> out;
  for (int i = 0; i < sys.size(); ++i)
    if (sys.differential()[i] != 0.0)
      out.push_back({sys.variable_names()[i], unknown_unit(sys, sys.variable_names()[i]), sys.nominal()[i]});
  return out;
}

// Hat functions on `knots` uniform knots over [t0, t1]: phi_j(t).
std::vector<double> knots_of(const std::vector<double>& t) {
  std::vector<double> k(kDisturbanceKnots);
  for (int j = 0; j < kDisturbanceKnots; ++j)
    k[j] = t.front() + (t.back() - t.front()) * j / (kDisturbanceKnots - 1);
  return k;
}
double hat(const std::vector<double>& knots, int j, double t) {
  const double h = knots[1] - knots[0];
  return std::max(0.0, 1.0 - std::abs(t - knots[j]) / h);
}

// Second differences of the knot values: the roughness a disturbance pays.
Eigen::MatrixXd roughness(int hats, int extra) {
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(hats - 2, hats + extra);
  for (int j = 0; j + 2 < hats; ++j) D(j, j) = 1, D(j, j + 1) = -2, D(j, j + 2) = 1;
  return D.transpose() * D;
}

// A balance or sensor: the linearised residual of each run r0 + J c.
struct Candidate {
  BalanceFinding finding;
  std::string variable;  // a state; empty for a sensor
  std::vector<double> scale;  // per run: the state's rate per unit coefficient
  std::vector<Eigen::MatrixXd> J;
  Eigen::MatrixXd P;
  Eigen::MatrixXd shapes;  // a state's hats: their values on the fine knots (Search::hat_shapes)
  std::vector<Eigen::VectorXd> c;  // fitted, per run, on its hats
  double ssr = 0;
  double lambda = 0;  // the roughness weight cross-validation chose
};

// A whisker of ridge that keeps the normal equations regular.
Eigen::MatrixXd ridge_of(const Candidate& cand, double mean_diagonal) {
  const auto p = cand.P.rows();
  return 1e-10 * std::max(mean_diagonal, 1e-300) * Eigen::MatrixXd::Identity(p, p);
}

// The linearised optimum seen from a point `at` whose simulated residual is
// r: min |r + J (c - at)|^2 + lambda c' P c (the fit's own roughness weight).
Eigen::VectorXd chord_target(const Candidate& cand, std::size_t k, const Eigen::VectorXd& r, const Eigen::VectorXd& at) {
  const Eigen::MatrixXd A = cand.J[k].transpose() * cand.J[k];
  const Eigen::MatrixXd M = A + cand.lambda * cand.P + ridge_of(cand, A.trace() / static_cast<double>(A.rows()));
  return M.ldlt().solve(cand.J[k].transpose() * (cand.J[k] * at - r));
}

// min sum_k |r0_k + J_k c_k|^2 + lambda c_k' P c_k, lambda by generalised
// cross-validation over all runs together.
void regularised_fit(Candidate& cand, const std::vector<Eigen::VectorXd>& r0) {
  const std::size_t nr = r0.size();
  const int p = static_cast<int>(cand.P.rows());
  std::vector<Eigen::MatrixXd> A(nr);
  std::vector<Eigen::VectorXd> g(nr);
  double n = 0, s0 = 0, trace = 0;
  for (std::size_t k = 0; k < nr; ++k) {
    A[k] = cand.J[k].transpose() * cand.J[k];
    g[k] = cand.J[k].transpose() * r0[k];
    n += static_cast<double>(r0[k].size());
    s0 += r0[k].squaredNorm();
    trace += A[k].trace() / p / nr;
  }
  const Eigen::MatrixXd ridge = ridge_of(cand, trace);
  double best = INFINITY;
  cand.ssr = s0;
  cand.c.assign(nr, Eigen::VectorXd::Zero(p));
  for (double e = -8; e <= 4; e += 0.25) {
    const double lambda = std::max(trace, 1e-300) * std::pow(10.0, e);
    double ssr = 0, edf = 0;
    std::vector<Eigen::VectorXd> c(nr);
    for (std::size_t k = 0; k < nr; ++k) {
      const auto M = (A[k] + lambda * cand.P + ridge).ldlt();
      c[k] = -M.solve(g[k]);
      ssr += r0[k].squaredNorm() + 2 * g[k].dot(c[k]) + c[k].dot(A[k] * c[k]);
      edf += M.solve(A[k]).trace();
    }
    const double gcv = n * ssr / ((n - edf) * (n - edf));
    if (ssr >= 0 && edf < n && gcv < best) best = gcv, cand.ssr = ssr, cand.c = std::move(c), cand.lambda = lambda;
  }
}

double excess_share(double gap_before, double gap_after) {
  const double e0 = std::max(gap_before - 1.0, 1e-12), e1 = std::max(gap_after - 1.0, 0.0);
  return (e0 - e1) / e0;
}

// What a disturbance of a state with this unit is, in words, by its sign.
std::string what_is_missed(const std::string& unit, bool positive, const std::string& name) {
  if (unit == "kg") return std::string("mass flow ") + (positive ? "into " : "out of ") + name;
  // A gas volume's energy: heat, or the enthalpy a flow carries.
  if (unit == "J" || unit == "K") return std::string("energy (heat or enthalpy flow) ") + (positive ? "into " : "out of ") + name;
  if (unit == "m/s") return std::string("a force in the ") + (positive ? "positive" : "negative") + " direction on " + name;
  if (unit == "rad/s") return std::string("a torque in the ") + (positive ? "positive" : "negative") + " direction on " + name;
  if (unit == "Pa") return std::string("a pressure ") + (positive ? "rise" : "fall") + " of " + name;
  return std::string("a ") + (positive ? "rise" : "fall") + " of " + name + " that its equations do not have";
}

// The state's unit back from its rate's (kg/s -> kg, m/s2 -> m/s).
std::string state_unit(const std::string& rate) {
  return rate.ends_with("/s2") ? rate.substr(0, rate.size() - 1) : rate.substr(0, rate.size() - 2);
}

// The phase where the fitted disturbance adds or removes most in all (its
// sum over the phase's samples, all runs: a net source or sink, which a
// wiggle about zero is not, nor a short phase's edge where the hats are
// poorly determined), and its mean there.
std::pair<int, double> largest_phase(const std::vector<DisturbanceShape>& shape, const std::vector<int>& runs,
                                     const UnexplainedInput& in) {
  const std::size_t np = in.phase_names->size();
  std::vector<double> sum(np, 0), count(np, 0);
  for (std::size_t q = 0; q < shape.size(); ++q) {
    const auto& run = (*in.runs)[runs[q]];
    const Disturbance d{"", shape[q].t, shape[q].value};
    for (std::size_t i = 0; i < run.t.size(); ++i) {
      const double v = d.at(run.t[i]);
      const int ph = (*in.phases)[runs[q]][i];
      sum[ph] += v, count[ph] += 1;
    }
  }
  int best = 0;
  for (std::size_t p = 0; p < np; ++p)
    if (std::abs(sum[p]) > std::abs(sum[best])) best = static_cast<int>(p);
  return {best, count[best] > 0 ? sum[best] / count[best] : 0.0};
}

}  // namespace

namespace {

// The search's shared facts: the verdict model's residuals on the runs it
// finishes, each run's knots, and the simulations spent.
class Search {
 public:
  Search(const UnexplainedInput& in, const DiagnoseOptions& opt) : in_(in), opt_(opt), runs_(*in.runs) {
    std::vector<std::vector<std::vector<double>>> sim(runs_.size());
    kept_.resize(runs_.size());
    parallel_for(static_cast<long>(runs_.size()), opt.threads, [&](int, long k) {
      // Kept at every knot but the last: a hat is zero up to the knot
      // before its first (at the first knot, the start's state).
      const auto at = knots_of(runs_[k].t);
      kept_[k] = in.keep(static_cast<int>(k), std::vector<double>(at.begin(), at.end() - 1));
      sim[k] = kept_[k].signals;
      ++simulations;
    });
    for (int k = 0; k < static_cast<int>(runs_.size()); ++k) {
      if (sim[k].empty()) continue;
      used.push_back(k);
      r0.push_back(residual(k, sim[k]));
      knots.push_back(knots_of(runs_[k].t));
      sim0.push_back(std::move(sim[k]));
      n += static_cast<double>(r0.back().size());
      s0 += r0.back().squaredNorm();
    }
    record_held();
  }

  std::vector<int> used;                               // runs the verdict model finishes
  std::vector<std::vector<std::vector<double>>> sim0;  // per used run: its signals
  std::vector<Eigen::VectorXd> r0;
  std::vector<std::vector<double>> knots;
  double n = 0, s0 = 0;
  std::atomic<long> simulations{0};

  // (measured - simulated) / sigma, signal after signal.
  Eigen::VectorXd residual(int k, const std::vector<std::vector<double>>& sim) const {
    const auto& run = runs_[k];
    Eigen::VectorXd r(run.signals.size() * run.t.size());
    for (std::size_t s = 0; s < run.signals.size(); ++s)
      for (std::size_t i = 0; i < run.t.size(); ++i) r[s * run.t.size() + i] = (run.y[s][i] - sim[s][i]) / run.sigma[s];
    return r;
  }

  // A disturbance of candidate `c` on used run q with these knot rates;
  // a content's (a mass, an energy, a temperature: never below 0) carries
  // what the state held along the verdict run, so that no withdrawal takes
  // more than it holds (Disturbance::held).
  Disturbance disturbance(const Candidate& c, std::size_t q, std::vector<double> rate) const {
    Disturbance d{c.variable, knots[q], std::move(rate)};
    if (const auto it = held[q].find(c.variable); it != held[q].end())
      d.held_t = held_t[q], d.held = it->second, d.per_held = true;
    return d;
  }

  // The states: one simulation per hat and run, each hat's amplitude moving
  // the state by about 1 % of its nominal magnitude (a content's: of what it
  // holds there) over the hat's width. With many states (a line of
  // cylinders has dozens) they are screened first on coarse hats - every
  // third knot's, a subspace of the fine hats', so a coarse fit's gap is no
  // smaller than the fine one's - on the run the verdict misses most (where
  // a balance that explains the gap must act most), and only the best
  // kFineStates get the fine hats on every run; the others keep their
  // coarse fit there, no correction on the other runs, reported as such.
  std::vector<Candidate> balances() {
    std::vector<Candidate> cands;
    for (const auto& st : model_states(*in_.model, *in_.registry)) {
      // ds/dt = v defines the velocity: nothing physical is missing from it,
      // and a drift there only pushes the piston through its stops. A drift
      // of a position reading is the sensors' offset and gain below.
      if (st.unit == "m" || st.unit == "rad") continue;
      Candidate c;
      c.variable = c.finding.balance = st.name;
      c.finding.unit = st.unit.empty() ? "1/s" : st.unit.ends_with("/s") ? st.unit + "2" : st.unit + "/s";
      c.finding.kind = st.unit == "kg" ? "mass" : st.unit == "J" || st.unit == "K" ? "energy"
                     : st.unit == "m/s" || st.unit == "rad/s" ? "force" : "state";
      for (std::size_t q = 0; q < used.size(); ++q) {
        const double magnitude = held[q].contains(st.name) ? 1.0 : st.nominal;  // a content's rate is per unit held
        c.scale.push_back(0.01 * magnitude / (knots[q][1] - knots[q][0]));
      }
      cands.push_back(std::move(c));
    }
    const std::size_t n = cands.size();
    const bool coarse_first = n * kDisturbanceKnots > n * kCoarseHats + kFineStates * kDisturbanceKnots;
    std::vector<Candidate*> all;
    for (auto& c : cands) all.push_back(&c);
    if (!coarse_first) {
      respond(all, hat_shapes(kDisturbanceKnots));
      return cands;
    }
    respond(all, hat_shapes(kCoarseHats), worst_run());
    for (auto& c : cands) regularised_fit(c, r0);
    std::sort(cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) { return a.ssr < b.ssr; });
    std::vector<Candidate*> best;
    for (std::size_t i = 0; i < kFineStates; ++i) best.push_back(&cands[i]);
    respond(best, hat_shapes(kDisturbanceKnots));
    return cands;
  }

  // The knot values of `hats` hat functions on every ((B - 1) / (hats - 1))-th
  // of the B knots: the fine hats themselves, or coarse ones whose
  // disturbance is still piecewise linear on the fine knots.
  static Eigen::MatrixXd hat_shapes(int hats) {
    const int stride = (kDisturbanceKnots - 1) / (hats - 1);
    std::vector<double> at(hats);  // the hats' knots, counted in fine knots
    for (int h = 0; h < hats; ++h) at[h] = h * stride;
    Eigen::MatrixXd T(kDisturbanceKnots, hats);
    for (int j = 0; j < kDisturbanceKnots; ++j)
      for (int h = 0; h < hats; ++h) T(j, h) = hat(at, h, j);
    return T;
  }

  // The used run with the largest misfit.
  std::size_t worst_run() const {
    std::size_t worst = 0;
    for (std::size_t q = 1; q < used.size(); ++q)
      if (r0[q].squaredNorm() > r0[worst].squaredNorm()) worst = q;
    return worst;
  }

  // Each candidate's output sensitivity to each hat of `shapes` (columns:
  // knot values), by one simulation per hat and run - on used run `only`
  // alone when given, the others' columns zero (no correction there); its
  // J, roughness and coefficients are then on those hats.
  void respond(const std::vector<Candidate*>& cs, const Eigen::MatrixXd& shapes,
               std::optional<std::size_t> only = std::nullopt) {
    const long H = shapes.cols();
    std::vector<long> qs;
    for (std::size_t q = 0; q < used.size(); ++q)
      if (!only || q == *only) qs.push_back(static_cast<long>(q));
    const long nr = static_cast<long>(qs.size());
    for (Candidate* c : cs) {
      c->P = roughness(static_cast<int>(H), 0);
      c->shapes = shapes;
      c->finding.hats = static_cast<int>(H);
      c->J.clear();
      for (std::size_t q = 0; q < used.size(); ++q) c->J.push_back(Eigen::MatrixXd::Zero(r0[q].size(), H));
    }
    if (in_.log)
      in_.log("unexplained: " + std::to_string(cs.size()) + " balances x " + std::to_string(nr) + " runs x " +
              std::to_string(H) + " hats: " + std::to_string(cs.size() * nr * H) + " simulations" +
              (only ? " (on run " + runs_[used[*only]].name + ", the one the verdict misses most)" : ""));
    parallel_for(static_cast<long>(cs.size()) * nr * H, opt_.threads, [&](int, long job) {
      const long i = job / (nr * H), q = qs[(job / H) % nr], j = job % H;
      Candidate& c = *cs[i];
      std::vector<double> rate(kDisturbanceKnots);
      int first = kDisturbanceKnots;  // the hat's first knot not zero
      for (int k = kDisturbanceKnots - 1; k >= 0; --k) {
        rate[k] = shapes(k, j) * c.scale[q];
        if (shapes(k, j) != 0.0) first = k;
      }
      const auto sim = simulate_hat(q, first, disturbance(c, q, std::move(rate)));
      ++simulations;
      if (!sim.empty()) c.J[q].col(j) = residual(used[q], sim) - r0[q];  // a failed run leaves the hat unused
    });
  }

  // Used run q with a disturbance that is zero up to the knot before
  // `first`: from the kept run's checkpoint there (knot i is checkpoint i).
  // Every hat goes on from the kept run, the first ones from its start: a
  // part of the circuit the disturbance does not reach is then the kept
  // run's row for row, its response exactly zero.
  std::vector<std::vector<double>> simulate_hat(std::size_t q, int first, Disturbance d) const {
    return simulate_from(used[q], std::max(first - 1, 0), {std::move(d)}, nullptr);
  }
  // Used run k with disturbances that are zero up to knot j, from the kept
  // run's checkpoint there (the other disturbed runs - confirmations, forms
  // - from its start, on the same terms as the hats).
  std::vector<std::vector<double>> simulate_from(int k, int j, const std::vector<Disturbance>& d, std::string* why) const {
    return kept_[k].from(static_cast<std::size_t>(j), d, why);
  }

  // The sensors: a smooth offset (in noise units) and a gain per run, exactly linear.
  std::vector<Candidate> sensors() const {
    const int B = kDisturbanceKnots;
    std::vector<Candidate> cands;
    for (const auto& name : runs_[used[0]].signals) {
      Candidate c;
      c.finding.balance = "sensor " + name;
      c.finding.kind = "sensor";
      c.finding.hats = B;
      c.P = roughness(B, 1);
      for (std::size_t q = 0; q < used.size(); ++q) {
        const auto& run = runs_[used[q]];
        Eigen::MatrixXd J = Eigen::MatrixXd::Zero(r0[q].size(), B + 1);
        const std::size_t m = run.t.size(), s = std::find(run.signals.begin(), run.signals.end(), name) - run.signals.begin();
        for (std::size_t i = 0; i < m && s < run.signals.size(); ++i) {
          for (int j = 0; j < B; ++j) J(s * m + i, j) = -hat(knots[q], j, run.t[i]);
          J(s * m + i, B) = -sim0[q][s][i] / run.sigma[s];
        }
        c.scale.push_back(s < run.signals.size() ? run.sigma[s] : 0.0);
        c.J.push_back(std::move(J));
      }
      cands.push_back(std::move(c));
    }
    return cands;
  }

  // A state's disturbance on used run q with coefficients `coef` (by
  // default its fit).
  Disturbance disturbance_of(const Candidate& c, std::size_t q, const Eigen::VectorXd* coef = nullptr) const {
    const Eigen::VectorXd& k = coef ? *coef : c.c[q];
    const Eigen::VectorXd knot_values = c.shapes * k;
    std::vector<double> rate(kDisturbanceKnots);
    for (int j = 0; j < kDisturbanceKnots; ++j) rate[j] = knot_values[j] * c.scale[q];
    return disturbance(c, q, std::move(rate));
  }

  // The best `kConfirm` predicted balances (cands sorted best first),
  // fitted on simulations: the fit is linear, the model is not. From no
  // disturbance, each step goes toward the linearised optimum seen from the
  // point last simulated (the probes' Jacobian kept: a chord step) and is
  // simulated; a step the model cannot run (a chamber emptied, a spool past
  // its end) or that does not lower the gap is tried again at a quarter of
  // its length. The gap is that of the last step that ran; why a longer one
  // could not is kept.
  void confirm(std::vector<Candidate>& cands) {
    int tried = 0;
    for (auto& c : cands)
      if (!c.variable.empty() && tried++ < kConfirm) refine(c);
  }

  struct Trial {
    double ssr = 0;
    std::vector<Eigen::VectorXd> r;  // per used run
    std::string why;                 // of the first run that failed
    bool ran() const { return why.empty(); }
  };

  Trial simulate_fit(const Candidate& c, const std::vector<Eigen::VectorXd>& coef) {
    const std::size_t nr = used.size();
    Trial t;
    t.r.resize(nr);
    std::vector<std::string> why(nr);
    parallel_for(static_cast<long>(nr), opt_.threads, [&](int, long q) {
      const auto sim = simulate_from(used[q], 0, {disturbance_of(c, q, &coef[q])}, &why[q]);
      ++simulations;
      if (!sim.empty()) t.r[q] = residual(used[q], sim);
    });
    for (std::size_t q = 0; q < nr && t.why.empty(); ++q)
      if (t.r[q].size() == 0) t.why = "run " + runs_[used[q]].name + ": " + why[q];
    for (const auto& r : t.r) t.ssr += r.squaredNorm();
    return t;
  }

  void refine(Candidate& c) {
    const std::size_t nr = used.size();
    const double predicted = c.finding.gap_after;
    std::vector<Eigen::VectorXd> at(nr), target = c.c;
    for (std::size_t q = 0; q < nr; ++q) at[q] = Eigen::VectorXd::Zero(target[q].size());
    double ssr = s0, step = 1;
    int accepted = 0;
    bool ran = false;
    for (int trial = 0; trial < kTrials && accepted < kSteps && step >= kShortestStep; ++trial) {
      std::vector<Eigen::VectorXd> next(nr);
      for (std::size_t q = 0; q < nr; ++q) next[q] = at[q] + step * (target[q] - at[q]);
      Trial t = simulate_fit(c, next);
      ran = ran || t.ran();
      if (t.ran() && t.ssr < ssr) {
        if (accepted++ == 0) c.finding.share = step;
        at = std::move(next), ssr = t.ssr;
        for (std::size_t q = 0; q < nr; ++q) target[q] = chord_target(c, q, t.r[q], at[q]);
        step = std::min(1.0, 2 * step);
        continue;
      }
      if (!t.ran() && c.finding.longer_step_failed.empty()) c.finding.longer_step_failed = t.why;
      if (in_.log)
        in_.log("  " + c.finding.balance + ": a step of " + rounded(100 * step, 2) + " % toward the fit " +
                (t.ran() ? "lowers no gap" : "leaves the model's domain (" + t.why + ")") + "; a quarter of it next");
      step /= 4;
    }
    c.finding.confirmed = ran;
    if (!ran) {  // stays predicted, with the linear fit
      c.finding.failure = c.finding.longer_step_failed;
    } else {
      c.c = std::move(at), c.ssr = ssr, c.finding.gap_after = std::sqrt(ssr / n);
      if (!accepted) c.finding.share = 0;
    }
    if (in_.log)
      in_.log("  " + c.finding.balance + ": predicted gap " + rounded(predicted, 2) +
              (ran ? ", simulated gap " + rounded(c.finding.gap_after, 2) + " after " + std::to_string(accepted) + " step(s)"
                   : ", no step of its fit runs (" + c.finding.failure + ")"));
  }

  // The missing term's form: on the reading when a sensor's correction is
  // the best of all (the gap looks like what a signal reads, not like what
  // a balance holds), and, unless that form beats its time-shaped
  // correction, on the best state balance, and on the next best when the
  // first's does not beat its own. The form that leaves least is kept.
  // Only a correction that could be named has a law to look for: one
  // whose time-shaped correction, simulated, removes less than
  // kMinExplained of the excess gap - or was only predicted - is not
  // searched (a search costs every candidate term's simulation on every
  // run in its first round).
  static bool named(const Candidate& c) { return c.finding.confirmed && c.finding.explained >= kMinExplained; }
  std::optional<FormFinding> form_of(const std::vector<Candidate>& cands) const {
    FormInput f{&runs_, used, r0, in_.netlist_of, in_.registry,
                [&](int k, const std::vector<Disturbance>& d, std::string* why) { return simulate_from(k, 0, d, why); },
                [&](int k, const std::vector<std::vector<double>>& sim) { return residual(k, sim); }, in_.log, opt_.threads};
    std::optional<FormFinding> best;
    if (!cands.empty() && cands.front().variable.empty() && named(cands.front()) && in_.netlist_of) {
      best = discover_reading_form(f, cands.front().finding.balance.substr(7), cands.front().finding.gap_after);
      if (best && best->beats_shape) return best;
    }
    int tried = 0;
    for (const auto& c : cands) {
      if (c.variable.empty() || !named(c) || tried == 2 || !in_.netlist_of) continue;
      ++tried;
      auto found = discover_form(f, c.variable, c.finding.unit, c.finding.gap_after);
      if (!found) break;
      const bool better = !best || (found->confirmed && (!best->confirmed || found->gap_after < best->gap_after));
      if (better) best = std::move(found);
      if (best->beats_shape) break;
    }
    return best;
  }

  std::vector<DisturbanceShape> shape_of(const Candidate& c) const {
    std::vector<DisturbanceShape> out;
    for (std::size_t q = 0; q < used.size(); ++q) {
      DisturbanceShape sh{runs_[used[q]].name, knots[q], {}, 0.0};
      if (c.variable.empty()) {
        for (int j = 0; j < kDisturbanceKnots; ++j) sh.value.push_back(c.c[q][j] * c.scale[q]);
        sh.gain = c.c[q][kDisturbanceKnots];
      } else {
        const Disturbance d = disturbance_of(c, q);
        for (const double t : knots[q]) sh.value.push_back(d.time_shaped(t));
      }
      out.push_back(std::move(sh));
    }
    return out;
  }

 private:
  const UnexplainedInput& in_;
  const DiagnoseOptions& opt_;
  const std::vector<MeasuredRun>& runs_;
  std::vector<KeptRun> kept_;                                   // per run (UnexplainedInput::keep)
  std::vector<std::vector<double>> held_t;                    // per used run: the output times
  std::vector<std::map<std::string, std::vector<double>>> held;  // per used run: each content state there

  // The verdict model's contents along each used run, at its output times.
  void record_held() {
    held_t.assign(used.size(), {});
    held.assign(used.size(), {});
    if (!in_.netlist_of) return;
    parallel_for(static_cast<long>(used.size()), opt_.threads, [&](int, long q) {
      const Netlist nl = in_.netlist_of(used[q]);
      System sys(elaborate(nl, *in_.registry));
      std::vector<int> content;
      for (int i = 0; i < sys.size(); ++i) {
        const std::string unit = unknown_unit(sys, sys.variable_names()[i]);
        if (sys.differential()[i] != 0.0 && (unit == "kg" || unit == "J" || unit == "K")) content.push_back(i);
      }
      SolverOptions so = solver_options(nl.simulation);
      so.threads = 1;
      std::vector<std::vector<double>> values(content.size());
      ++simulations;
      Evaluator eval(sys);
      const auto result = simulate(eval, so, [&](double t, const double* y, const double*) {
        held_t[q].push_back(t);
        for (std::size_t k = 0; k < content.size(); ++k) values[k].push_back(y[content[k]]);
      });
      if (!result.ok || !std::is_sorted(held_t[q].begin(), held_t[q].end())) {
        held_t[q].clear();
        return;
      }
      for (std::size_t k = 0; k < content.size(); ++k) held[q][sys.variable_names()[content[k]]] = std::move(values[k]);
    });
  }
};

std::string percent(double share) { return std::to_string(static_cast<int>(std::lround(100 * share))) + " %"; }

// The report's sentence: where the gap lies, and what the best balance's
// disturbance says, or that no single one explains it.
std::string sentence_of(const Unexplained& u, const Candidate& best, const std::string& phase, double mean) {
  std::string s = "No candidate explains the remaining gap (" + rounded(u.gap, 2) + " x noise, most of it in " + u.signal +
                  (u.phase.empty() ? "" : " during " + u.phase) + "); ";
  if (best.finding.explained < kMinExplained)
    return s + "nor does a smooth disturbance of any single balance (the best, on " + best.finding.balance +
           ", removes " + percent(best.finding.explained) + " of the excess gap).";
  const bool sensor = best.variable.empty();
  s += sensor ? "the reading of " + best.finding.balance.substr(7) + " is off (a drifting offset and gain)"
              : "the model misses " + what_is_missed(state_unit(best.finding.unit), mean > 0, best.finding.balance);
  return s + ", mostly" + (phase.empty() ? "" : " during " + phase) + " (on average " + rounded(std::abs(mean), 2) + " " +
         (sensor ? "in the signal's unit" : best.finding.unit) + " there), which removes " +
         percent(best.finding.explained) + " of the excess gap.";
}

}  // namespace

void explain_by_balances(const UnexplainedInput& in, const DiagnoseOptions& opt, Unexplained& u) {
  const auto t_start = std::chrono::steady_clock::now();
  Search search(in, opt);
  if (search.used.empty()) return;
  u.gap_all_runs = std::sqrt(search.s0 / search.n);
  std::vector<Candidate> cands = search.balances();
  for (auto& c : search.sensors()) cands.push_back(std::move(c));
  for (auto& c : cands) {
    regularised_fit(c, search.r0);
    c.finding.gap_after = std::sqrt(std::max(c.ssr, 0.0) / search.n);
    c.finding.confirmed = c.variable.empty();  // a sensor's residual is exactly linear
  }
  std::sort(cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) { return a.ssr < b.ssr; });
  search.confirm(cands);
  // Best first: confirmed before predicted-only, then by the gap left.
  std::stable_sort(cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) {
    if (a.finding.confirmed != b.finding.confirmed) return a.finding.confirmed;
    return a.ssr < b.ssr;
  });
  for (auto& c : cands) {
    c.finding.explained = excess_share(u.gap_all_runs, c.finding.gap_after);
    u.balances.push_back(c.finding);
  }
  u.form = search.form_of(cands);
  u.shape = search.shape_of(cands.front());
  const auto [phase, mean] = largest_phase(u.shape, search.used, in);
  u.sentence = sentence_of(u, cands.front(), in.phase_names->empty() ? "" : (*in.phase_names)[phase], mean);
  u.simulations = search.simulations + (u.form ? u.form->simulations : 0);
  u.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  if (in.log)
    in.log("unexplained: " + u.sentence + " [" + std::to_string(u.simulations) + " simulations, " + rounded(u.seconds, 2) +
           " s]");
}

std::string unexplained_json(const std::optional<Unexplained>& u, const std::function<std::string(double)>& num,
                             const std::function<std::string(const std::string&)>& str) {
  if (!u) return "null";
  std::ostringstream o;
  o << "{\"gap\": " << num(u->gap) << ", \"gap_all_runs\": " << num(u->gap_all_runs) << ", \"signal\": "
    << str(u->signal) << ", \"phase\": " << str(u->phase) << ", \"sentence\": " << str(u->sentence)
    << ",\n  \"windows\": [";
  for (std::size_t i = 0; i < u->windows.size(); ++i) {
    const auto& w = u->windows[i];
    o << (i ? ", " : "") << "{\"run\": " << str(w.run) << ", \"signal\": " << str(w.signal)
      << ", \"t_start\": " << num(w.t0) << ", \"t_end\": " << num(w.t1) << ", \"gap\": " << num(w.rms) << "}";
  }
  o << "],\n  \"balances\": [";
  for (std::size_t i = 0; i < u->balances.size(); ++i) {
    const auto& b = u->balances[i];
    o << (i ? ",\n    " : "\n    ") << "{\"balance\": " << str(b.balance) << ", \"kind\": " << str(b.kind)
      << ", \"unit\": " << str(b.unit) << ", \"gap_after\": " << num(b.gap_after)
      << ", \"explained\": " << num(b.explained) << ", \"confirmed\": " << (b.confirmed ? "true" : "false")
      << ", \"failure\": " << (b.failure.empty() ? std::string("null") : str(b.failure))
      << ", \"share\": " << num(b.share) << ", \"longer_step_failed\": "
      << (b.longer_step_failed.empty() ? std::string("null") : str(b.longer_step_failed)) << ", \"hats\": " << b.hats << "}";
  }
  o << "],\n  \"shape\": [";
  for (std::size_t i = 0; i < u->shape.size(); ++i) {
    const auto& sh = u->shape[i];
    o << (i ? ",\n    " : "\n    ") << "{\"run\": " << str(sh.run) << ", \"gain\": " << num(sh.gain) << ", \"t\": [";
    for (std::size_t j = 0; j < sh.t.size(); ++j) o << (j ? ", " : "") << num(sh.t[j]);
    o << "], \"value\": [";
    for (std::size_t j = 0; j < sh.value.size(); ++j) o << (j ? ", " : "") << num(sh.value[j]);
    o << "]}";
  }
  o << "],\n  \"form\": " << (u->form ? form_json(*u->form, num, str) : std::string("null"));
  o << ",\n  \"simulations\": " << u->simulations << ", \"seconds\": " << num(u->seconds) << "}";
  return o.str();
}

namespace {

// The best balance's disturbance over time, one line per run, with axes.
std::string svg_shape(const Unexplained& u, const std::function<std::string(const std::string&)>& html) {
  const double W = 620, H = 220, l = 70, r = 70, t = 10, b = 36;  // the runs' names right of the plot
  // Symmetric about zero, so that the sign reads at a glance.
  double t0 = INFINITY, t1 = -INFINITY, top = 0;
  for (const auto& sh : u.shape) {
    t0 = std::min(t0, sh.t.front()), t1 = std::max(t1, sh.t.back());
    for (double v : sh.value) top = std::max(top, 1.1 * std::abs(v));
  }
  if (!(top > 0)) top = 1;
  if (!(t1 > t0)) t1 = t0 + 1;
  const double lo = -top, hi = top;
  const auto X = [&](double x) { return l + (W - l - r) * (x - t0) / (t1 - t0); };
  const auto Y = [&](double y) { return H - b - (H - t - b) * (y - lo) / (hi - lo); };
  std::ostringstream o;
  o << "<svg id=\"unexplained-shape\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
    << "\" viewBox=\"0 0 " << W << " " << H << "\" font-size=\"11\">\n";
  o << "<line x1=\"" << l << "\" x2=\"" << W - r << "\" y1=\"" << Y(0) << "\" y2=\"" << Y(0)
    << "\" stroke=\"#999\" stroke-dasharray=\"3 3\"/>\n";
  o << "<rect x=\"" << l << "\" y=\"" << t << "\" width=\"" << W - l - r << "\" height=\"" << H - t - b
    << "\" fill=\"none\" stroke=\"#444\"/>\n";
  for (int k = 0; k <= 4; ++k) {
    const double tv = t0 + (t1 - t0) * k / 4, yv = lo + (hi - lo) * k / 4;
    o << "<text x=\"" << X(tv) << "\" y=\"" << H - b + 14 << "\" text-anchor=\"middle\">" << rounded(tv, 2) << "</text>"
      << "<text x=\"" << l - 4 << "\" y=\"" << Y(yv) + 4 << "\" text-anchor=\"end\">" << rounded(yv, 2) << "</text>\n";
  }
  o << "<text x=\"" << (l + W - r) / 2 << "\" y=\"" << H - 4 << "\" text-anchor=\"middle\">t [s]</text>\n";
  const char* const colours[] = {"#4c8fd6", "#d64c4c", "#4cb04c", "#f0a030", "#9b6bd6", "#666"};
  for (std::size_t i = 0; i < u.shape.size(); ++i) {
    const auto& sh = u.shape[i];
    o << "<polyline fill=\"none\" stroke-width=\"1.5\" stroke=\"" << colours[i % 6] << "\" points=\"";
    for (std::size_t j = 0; j < sh.t.size(); ++j) o << X(sh.t[j]) << "," << Y(sh.value[j]) << " ";
    o << "\"><title>" << html(sh.run) << "</title></polyline>\n";
    o << "<text x=\"" << W - r + 6 << "\" y=\"" << t + 10 + 13 * i << "\" fill=\""
      << colours[i % 6] << "\">" << html(sh.run) << "</text>\n";
  }
  const auto& best = u.balances.front();
  o << "<text x=\"" << l + 6 << "\" y=\"" << t + 14 << "\">" << html(best.balance) << " ["
    << html(best.kind == "sensor" ? "offset" : best.unit) << "]</text>\n</svg>\n";
  return o.str();
}

}  // namespace

std::string unexplained_html(const std::optional<Unexplained>& u,
                             const std::function<std::string(const std::string&)>& html) {
  if (!u || u->balances.empty()) return "";
  std::ostringstream o;
  o << "<h2>What no candidate explains</h2>\n<p id=\"unexplained\">" << html(u->sentence) << "</p>\n"
    << svg_shape(*u, html) << "<p>The fitted disturbance of the best balance, per run (its knots joined). Gap of all "
    << "runs with the verdict's model: " << rounded(u->gap_all_runs, 2) << " x noise; each balance's own disturbance "
    << "fitted:</p>\n<table id=\"balances\"><tr><th>balance</th><th>kind</th><th>gap after</th>"
    << "<th>excess gap removed</th></tr>\n";
  for (std::size_t i = 0; i < u->balances.size() && i < 8; ++i) {
    const auto& b = u->balances[i];
    o << "<tr><td class=\"l\">" << html(b.balance) << "</td><td class=\"l\">" << html(b.kind) << "</td><td>"
      << rounded(b.gap_after, 2)
      << (b.hats < kDisturbanceKnots ? " (predicted on " + std::to_string(b.hats) + " coarse hats of the run missed most; screened only)"
          : !b.confirmed ? b.failure.empty() ? " (predicted)" : " (predicted; its simulation failed: " + html(b.failure) + ")"
          : !b.longer_step_failed.empty() ? " (fitted on simulations from " + rounded(100 * b.share, 2) +
                                                  " % of its linear fit; a longer step left the model's domain: " +
                                                  html(b.longer_step_failed) + ")"
                                            : "")
      << "</td><td>"
      << std::lround(100 * b.explained) << " %</td></tr>\n";
  }
  o << "</table>\n";
  if (u->form) o << form_html(*u->form, html);
  return o.str();
}

}  // namespace pneumo::diagnose
