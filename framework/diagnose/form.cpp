#include "framework/diagnose/form.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "framework/assembly/system.hpp"
#include "framework/core/parallel.hpp"
#include "framework/core/text.hpp"
#include "framework/diagnose/statistics.hpp"
#include "framework/run/run.hpp"

namespace pneumo::diagnose {

std::string unknown_unit(const System& sys, const std::string& name) {
  static const std::pair<const char*, const char*> node[] = {
      {"p at ", "Pa"}, {"T at ", "K"}, {"s at ", "m"}, {"v at ", "m/s"}};
  for (const auto& [prefix, unit] : node)
    if (name.rfind(prefix, 0) == 0) return unit;
  const auto dot = name.rfind('.');
  if (dot == std::string::npos) return "";
  const int c = sys.circuit().find(name.substr(0, dot));
  if (c < 0) return "";
  for (const auto& v : sys.circuit().components[c]->info().variables)
    if (v.name == name.substr(dot + 1)) return v.unit;
  return "";
}

namespace {

using Of = DisturbanceFactor::Of;

// The rate's unit of a quantity's (m -> m/s, m/s -> m/s2).
std::string rate_unit_of(const std::string& unit) {
  if (unit.ends_with("/s")) return unit + "2";
  return unit.empty() ? "1/s" : unit + "/s";
}

// One unknown the dictionary reads, sampled at the output times of each used run.
struct Variable {
  std::string name, unit;
  std::vector<std::vector<double>> y, yp;
  double lo = INFINITY, hi = -INFINITY;
  bool unknown = false;  // a System unknown: its rate is known too
};

bool is_velocity(const std::string& unit) { return unit == "m/s" || unit == "rad/s"; }
bool is_position(const std::string& unit) { return unit == "m" || unit == "rad"; }

// What the dictionary may read: the System's unknowns, then every
// component's local variables (but a port's entering-stream temperature,
// no gas's state) and observables, by their units.
struct Readable {
  std::string name, unit;
  int unknown = -1;
  Probe probe;
};

// A physical node (pneumatic, thermal, translational) of the circuit: the
// components with a port at it. `held`: its across variable is a constant (a
// source's pressure, the atmosphere, a fixed temperature, a wall) - what
// happens on one side of it does not reach the other.
struct PhysicalNode {
  std::vector<int> components;
  bool held = false;
};

// Signal wires carry commands, not the quantities a balance's missing term
// reads (a sequencer is wired to every valve of a line): they make no node.
std::vector<PhysicalNode> physical_nodes(const System& sys) {
  const Circuit& c = sys.circuit();
  std::vector<PhysicalNode> out;
  for (const auto& ports : sys.nodes()) {
    const Component& first = *c.components[ports.front().component];
    if (first.info().ports[ports.front().port].domain == Domain::signal) continue;
    PhysicalNode node;
    for (const auto& p : ports) {
      node.components.push_back(p.component);
      node.held = node.held || sys.holds_constant(p.component, c.components[p.component]->port_offset(p.port));
    }
    out.push_back(std::move(node));
  }
  return out;
}

// The components a missing term may read: those of `near` (the components
// whose equations read the balance's state, or the one a reading comes
// from), and those within three physical nodes of them - a force on a piston
// or a chamber's leak depends on the cylinder's own chambers and position
// and on its drive (the throttles at its ports, the lines behind them, their
// valve), not on another cylinder's. The search does not cross a held node:
// a supply or exhaust manifold joins every valve of a line, but its pressure
// is the source's, whatever the other drives do. On a small circuit that is
// most of it; on a line of cylinders the dictionary would otherwise grow
// with the square of the line's pressures (their differences).
std::vector<char> neighbourhood(const System& sys, std::vector<char> near) {
  constexpr int kHops = 3;
  const auto nodes = physical_nodes(sys);
  for (int hop = 0; hop < kHops; ++hop) {
    const std::vector<char> from = near;
    for (const auto& node : nodes)
      if (!node.held && std::any_of(node.components.begin(), node.components.end(), [&](int c) { return from[c] != 0; }))
        for (int c : node.components) near[c] = 1;
  }
  return near;
}

// Where a missing term starts: the components that read the balance's state
// (unknown `balance`; all components when it is none), or the component
// whose output `reading` is.
std::vector<char> seed_of(const System& sys, int balance, const std::string& reading) {
  const Circuit& circuit = sys.circuit();
  std::vector<char> seed(circuit.components.size(), 0);
  if (!reading.empty()) {
    for (const auto& p : circuit.probes)
      if (p.name == reading && p.component >= 0) seed[p.component] = 1;
    return seed;
  }
  if (balance < 0) return std::vector<char>(circuit.components.size(), 1);
  for (int c : sys.components_reading(balance)) seed[c] = 1;
  return seed;
}

std::vector<Readable> readables(const System& sys, const std::vector<char>& near) {
  static const std::set<std::string> units = {"m", "m/s", "rad", "rad/s", "Pa", "K"};
  std::vector<Readable> out;
  const auto& names = sys.variable_names();
  for (int i = 0; i < sys.size(); ++i) {
    const auto readers = sys.components_reading(i);
    if (std::none_of(readers.begin(), readers.end(), [&](int c) { return near[c] != 0; })) continue;
    if (const std::string u = unknown_unit(sys, names[i]); units.count(u)) out.push_back({names[i], u, i, {}});
  }
  const Circuit& circuit = sys.circuit();
  for (int c = 0; c < static_cast<int>(circuit.components.size()); ++c) {
    if (!near[c]) continue;
    const Component& comp = *circuit.components[c];
    std::vector<std::string> quantities;
    for (auto& q : local_variable_names(comp))
      if (!is_entering_stream_temperature(q)) quantities.push_back(std::move(q));
    for (const auto& o : comp.info().observables) quantities.push_back(o.name);
    for (const auto& q : quantities) {
      Probe p = find_probe(circuit, c, q);
      if (p.index >= 0 && units.count(p.unit)) out.push_back({comp.name() + "." + q, p.unit, -1, p});
    }
  }
  return out;
}

// True when b's samples are an affine function of a's (a flange's position
// and the piston's stroke, a port's pressure and its node's).
bool affine_twin(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size() || a.size() < 3) return false;
  const Eigen::Map<const Eigen::VectorXd> x(a.data(), static_cast<Eigen::Index>(a.size())),
      y(b.data(), static_cast<Eigen::Index>(b.size()));
  const Eigen::VectorXd dx = x.array() - x.mean(), dy = y.array() - y.mean();
  const double sxx = dx.squaredNorm(), syy = dy.squaredNorm();
  if (!(sxx > 0) || !(syy > 0)) return false;
  const double r = dx.dot(dy) / std::sqrt(sxx * syy);
  return std::abs(r) > 1 - 1e-9;
}

std::vector<double> joined(const Variable& v) {
  std::vector<double> out;
  for (const auto& run : v.y) out.insert(out.end(), run.begin(), run.end());
  return out;
}

// The variables along the verdict model's runs: positions, velocities,
// pressures, temperatures; one of each set that moves together, none that
// stays constant. Near the balance's state (`largest`: its largest
// magnitude), or near the component of the output `reading`; `times`: the
// output times each run's samples are at.
std::vector<Variable> record(const FormInput& in, const std::string& balance, const std::string& reading, double& largest,
                             std::vector<std::vector<double>>* times = nullptr) {
  const std::size_t nr = in.used.size();
  std::vector<std::vector<Readable>> read(nr);
  std::vector<std::vector<std::vector<double>>> y_of(nr), yp_of(nr);  // per run, per readable
  std::vector<std::vector<double>> t_of(nr);
  std::vector<double> largest_of(nr, 0.0);
  parallel_for(static_cast<long>(nr), in.threads, [&](int, long q) {
    const Netlist nl = in.netlist_of(in.used[q]);
    System sys(elaborate(nl, *in.registry));
    const auto& names = sys.variable_names();
    const auto it = std::find(names.begin(), names.end(), balance);
    const int b = it == names.end() ? -1 : static_cast<int>(it - names.begin());
    read[q] = readables(sys, neighbourhood(sys, seed_of(sys, b, reading)));
    y_of[q].resize(read[q].size()), yp_of[q].resize(read[q].size());
    SolverOptions so = solver_options(nl.simulation);
    so.threads = 1;
    Evaluator eval(sys);
    simulate(eval, so, [&](double t, const double* y, const double* yp) {
      if (b >= 0) largest_of[q] = std::max(largest_of[q], std::abs(y[b]));
      t_of[q].push_back(t);
      for (std::size_t k = 0; k < read[q].size(); ++k) {
        const Readable& r = read[q][k];
        y_of[q][k].push_back(r.unknown >= 0 ? y[r.unknown] : eval.probe(r.probe, t, y, yp));
        yp_of[q][k].push_back(r.unknown >= 0 ? yp[r.unknown] : 0.0);
      }
    });
  });
  if (times) *times = std::move(t_of);
  // The first run's readables name the variables (every run's circuit is the model's).
  std::vector<Variable> vars;
  for (const auto& r : read[0])
    vars.push_back({r.name, r.unit, std::vector<std::vector<double>>(nr), std::vector<std::vector<double>>(nr),
                    INFINITY, -INFINITY, r.unknown >= 0});
  for (std::size_t q = 0; q < nr; ++q) {
    largest = std::max(largest, largest_of[q]);
    for (std::size_t k = 0; k < vars.size() && k < read[q].size(); ++k)
      vars[k].y[q] = std::move(y_of[q][k]), vars[k].yp[q] = std::move(yp_of[q][k]);
  }
  for (auto& v : vars)
    for (const auto& run : v.y)
      for (double x : run) v.lo = std::min(v.lo, x), v.hi = std::max(v.hi, x);
  std::vector<Variable> out;
  for (auto& v : vars) {
    const double span = v.hi - v.lo;
    if (!(span > 1e-9 * std::max(1.0, std::abs(v.hi)))) continue;
    const bool twin = std::any_of(out.begin(), out.end(), [&](const Variable& w) { return affine_twin(joined(w), joined(v)); });
    if (!twin) out.push_back(std::move(v));
  }
  return out;
}

// A candidate term: its factors, how it reads, the unit its coefficient
// has, and its RMS along the runs (to size its probe: not its peak, which
// an acceleration at a stop makes a thousand times its typical value).
struct Entry {
  std::vector<DisturbanceFactor> factors;
  std::string text, unit;  // the term's own unit ("" when dimensionless)
  double rms = 0;
};

// Lengths in mm, the rest in SI.
std::string shown(double v, const std::string& unit) {
  if (unit == "m") return rounded(1e3 * v, 3) + " mm";
  return rounded(v, 3) + (unit.empty() ? "" : " " + unit);
}

std::string factor_text(const DisturbanceFactor& f, const std::string& unit) {
  switch (f.of) {
    case Of::value: return "[" + f.variable + "]";
    case Of::rate: return "d[" + f.variable + "]/dt";
    case Of::magnitude: return "|[" + f.variable + "]|";
    case Of::sign: return "sgn([" + f.variable + "])";
    case Of::bump:
      return "bump([" + f.variable + "]; centre " + shown(f.centre, unit) + ", width " + shown(f.width, unit) + ")";
    case Of::difference: return "([" + f.variable + "] - [" + f.other + "])";
  }
  return "";
}

std::string factor_unit(const DisturbanceFactor& f, const std::string& unit) {
  if (f.of == Of::sign || f.of == Of::bump) return "";
  return f.of == Of::rate ? rate_unit_of(unit) : unit;
}

class Dictionary {
 public:
  explicit Dictionary(std::vector<Variable> vars) : vars_(std::move(vars)) {
    for (std::size_t k = 0; k < vars_.size(); ++k) index_[vars_[k].name] = static_cast<int>(k);
  }
  const std::vector<Variable>& vars() const { return vars_; }

  Entry entry(std::vector<DisturbanceFactor> factors) const {
    Entry e{std::move(factors), "", "", 0};
    for (const auto& f : e.factors) {
      const std::string& u = vars_[index_.at(f.variable)].unit;
      e.text += (e.text.empty() ? "" : " * ") + factor_text(f, u);
      const std::string fu = factor_unit(f, u);
      if (!fu.empty()) e.unit += (e.unit.empty() ? "" : "*") + fu;
    }
    if (e.text.empty()) e.text = "1";
    double sum = 0, count = 0;
    for (std::size_t q = 0; q < vars_[0].y.size(); ++q)
      for (std::size_t i = 0; i < samples(q); ++i) sum += std::pow(value(e.factors, q, i), 2), count += 1;
    e.rms = count > 0 ? std::sqrt(sum / count) : 0.0;
    return e;
  }

  double value(const std::vector<DisturbanceFactor>& factors, std::size_t q, std::size_t i) const {
    double v = 1;
    for (const auto& f : factors) {
      const Variable& a = vars_[index_.at(f.variable)];
      const double other = f.other.empty() ? 0.0 : vars_[index_.at(f.other)].y[q][i];
      v *= f(a.y[q][i], a.yp[q][i], other);
    }
    return v;
  }

 private:
  std::size_t samples(std::size_t q) const {
    std::size_t n = SIZE_MAX;
    for (const auto& v : vars_) n = std::min(n, v.y[q].size());
    return n == SIZE_MAX ? 0 : n;
  }
  std::vector<Variable> vars_;
  std::map<std::string, int> index_;
};

constexpr int kBumpCentres = 16;
constexpr double kBumpWidths[] = {1.0 / 25, 1.0 / 10};  // of the stroke the runs cover

DisturbanceFactor read(Of of, const std::string& variable, const std::string& other = "") {
  DisturbanceFactor f;
  f.of = of, f.variable = variable, f.other = other;
  return f;
}

// The speed a sign's smoothing is sized by: the 99th percentile of |v|
// along the runs, not its peak - a servo that takes a replayed position at
// the start moves metres per second for one step, and a sign smoothed over
// a twentieth of that is a viscous law at the speeds the runs hold.
double typical_speed(const Variable& v) {
  std::vector<double> a = joined(v);
  for (double& x : a) x = std::abs(x);
  const auto k = a.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(a.size() - 1));
  std::nth_element(a.begin(), k, a.end());
  return *k > 0 ? *k : std::max(std::abs(v.lo), std::abs(v.hi));
}

// The candidate terms: single factors by the variables' units, bumps over
// each position's range, and sign(v) and v times each non-velocity factor
// (sign(v) times each bump: friction concentrated somewhere on the stroke).
std::vector<Entry> candidate_terms(const Dictionary& dict) {
  std::vector<std::vector<DisturbanceFactor>> single, other, bumps;
  const auto sign = [](const Variable& v) {
    return DisturbanceFactor{Of::sign, v.name, "", 0, 0.05 * typical_speed(v)};
  };
  for (const auto& v : dict.vars()) {
    if (is_velocity(v.unit)) {
      single.push_back({read(Of::value, v.name)});
      single.push_back({read(Of::magnitude, v.name)});
      single.push_back({sign(v)});
      if (v.unknown) single.push_back({read(Of::rate, v.name)});
      continue;
    }
    other.push_back({read(Of::value, v.name)});
    if (is_position(v.unit))
      for (double w : kBumpWidths)
        for (int j = 0; j < kBumpCentres; ++j)
          bumps.push_back({{Of::bump, v.name, "", v.lo + (v.hi - v.lo) * (j + 0.5) / kBumpCentres, w * (v.hi - v.lo)}});
  }
  const auto& vars = dict.vars();
  for (std::size_t a = 0; a < vars.size(); ++a)
    for (std::size_t b = a + 1; b < vars.size(); ++b)
      if (vars[a].unit == "Pa" && vars[b].unit == "Pa") other.push_back({read(Of::difference, vars[a].name, vars[b].name)});
  std::vector<Entry> out{dict.entry({})};
  for (const auto* set : {&other, &single, &bumps})
    for (const auto& f : *set) out.push_back(dict.entry(f));
  for (const auto& v : vars) {
    if (!is_velocity(v.unit)) continue;
    for (const auto& f : other) {
      out.push_back(dict.entry({sign(v), f[0]}));
      out.push_back(dict.entry({read(Of::value, v.name), f[0]}));
    }
    for (const auto& f : bumps) out.push_back(dict.entry({sign(v), f[0]}));
  }
  std::erase_if(out, [](const Entry& e) { return !(e.rms > 0) || !std::isfinite(e.rms); });
  return out;
}

// The runs' normal equations for the linearised residuals r0 + J c: per
// run, so that a run can be left out.
struct Normal {
  std::vector<Eigen::MatrixXd> G;
  std::vector<Eigen::VectorXd> h;
  std::vector<double> s;
  double n = 0;

  // One more run: its sensitivities J (a column a term) and residuals r.
  void add(const Eigen::MatrixXd& J, const Eigen::VectorXd& r) {
    G.push_back(J.transpose() * J);
    h.push_back(J.transpose() * r);
    s.push_back(r.squaredNorm());
    n += static_cast<double>(r.size());
  }
  static Normal of(const std::vector<Eigen::MatrixXd>& J, const std::vector<Eigen::VectorXd>& r) {
    Normal N;
    for (std::size_t q = 0; q < r.size(); ++q) N.add(J[q], r[q]);
    return N;
  }

  Eigen::VectorXd fit(const std::vector<int>& S, int skip) const {
    const int p = static_cast<int>(S.size());
    if (p == 0) return Eigen::VectorXd();
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(p, p);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(p);
    for (std::size_t q = 0; q < G.size(); ++q) {
      if (static_cast<int>(q) == skip) continue;
      for (int a = 0; a < p; ++a) {
        g[a] += h[q][S[a]];
        for (int b = 0; b < p; ++b) A(a, b) += G[q](S[a], S[b]);
      }
    }
    A.diagonal().array() += 1e-10 * std::max(A.diagonal().maxCoeff(), 1e-300);
    return -A.ldlt().solve(g);
  }
  double ssr(const std::vector<int>& S, std::size_t q, const Eigen::VectorXd& c) const {
    double v = s[q];
    for (std::size_t a = 0; a < S.size(); ++a) {
      v += 2 * h[q][S[a]] * c[a];
      for (std::size_t b = 0; b < S.size(); ++b) v += c[a] * G[q](S[a], S[b]) * c[b];
    }
    return v;
  }
  // Leave-one-run-out: each run predicted by the fit to the others.
  double cross_validated(const std::vector<int>& S) const {
    double total = 0;
    for (std::size_t q = 0; q < G.size(); ++q) total += ssr(S, q, fit(S, static_cast<int>(q)));
    return total;
  }
};

constexpr int kMaxTerms = 4;
constexpr std::size_t kTried = 3;  // additions simulated per round
constexpr std::size_t kScreened = 24;  // terms linearised after the first round (Discovery::linearise)

// What a term must gain to be taken: a run's worth of noise (sum of squares
// of unit-variance residuals) per run, and a percent of the excess.
double needed(const Normal& N, double ssr) {
  return static_cast<double>(N.G.size()) + 0.01 * std::max(ssr - N.n, 0.0);
}

bool same_factor(const DisturbanceFactor& a, const DisturbanceFactor& b) {
  return a.of == b.of && a.variable == b.variable && a.other == b.other && a.centre == b.centre && a.width == b.width;
}

// For each term that is a factor times a quantity (sgn(v) * p, v * x), the
// term of that factor alone, else -1: with it the term becomes an affine law
// of the quantity under the same factor - a friction a + b p that takes the
// sign of the motion (eq. 8 of the end-cushioning paper) - as a term with
// the constant is an affine law (a spring with its preload).
std::vector<int> partners(const std::vector<Entry>& terms) {
  std::vector<int> out(terms.size(), -1);
  for (std::size_t k = 0; k < terms.size(); ++k) {
    if (terms[k].factors.size() != 2) continue;
    for (std::size_t j = 0; j < terms.size(); ++j)
      if (terms[j].factors.size() == 1 && same_factor(terms[j].factors[0], terms[k].factors[0]))
        out[k] = static_cast<int>(j);
  }
  return out;
}

// The additions to the form's terms `S` - one term, or one with the
// constant, or one with its partner (affine laws that neither term alone
// fits) - with how much each, refitted with S, lowers `error` (of the terms
// fitted); best first. The constant is candidate 0.
std::vector<std::pair<double, std::vector<int>>> additions(const std::vector<int>& S, const std::vector<char>& usable,
                                                           const std::vector<int>& partner,
                                                           const std::function<double(const std::vector<int>&)>& error) {
  const double before = error(S);
  std::vector<std::pair<double, std::vector<int>>> ranked;
  const auto consider = [&](std::vector<int> added) {
    auto T = S;
    T.insert(T.end(), added.begin(), added.end());
    ranked.emplace_back(before - error(T), std::move(added));
  };
  const auto free = [&](int k) { return k >= 0 && usable[k] && std::find(S.begin(), S.end(), k) == S.end(); };
  for (int k = 0; k < static_cast<int>(usable.size()); ++k) {
    if (!free(k)) continue;
    consider({k});
    if (k > 0 && free(0)) consider({k, 0});
    if (free(partner[k])) consider({k, partner[k]});
  }
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  return ranked;
}

// The additions that lower the cross-validated error by enough (a term's
// price each), best first, at most `count`.
std::vector<std::vector<int>> best_additions(const Normal& N, const std::vector<int>& S, const std::vector<char>& usable,
                                             const std::vector<int>& partner, std::size_t count) {
  const double price = needed(N, N.cross_validated(S));
  std::vector<std::vector<int>> out;
  const auto cv = [&](const std::vector<int>& T) { return N.cross_validated(T); };
  for (auto& [gain, added] : additions(S, usable, partner, cv))
    if (out.size() < count && gain >= static_cast<double>(added.size()) * price) out.push_back(std::move(added));
  return out;
}

// A term's parameters: its coefficient, and a bump's centre and width.
double parameter_count(const Entry& e) {
  double p = 1;
  for (const auto& f : e.factors) p += f.of == Of::bump ? 2 : 0;
  return p;
}

// The form's parameters for Gauss-Newton: each term's coefficient, and a
// bump's centre and width.
struct Parameter {
  int term, factor = -1;  // factor < 0: the coefficient
  bool width = false;
};

double& slot(std::vector<DisturbanceTerm>& terms, const Parameter& p) {
  auto& t = terms[p.term];
  if (p.factor < 0) return t.coefficient;
  return p.width ? t.factors[p.factor].width : t.factors[p.factor].centre;
}

// A bump narrower than half a percent of the stroke is a step the solver
// cannot resolve, one wider than a quarter of it no longer a bump but a
// smooth law the other terms say plainly: Gauss-Newton is let in neither.
bool bump_out_of_range(const std::vector<DisturbanceTerm>& terms, double range) {
  for (const auto& t : terms)
    for (const auto& f : t.factors)
      if (f.of == Of::bump && !(f.width > range / 200 && f.width < range / 4)) return true;
  return false;
}

class Refiner {
 public:
  Refiner(const FormInput& in, std::string balance, std::atomic<long>& sims)
      : in_(in), balance_(std::move(balance)), sims_(sims) {}

  // The residuals of every used run with `terms` in the model; false when one failed.
  bool residuals(const std::vector<DisturbanceTerm>& terms, std::vector<Eigen::VectorXd>& r, std::string* why) const {
    std::vector<std::vector<Eigen::VectorXd>> rs;
    std::vector<std::string> whys;
    const bool ran = residuals_of({terms}, rs, whys)[0];
    r = std::move(rs[0]);
    if (!ran && why) *why = whys[0];
    return ran;
  }

  // The same for several sets of terms, all their runs on the threads at
  // once (a set's runs alone keep a thread idle when they are odd in
  // number). Per set: whether every run ran, else why the first failed.
  std::vector<char> residuals_of(const std::vector<std::vector<DisturbanceTerm>>& sets,
                                 std::vector<std::vector<Eigen::VectorXd>>& r, std::vector<std::string>& why) const {
    const std::size_t nr = in_.used.size(), ns = sets.size();
    r.assign(ns, std::vector<Eigen::VectorXd>(nr));
    std::vector<std::string> reasons(ns * nr);
    parallel_for(static_cast<long>(ns * nr), in_.threads, [&](int, long job) {
      const std::size_t k = static_cast<std::size_t>(job) / nr, q = static_cast<std::size_t>(job) % nr;
      const auto sim = in_.simulate(in_.used[q], {Disturbance{balance_, {}, {}, sets[k]}}, &reasons[job]);
      ++sims_;
      if (!sim.empty()) r[k][q] = in_.residual(in_.used[q], sim);
    });
    std::vector<char> ran(ns, 1);
    why.assign(ns, "");
    for (std::size_t k = 0; k < ns; ++k)
      for (std::size_t q = 0; q < nr && ran[k]; ++q)
        if (r[k][q].size() == 0) {
          ran[k] = 0;
          why[k] = "run " + (*in_.runs)[in_.used[q]].name + ": " + reasons[k * nr + q];
        }
    return ran;
  }

  // Damped Gauss-Newton steps from `terms` while each lowers the simulated
  // sum of squares by more than a percent, at most four; `terms`, `ssr` and
  // the runs' residuals `r` end at the best. Returns whether the fourth
  // still did (not converged).
  bool refine(std::vector<DisturbanceTerm>& terms, double& ssr, std::vector<Eigen::VectorXd>& r, double range) const {
    const std::vector<Parameter> params = parameters(terms);
    for (int it = 0; it < 4; ++it) {
      const Eigen::VectorXd r_all = stacked(r);
      Eigen::MatrixXd J;
      if (!jacobian(terms, params, r_all, J)) return false;
      Eigen::MatrixXd A = J.transpose() * J;
      A.diagonal() *= 1.001;
      const Eigen::VectorXd delta = -A.ldlt().solve(J.transpose() * r_all);
      const double before = ssr;
      if (!step(terms, params, delta, range, ssr, r) || ssr > 0.99 * before) return false;
    }
    return true;
  }

  static Eigen::VectorXd stacked(const std::vector<Eigen::VectorXd>& r) {
    Eigen::Index n = 0;
    for (const auto& v : r) n += v.size();
    Eigen::VectorXd out(n);
    n = 0;
    for (const auto& v : r) out.segment(n, v.size()) = v, n += v.size();
    return out;
  }

 private:
  static std::vector<Parameter> parameters(const std::vector<DisturbanceTerm>& terms) {
    std::vector<Parameter> params;
    for (int j = 0; j < static_cast<int>(terms.size()); ++j) {
      params.push_back({j});
      for (int f = 0; f < static_cast<int>(terms[j].factors.size()); ++f)
        if (terms[j].factors[f].of == Of::bump) params.push_back({j, f, false}), params.push_back({j, f, true});
    }
    return params;
  }

  // Forward differences of the stacked residuals in each parameter.
  bool jacobian(const std::vector<DisturbanceTerm>& terms, const std::vector<Parameter>& params,
                const Eigen::VectorXd& r_all, Eigen::MatrixXd& J) const {
    J.resize(r_all.size(), static_cast<Eigen::Index>(params.size()));
    std::vector<std::vector<DisturbanceTerm>> moved(params.size(), terms);
    std::vector<double> h(params.size());
    for (std::size_t p = 0; p < params.size(); ++p) {
      double& v = slot(moved[p], params[p]);
      h[p] = params[p].factor < 0 ? std::max(0.05 * std::abs(v), 1e-12)
                                  : 0.05 * terms[params[p].term].factors[params[p].factor].width;
      v += h[p];
    }
    std::vector<std::vector<Eigen::VectorXd>> rp;
    std::vector<std::string> why;
    const std::vector<char> ran = residuals_of(moved, rp, why);
    for (std::size_t p = 0; p < params.size(); ++p) {
      if (!ran[p]) return false;
      J.col(static_cast<Eigen::Index>(p)) = (stacked(rp[p]) - r_all) / h[p];
    }
    return true;
  }

  // The step, or its half or quarter, that lowers the sum of squares.
  bool step(std::vector<DisturbanceTerm>& terms, const std::vector<Parameter>& params, const Eigen::VectorXd& delta,
            double range, double& ssr, std::vector<Eigen::VectorXd>& r) const {
    for (double f : {1.0, 0.5, 0.25}) {
      auto trial = terms;
      for (std::size_t p = 0; p < params.size(); ++p) slot(trial, params[p]) += f * delta[static_cast<Eigen::Index>(p)];
      std::vector<Eigen::VectorXd> rt;
      if (bump_out_of_range(trial, range) || !residuals(trial, rt, nullptr)) continue;
      const double s = stacked(rt).squaredNorm();
      if (s >= ssr) continue;
      terms = std::move(trial), ssr = s, r = std::move(rt);
      return true;
    }
    return false;
  }

  const FormInput& in_;
  std::string balance_;
  std::atomic<long>& sims_;
};

std::string coefficient_unit(const std::string& rate, const std::string& term) {
  if (term.empty()) return rate;
  if (term == rate) return "";
  return rate + "/(" + term + ")";
}

// The terms as found: coefficient, unit, text, and the formula.
void describe(FormFinding& f, const std::vector<DisturbanceTerm>& terms, const Dictionary& dict) {
  std::ostringstream o;
  o << (f.reading ? "the reading " + f.balance : "d[" + f.balance + "]/dt") << " gains ";
  for (std::size_t j = 0; j < terms.size(); ++j) {
    const Entry e = dict.entry(terms[j].factors);
    FormTermFinding t{e.text, terms[j].coefficient, coefficient_unit(f.unit, e.unit)};
    o << (j == 0 ? (t.coefficient < 0 ? "-" : "") : (t.coefficient < 0 ? " - " : " + ")) << rounded(std::abs(t.coefficient), 3)
      << (t.unit.empty() ? "" : " " + t.unit) << (e.factors.empty() ? "" : " * " + e.text);
    f.terms.push_back(std::move(t));
  }
  o << " [" << f.unit << "]";
  f.formula = o.str();
}

std::string sentence_of(const FormFinding& f) {
  if (f.terms.empty() && f.gap_before <= 1.1)
    return "Nothing is left on " + f.balance + " for a form to explain (gap " + rounded(f.gap_before, 2) + " x noise).";
  if (f.terms.empty())
    return std::string("No function of the model's states beats the time-shaped correction on ") +
           (f.reading ? "the reading " : "") + f.balance +
           " across runs (none lowers the error on a run it was not fitted to).";
  if (!f.confirmed) return "The form found (" + f.formula + ") could not be simulated: " + f.failure + ".";
  const std::string with = f.reading ? "with it (the reading's terms do not act on the model: no simulation needed)"
                                     : "simulated with it";
  std::string s = "The missing term's form: " + f.formula + "; " + with + ", the gap is " + rounded(f.gap_after, 2) +
                  " x noise (from " + rounded(f.gap_before, 2) + "; the time-shaped correction leaves " +
                  rounded(f.gap_shape, 2) + ").";
  if (!f.beats_shape) s += " It does not beat the time-shaped correction: read it as a lead, not a finding.";
  return s;
}

}  // namespace

namespace {

// The rounds of forward selection: each linearises every candidate around
// the form so far (one simulation per candidate and run), adds the one
// that predicts the left-out runs best, and keeps it only when the model
// simulated with the refined form gains as much as the prediction had to.
class Discovery {
 public:
  Discovery(const FormInput& in, std::string balance, std::vector<Entry> terms, double amplitude, double range)
      : in_(in), balance_(std::move(balance)), terms_(std::move(terms)), partner_(partners(terms_)),
        amplitude_(amplitude), range_(range), refiner_(in, balance_, sims) {
    for (const auto& t : terms_) parameters_of_.push_back(parameter_count(t));
  }

  std::atomic<long> sims{0};
  std::vector<DisturbanceTerm> form;
  std::vector<int> chosen;  // the candidates the form's terms came from
  double ssr = 0, n = 0;
  std::string failure;

  void run(const std::vector<Eigen::VectorXd>& r0) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<Eigen::VectorXd> r = r0;
    for (const auto& v : r) ssr += v.squaredNorm(), n += static_cast<double>(v.size());
    while (static_cast<int>(chosen.size()) < kMaxTerms && ssr > 1.1 * n) {
      const std::size_t had = chosen.size();
      if (!round(r)) break;
      if (!in_.log) continue;
      std::string added;
      for (std::size_t a = had; a < chosen.size(); ++a) added += (added.empty() ? "" : ", ") + terms_[chosen[a]].text;
      in_.log("  form: + " + added + ": gap " + rounded(std::sqrt(ssr / n), 2) + " [" + std::to_string(sims) +
              " simulations, " + rounded(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2) +
              " s]");
    }
  }

 private:
  // The runs' sensitivities to each candidate added to the form. The first
  // round linearises every candidate on every run; later ones only the
  // form's terms, the constant and the terms of the additions that the
  // first round's sensitivities, with the residuals left now, rank best -
  // until kScreened are new: the form moves the model little next to what
  // tells one term from another, and it saves simulations where the
  // dictionary is longer than twice that. The others are unusable.
  Normal linearise(const std::vector<Eigen::VectorXd>& r, std::vector<char>& usable) {
    const std::size_t nr = in_.used.size(), T = terms_.size();
    usable.assign(T, 1);
    if (!first_.empty()) usable = screened(r);
    std::vector<Eigen::MatrixXd> J(nr);
    for (std::size_t q = 0; q < nr; ++q) J[q] = Eigen::MatrixXd::Zero(r[q].size(), static_cast<Eigen::Index>(T));
    std::vector<std::pair<long, long>> jobs;  // (term, run)
    for (std::size_t k = 0; k < T; ++k)
      for (std::size_t q = 0; q < nr && usable[k]; ++q) jobs.emplace_back(static_cast<long>(k), static_cast<long>(q));
    std::vector<char> failed(T, 0);
    parallel_for(static_cast<long>(jobs.size()), in_.threads, [&](int, long job) {
      const auto [k, q] = jobs[job];
      const double eps = amplitude_ / terms_[k].rms;
      auto probed = form;
      probed.push_back({eps, terms_[k].factors});
      const auto sim = in_.simulate(in_.used[q], {Disturbance{balance_, {}, {}, probed}}, nullptr);
      ++sims;
      if (sim.empty()) failed[k] = 1;
      else J[q].col(k) = (in_.residual(in_.used[q], sim) - r[q]) / eps;
    });
    for (std::size_t k = 0; k < T; ++k) usable[k] = usable[k] && !failed[k];
    Normal N = Normal::of(J, r);
    if (first_.empty() && T > 2 * kScreened) {
      for (auto& j : J) first_.push_back(j.cast<float>()), j.resize(0, 0);
      first_usable_ = usable;
    }
    return N;
  }

  std::vector<char> screened(const std::vector<Eigen::VectorXd>& r) const {
    Normal N;
    for (std::size_t q = 0; q < r.size(); ++q) N.add(first_[q].cast<double>(), r[q]);
    std::vector<char> wanted(terms_.size(), 0);
    wanted[0] = 1;
    for (int k : chosen) wanted[k] = 1;
    std::size_t fresh = 0;
    const auto cv = [&](const std::vector<int>& S) { return N.cross_validated(S); };
    for (const auto& [gain, added] : additions(chosen, first_usable_, partner_, cv)) {
      if (fresh >= kScreened) break;
      for (int k : added) fresh += wanted[k] ? 0 : 1, wanted[k] = 1;
    }
    return wanted;
  }

  // The linearisation ranks the additions; the best few are simulated
  // with their linearised coefficients, for a large gap moves the model far
  // from where it was linearised. Scored by what each leaves (each
  // parameter it brings at the price of what a term must gain), they are
  // refined best first, and the first whose refined form still gains its
  // price is kept: Gauss-Newton costs a simulation per parameter and run a
  // step, and refining every trial took most of each later round (on a
  // line of six cylinders the form took 810 simulations so, 663 now).
  bool round(std::vector<Eigen::VectorXd>& r) {
    std::vector<char> usable;
    const Normal N = linearise(r, usable);
    const double price = needed(N, ssr);
    const auto tried = best_additions(N, chosen, usable, partner_, kTried);
    std::vector<std::vector<int>> sets;  // chosen and each addition
    std::vector<std::vector<DisturbanceTerm>> trials;
    for (const auto& added : tried) {
      auto S = chosen;
      S.insert(S.end(), added.begin(), added.end());
      const Eigen::VectorXd delta = N.fit(S, -1);
      auto trial = form;
      for (std::size_t a = 0; a < S.size(); ++a) {
        if (a < chosen.size()) trial[a].coefficient += delta[a];
        else trial.push_back({delta[a], terms_[S[a]].factors});
      }
      sets.push_back(std::move(S));
      trials.push_back(std::move(trial));
    }
    std::vector<std::vector<Eigen::VectorXd>> rts;
    std::vector<std::string> whys;
    const std::vector<char> ran = refiner_.residuals_of(trials, rts, whys);
    std::vector<std::pair<double, std::size_t>> order;  // (score, trial) of those that ran
    std::vector<double> cost(trials.size(), 0), s(trials.size(), 0);
    for (std::size_t i = 0; i < trials.size(); ++i) {
      if (!ran[i]) {
        if (form.empty() && failure.empty()) failure = whys[i];
        continue;
      }
      for (int k : tried[i]) cost[i] += parameters_of_[k] * price;
      s[i] = Refiner::stacked(rts[i]).squaredNorm();
      order.emplace_back(s[i] + cost[i], i);
    }
    std::sort(order.begin(), order.end());
    for (const auto& [score, i] : order) {
      const bool unfinished = refiner_.refine(trials[i], s[i], rts[i], range_);
      if (ssr - s[i] < cost[i]) continue;
      form = std::move(trials[i]), chosen = std::move(sets[i]), ssr = s[i], r = std::move(rts[i]);
      // Refined on while its steps still pay, before the next round: a term
      // added later must not take the credit for steps its predecessors had
      // yet to make (a strong spring's coefficients, four steps from their
      // linearisation, else carry in a bump that does nothing).
      if (unfinished) refiner_.refine(form, ssr, r, range_);
      return true;
    }
    return false;
  }

  const FormInput& in_;
  std::string balance_;
  std::vector<Entry> terms_;
  std::vector<int> partner_;
  double amplitude_, range_;
  Refiner refiner_;
  std::vector<double> parameters_of_;
  std::vector<Eigen::MatrixXf> first_;  // the first round's sensitivities, per run (ranking needs no more digits)
  std::vector<char> first_usable_;
};

// The runs' normal equations for a reading's terms: a term added to the
// reading moves the residual by -term / sigma on that signal's samples (the
// term at the output times, interpolated to the run's), nothing elsewhere.
// Each column is the term over its RMS (a coefficient c' = c x RMS): a
// pressure in Pa and a sign are twelve decades apart in the normal
// equations, where the fit's tiny ridge would otherwise hold the sign's
// coefficient at zero.
Normal reading_normal(const FormInput& in, const std::string& signal, const Dictionary& dict,
                      const std::vector<Entry>& terms, const std::vector<std::vector<double>>& times) {
  Normal N;
  for (std::size_t q = 0; q < in.used.size(); ++q) {
    const MeasuredRun& run = (*in.runs)[in.used[q]];
    const std::size_t m = run.t.size();
    const auto s = static_cast<std::size_t>(std::find(run.signals.begin(), run.signals.end(), signal) - run.signals.begin());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(in.r0[q].size(), static_cast<Eigen::Index>(terms.size()));
    if (s < run.signals.size() && times[q].size() >= 2) {
      std::vector<double> v(times[q].size());
      for (std::size_t k = 0; k < terms.size(); ++k) {
        for (std::size_t j = 0; j < v.size(); ++j) v[j] = dict.value(terms[k].factors, q, j);
        for (std::size_t i = 0; i < m; ++i)
          J(static_cast<Eigen::Index>(s * m + i), static_cast<Eigen::Index>(k)) =
              -interp(times[q], v, run.t[i]) / (run.sigma[s] * terms[k].rms);
      }
    }
    N.add(J, in.r0[q]);
  }
  return N;
}

struct ReadingFit {
  std::vector<int> S;  // the chosen terms
  Eigen::VectorXd c;   // their coefficients
  double ssr = 0;
};

// Forward selection as for a balance, but exact: the residual is linear in
// the reading's terms, so every addition's fit is its confirmation.
ReadingFit select_reading_terms(const Normal& N, const std::vector<Entry>& terms) {
  const std::vector<int> partner = partners(terms);
  const std::vector<char> usable(terms.size(), 1);
  ReadingFit best;
  for (double s : N.s) best.ssr += s;
  while (static_cast<int>(best.S.size()) < kMaxTerms && best.ssr > 1.1 * N.n) {
    const double price = needed(N, best.ssr);
    std::optional<ReadingFit> next;
    double next_score = INFINITY;
    for (const auto& added : best_additions(N, best.S, usable, partner, kTried)) {
      ReadingFit trial{best.S, {}, 0};
      trial.S.insert(trial.S.end(), added.begin(), added.end());
      trial.c = N.fit(trial.S, -1);
      for (std::size_t q = 0; q < N.G.size(); ++q) trial.ssr += N.ssr(trial.S, q, trial.c);
      double parameters = 0;
      for (int k : added) parameters += parameter_count(terms[k]);
      const double score = trial.ssr + parameters * price;
      if (best.ssr - trial.ssr >= parameters * price && score < next_score) next_score = score, next = std::move(trial);
    }
    if (!next) break;
    best = std::move(*next);
  }
  return best;
}

}  // namespace

std::optional<FormFinding> discover_reading_form(const FormInput& in, const std::string& signal, double gap_shape) {
  const std::size_t nr = in.used.size();
  if (nr < 2 || !in.netlist_of) return std::nullopt;
  const Circuit circuit = elaborate(in.netlist_of(in.used[0]), *in.registry);
  const auto probe = std::find_if(circuit.probes.begin(), circuit.probes.end(), [&](const Probe& p) { return p.name == signal; });
  if (probe == circuit.probes.end() || probe->component < 0 || probe->integral) return std::nullopt;
  double largest = 0;
  std::vector<std::vector<double>> times;
  const Dictionary dict(record(in, "", signal, largest, &times));
  if (dict.vars().empty()) return std::nullopt;
  const std::vector<Entry> terms = candidate_terms(dict);
  FormFinding f;
  f.balance = signal, f.unit = probe->unit, f.reading = true, f.gap_shape = gap_shape;
  f.dictionary = static_cast<int>(terms.size());
  for (const auto& v : dict.vars()) f.read.push_back(v.name);
  if (in.log) in.log("form of the reading " + signal + ": " + std::to_string(terms.size()) + " candidate terms x " + std::to_string(nr) + " runs");
  const Normal N = reading_normal(in, signal, dict, terms, times);
  const ReadingFit fit = select_reading_terms(N, terms);
  double s0 = 0;
  for (double s : N.s) s0 += s;
  f.gap_before = std::sqrt(s0 / N.n);
  if (!fit.S.empty()) {
    f.confirmed = true;
    f.gap_after = std::sqrt(fit.ssr / N.n);
    f.beats_shape = f.gap_after <= 1.05 * gap_shape || f.gap_after <= 1.5;
    std::vector<DisturbanceTerm> form;
    for (std::size_t a = 0; a < fit.S.size(); ++a)
      form.push_back({fit.c[static_cast<Eigen::Index>(a)] / terms[fit.S[a]].rms, terms[fit.S[a]].factors});
    describe(f, form, dict);
  }
  f.simulations = static_cast<long>(nr);
  f.sentence = sentence_of(f);
  if (in.log) in.log("form: " + f.sentence + " [" + std::to_string(f.simulations) + " simulations]");
  return f;
}

std::optional<FormFinding> discover_form(const FormInput& in, const std::string& balance, const std::string& rate_unit,
                                         double gap_shape) {
  const std::size_t nr = in.used.size();
  if (nr < 2) return std::nullopt;
  double largest = 0;
  const Dictionary dict(record(in, balance, "", largest));
  if (dict.vars().empty()) return std::nullopt;
  std::vector<Entry> terms = candidate_terms(dict);
  FormFinding f;
  f.balance = balance, f.unit = rate_unit, f.gap_shape = gap_shape, f.dictionary = static_cast<int>(terms.size());
  for (const auto& v : dict.vars()) f.read.push_back(v.name);
  // Each term's probe moves the balance's state by about a percent of its
  // largest magnitude along the runs over a ninth of the run (the System's
  // nominal magnitude is a scale for the solver, a decade or more off).
  const auto& t = (*in.runs)[in.used[0]].t;
  const double amplitude = 0.01 * largest / std::max((t.back() - t.front()) / 9, 1e-12);
  if (!(amplitude > 0)) return std::nullopt;
  double range = 0;
  for (const auto& v : dict.vars())
    if (is_position(v.unit)) range = std::max(range, v.hi - v.lo);
  if (in.log) in.log("form of " + balance + ": " + std::to_string(terms.size()) + " candidate terms x " + std::to_string(nr) + " runs a round");
  Discovery d(in, balance, std::move(terms), amplitude, range);
  d.run(in.r0);
  f.gap_before = 0;
  for (const auto& r : in.r0) f.gap_before += r.squaredNorm();
  f.gap_before = std::sqrt(f.gap_before / d.n);
  f.failure = d.failure;
  if (!d.form.empty()) {
    f.confirmed = true;
    f.gap_after = std::sqrt(d.ssr / d.n);
    f.beats_shape = f.gap_after <= 1.05 * gap_shape || f.gap_after <= 1.5;
    describe(f, d.form, dict);
  }
  f.simulations = d.sims + static_cast<long>(nr);
  f.sentence = sentence_of(f);
  if (in.log) in.log("form: " + f.sentence + " [" + std::to_string(f.simulations) + " simulations]");
  return f;
}

std::string form_json(const FormFinding& f, const std::function<std::string(double)>& num,
                      const std::function<std::string(const std::string&)>& str) {
  std::ostringstream o;
  o << "{\"balance\": " << str(f.balance) << ", \"reading\": " << (f.reading ? "true" : "false")
    << ", \"unit\": " << str(f.unit) << ", \"formula\": " << str(f.formula)
    << ", \"terms\": [";
  for (std::size_t j = 0; j < f.terms.size(); ++j)
    o << (j ? ", " : "") << "{\"term\": " << str(f.terms[j].text) << ", \"coefficient\": " << num(f.terms[j].coefficient)
      << ", \"unit\": " << str(f.terms[j].unit) << "}";
  o << "], \"gap_before\": " << num(f.gap_before) << ", \"gap_after\": " << num(f.gap_after)
    << ", \"gap_time_shaped\": " << num(f.gap_shape) << ", \"confirmed\": " << (f.confirmed ? "true" : "false")
    << ", \"beats_time_shaped\": " << (f.beats_shape ? "true" : "false")
    << ", \"failure\": " << (f.failure.empty() ? std::string("null") : str(f.failure))
    << ", \"dictionary\": " << f.dictionary << ", \"read\": [";
  for (std::size_t j = 0; j < f.read.size(); ++j) o << (j ? ", " : "") << str(f.read[j]);
  o << "], \"simulations\": " << f.simulations
    << ", \"sentence\": " << str(f.sentence) << "}";
  return o.str();
}

std::string form_html(const FormFinding& f, const std::function<std::string(const std::string&)>& html) {
  std::ostringstream o;
  o << "<h3>The missing term's form</h3>\n<p id=\"form\">" << html(f.sentence) << "</p>\n";
  if (f.terms.empty()) return o.str();
  o << "<table id=\"form-terms\"><tr><th>term</th><th>coefficient</th><th>unit</th></tr>\n";
  for (const auto& t : f.terms)
    o << "<tr><td class=\"l\">" << html(t.text) << "</td><td>" << rounded(t.coefficient, 3) << "</td><td class=\"l\">"
      << html(t.unit) << "</td></tr>\n";
  o << "</table>\n<p>Chosen from " << f.dictionary << " candidate terms by leave-one-run-out prediction error; "
    << f.simulations << " simulations.</p>\n";
  return o.str();
}

}  // namespace pneumo::diagnose
