#include "framework/diagnose/diagnose.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <numeric>
#include <optional>

#include "framework/analysis/run_metrics.hpp"
#include "framework/core/parallel.hpp"
#include "framework/diagnose/phases.hpp"
#include "framework/diagnose/ranking.hpp"
#include "framework/diagnose/statistics.hpp"
#include "framework/diagnose/unexplained.hpp"
#include "framework/run/run.hpp"

namespace pneumo::diagnose {


namespace {

constexpr long kDisturbedMaxSteps = 20000;  // a disturbed run's step budget (the cushion rig's nominal run takes 1225)
constexpr double kFailedResidual = 1e4;  // per sample, for a run the solver could not finish

// One measured signal of one run inside a concatenated residual vector.
struct Segment {
  int run = 0, signal = 0;  // signal: index into the run's signals
  std::size_t offset = 0, n = 0;
};

struct Layout {
  std::vector<int> runs;  // indices into all runs
  std::vector<Segment> segments;
  std::size_t size = 0;
};

struct Model {  // a patched model ready to run
  std::string text;
  MeasurementModel measurement;
};

class Engine {
 public:
  Engine(const std::string& model_file, const Registry& registry, const DiagnoseOptions& options)
      : model_file_(model_file), registry_(registry), options_(options) {
    std::ifstream in(model_file);
    if (!in) throw InputError(SourceLocation{model_file, 0, 0}, "", "", "cannot open the model file");
    std::stringstream ss;
    ss << in.rdbuf();
    model_text_ = ss.str();
    base_netlist_ = parse_netlist(model_text_, model_file);
    (void)elaborate(base_netlist_, registry);  // input errors now
    model_yaml_ = YAML::Load(model_text_);
  }

  const Netlist& base() const { return base_netlist_; }
  const YAML::Node& yaml() const { return model_yaml_; }
  std::vector<MeasuredRun> runs;
  std::vector<std::string> phase_names;
  std::vector<std::vector<int>> phases;            // per run, per sample
  std::vector<std::vector<double>> phase_times;    // per run: each phase's start, then the run's end
  std::atomic<long> simulations{0};

  Model model(const std::vector<EffectInstance>& effects) const {
    Model m;
    m.text = effects.empty() ? model_text_ : YAML::Dump(apply_effects(model_yaml_, effects, &m.measurement));
    return m;
  }

  // The model at run `k`'s operating point over its measured span.
  Netlist netlist_of(const Model& m, int k) const {
    const MeasuredRun& run = runs[k];
    Netlist nl = parse_netlist(m.text, model_file_);
    for (const auto& [name, value] : run.operating_point) apply_override(nl, name + "=" + value);
    nl.simulation.t_end = run.t.back() + 1e-9;
    const double dt = (run.t.back() - run.t.front()) / std::max<std::size_t>(1, run.t.size() - 1);
    nl.simulation.output_interval = std::min(nl.simulation.output_interval, dt);
    return nl;
  }

  // Simulated signals of run `k` at its measurement times; empty if the run failed.
  std::vector<std::vector<double>> simulate(const Model& m, int k, const std::vector<Disturbance>& disturbances = {}) {
    ++simulations;
    const MeasuredRun& run = runs[k];
    RunResult res;
    try {
      const Netlist nl = netlist_of(m, k);
      SolverOptions so = solver_options(nl.simulation);
      so.disturbances = disturbances;
      // A disturbance that drives a state out of its domain (a chamber's
      // mass below zero) leaves the solver crawling: such a run fails.
      if (!disturbances.empty()) so.max_steps = kDisturbedMaxSteps;
      res = run_circuit(elaborate(nl, registry_), so);
    } catch (const std::exception&) {
      return {};
    }
    if (!res.solver.ok || res.table.rows.size() < 2) return {};
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
      std::vector<double> at;
      at.reserve(run.t.size());
      for (double t : run.t) at.push_back(interp(ts, ys, t));
      out.push_back(std::move(at));
    }
    return out;
  }

  static std::vector<double> lag_filter(const std::vector<double>& ts, const std::vector<double>& u, double tau) {
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

  Layout layout(Role role) const {
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

  // Normalised residuals (measured - simulated)/sigma for several models at once.
  std::vector<std::vector<double>> residuals(const std::vector<Model>& models, const Layout& L) {
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
          r[m][seg.offset + i] = out_sim[j].empty() ? kFailedResidual
                                                    : (run.y[seg.signal][i] - out_sim[j][seg.signal][i]) /
                                                          run.sigma[seg.signal];
      }
    return r;
  }

  GapTable gaps(const std::vector<double>& r, const Layout& L) const {
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

  struct Significance {
    double lr = 0, n_eff = 0, delta_bic = 0, p = 1;
  };
  // Likelihood ratio of model 1 over model 0 after whitening both residual
  // series with the AR(p) model of model 1's (each signal of each run its
  // own series): under "model 0 is as good" the whitened residuals are near
  // white, so a change that is smooth like the residual it leaves - the
  // kind an AR(1) effective sample size over-credits - counts only as much
  // as it stands out of that residual's own predictable course.
  Significance significance(const std::vector<double>& r0, const std::vector<double>& r1, const Layout& L,
                            int added_parameters) const {
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

  struct Fit {
    std::vector<EffectInstance> effects;
    std::vector<double> r_cal;
    double screening = 0;  // linearised share of SSR removed at the start
    int evaluations = 0;
  };

  // Bounded Levenberg-Marquardt in scaled coordinates u in [0, 1]; with
  // `grid_start`, a coarse grid over the last effect's parameters (the
  // others held at their start values) picks the starting point.
  Fit fit(std::vector<EffectInstance> start, const Layout& cal, const std::vector<double>& r_start_hint,
          int max_iterations, bool grid_start = false) {
    struct P {
      const EffectParameter* spec;
      int effect, index;
    };
    std::vector<P> ps;
    for (int e = 0; e < static_cast<int>(start.size()); ++e)
      for (int i = 0; i < static_cast<int>(start[e].effect->parameters.size()); ++i)
        ps.push_back({&start[e].effect->parameters[i], e, i});
    const int np = static_cast<int>(ps.size());
    auto to_u = [&](const P& p, double v) {
      const auto& s = *p.spec;
      return s.log_scale ? std::log(v / s.lower) / std::log(s.upper / s.lower) : (v - s.lower) / (s.upper - s.lower);
    };
    auto from_u = [&](const P& p, double u) {
      const auto& s = *p.spec;
      u = std::clamp(u, 0.0, 1.0);
      return s.log_scale ? s.lower * std::pow(s.upper / s.lower, u) : s.lower + u * (s.upper - s.lower);
    };
    auto instances = [&](const Eigen::VectorXd& u) {
      auto inst = start;
      for (int k = 0; k < np; ++k) inst[ps[k].effect].values[ps[k].index] = from_u(ps[k], u[k]);
      return inst;
    };
    Eigen::VectorXd u(np);
    for (int k = 0; k < np; ++k) u[k] = to_u(ps[k], start[ps[k].effect].values[ps[k].index]);
    Fit f;
    std::vector<double> r = r_start_hint.empty() ? residuals({model(instances(u))}, cal)[0] : r_start_hint;
    f.evaluations += 1;
    std::vector<int> last;  // the last effect's parameters
    for (int k = 0; k < np; ++k)
      if (ps[k].effect == static_cast<int>(start.size()) - 1) last.push_back(k);
    if (grid_start && (last.size() == 1 || last.size() == 2)) {
      // A coarse grid of starting points (in scaled coordinates) against
      // local minima: the best point, or the initial values, starts LM.
      const std::vector<double> levels = last.size() == 1 ? std::vector<double>{0.05, 0.25, 0.5, 0.75, 0.95}
                                                          : std::vector<double>{0.15, 0.5, 0.85};
      std::vector<Eigen::VectorXd> points;
      for (double a : levels) {
        Eigen::VectorXd p = u;
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
      std::vector<Model> models;
      for (const auto& p : points) models.push_back(model(instances(p)));
      const auto rs = residuals(models, cal);
      f.evaluations += static_cast<int>(points.size());
      double best = ssr_of(r.data(), r.size());
      for (std::size_t k = 0; k < points.size(); ++k)
        if (const double c = ssr_of(rs[k].data(), rs[k].size()); c < best) {
          best = c;
          u = points[k];
          r = rs[k];
        }
    }
    double cost = ssr_of(r.data(), r.size());
    const double cost0 = cost;
    double lambda = 1e-2;
    const double h = 3e-3;
    for (int it = 0; it < max_iterations && np > 0; ++it) {
      std::vector<Model> probes;
      std::vector<double> steps(np);
      for (int k = 0; k < np; ++k) {
        Eigen::VectorXd up = u;
        steps[k] = u[k] + h <= 1.0 ? h : -h;
        up[k] += steps[k];
        probes.push_back(model(instances(up)));
      }
      const auto rp = residuals(probes, cal);
      f.evaluations += np;
      Eigen::MatrixXd J(r.size(), np);
      for (int k = 0; k < np; ++k)
        for (std::size_t i = 0; i < r.size(); ++i) J(i, k) = (rp[k][i] - r[i]) / steps[k];
      const Eigen::Map<const Eigen::VectorXd> rv(r.data(), r.size());
      const Eigen::MatrixXd A = J.transpose() * J;
      const Eigen::VectorXd g = J.transpose() * rv;
      if (it == 0) {  // screening: SSR removed by the unconstrained Gauss-Newton step
        const Eigen::VectorXd d = A.ldlt().solve(-g);
        f.screening = std::clamp(-(g.dot(d)) / std::max(cost0, 1e-300), 0.0, 1.0);
        if (f.screening < screen_cutoff_) break;  // the caller decides; no full fit
      }
      bool accepted = false;
      for (int tries = 0; tries < 6 && !accepted; ++tries) {
        Eigen::MatrixXd M = A;
        for (int k = 0; k < np; ++k) M(k, k) += lambda * std::max(A(k, k), 1e-12) + 1e-12;
        const Eigen::VectorXd d = M.ldlt().solve(-g);
        Eigen::VectorXd un = (u + d).cwiseMax(0.0).cwiseMin(1.0);
        if ((un - u).norm() < 1e-7) break;
        const auto rn = residuals({model(instances(un))}, cal)[0];
        f.evaluations += 1;
        const double cn = ssr_of(rn.data(), rn.size());
        if (cn < cost) {
          const double gain = (cost - cn) / cost;
          u = un;
          r = rn;
          cost = cn;
          lambda = std::max(lambda / 4, 1e-7);
          accepted = true;
          if (gain < 1e-4) it = max_iterations;  // converged
        } else {
          lambda *= 8;
        }
      }
      if (!accepted) break;
    }
    f.effects = instances(u);
    f.r_cal = r;
    return f;
  }
  double screen_cutoff_ = -1;  // < 0: never stop at screening

  // What the unpatched model's run at each operating point tells the
  // phases (framework/diagnose/phases.hpp): its events' first times and
  // its metrics' values.
  void compute_phases(const std::vector<PhaseDecl>& declared) {
    const Model base = model({});
    std::vector<PhaseStarts> starts(runs.size());
    std::vector<std::vector<double>> times;
    for (std::size_t k = 0; k < runs.size(); ++k) {
      times.push_back(runs[k].t);
      Netlist nl = netlist_of(base, static_cast<int>(k));
      const std::vector<bool> all(nl.metrics.size(), true);
      add_metric_outputs(nl, all);
      RunResult res;
      try {
        res = run_simulation(nl, registry_);
      } catch (const std::exception&) {
        continue;  // input errors surfaced when the model was loaded; a failed run gets one phase
      }
      ++simulations;
      for (const auto& e : res.solver.events)
        if (!e.tag.empty()) starts[k].emplace(e.component + "." + e.tag, e.t);
      if (!declared.empty() && res.solver.ok) {
        const auto values = evaluate_metrics(nl, all, res, {});
        for (std::size_t i = 0; i < nl.metrics.size(); ++i) starts[k][nl.metrics[i].name] = values[i];
      }
    }
    Phases ph = assign_phases(declared, times, starts);
    phase_names = std::move(ph.names);
    phases = std::move(ph.of_sample);
    phase_times = std::move(ph.times);
  }

  const DiagnoseOptions& options() const { return options_; }
  const Registry& registry() const { return registry_; }

 private:
  std::string model_file_, model_text_;
  const Registry& registry_;
  DiagnoseOptions options_;
  Netlist base_netlist_;
  YAML::Node model_yaml_;
};

// An effect fitted back to its null value has vanished: no claim. (False
// for a structural switch, which has no null.)
bool at_null(const EffectInstance& inst) {
  bool vanished = true, has_null = false;
  for (std::size_t i = 0; i < inst.values.size(); ++i) {
    const auto& spec = inst.effect->parameters[i];
    if (!spec.null_value) continue;
    has_null = true;
    auto u = [&](double v) {
      return spec.log_scale ? std::log(v / spec.lower) / std::log(spec.upper / spec.lower)
                            : (v - spec.lower) / (spec.upper - spec.lower);
    };
    vanished = vanished && std::abs(u(inst.values[i]) - u(*spec.null_value)) < 0.01;
  }
  return has_null && vanished;
}

// Significant windows: chi-square of each window (1/60 of the run) against
// the noise level (under "model right" the normalised residuals are white
// with unit variance).
void significant_windows(const std::vector<MeasuredRun>& runs, const Layout& L, const std::vector<double>& r,
                         std::vector<WindowFinding>& out) {
  for (const auto& seg : L.segments) {
    const auto& run = runs[seg.run];
    const double span = run.t.back() - run.t.front();
    const double wlen = span / 60;
    std::size_t i = 0;
    WindowFinding open;
    bool is_open = false;
    while (i < seg.n) {
      std::size_t j = i;
      double s = 0;
      while (j < seg.n && run.t[j] < run.t[i] + wlen) s += r[seg.offset + j] * r[seg.offset + j], ++j;
      const double nw = static_cast<double>(j - i);
      const double z = (s - nw) / std::sqrt(2 * nw);
      if (z > 4) {
        if (is_open) {
          open.t1 = run.t[j - 1];
          open.z = std::max(open.z, z);
          open.rms = std::max(open.rms, std::sqrt(s / nw));
        } else {
          open = {run.name, run.signals[seg.signal], run.t[i], run.t[j - 1], std::sqrt(s / nw), z};
          is_open = true;
        }
      } else if (is_open) {
        out.push_back(open);
        is_open = false;
      }
      i = j;
    }
    if (is_open) out.push_back(open);
  }
}

// What the verdict leaves (DiagnosisReport::unexplained): where the
// remaining validation gap lies, and which balance's disturbance explains it.
Unexplained leftover(Engine& eng, const Model& verdict, const DiagnosisReport& rep, const Layout& cal,
                     const Layout& val, const std::vector<double>& r_cal, const std::vector<double>& r_val,
                     const std::function<void(const std::string&)>& log) {
  Unexplained u;
  const GapTable& g = rep.validation_after;
  u.gap = g.total.rms;
  std::size_t s = 0, p = 0;
  for (std::size_t k = 0; k < g.signals.size(); ++k)
    if (g.by_signal[k].ssr > g.by_signal[s].ssr) s = k;
  for (std::size_t k = 0; k < g.phase_total.size(); ++k)
    if (g.by_phase[s][k].ssr > g.by_phase[s][p].ssr) p = k;
  u.signal = g.signals.empty() ? "" : g.signals[s];
  u.phase = rep.phase_names.empty() ? "" : rep.phase_names[p];
  significant_windows(eng.runs, cal, r_cal, u.windows);
  significant_windows(eng.runs, val, r_val, u.windows);
  const Netlist model = eng.netlist_of(verdict, 0);
  UnexplainedInput in{&eng.runs, &eng.phase_names, &eng.phases, &model, &eng.registry(),
                      [&](int k, const std::vector<Disturbance>& d) { return eng.simulate(verdict, k, d); }, log};
  explain_by_balances(in, eng.options(), u);
  return u;
}

std::string fmt(const char* f, double a, double b = 0, double c = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b, c);
  return buf;
}

}  // namespace

DiagnosisReport diagnose(const std::string& model_file, const std::string& runs_dir,
                         const std::string& catalogue_file, const Registry& registry, const DiagnoseOptions& opt) {
  const auto t_start = std::chrono::steady_clock::now();
  auto log = [&](const std::string& s) {
    if (!opt.progress) return;
    if (opt.log) opt.log(s);
    else std::cerr << s << std::endl;
  };
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count(); };
  Engine eng(model_file, registry, opt);
  eng.runs = load_runs(runs_dir, eng.base());
  const Catalogue cat = load_catalogue(catalogue_file, eng.yaml(), model_file, registry);
  for (const auto& e : cat.effects)  // a run's operating point would override the re-calibrated value
    for (const auto& run : eng.runs)
      for (const auto& op : run.operating_point)
        if (op.first == e.recalibrates)
          throw InputError(e.where, "", op.first,
                           "recalibrate: '" + op.first + "' is set by the operating point of run '" + run.name +
                               "', so it cannot be re-calibrated");

  DiagnosisReport rep;
  rep.model_file = model_file;
  rep.catalogue_file = catalogue_file;
  rep.runs_dir = runs_dir;
  for (const auto& r : eng.runs) (r.role == Role::calibration ? rep.calibration_runs : rep.validation_runs).push_back(r.name);
  {
    std::map<std::string, std::vector<double>> sig;
    for (const auto& r : eng.runs)
      for (std::size_t s = 0; s < r.signals.size(); ++s) sig[r.signals[s]].push_back(r.sigma[s]);
    for (auto& [name, v] : sig) {
      std::sort(v.begin(), v.end());
      rep.noise.emplace_back(name, v[v.size() / 2]);
    }
  }
  for (const Probe& p : elaborate(eng.base(), registry).probes) rep.signal_units.emplace_back(p.name, p.unit);
  log(fmt("diagnose: %g runs, ", eng.runs.size()) + std::to_string(cat.effects.size()) + " candidate effects, " +
      std::to_string(opt.threads) + " threads");
  eng.compute_phases(cat.phases);
  rep.phase_names = eng.phase_names;
  const Layout cal = eng.layout(Role::calibration), val = eng.layout(Role::validation);

  // Where: the unpatched model.
  const Model base_model = eng.model({});
  const auto r_cal0 = eng.residuals({base_model}, cal)[0];
  const auto r_val0 = eng.residuals({base_model}, val)[0];
  rep.calibration_before = eng.gaps(r_cal0, cal);
  rep.validation_before = eng.gaps(r_val0, val);
  log(fmt("base model: validation gap %.3g (noise = 1), calibration gap %.3g  [%.1f s]",
          rep.validation_before.total.rms, rep.calibration_before.total.rms, elapsed()));
  // Significant windows: chi-square of each window against the noise level
  // (under "model right" the normalised residuals are white with unit variance).
  significant_windows(eng.runs, cal, r_cal0, rep.windows);
  significant_windows(eng.runs, val, r_val0, rep.windows);

  // Which: screening and fits of every available candidate.
  struct Cand {
    const Effect* e;
    Engine::Fit fit;
    std::vector<double> r_val;
  };
  std::vector<Cand> cands;
  std::vector<EffectResult> results;
  for (const auto& e : cat.effects) {
    EffectResult er;
    er.name = e.name;
    er.description = e.description;
    er.unavailable = e.unavailable;
    for (const auto& p : e.parameters) {
      er.parameter_names.push_back(p.name);
      er.parameter_units.push_back(p.unit);
      er.values.push_back(p.null_value ? *p.null_value : p.initial);
    }
    er.gap_before = er.gap_after = rep.validation_before.total.rms;
    results.push_back(er);
  }
  // Screening: for an effect with a null, the share of the unpatched model's
  // calibration misfit that a Gauss-Newton step from the sensitivities would
  // remove, from the null (where the model is the unpatched one) and from the
  // initial values - a share of a far start's own large misfit says little
  // about the data. A structural switch has no point in its family that is
  // the unpatched model: the share of its own misfit at the initial values.
  std::vector<std::pair<double, int>> screened;
  eng.screen_cutoff_ = 2.0;  // always stop after the sensitivities
  const double ssr_cal0 = ssr_of(r_cal0.data(), r_cal0.size());
  for (std::size_t k = 0; k < cat.effects.size(); ++k) {
    const Effect& e = cat.effects[k];
    if (!e.unavailable.empty()) {
      log("  " + e.name + ": " + e.unavailable);
      continue;
    }
    std::vector<double> init, null;
    for (const auto& p : e.parameters) {
      init.push_back(p.initial);
      if (p.null_value) null.push_back(*p.null_value);
    }
    double gain = 0;
    for (const auto* start : {&init, &null}) {
      if (start->size() != e.parameters.size() || (start == &null && null == init)) continue;
      const auto f = eng.fit({EffectInstance{&e, *start}}, cal, {}, 1);
      const double reference = null.size() == init.size() ? ssr_cal0 : ssr_of(f.r_cal.data(), f.r_cal.size());
      gain = std::max(gain, 1 - ssr_of(f.r_cal.data(), f.r_cal.size()) * (1 - f.screening) / reference);
    }
    results[k].screening_improvement = gain;
    screened.push_back({gain, static_cast<int>(k)});
    log(fmt("  screening %-2.0f ", k + 1) + e.name + fmt(": linearised improvement %.1f %%  [%.1f s]", 100 * gain, elapsed()));
  }
  std::sort(screened.begin(), screened.end(), std::greater<>());
  eng.screen_cutoff_ = -1;
  for (std::size_t q = 0; q < screened.size(); ++q) {
    const int k = screened[q].second;
    const Effect& e = cat.effects[k];
    if (static_cast<int>(q) >= opt.screen_keep || screened[q].first < 0.002) {
      results[k].screened_out = true;
      continue;
    }
    std::vector<double> init;
    for (const auto& p : e.parameters) init.push_back(p.initial);
    auto f = eng.fit({EffectInstance{&e, init}}, cal, {}, opt.max_iterations, true);
    const auto r_val = eng.residuals({eng.model(f.effects)}, val)[0];
    auto& er = results[k];
    er.values = f.effects[0].values;
    er.fit_evaluations = f.evaluations;
    er.validation_after = eng.gaps(r_val, val);
    er.gap_after = er.validation_after.total.rms;
    for (const auto& seg : val.segments)
      if (seg.signal == 0 && r_val[seg.offset] == kFailedResidual) ++er.failed_validation_runs;
    const auto s = eng.significance(r_val0, r_val, val, static_cast<int>(e.parameters.size()));
    er.lr_eff = s.lr;
    er.delta_bic = s.delta_bic;
    er.p_value = s.p;
    er.n_eff = s.n_eff;
    er.significant = s.delta_bic > opt.significance_bic && er.gap_before > opt.adequate_gap &&
                     practically_significant(rep.validation_before, er.validation_after, opt);
    log(fmt("  fit %-2.0f/%-2.0f ", q + 1, std::min<double>(screened.size(), opt.screen_keep)) + e.name +
        fmt(": validation gap %.3g -> %.3g, dBIC %.3g", er.gap_before, er.gap_after, er.delta_bic) +
        fmt("  (%.0f simulations) [%.1f s]", f.evaluations * cal.runs.size(), elapsed()) +
        (er.failed_validation_runs ? " - the solver failed on a validation run at the fitted values" : ""));
    cands.push_back({&e, f, r_val});
  }
  const std::vector<int> order = rank_effects(results);

  // Groups: near-collinear improvement patterns that the data do not separate.
  auto cand_of = [&](const std::string& n) -> const Cand* {
    for (const auto& c : cands)
      if (c.e->name == n) return &c;
    return nullptr;
  };
  auto improvement_cosine = [&](const Cand& a, const Cand& b) {
    double ab = 0, aa = 0, bb = 0;
    for (std::size_t i = 0; i < r_val0.size(); ++i) {
      const double da = r_val0[i] - a.r_val[i], db = r_val0[i] - b.r_val[i];
      ab += da * db, aa += da * da, bb += db * db;
    }
    return aa > 0 && bb > 0 ? ab / std::sqrt(aa * bb) : 0.0;
  };
  for (auto& er : results) {
    const Cand* a = cand_of(er.name);
    if (!a || !er.significant) continue;
    for (const auto& other : results) {
      const Cand* b = cand_of(other.name);
      if (!b || b == a || !other.significant) continue;
      // Indistinguishable: same improvement pattern, and neither fit is
      // significantly better than the other on the validation runs.
      const auto s_ab = eng.significance(b->r_val, a->r_val, val, 0);
      if (improvement_cosine(*a, *b) > opt.group_cosine && std::abs(s_ab.lr) < opt.significance_bic)
        er.group.push_back(other.name);
    }
  }

  // Forward selection. First the best-ranked significant effect.
  std::vector<EffectInstance> chosen;
  std::vector<double> r_val_cur = r_val0, r_cal_cur = r_cal0;
  auto name_in_verdict = [&](const std::string& name) {
    rep.verdict.push_back(name);
    for (const auto& er : results)
      if (er.name == name) {
        auto g = er.group;
        g.insert(g.begin(), er.name);
        rep.verdict_groups.push_back(g);
      }
  };
  const Cand* best = nullptr;
  for (int k : order)
    if (results[k].significant) {
      best = cand_of(results[k].name);
      break;
    }
  if (best) {
    chosen = best->fit.effects;
    r_val_cur = best->r_val;
    r_cal_cur = best->fit.r_cal;
    // Polish the first effect alone with a second iteration budget, so that a
    // second effect is credited only for what the first cannot do (a joint
    // fit would otherwise also get the first effect's unfinished iterations).
    log("  polishing " + best->e->name + fmt("  [%.1f s]", elapsed()));
    auto polished = eng.fit(chosen, cal, r_cal_cur, opt.max_iterations);
    if (ssr_of(polished.r_cal.data(), polished.r_cal.size()) < ssr_of(r_cal_cur.data(), r_cal_cur.size())) {
      chosen = polished.effects;
      r_cal_cur = polished.r_cal;
      r_val_cur = eng.residuals({eng.model(chosen)}, val)[0];
      for (auto& er : results)
        if (er.name == best->e->name) {
          er.values = chosen[0].values;
          er.validation_after = eng.gaps(r_val_cur, val);
          er.gap_after = er.validation_after.total.rms;
        }
    }
    name_in_verdict(best->e->name);
  }
  auto gap_of = [](const std::vector<double>& r) { return std::sqrt(ssr_of(r.data(), r.size()) / r.size()); };
  auto ssr = [](const std::vector<double>& r) { return ssr_of(r.data(), r.size()); };
  // Then, while a gap is left: re-screen the remaining candidates against it
  // (each added to the current model: the linearised gain from its initial
  // values with every parameter free, and the direct gain at its single fit -
  // what one effect improves alone says little about what it adds to another),
  // fit the best four jointly with the chosen effects, and add the one that
  // removes the most of the validation gap among those that pass both gates
  // against the current model.
  while (best && static_cast<int>(rep.verdict.size()) < opt.max_effects && gap_of(r_val_cur) > opt.adequate_gap) {
    const double c0 = ssr(r_cal_cur);
    std::vector<std::pair<double, EffectInstance>> rescreen;
    eng.screen_cutoff_ = 2.0;
    for (int k : order) {
      const Effect* e = cat.find(results[k].name);
      bool skip = false;
      for (const auto& ch : chosen) skip = skip || ch.effect == e || effects_conflict(*ch.effect, *e);
      for (const auto& g : rep.verdict_groups)
        for (const auto& n : g) skip = skip || n == e->name;
      if (skip) continue;
      std::vector<double> init;
      for (const auto& p : e->parameters) init.push_back(p.initial);
      auto start = chosen;
      start.push_back({e, init});
      const auto lin = eng.fit(start, cal, {}, 1);
      const double at_init = ssr(lin.r_cal);
      double gain = 1 - at_init * (1 - lin.screening) / c0;
      EffectInstance from{e, init};
      if (const Cand* c = cand_of(e->name)) {
        start.back() = c->fit.effects[0];
        const double at_fit = ssr(eng.residuals({eng.model(start)}, cal)[0]);
        if (at_fit < at_init) from = c->fit.effects[0];
        gain = std::max(gain, 1 - at_fit / c0);
      }
      log("  re-screening " + e->name + fmt(" against the gap left: %.1f %%", 100 * gain));
      rescreen.push_back({gain, from});
    }
    eng.screen_cutoff_ = -1;
    std::stable_sort(rescreen.begin(), rescreen.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    if (rescreen.size() > 4) rescreen.resize(4);
    struct Step {
      const Effect* e;
      Engine::Fit fit;
      std::vector<double> r_val;
      GapTable gap;
    };
    const GapTable gap_cur = eng.gaps(r_val_cur, val);
    std::optional<Step> bs;
    for (const auto& [gain, add] : rescreen) {
      const Effect* e = add.effect;
      auto start = chosen;
      start.push_back(add);
      log("  forward selection: " + rep.verdict.back() + " + " + e->name + fmt("  [%.1f s]", elapsed()));
      auto f = eng.fit(start, cal, {}, opt.max_iterations, true);
      if (at_null(f.effects.back())) {
        log("    " + e->name + " fitted back to its null value: not added");
        continue;
      }
      Step st{e, f, eng.residuals({eng.model(f.effects)}, val)[0], {}};
      st.gap = eng.gaps(st.r_val, val);
      const auto s = eng.significance(r_val_cur, st.r_val, val, static_cast<int>(e->parameters.size()));
      std::string why;
      const bool practical = practically_significant(gap_cur, st.gap, opt, &why);
      log("    + " + e->name + fmt(": validation gap %.3g -> %.3g, dBIC %.3g", gap_cur.total.rms, st.gap.total.rms,
                                    s.delta_bic) +
          (practical ? ", removes enough of the gap of " + why : ", not practically significant"));
      if (s.delta_bic > opt.significance_bic && practical && (!bs || st.gap.total.rms < bs->gap.total.rms))
        bs = std::move(st);
    }
    if (!bs) break;
    chosen = bs->fit.effects;
    r_val_cur = bs->r_val;
    r_cal_cur = bs->fit.r_cal;
    name_in_verdict(bs->e->name);
  }
  for (const auto& c : chosen) rep.final_values.emplace_back(c.effect->name, c.values);
  rep.validation_after = eng.gaps(r_val_cur, val);

  // Traces for the report: validation runs, measured against before and after.
  {
    const Model after = eng.model(chosen);
    for (int k : val.runs) {
      const auto before_sim = eng.simulate(base_model, k);
      const auto after_sim = eng.simulate(after, k);
      const auto& run = eng.runs[k];
      const std::size_t stride = std::max<std::size_t>(1, run.t.size() / 400);
      for (std::size_t s = 0; s < run.signals.size(); ++s) {
        TracePlot tp;
        tp.run = run.name;
        tp.signal = run.signals[s];
        tp.phase_times = eng.phase_times[k];
        for (std::size_t i = 0; i < run.t.size(); i += stride) {
          tp.t.push_back(run.t[i]);
          tp.measured.push_back(run.y[s][i]);
          tp.before.push_back(before_sim.empty() ? NAN : before_sim[s][i]);
          tp.after.push_back(after_sim.empty() ? NAN : after_sim[s][i]);
        }
        rep.plots.push_back(std::move(tp));
      }
    }
  }
  rep.effects = results;
  std::sort(rep.effects.begin(), rep.effects.end(), [](const EffectResult& a, const EffectResult& b) {
    if ((a.rank == 0) != (b.rank == 0)) return a.rank != 0;
    return a.rank < b.rank;
  });
  if (rep.validation_after.total.rms > opt.adequate_gap)
    rep.unexplained = leftover(eng, eng.model(chosen), rep, cal, val, r_cal_cur, r_val_cur, log);
  rep.seconds = elapsed();
  rep.simulations = eng.simulations;
  std::string v;
  for (const auto& n : rep.verdict) v += (v.empty() ? "" : ", ") + n;
  log(fmt("verdict: [", 0) + v + fmt("]; validation gap %.3g -> %.3g; %.1f s", rep.validation_before.total.rms,
                                     rep.validation_after.total.rms, rep.seconds));
  return rep;
}

}  // namespace pneumo::diagnose
