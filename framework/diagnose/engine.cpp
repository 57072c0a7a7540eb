#include "framework/diagnose/engine.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "framework/analysis/run_metrics.hpp"
#include "framework/core/parallel.hpp"
#include "framework/diagnose/departure.hpp"
#include "framework/diagnose/statistics.hpp"
#include "framework/fit/bounded_lm.hpp"
#include "framework/run/parts.hpp"
#include "framework/run/run.hpp"

namespace pneumo::diagnose::engine {

namespace {

// The fitted effects' parameters, each mapped onto u in [0, 1] between its
// bounds (logarithmically for a log-scale parameter) so that one step size
// and one damping suit them all.
class ScaledParameters {
 public:
  explicit ScaledParameters(std::vector<EffectInstance> start) : start_(std::move(start)) {
    for (int e = 0; e < static_cast<int>(start_.size()); ++e)
      for (int i = 0; i < static_cast<int>(start_[e].effect->parameters.size()); ++i)
        ps_.push_back({bound_of(start_[e].effect->parameters[i]), e, i});
  }
  int size() const { return static_cast<int>(ps_.size()); }

  Eigen::VectorXd start_point() const {
    Eigen::VectorXd u(size());
    for (int k = 0; k < size(); ++k) u[k] = ps_[k].bound.to_u(start_[ps_[k].effect].values[ps_[k].index]);
    return u;
  }
  std::vector<EffectInstance> instances(const Eigen::VectorXd& u) const {
    auto inst = start_;
    for (int k = 0; k < size(); ++k) inst[ps_[k].effect].values[ps_[k].index] = ps_[k].bound.from_u(u[k]);
    return inst;
  }
  // Indices of the last effect's parameters (the one a grid start explores).
  std::vector<int> last_effect() const {
    std::vector<int> last;
    for (int k = 0; k < size(); ++k)
      if (ps_[k].effect == static_cast<int>(start_.size()) - 1) last.push_back(k);
    return last;
  }

 private:
  struct P {
    fit::ScaledBound bound;
    int effect, index;
  };
  static fit::ScaledBound bound_of(const EffectParameter& s) { return {s.lower, s.upper, s.log_scale}; }
  std::vector<EffectInstance> start_;
  std::vector<P> ps_;
};

// A coarse grid of starting points (in scaled coordinates) over the last
// effect's one or two parameters, the others at `u0`: against local minima.
std::vector<Eigen::VectorXd> grid_starts(const ScaledParameters& sp, const Eigen::VectorXd& u0) {
  const std::vector<int> last = sp.last_effect();
  if (last.size() != 1 && last.size() != 2) return {};
  const std::vector<double> levels = last.size() == 1 ? std::vector<double>{0.05, 0.25, 0.5, 0.75, 0.95}
                                                      : std::vector<double>{0.15, 0.5, 0.85};
  std::vector<Eigen::VectorXd> points;
  for (double a : levels) {
    Eigen::VectorXd p = u0;
    p[last[0]] = a;
    if (last.size() == 1) {
      points.push_back(p);
    } else {
      for (double b : levels) {
        p[last[1]] = b;
        points.push_back(p);
      }
    }
  }
  return points;
}

// The residuals on layout `L` of the models at scaled points, evaluated together.
fit::BatchResiduals batch(Engine& eng, const ScaledParameters& sp, const Layout& L) {
  return [&eng, &sp, &L](const std::vector<Eigen::VectorXd>& points) {
    std::vector<Model> models;
    for (const auto& p : points) models.push_back(eng.model(sp.instances(p)));
    return eng.residuals(models, L);
  };
}

// The reading gain * y + offset of a signal whose measurement model has them.
void read_through(const MeasurementModel& mm, const std::string& signal, std::vector<double>& ys) {
  const auto g = mm.gain.find(signal), o = mm.offset.find(signal);
  const double gain = g == mm.gain.end() ? 1.0 : g->second, offset = o == mm.offset.end() ? 0.0 : o->second;
  if (gain == 1.0 && offset == 0.0) return;
  for (double& y : ys) y = gain * y + offset;
}

// The instances in order, each effect's values bit for bit, those at a null
// that leaves the model as it is left out - unless another instance sets
// what it sets, when the order of the two decides and no name is given.
std::optional<std::string> memo_key(const std::vector<EffectInstance>& effects,
                                    const std::set<const Effect*>& vanishing) {
  std::string key;
  for (const auto& inst : effects) {
    const bool left_out = vanishing.count(inst.effect) && inst.values == inst.effect->null_values();
    if (left_out) {
      for (const auto& other : effects)
        if (other.effect != inst.effect && effects_conflict(*inst.effect, *other.effect)) return std::nullopt;
      continue;
    }
    key += inst.effect->name;
    for (double v : inst.values) {
      char buf[32];
      std::snprintf(buf, sizeof buf, " %a", v);
      key += buf;
    }
    key += ';';
  }
  return key;
}

std::vector<double> lag_filter(const std::vector<double>& ts, const std::vector<double>& u, double tau) {
  std::vector<double> y(u.size());
  y[0] = u[0];
  for (std::size_t i = 1; i < u.size(); ++i) {
    const double h = ts[i] - ts[i - 1], a = std::exp(-h / tau);
    const double slope = h > 0 ? (u[i] - u[i - 1]) / h : 0.0;
    // y' = (u - y)/tau with u linear over the step: exact solution.
    y[i] = a * y[i - 1] + (1 - a) * u[i - 1] + slope * (h - tau * (1 - a));
  }
  return y;
}

}  // namespace

Engine::Engine(const std::string& model_file, const Registry& base, const DiagnoseOptions& options)
    : loaded_(load_model(model_file, base, options.sets)), options_(options) {
  anchor_.memo_key = "";
  base_probes_ = elaborate(loaded_.netlist, loaded_.registry).probes;  // input errors now
}

Model Engine::model(const std::vector<EffectInstance>& effects) const {
  Model m;
  m.netlist = apply_effects(loaded_.netlist, effects, &m.measurement, &m.run_factors);
  m.memo_key = memo_key(effects, vanishing_);
  return m;
}

void Engine::learn_nulls(const std::vector<Effect>& effects) {
  for (const auto& e : effects)
    if (e.unavailable.empty() && vanishes_at_null(e, loaded_.netlist, loaded_.registry)) vanishing_.insert(&e);
}

Netlist Engine::netlist_of(const Model& m, int k, const Setting& at) const {
  const MeasuredRun& run = runs[k];
  Netlist nl = m.netlist;
  for (const auto& op : run.operating_point) op.apply(nl);
  for (const auto& [name, value] : at) set_si_value(nl, ParameterPath::parse(name), value);
  apply_run_factors(nl, m.run_factors);
  nl.simulation.t_end = run.t.back() + 1e-9;
  const double dt = (run.t.back() - run.t.front()) / std::max<std::size_t>(1, run.t.size() - 1);
  nl.simulation.output_interval = std::min(nl.simulation.output_interval, dt);
  return nl;
}

std::vector<std::vector<double>> Engine::simulate(const Model& m, int k, const std::vector<Disturbance>& disturbances,
                                                  const Setting& at, std::string* why) {
  const bool remembered = m.memo_key && disturbances.empty() && at.empty();
  const std::string key = remembered ? *m.memo_key + "@" + std::to_string(k) : "";
  if (remembered)
    if (auto signals = memo_.find(key)) return std::move(*signals);
  std::optional<RunResult> res = remembered ? run_resumed(m, k, why) : std::nullopt;
  if (!res) res = run(m, k, disturbances, at, {}, why);
  if (!res) return {};
  auto out = signals_of(m, k, *res, why);
  if (remembered && !out.empty()) memo_.keep(key, out);
  return out;
}

std::optional<RunResult> Engine::run(const Model& m, int k, const std::vector<Disturbance>& disturbances,
                                     const Setting& at, const Resumption& resumption, std::string* why,
                                     long max_total_steps) {
  ++simulations;
  try {
    const Netlist nl = netlist_of(m, k, at);
    SolverOptions so = solver_options(nl.simulation);
    so.disturbances = disturbances;
    // A disturbance that drives a state out of its domain (a chamber's
    // mass below zero) leaves the solver crawling: such a run fails.
    if (!disturbances.empty()) so.max_steps = kDisturbedMaxSteps;
    so.max_total_steps = max_total_steps;
    if (!disturbances.empty() && at.empty())
      if (auto system = assembled(m, k, nl, so)) return run_assembled(*system, so, resumption);
    return run_circuit(elaborate(nl, loaded_.registry), so, resumption);
  } catch (const std::exception& ex) {
    note_failure(runs[k].name, ex.what());
    if (why) *why = ex.what();
    return std::nullopt;
  }
}

std::vector<double> Engine::stops(int k) const {
  const auto& t = runs[k].t;
  const std::size_t stride = std::max<std::size_t>(1, t.size() / kKeptCheckpoints);
  std::vector<double> times;
  for (std::size_t i = 0; i < t.size(); i += stride) times.push_back(t[i]);
  return times;
}

void Engine::anchor(const std::vector<EffectInstance>& effects) {
  std::lock_guard lock(kept_mutex_);
  anchor_ = model(effects);
  if (!anchor_.memo_key) anchor_.memo_key = "";  // a model the memo cannot name anchors nothing
  anchor_kept_.clear();
}

Engine::Kept Engine::kept_for(const Model& m, int k) {
  std::lock_guard lock(kept_mutex_);
  auto kept = [&](std::map<int, Kept>& cache, const Model& which, const Kept& from) {
    if (auto it = cache.find(k); it != cache.end()) return it->second;
    return cache.emplace(k, keep_resumed(which, k, from)).first->second;
  };
  const Kept unpatched = kept(unpatched_kept_, model({}), Kept{});
  const std::string& a = *anchor_.memo_key;
  if (!a.empty() && m.memo_key->compare(0, a.size(), a) == 0) return kept(anchor_kept_, anchor_, unpatched);
  return unpatched;
}

Engine::Departure Engine::departure(const Model& m, int k, const Kept& from) {
  Departure d;
  const Netlist nl = netlist_of(m, k);
  d.options = solver_options(nl.simulation);
  d.system = assembled(m, k, nl, d.options);
  if (d.system && from.run && from.system)
    d.checkpoint = last_checkpoint_before_departure(*from.system, *d.system, *from.run, d.options);
  return d;
}

Engine::Kept Engine::keep_resumed(const Model& m, int k, const Kept& from) {
  try {
    const Departure d = departure(m, k, from);
    if (!d.system || (from.run && !from.system)) return {};
    const long j = d.checkpoint;
    Resumption keep{stops(k), j >= 1 ? &from.run->checkpoints[j] : nullptr, j >= 1 ? &from.run->table : nullptr};
    keep.in_passing = true;
    ++simulations;
    RunResult res = run_assembled(*d.system, d.options, keep);
    if (!res.solver.ok) return {};
    // Up to where it departs, its run is the one it resumed from: so are
    // the checkpoints there.
    if (j >= 1)
      res.checkpoints.insert(res.checkpoints.begin(), from.run->checkpoints.begin(), from.run->checkpoints.begin() + j + 1);
    return {d.system, std::make_shared<const RunResult>(std::move(res)), *m.memo_key};
  } catch (const std::exception&) {
    return {};  // its own run reports what failed
  }
}

std::optional<RunResult> Engine::run_resumed(const Model& m, int k, std::string* why) {
  const Kept kept = kept_for(m, k);
  if (!kept.run) return std::nullopt;
  if (*m.memo_key == kept.key) return *kept.run;
  Departure d;
  try {
    d = departure(m, k, kept);
  } catch (const std::exception&) {
    return std::nullopt;  // the whole run reports it
  }
  if (!d.system || d.checkpoint < 1) return std::nullopt;
  ++simulations;
  try {
    RunResult res = run_assembled(*d.system, d.options, {{}, &kept.run->checkpoints[d.checkpoint], &kept.run->table});
    // A restart the solver fails on is no verdict on the model: the whole run is.
    if (res.solver.ok) return res;
  } catch (const std::exception& ex) {
    if (why) *why = ex.what();
  }
  return std::nullopt;
}

std::shared_ptr<const System> Engine::assembled(const Model& m, int k, const Netlist& nl, const SolverOptions& so) {
  if (!m.memo_key) return nullptr;
  const std::string key = *m.memo_key + "@" + std::to_string(k);
  {
    std::lock_guard lock(assembled_mutex_);
    if (auto it = assembled_.find(key); it != assembled_.end()) return it->second;
  }
  Circuit circuit = elaborate(nl, loaded_.registry);
  std::shared_ptr<const System> system;
  if (independent_parts(circuit).size() <= 1)
    system = std::make_shared<const System>(std::move(circuit), assembly_options(so));
  std::lock_guard lock(assembled_mutex_);
  // The models one stage runs many times are few; a later stage's replace them.
  if (assembled_.size() >= kAssembledModels) assembled_.clear();
  return assembled_.emplace(key, std::move(system)).first->second;
}

std::vector<std::vector<double>> Engine::signals_of(const Model& m, int k, const RunResult& res, std::string* why) {
  const MeasuredRun& run = runs[k];
  if (!res.solver.ok || res.table.rows.size() < 2) {
    const std::string reason = res.solver.ok ? "fewer than two output rows" : res.solver.message;
    note_failure(run.name, reason);
    if (why) *why = reason;
    return {};
  }
  std::vector<double> ts;
  for (const auto& row : res.table.rows) ts.push_back(row[0]);
  std::vector<std::vector<double>> out;
  for (const auto& s : run.signals) {
    const int c = res.table.column(s);
    std::vector<double> ys;
    for (const auto& row : res.table.rows) ys.push_back(row[c]);
    if (auto it = m.measurement.lag.find(s); it != m.measurement.lag.end() && it->second > 0) {
      ys = lag_filter(ts, ys, it->second);
    }
    read_through(m.measurement, s, ys);
    std::vector<double> at_t;
    at_t.reserve(run.t.size());
    for (double t : run.t) at_t.push_back(interp(ts, ys, t));
    out.push_back(std::move(at_t));
  }
  return out;
}

std::shared_ptr<const RunResult> Engine::keep(const Model& m, int k, const std::vector<double>& times, std::string* why) {
  auto res = run(m, k, {}, {}, {times, nullptr}, why);
  return res ? std::make_shared<const RunResult>(std::move(*res)) : nullptr;
}

std::vector<std::vector<double>> Engine::simulate_from(const Model& m, int k, const RunResult& kept, std::size_t j,
                                                       const std::vector<Disturbance>& disturbances, std::string* why) {
  if (j >= kept.checkpoints.size()) return simulate(m, k, disturbances, {}, why);
  const RunCheckpoint& from = kept.checkpoints[j];
  const long budget = disturbances.empty() ? 0 : kDisturbedStepsPerKept * std::max(kept.solver.stats.steps, 1L);
  const auto res = run(m, k, disturbances, {}, {{}, &from, &kept.table}, why, budget);
  return res ? signals_of(m, k, *res, why) : std::vector<std::vector<double>>{};
}

Layout Engine::layout(Role role) const {
  Layout L;
  for (int k = 0; k < static_cast<int>(runs.size()); ++k) {
    if (runs[k].role != role) continue;
    L.runs.push_back(k);
    for (int s = 0; s < static_cast<int>(runs[k].signals.size()); ++s) {
      L.segments.push_back({k, s, L.size, runs[k].t.size()});
      L.size += runs[k].t.size();
    }
  }
  return L;
}

std::vector<std::vector<double>> Engine::residuals(const std::vector<Model>& models, const Layout& L) {
  const int nr = static_cast<int>(L.runs.size());
  std::vector<std::vector<std::vector<double>>> out_sim(models.size() * nr);
  parallel_for(static_cast<long>(models.size()) * nr, options_.threads,
               [&](int, long j) { out_sim[j] = simulate(models[j / nr], L.runs[j % nr]); });
  std::vector<std::vector<double>> r(models.size(), std::vector<double>(L.size));
  for (std::size_t m = 0; m < models.size(); ++m)
    for (const auto& seg : L.segments) {
      const int j = static_cast<int>(m) * nr +
                    static_cast<int>(std::find(L.runs.begin(), L.runs.end(), seg.run) - L.runs.begin());
      const auto& run = runs[seg.run];
      for (std::size_t i = 0; i < seg.n; ++i)
        r[m][seg.offset + i] = out_sim[j].empty()
                                   ? kFailedResidual
                                   : (run.y[seg.signal][i] - out_sim[j][seg.signal][i]) / run.sigma[seg.signal];
    }
  return r;
}

GapTable Engine::gaps(const std::vector<double>& r, const Layout& L) const {
  GapTable g;
  std::map<std::string, int> idx;
  for (const auto& seg : L.segments) {
    const auto& name = runs[seg.run].signals[seg.signal];
    if (!idx.count(name)) {
      idx[name] = static_cast<int>(g.signals.size());
      g.signals.push_back(name);
    }
  }
  g.by_signal.assign(g.signals.size(), {});
  g.by_phase.assign(g.signals.size(), std::vector<Gap>(phase_names.size()));
  g.phase_total.assign(phase_names.size(), {});
  for (const auto& seg : L.segments) {
    const int s = idx[runs[seg.run].signals[seg.signal]];
    for (std::size_t i = 0; i < seg.n; ++i) {
      const double q = r[seg.offset + i] * r[seg.offset + i];
      const int ph = phases[seg.run][i];
      for (Gap* gp : {&g.total, &g.by_signal[s], &g.by_phase[s][ph], &g.phase_total[ph]}) {
        gp->ssr += q;
        gp->n += 1;
      }
    }
  }
  auto fin = [](Gap& x) { x.rms = x.n ? std::sqrt(x.ssr / x.n) : 0.0; };
  fin(g.total);
  for (auto& x : g.by_signal) fin(x);
  for (auto& a : g.by_phase)
    for (auto& x : a) fin(x);
  for (auto& x : g.phase_total) fin(x);
  return g;
}

// Under "model 0 is as good" the whitened residuals are near white, so a
// change that is smooth like the residual it leaves - the kind an AR(1)
// effective sample size over-credits - counts only as much as it stands out
// of that residual's own predictable course.
Engine::Significance Engine::significance(const std::vector<double>& r0, const std::vector<double>& r1,
                                          const Layout& L, int added_parameters) const {
  Significance s;
  for (const auto& seg : L.segments) {
    double m = 0;
    s.lr += whitened_log_ratio(&r0[seg.offset], &r1[seg.offset], seg.n, &m);
    s.n_eff += m;
  }
  s.delta_bic = s.lr - added_parameters * std::log(std::max(2.0, s.n_eff));
  // A switch without free parameters (k = 0) has no chi-square reference.
  s.p = s.lr <= 0 ? 1.0 : added_parameters > 0 ? gamma_q(0.5 * added_parameters, 0.5 * s.lr) : NAN;
  return s;
}

double Engine::preference(const std::vector<double>& r0, const std::vector<double>& r1, const Layout& L) const {
  VuongSums d;
  for (const auto& seg : L.segments) add_vuong_terms(&r0[seg.offset], &r1[seg.offset], seg.n, d);
  return vuong_z(d);
}

Engine::Fit Engine::fit(std::vector<EffectInstance> start, const Layout& cal, const std::vector<double>& r_start_hint,
                        int max_iterations, bool grid_start) {
  const ScaledParameters sp(std::move(start));
  const fit::BatchResiduals at = batch(*this, sp, cal);
  const Eigen::VectorXd u0 = sp.start_point();
  fit::BoundedLmOptions lm_options;
  lm_options.max_iterations = max_iterations;
  const auto lm =
      fit::bounded_lm(at, u0, r_start_hint, grid_start ? grid_starts(sp, u0) : std::vector<Eigen::VectorXd>{}, lm_options);
  Fit f;
  f.effects = sp.instances(lm.u);
  f.r_cal = lm.r;
  f.evaluations = lm.evaluations;
  return f;
}

Engine::Linearisation Engine::linearise(const std::vector<EffectInstance>& at, const Layout& L, int first) {
  const ScaledParameters sp(at);
  const fit::BatchResiduals res = batch(*this, sp, L);
  const Eigen::VectorXd u = sp.start_point();
  Linearisation lin;
  lin.r = res({u})[0];
  std::vector<long> columns;
  for (long k = first; k < sp.size(); ++k) columns.push_back(k);
  lin.J = fit::forward_differences(res, u, lin.r, columns);
  return lin;
}

void Engine::compute_phases(const std::vector<PhaseDecl>& declared) {
  declared_phases_ = declared;
  phase_starts_.clear();
  std::vector<std::vector<double>> times;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    times.push_back(runs[k].t);
    phase_starts_.push_back(phase_starts(static_cast<int>(k), {}));
  }
  Phases ph = assign_phases(declared, times, phase_starts_);
  phase_names = std::move(ph.names);
  phases = std::move(ph.of_sample);
  phase_times = std::move(ph.times);
}

std::vector<int> Engine::phases_at(int k, const Setting& at) {
  std::vector<std::vector<double>> times;
  for (const auto& r : runs) times.push_back(r.t);
  times.push_back(runs[k].t);
  auto starts = phase_starts_;
  starts.push_back(phase_starts(k, at));
  Phases ph = assign_phases(declared_phases_, times, starts);
  if (ph.names != phase_names) return std::vector<int>(runs[k].t.size(), -1);  // renamed: no phase to show
  return ph.of_sample.back();
}

std::size_t Engine::failure_count() const {
  const std::lock_guard<std::mutex> lock(failures_mutex_);
  return failures_.size();
}

std::vector<std::string> Engine::failures_since(std::size_t mark) const {
  const std::lock_guard<std::mutex> lock(failures_mutex_);
  return {failures_.begin() + static_cast<long>(std::min(mark, failures_.size())), failures_.end()};
}

// What the unpatched model's run at run `k`'s span and operating point
// (with `at` on top) tells the phases: its events' first times and its
// metrics' values; empty when it fails (a failed run gets one phase).
PhaseStarts Engine::phase_starts(int k, const Setting& at) {
  Netlist nl = netlist_of(model({}), k, at);
  const std::vector<bool> all(nl.metrics.size(), true);
  add_metric_outputs(nl, all);
  PhaseStarts starts;
  RunResult res;
  try {
    res = run_simulation(nl, loaded_.registry);
  } catch (const std::exception& ex) {
    note_failure(runs[k].name, ex.what());  // input errors surfaced when the model was loaded
    return starts;
  }
  ++simulations;
  for (const auto& e : res.solver.events)
    if (!e.tag.empty()) starts.emplace(e.component + "." + e.tag, e.t);
  if (!declared_phases_.empty() && res.solver.ok) {
    const auto values = evaluate_metrics(nl, all, res, {});
    for (std::size_t i = 0; i < nl.metrics.size(); ++i) starts[nl.metrics[i].name] = values[i];
  }
  return starts;
}

void Engine::note_failure(const std::string& run, const std::string& why) {
  const std::lock_guard<std::mutex> lock(failures_mutex_);
  failures_.push_back("run " + run + ": " + why);
}

}  // namespace pneumo::diagnose::engine
