#include "framework/study/optimize.hpp"

#include <nlopt.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include <unistd.h>

#include "framework/core/text.hpp"
#include "framework/core/units.hpp"
#include "framework/io/files.hpp"
#include "framework/io/results.hpp"
#include "framework/study/sweep.hpp"

namespace pneumo::study {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

SourceLocation args_where(const Netlist& nl) { return SourceLocation{nl.file, 1, 1}; }

// Inverse of the standard normal CDF by bisection on erfc (60 halvings of
// [-40, 40] reach the double's resolution; a few hundred calls per study).
double inverse_normal(double u) {
  double lo = -40.0, hi = 40.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::sqrt(2.0)) < u ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// n points in [0, 1]^k, one in each of n equal slices of every axis.
std::vector<std::vector<double>> latin_hypercube(int n, int k, unsigned long seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(0.0, 1.0);
  std::vector<std::vector<double>> u(n, std::vector<double>(k));
  for (int j = 0; j < k; ++j) {
    std::vector<int> slot(n);
    for (int i = 0; i < n; ++i) slot[i] = i;
    std::shuffle(slot.begin(), slot.end(), rng);
    for (int i = 0; i < n; ++i) u[i][j] = (slot[i] + jitter(rng)) / n;
  }
  return u;
}

double quantile_of(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const auto i = static_cast<std::size_t>(pos);
  return i + 1 < v.size() ? v[i] + (pos - i) * (v[i + 1] - v[i]) : v.back();
}

double mean_of(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s / v.size();
}

double sd_of(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double m = mean_of(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / (v.size() - 1));
}

double robust_value(const Robust& r, const std::vector<double>& v) {
  switch (r.kind) {
    case Robust::Kind::mean: return mean_of(v);
    case Robust::Kind::mean_ksd: return mean_of(v) + r.k * sd_of(v);
    case Robust::Kind::quantile: return quantile_of(v, r.k);
  }
  return kNaN;
}

// The exact bits of a design point and a sample index: the journal's key.
std::string run_key(const std::vector<double>& x, int sample) {
  std::string key;
  char buf[24];
  for (double v : x) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    std::snprintf(buf, sizeof buf, "%016llx:", static_cast<unsigned long long>(bits));
    key += buf;
  }
  return key + std::to_string(sample);
}

std::string full_digits(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Finished runs, appended one line each (flushed), read back on a restart.
// The first line identifies the optimisation; a journal of another is refused.
class RunJournal {
 public:
  RunJournal(const std::string& path, const std::string& identity) : path_(path) {
    if (path.empty()) return;
    std::error_code ec;
    const bool present = std::filesystem::exists(std::filesystem::symlink_status(path, ec));
    if (present) check_input_file(path, "journal");
    std::ifstream in(present ? path : std::string());
    std::string line;
    if (in && std::getline(in, line)) {
      if (line != identity)
        throw InputError(SourceLocation{path, 1, 1}, "", "",
                         "this journal belongs to another optimisation (netlist, design, samples or metrics differ); "
                         "remove it or choose another -o");
      while (std::getline(in, line)) {
        const auto comma = line.find(',');
        if (comma != std::string::npos && !line.empty() && line.back() == ';') done_[line.substr(0, comma)] = line;
      }
    }
    out_ = open_journal(path);
    if (!in) write(identity);
  }
  ~RunJournal() {
    if (out_) std::fclose(out_);
  }
  RunJournal(const RunJournal&) = delete;
  RunJournal& operator=(const RunJournal&) = delete;
  // The recorded line of a run (key,ok|failed,metrics...;), or "".
  std::string find(const std::string& key) const {
    const auto it = done_.find(key);
    return it == done_.end() ? "" : it->second;
  }
  void write(const std::string& line) {
    if (path_.empty()) return;
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string text = line + "\n";
    if (std::fwrite(text.data(), 1, text.size(), out_) != text.size() || std::fflush(out_) != 0)
      throw std::runtime_error("cannot write the journal '" + path_ + "'");
  }

 private:
  std::string path_;
  std::map<std::string, std::string> done_;
  std::FILE* out_ = nullptr;
  std::mutex mutex_;
};

class DesignEvaluator {
 public:
  DesignEvaluator(const Model& model, const OptimizeProblem& p, const OptimizeOptions& o)
      : problem_(p), options_(o), registry_(model.registry), netlist_(model.netlist) {
    const Netlist& nl = model.netlist;
    std::vector<std::string> names = p.objectives;
    for (const auto& c : p.constraints)
      if (std::find(names.begin(), names.end(), c.metric) == names.end()) names.push_back(c.metric);
    metrics_ = select_metrics(nl, registry_, names);
    for (const auto& r : p.design) parameters_.push_back(r.parameter);
    for (const auto& u : p.uncertain) parameters_.push_back(u.parameter);
    const int n = p.uncertain.empty() ? 1 : p.samples;
    for (const auto& u : latin_hypercube(n, static_cast<int>(p.uncertain.size()), p.seed)) {
      Sample s;
      for (std::size_t j = 0; j < u.size(); ++j) s.push_back(p.uncertain[j].quantile(u[j]));
      samples_.push_back(std::move(s));
    }
    std::string identity = "# pneumo optimize journal " + std::to_string(std::hash<std::string>{}(model.identity()));
    for (const auto& r : p.design) identity += " " + r.parameter.name;
    for (const auto& u : p.uncertain) identity += " " + u.parameter.name + "=" + u.text;
    for (const auto& m : metrics_) identity += " " + m.name;
    identity += " samples " + std::to_string(n) + " seed " + std::to_string(p.seed);
    journal_ = std::make_unique<RunJournal>(o.journal, identity);
    runner_ = std::make_unique<SweepRunner>(netlist_, registry_, parameters_, metrics_);
  }

  const std::vector<Metric>& metrics() const { return metrics_; }
  int sample_count() const { return static_cast<int>(samples_.size()); }
  long runs() const { return runs_; }
  long resumed() const { return resumed_; }
  long failed() const { return failed_; }
  const std::vector<PointResult>& history() const { return history_; }

  const PointResult& evaluate(const std::vector<double>& x) {
    for (const auto& h : history_)
      if (h.x == x) return h;
    const int n = sample_count();
    std::vector<RunRecord> rec(n);
    std::atomic<int> next{0};
    auto worker = [&] {
      for (int j; (j = next++) < n;) rec[j] = run_or_recall(x, j);
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < std::min(options_.threads, n); ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    failed_ += std::count_if(rec.begin(), rec.end(), [](const RunRecord& r) { return !r.ok; });
    history_.push_back(summarise(x, rec));
    return history_.back();
  }

 private:
  RunRecord run_or_recall(const std::vector<double>& x, int j) {
    const std::string key = run_key(x, j);
    if (const std::string line = journal_->find(key); !line.empty()) {
      ++resumed_;
      return parse_line(line);
    }
    Sample s = x;
    s.insert(s.end(), samples_[j].begin(), samples_[j].end());
    RunRecord r = runner_->run(s);
    ++runs_;
    std::string line = key + (r.ok ? ",ok" : ",failed");
    for (double v : r.metrics) line += "," + full_digits(v);
    journal_->write(line + ";");
    return r;
  }

  static RunRecord parse_line(const std::string& line) {
    RunRecord r;
    std::stringstream ss(line.substr(0, line.size() - 1));
    std::string cell;
    std::getline(ss, cell, ',');
    std::getline(ss, cell, ',');
    r.ok = cell == "ok";
    r.reason = r.ok ? "" : "failed (recorded in the journal)";
    while (std::getline(ss, cell, ',')) r.metrics.push_back(std::stod(cell));
    return r;
  }

  PointResult summarise(const std::vector<double>& x, const std::vector<RunRecord>& rec) const {
    PointResult p;
    p.x = x;
    p.metric.assign(metrics_.size(), {});
    for (std::size_t j = 0; j < rec.size(); ++j) {
      if (!rec[j].ok) {
        p.feasible_runs = false;
        if (p.reason.empty()) p.reason = "run " + std::to_string(j) + " failed: " + rec[j].reason;
        continue;
      }
      for (std::size_t m = 0; m < metrics_.size(); ++m) {
        if (std::isnan(rec[j].metrics[m]) && p.feasible_runs) {
          p.feasible_runs = false;
          p.reason = metrics_[m].name + " undefined in run " + std::to_string(j) + " (its event did not happen)";
        }
        p.metric[m].push_back(rec[j].metrics[m]);
      }
    }
    for (const auto& v : p.metric) p.robust.push_back(p.feasible_runs ? robust_value(problem_.robust, v) : kNaN);
    for (const auto& c : problem_.constraints) {
      const auto& samples = p.metric[index_of(c.metric)];
      const double v = p.feasible_runs ? robust_value(c.statistic.value_or(problem_.robust), samples) : kNaN;
      p.constrained.push_back(v);
      const double excess = (c.at_least ? c.limit - v : v - c.limit) / std::max(std::abs(c.limit), 1e-300);
      p.violation = std::max(p.violation, std::isnan(excess) ? 1.0 : excess);
    }
    return p;
  }

 public:
  int index_of(const std::string& metric) const {
    for (std::size_t m = 0; m < metrics_.size(); ++m)
      if (metrics_[m].name == metric) return static_cast<int>(m);
    return -1;
  }

 private:
  const OptimizeProblem& problem_;
  const OptimizeOptions& options_;
  const Registry& registry_;
  Netlist netlist_;  // the model with its --set
  std::vector<Metric> metrics_;
  std::vector<StudyParameter> parameters_;
  std::vector<Sample> samples_;
  std::unique_ptr<RunJournal> journal_;
  std::unique_ptr<SweepRunner> runner_;  // each run edits a copy of the netlist
  std::vector<PointResult> history_;
  std::atomic<long> runs_{0}, resumed_{0};
  long failed_ = 0;
};

// Feasible within a relative constraint tolerance (COBYLA ends on the boundary).
constexpr double kConstraintTolerance = 1e-6;

// One NLopt run in the unit cube of the design variables.
class Search {
 public:
  Search(DesignEvaluator& ev, const OptimizeProblem& p, const OptimizeOptions& o, int objective,
         std::vector<Constraint> constraints)
      : ev_(ev), p_(p), o_(o), objective_(objective), constraints_(std::move(constraints)),
        t0_(std::chrono::steady_clock::now()) {}

  std::vector<double> unit_of(const std::vector<double>& x) const {
    std::vector<double> u(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) u[i] = (x[i] - p_.design[i].lo) / (p_.design[i].hi - p_.design[i].lo);
    return u;
  }
  std::vector<double> x_of(const std::vector<double>& u) const {
    std::vector<double> x(u.size());
    for (std::size_t i = 0; i < u.size(); ++i) x[i] = p_.design[i].lo + u[i] * (p_.design[i].hi - p_.design[i].lo);
    return x;
  }

  // Runs `algorithm` from u (updated to the optimiser's end point).
  // DIRECT allocates its work arrays for the whole budget up front, so it is
  // given a small budget first and restarted with four times as much while
  // it uses it all: DIRECT is deterministic, a restart retraces the points
  // evaluated so far (answered from the history, no new runs), and memory
  // stays proportional to the points actually evaluated.
  void run(nlopt::algorithm algorithm, std::vector<double>& u, int budget) {
    if (algorithm != nlopt::GN_ORIG_DIRECT_L) {
      (void)run_once(algorithm, u, budget);
      return;
    }
    const std::vector<double> start = u;
    for (long chunk = std::min(budget, kFirstDirectBudget);; chunk = std::min<long>(budget, chunk * 4)) {
      u = start;
      if (!run_once(algorithm, u, static_cast<int>(chunk)) || chunk >= budget) return;
    }
  }

  // True if NLopt stopped because the budget was used up.
  bool run_once(nlopt::algorithm algorithm, std::vector<double>& u, int budget) {
    if (budget <= 0) return false;
    const auto n = static_cast<unsigned>(u.size());
    nlopt::opt opt(algorithm, n);
    opt.set_lower_bounds(std::vector<double>(n, 0.0));
    opt.set_upper_bounds(std::vector<double>(n, 1.0));
    global_ = algorithm == nlopt::GN_ORIG_DIRECT_L;
    opt.set_min_objective(&Search::objective_cb, this);
    if (algorithm != nlopt::LN_BOBYQA)
      for (std::size_t c = 0; c < constraints_.size(); ++c)
        opt.add_inequality_constraint(&Search::constraint_cb, &slots_.emplace_back(Slot{this, c}), 0.0);
    opt.set_maxeval(budget);
    opt.set_xtol_rel(1e-5);
    if (algorithm == nlopt::LN_COBYLA || algorithm == nlopt::LN_BOBYQA) opt.set_initial_step(0.1);
    double f = 0.0;
    try {
      return opt.optimize(u, f) == nlopt::MAXEVAL_REACHED;
    } catch (const std::exception&) {
      // NLopt's stops (round-off, forced) keep the best point it had in u.
    }
    return false;
  }

  // The best feasible point evaluated so far (or the least infeasible one).
  const PointResult* best() const {
    const PointResult* b = nullptr;
    for (const auto& h : ev_.history()) {
      if (!h.feasible_runs) continue;
      const bool ok = feasible(h);
      if (!b || (ok && !feasible(*b)) || (ok == feasible(*b) && (ok ? h.robust[objective_] < b->robust[objective_]
                                                                      : h.violation < b->violation)))
        b = &h;
    }
    return b;
  }

  // A constraint's statistic at a point (its own, or --robust's).
  double value(const PointResult& h, const Constraint& c) const {
    return robust_value(c.statistic.value_or(p_.robust), h.metric[ev_.index_of(c.metric)]);
  }

  bool feasible(const PointResult& h) const {
    if (!h.feasible_runs) return false;
    for (const auto& c : constraints_) {
      const double v = value(h, c);
      if ((c.at_least ? c.limit - v : v - c.limit) > kConstraintTolerance * std::max(std::abs(c.limit), 1e-300))
        return false;
    }
    return true;
  }

 private:
  struct Slot {
    Search* self;
    std::size_t constraint;
  };

  const PointResult& at(const std::vector<double>& u) {
    const PointResult& r = ev_.evaluate(x_of(u));
    progress();
    return r;
  }

  static double objective_cb(const std::vector<double>& u, std::vector<double>&, void* data) {
    auto* s = static_cast<Search*>(data);
    const PointResult& r = s->at(u);
    if (!r.feasible_runs) return s->global_ ? HUGE_VAL : 1e30;
    return r.robust[s->objective_];
  }

  static double constraint_cb(const std::vector<double>& u, std::vector<double>&, void* data) {
    const auto* slot = static_cast<Slot*>(data);
    Search* s = slot->self;
    const PointResult& r = s->at(u);
    const Constraint& c = s->constraints_[slot->constraint];
    if (!r.feasible_runs) return 1.0;
    const double v = s->value(r, c);
    return (c.at_least ? c.limit - v : v - c.limit) / std::max(std::abs(c.limit), 1e-300);
  }

  // One line on a terminal, rewritten at most every 0.2 s; nothing when
  // stderr is a file (the summary says it all).
  void progress() {
    if (!o_.progress || !isatty(2)) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(200)) return;
    last_ = now;
    const long evals = static_cast<long>(ev_.history().size());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    const PointResult* b = best();
    std::ostringstream line;
    line << "[" << evals << " points] " << ev_.runs() << " runs";
    if (ev_.resumed() > 0) line << " (+" << ev_.resumed() << " from the journal)";
    if (b && feasible(*b)) {
      line << ", best " << ev_.metrics()[objective_].name << " " << std::setprecision(4) << b->robust[objective_]
           << " " << ev_.metrics()[objective_].si_unit << " at";
      for (std::size_t i = 0; i < b->x.size(); ++i)
        line << " " << p_.design[i].parameter.name << "=" << p_.design[i].parameter.shown(b->x[i]);
    }
    const long left = std::max<long>(0, o_.max_evaluations - evals);
    line << ", ETA " << std::setprecision(2) << (evals > 0 ? s / evals * left : 0.0) << " s";
    std::cerr << "\r" << line.str() << "        " << std::flush;
  }

  DesignEvaluator& ev_;
  const OptimizeProblem& p_;
  const OptimizeOptions& o_;
  int objective_;
  std::vector<Constraint> constraints_;
  std::deque<Slot> slots_;
  bool global_ = false;
  static constexpr int kFirstDirectBudget = 256;
  std::chrono::steady_clock::time_point t0_, last_{};
};

// The default: DIRECT-L over the whole box for a first look, COBYLA from
// its best point for the last digits.
std::vector<double> search(Search& s, const std::string& algorithm, std::vector<double> u, int budget) {
  if (algorithm == "direct+cobyla") {
    const int global = std::max(1, static_cast<int>(static_cast<long>(budget) * 3 / 5));
    s.run(nlopt::GN_ORIG_DIRECT_L, u, global);
    if (const PointResult* b = s.best()) u = s.unit_of(b->x);
    s.run(nlopt::LN_COBYLA, u, budget - global);
  } else if (algorithm == "cobyla") {
    s.run(nlopt::LN_COBYLA, u, budget);
  } else if (algorithm == "bobyqa") {
    s.run(nlopt::LN_BOBYQA, u, budget);
  } else {
    s.run(nlopt::GN_ORIG_DIRECT_L, u, budget);
  }
  return u;
}

// Non-dominated feasible points (both objectives minimised), by f1.
std::vector<ParetoPoint> front_of(const std::vector<PointResult>& history, const Search& s, int f1, int f2) {
  std::vector<ParetoPoint> pts;
  for (const auto& h : history)
    if (s.feasible(h)) pts.push_back({h.x, h.robust[f1], h.robust[f2]});
  std::sort(pts.begin(), pts.end(), [](const ParetoPoint& a, const ParetoPoint& b) {
    return a.f1 < b.f1 || (a.f1 == b.f1 && a.f2 < b.f2);
  });
  std::vector<ParetoPoint> front;
  for (const auto& p : pts)
    if (front.empty() || p.f2 < front.back().f2) front.push_back(p);
  return front;
}

// The feasible interval of the single design variable around the optimum:
// a scan of the bounds, then bisection of each edge.
void feasible_interval(DesignEvaluator& ev, Search& s, const OptimizeProblem& p, OptimizeResult& r) {
  const double lo = p.design[0].lo, hi = p.design[0].hi, x0 = r.best.x[0];
  auto ok = [&](double x) { return s.feasible(ev.evaluate({x})); };
  auto edge = [&](double in, double out) {
    for (int i = 0; i < 10; ++i) {
      const double mid = 0.5 * (in + out);
      (ok(mid) ? in : out) = mid;
    }
    return in;
  };
  const int n = 16;
  double a = x0, b = x0;
  for (int i = 1; i <= n; ++i) {  // outward from the optimum in steps of the scan
    const double x = x0 - i * (hi - lo) / n;
    if (x < lo) { a = ok(lo) ? lo : edge(a, lo); break; }
    if (!ok(x)) { a = edge(a, x); break; }
    a = x;
  }
  for (int i = 1; i <= n; ++i) {
    const double x = x0 + i * (hi - lo) / n;
    if (x > hi) { b = ok(hi) ? hi : edge(b, hi); break; }
    if (!ok(x)) { b = edge(b, x); break; }
    b = x;
  }
  r.feasible_lo = a;
  r.feasible_hi = b;
}

Uncertain::Kind kind_of(const std::string& k) {
  if (k == "normal") return Uncertain::Kind::normal;
  if (k == "uniform") return Uncertain::Kind::uniform;
  if (k == "lognormal") return Uncertain::Kind::lognormal;
  throw std::invalid_argument(k);
}

}  // namespace

double Uncertain::quantile(double u) const {
  switch (kind) {
    case Kind::uniform: return a + u * (b - a);
    case Kind::normal: return a + b * inverse_normal(u);
    case Kind::lognormal: {  // mean a, sd b of the quantity itself
      const double s2 = std::log(1.0 + b * b / (a * a));
      return std::exp(std::log(a) - 0.5 * s2 + std::sqrt(s2) * inverse_normal(u));
    }
  }
  return kNaN;
}

Uncertain parse_uncertain(const Netlist& nl, const Registry& registry, const std::string& spec) {
  const std::string option = "--uncertain " + spec;
  const auto eq = spec.find('=');
  const auto parts = eq == std::string::npos ? std::vector<std::string>{} : split_trimmed(spec.substr(eq + 1), ':');
  if (eq == std::string::npos || eq == 0 || parts.size() != 3)
    throw InputError(args_where(nl), "", "",
                     option + ": expected NAME=normal:MEAN:SD, NAME=uniform:LOW:HIGH or NAME=lognormal:MEAN:SD");
  Uncertain u;
  u.text = spec.substr(eq + 1);
  u.parameter = resolve_parameter(nl, registry, trim(spec.substr(0, eq)));
  try {
    u.kind = kind_of(parts[0]);
  } catch (const std::invalid_argument&) {
    throw InputError(args_where(nl), u.parameter.component, u.parameter.parameter,
                     option + ": unknown distribution '" + parts[0] + "' (normal, uniform, lognormal)");
  }
  u.a = parse_value(nl, registry, u.parameter, parts[1], option);
  u.b = parse_value(nl, registry, u.parameter, parts[2], option);
  const bool ok = u.kind == Uncertain::Kind::uniform ? u.b > u.a
                  : u.kind == Uncertain::Kind::normal ? u.b > 0
                                                      : u.a > 0 && u.b > 0;
  if (!ok)
    throw InputError(args_where(nl), u.parameter.component, u.parameter.parameter,
                     option + (u.kind == Uncertain::Kind::uniform ? ": HIGH must be greater than LOW"
                                                                  : ": SD (and for lognormal MEAN) must be > 0"));
  return u;
}

Robust parse_robust(const std::string& text) {
  Robust r;
  r.text = text;
  const auto colon = text.find(':');
  const std::string kind = text.substr(0, colon);
  double k = kNaN;
  if (colon != std::string::npos) {
    char* end = nullptr;
    k = std::strtod(text.c_str() + colon + 1, &end);
    if (*end != '\0') k = kNaN;
  }
  if (kind == "mean" && colon == std::string::npos) return r;
  if (kind == "mean+ksd" && std::isfinite(k) && k >= 0) {
    r.kind = Robust::Kind::mean_ksd;
    r.k = k;
    return r;
  }
  if (kind == "quantile" && k > 0 && k < 1) {
    r.kind = Robust::Kind::quantile;
    r.k = k;
    return r;
  }
  throw InputError(SourceLocation{"--robust", 0, 0}, "", "",
                   "--robust " + text + ": expected mean, mean+ksd:K (K >= 0) or quantile:Q (0 < Q < 1)");
}

Constraint parse_constraint(const std::vector<Metric>& available, const std::string& text) {
  Constraint c;
  c.text = text;
  auto op = text.find("<=");
  if (op == std::string::npos) {
    op = text.find(">=");
    c.at_least = op != std::string::npos;
  }
  const auto fail = [&](const std::string& why) {
    throw InputError(SourceLocation{"--constraint", 0, 0}, "", "", "--constraint " + text + ": " + why);
  };
  if (op == std::string::npos || op == 0) fail("expected METRIC<=VALUE or METRIC>=VALUE, e.g. t_cushion<=0.1s");
  c.metric = trim(text.substr(0, op));
  if (const auto open = c.metric.find('('); open != std::string::npos) {
    // STATISTIC(METRIC): the statistic replaces --robust for this constraint.
    const std::string statistic = trim(c.metric.substr(0, open));
    if (c.metric.back() != ')' || statistic.empty())
      fail("'" + c.metric + "': parentheses hold the metric after a statistic, e.g. quantile:0.9(t_cushion)<=0.1s; "
           "without a statistic write the metric alone");
    try {
      c.statistic = parse_robust(statistic);
    } catch (const InputError&) {
      fail("unknown statistic '" + statistic + "' before the parentheses: use mean, mean+ksd:K (K >= 0) or quantile:Q (0 < Q < 1)");
    }
    c.metric = trim(c.metric.substr(open + 1, c.metric.size() - open - 2));
  }
  const auto m = std::find_if(available.begin(), available.end(), [&](const Metric& x) { return x.name == c.metric; });
  if (m == available.end()) fail("unknown metric '" + c.metric + "'");
  try {
    const auto q = units::parse_quantity(trim(text.substr(op + 2)));
    if (q.had_unit && !(q.dim == units::dimension_of(m->unit)))
      fail("the value's unit is not of " + c.metric + "'s dimension (" + m->unit + ")");
    c.limit = q.si_value;
  } catch (const units::ParseError& e) {
    fail(std::string("cannot read the value: ") + e.what());
  }
  return c;
}

std::vector<Range> parse_design(const Netlist& nl, const Registry& registry, const std::vector<std::string>& specs) {
  auto ranges = parse_ranges(nl, registry, specs, "--design");
  for (const auto& r : ranges) {
    if (r.parameter.component.empty()) continue;
    const ComponentDecl* decl = nl.component(r.parameter.component);
    const ParameterSpec* spec = registry.find(decl->type)->info->parameter(r.parameter.parameter);
    if (!spec->in_range(r.lo) || !spec->in_range(r.hi))
      throw InputError(args_where(nl), r.parameter.component, r.parameter.parameter,
                       "--design " + r.parameter.name + ": the bounds leave the parameter's valid range " +
                           spec->range_text());
  }
  return ranges;
}

bool PointResult::feasible() const { return feasible_runs && violation <= kConstraintTolerance; }

OptimizeResult optimize(const Model& model, const OptimizeProblem& p, const OptimizeOptions& o) {
  DesignEvaluator ev(model, p, o);
  OptimizeResult r;
  for (const auto& m : ev.metrics()) {
    r.metric_names.push_back(m.name);
    r.metric_units.push_back(m.si_unit);
  }
  const int f1 = ev.index_of(p.objectives[0]);
  Search s(ev, p, o, f1, p.constraints);
  std::vector<double> u(p.design.size(), 0.5);
  u = search(s, o.algorithm, u, o.max_evaluations);
  if (o.pareto && p.objectives.size() == 2) {
    // The epsilon-constraint front: the second objective's range from its
    // own optimum to its value at the first's, each level a bound on it.
    const int f2 = ev.index_of(p.objectives[1]);
    Search s2(ev, p, o, f2, p.constraints);
    (void)search(s2, o.algorithm, std::vector<double>(p.design.size(), 0.5), o.max_evaluations);
    // Copies: the history grows (and moves) with every point evaluated.
    const PointResult* pa = s.best();
    const PointResult* pb = s2.best();
    if (pa && pb && s.feasible(*pa) && s2.feasible(*pb)) {
      const PointResult a = *pa;
      const double hi = a.robust[f2], lo = pb->robust[f2];
      for (int k = 1; k < o.pareto_points; ++k) {
        auto cs = p.constraints;
        cs.push_back({p.objectives[1], hi + (lo - hi) * k / o.pareto_points, false, "pareto level", std::nullopt});
        Search sk(ev, p, o, f1, cs);
        std::vector<double> uk = sk.unit_of(a.x);
        sk.run(nlopt::LN_COBYLA, uk, std::max(10, o.max_evaluations / 2));
      }
    }
    r.front = front_of(ev.history(), s, f1, f2);
  }
  if (const PointResult* b = s.best()) {
    r.best = *b;
    r.found = s.feasible(*b);
  }
  if (o.auto_adjust && r.found && p.design.size() == 1) feasible_interval(ev, s, p, r);
  if (o.progress && isatty(2)) std::cerr << "\n";
  r.runs = ev.runs();
  r.runs_resumed = ev.resumed();
  r.failed_runs = ev.failed();
  r.evaluations = static_cast<long>(ev.history().size());
  r.history = ev.history();
  return r;
}

OptimizeResult evaluate_design(const Model& model, const OptimizeProblem& p, const OptimizeOptions& o,
                               const std::vector<double>& x) {
  DesignEvaluator ev(model, p, o);
  Search s(ev, p, o, ev.index_of(p.objectives[0]), p.constraints);
  OptimizeResult r;
  for (const auto& m : ev.metrics()) {
    r.metric_names.push_back(m.name);
    r.metric_units.push_back(m.si_unit);
  }
  r.best = ev.evaluate(x);
  r.found = s.feasible(r.best);
  r.runs = ev.runs();
  r.runs_resumed = ev.resumed();
  r.failed_runs = ev.failed();
  r.evaluations = 1;
  r.history = ev.history();
  return r;
}

void write_result_yaml(const OptimizeProblem& p, const OptimizeOptions& o, const OptimizeResult& r,
                       const std::string& path) {
  std::ostringstream y;
  y << std::setprecision(10);
  y << "# pneumo optimize: the design that minimises " << p.objectives[0] << " ("
    << (p.uncertain.empty() ? "nominal run" : p.robust.text + " over " + std::to_string(p.samples) + " samples")
    << "); SI values\n";
  y << "found: " << (r.found ? "true" : "false") << "\n";
  if (!r.best.reason.empty()) y << "reason: \"" << r.best.reason << "\"\n";
  y << "optimum:\n";
  for (std::size_t i = 0; i < p.design.size() && i < r.best.x.size(); ++i)
    y << "  " << p.design[i].parameter.name << ": {value: " << r.best.x[i] << ", unit: \"" << p.design[i].parameter.unit
      << "\", lower: " << p.design[i].lo << ", upper: " << p.design[i].hi << "}\n";
  y << "metrics:\n";
  for (std::size_t m = 0; m < r.metric_names.size() && m < r.best.metric.size(); ++m) {
    const auto& v = r.best.metric[m];
    y << "  " << r.metric_names[m] << ": {unit: \"" << r.metric_units[m] << "\"";
    if (!v.empty())
      y << ", robust: " << r.best.robust[m] << ", mean: " << mean_of(v) << ", sd: " << sd_of(v)
        << ", q05: " << quantile_of(v, 0.05) << ", q50: " << quantile_of(v, 0.5) << ", q95: " << quantile_of(v, 0.95)
        << ", min: " << quantile_of(v, 0.0) << ", max: " << quantile_of(v, 1.0);
    y << ",\n    values: [";  // one per uncertainty sample, in the samples' order
    for (std::size_t j = 0; j < v.size(); ++j) y << (j ? ", " : "") << v[j];
    y << "]}\n";
  }
  y << "constraints:\n";
  for (const auto& c : p.constraints) y << "  - \"" << c.text << "\"\n";
  y << "uncertain:\n";
  for (const auto& u : p.uncertain) y << "  " << u.parameter.name << ": \"" << u.text << "\"\n";
  y << "robust: \"" << p.robust.text << "\"\nsamples: " << (p.uncertain.empty() ? 1 : p.samples) << "\nseed: " << p.seed
    << "\nalgorithm: " << o.algorithm << "\nevaluations: " << r.evaluations << "\nruns: " << r.runs
    << "\nruns_from_journal: " << r.runs_resumed << "\n";
  if (o.auto_adjust && r.found && !p.design.empty())
    y << "feasible_interval: [" << r.feasible_lo << ", " << r.feasible_hi << "]\n";
  if (!r.front.empty()) {
    y << "pareto_front:  # " << p.objectives[0] << ", " << p.objectives[1] << ", design\n";
    for (const auto& f : r.front) {
      y << "  - [" << f.f1 << ", " << f.f2;
      for (double x : f.x) y << ", " << x;
      y << "]\n";
    }
  }
  write_text_atomic(path, y.str());
}

}  // namespace pneumo::study
