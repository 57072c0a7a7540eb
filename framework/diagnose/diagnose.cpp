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
#include "framework/diagnose/engine.hpp"
#include "framework/diagnose/phases.hpp"
#include "framework/diagnose/ranking.hpp"
#include "framework/diagnose/sensors.hpp"
#include "framework/diagnose/statistics.hpp"
#include "framework/diagnose/unexplained.hpp"
#include "framework/run/run.hpp"

namespace pneumo::diagnose {


using namespace engine;

namespace {

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

// Which sensor would separate each verdict effect from those the data cannot
// tell apart from it (its group), each at its own single fit: measured
// noise per SI unit where a signal has the unit, the measured quantities by
// their output's COMPONENT.QUANTITY.
std::vector<SensorChoice> decisive_sensors(const Engine& eng, const DiagnosisReport& rep,
                                           const std::map<std::string, std::vector<EffectInstance>>& fits) {
  std::map<std::string, std::vector<double>> sigmas;
  std::map<std::string, std::string> measured;
  for (const auto& [signal, unit] : rep.signal_units) {
    for (const auto& [name, sigma] : rep.noise)
      if (name == signal) sigmas[unit].push_back(sigma);
    for (const auto& o : eng.base().outputs)
      if (o.name == signal) measured[o.component + "." + o.quantity] = signal;
  }
  std::map<std::string, double> by_unit;
  for (auto& [unit, v] : sigmas) {
    std::sort(v.begin(), v.end());
    by_unit[unit] = v[v.size() / 2];
  }
  const auto noise = sensor_noise(by_unit);
  auto netlists = [&](const std::vector<EffectInstance>& effects) {
    const Model m = eng.model(effects);
    std::vector<Netlist> out;
    for (std::size_t k = 0; k < eng.runs.size(); ++k) out.push_back(eng.netlist_of(m, static_cast<int>(k)));
    return out;
  };
  std::vector<SensorChoice> out;
  for (const auto& group : rep.verdict_groups) {
    if (group.size() < 2 || !fits.count(group[0])) continue;
    const auto runs_a = netlists(fits.at(group[0]));
    for (std::size_t j = 1; j < group.size(); ++j)
      if (fits.count(group[j]))
        out.push_back(choose_sensor(group[0], group[j], runs_a, netlists(fits.at(group[j])), eng.registry(), noise,
                                    measured, eng.options().threads));
  }
  return out;
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
  {
    std::map<std::string, std::vector<EffectInstance>> fits;
    for (const auto& c : cands) fits[c.e->name] = c.fit.effects;
    rep.sensors = decisive_sensors(eng, rep, fits);
  }
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
