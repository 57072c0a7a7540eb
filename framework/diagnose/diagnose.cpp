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
#include <set>

#include "framework/analysis/run_metrics.hpp"
#include "framework/core/parallel.hpp"
#include "framework/core/text.hpp"
#include "framework/core/units.hpp"
#include "framework/diagnose/engine.hpp"
#include "framework/diagnose/next_run.hpp"
#include "framework/diagnose/phases.hpp"
#include "framework/diagnose/ranking.hpp"
#include "framework/diagnose/sensors.hpp"
#include "framework/diagnose/statistics.hpp"
#include "framework/diagnose/unexplained.hpp"
#include "framework/fit/bounded_lm.hpp"
#include "framework/run/run.hpp"

namespace pneumo::diagnose {


using namespace engine;

namespace {

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
                      log, [&](int k) { return eng.netlist_of(verdict, k); },
                      [&](int k, const std::vector<double>& times) {
                        KeptRun r;
                        const auto kept = eng.keep(verdict, k, times);
                        if (!kept) return r;
                        r.signals = eng.signals_of(verdict, k, *kept, nullptr);
                        r.from = [&eng, &verdict, k, kept](std::size_t j, const std::vector<Disturbance>& d,
                                                          std::string* why) {
                          return eng.simulate_from(verdict, k, *kept, j, d, why);
                        };
                        return r;
                      }};
  explain_by_balances(in, eng.options(), u);
  return u;
}

// The effects each member of a verdict slot's group was fitted with: alone
// for the first slot, beside the effects already chosen for the later ones.
using SlotFits = std::map<std::string, std::vector<EffectInstance>>;

// Which sensor would separate each verdict effect from those the data cannot
// tell apart from it (its slot's group), each at its own fit: measured
// noise per SI unit where a signal has the unit, the measured quantities by
// their output's COMPONENT.QUANTITY.
std::vector<SensorChoice> decisive_sensors(const Engine& eng, const DiagnosisReport& rep,
                                           const std::vector<SlotFits>& slot_fits) {
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
  for (std::size_t i = 0; i < rep.verdict_groups.size() && i < slot_fits.size(); ++i) {
    const auto& group = rep.verdict_groups[i];
    const auto& fits = slot_fits[i];
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

// One diagnosis, step by step (docs/how-to/diagnose.md):
// the data and the unpatched model's gap (where), every candidate screened
// and fitted alone, ranked and grouped (which), the verdict by forward
// selection, then what it leaves unexplained and which sensor would decide.
class Diagnosis {
 public:
  Diagnosis(const std::string& model_file, const std::string& runs_dir, const std::string& catalogue_file,
            const Registry& base, const DiagnoseOptions& opt)
      : opt_(opt), eng_(model_file, base, opt) {
    eng_.runs = load_runs(runs_dir, eng_.base(), eng_.base_probes(), eng_.registry());
    cat_ = candidates(catalogue_file, eng_.registry());
    recalibrate_each_runs_values();
    eng_.learn_nulls(cat_.effects);
    axes_ = experiment_axes();
    rep_.model_file = model_file;
    rep_.catalogue_file = catalogue_file;
    rep_.runs_dir = runs_dir;
  }

  DiagnosisReport run() {
    describe_data();
    where();
    fit_alone(screen());
    order_ = rank_effects(results_);
    group();
    if (const EffectResult* first = first_effect()) {
      const Selection before = selection();
      select_from(*first);
      if (!explains_the_data(eng_.gaps(r_val_cur_, val_), opt_)) try_other_first_effects(before);
    }
    finish();
    return std::move(rep_);
  }

 private:
  struct Cand {
    const Effect* e;
    Engine::Fit fit;
    std::vector<double> r_val;
  };
  struct Step {
    const Effect* e;
    Engine::Fit fit;
    std::vector<double> r_val;
    GapTable gap;
  };

  void log(const std::string& s) const {
    if (!opt_.progress) return;
    if (opt_.log) opt_.log(s);
    else std::cerr << s << std::endl;
  }
  double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start_).count(); }
  static double ssr(const std::vector<double>& r) { return ssr_of(r.data(), r.size()); }
  // A screen's gain: 1 less the share of the misfit `reference` that is
  // left once the linearised step from `lin` is taken.
  static double linear_gain(const Engine::Linearisation& lin, double reference) {
    return 1 - ssr(lin.r) * (1 - fit::gauss_newton_share(lin.J, lin.r)) / reference;
  }
  // Where a linearised screen starts: the initial values, and the null when
  // the effect has one that differs from them.
  static std::vector<std::vector<double>> linearisation_starts(const Effect& e) {
    std::vector<std::vector<double>> starts = {e.initial_values()};
    if (auto null = e.null_values(); !null.empty() && null != starts[0]) starts.push_back(std::move(null));
    return starts;
  }
  // Runs that failed since `mark` (Engine::failure_count()): counted, and
  // the first few reasons kept for the report and logged.
  void keep_failures(std::size_t mark, long& count, std::vector<std::string>& reasons, const std::string& whose) const {
    const auto failed = eng_.failures_since(mark);
    if (failed.empty()) return;
    count += static_cast<long>(failed.size());
    for (const auto& f : failed)
      if (reasons.size() < kKeptFailures && std::find(reasons.begin(), reasons.end(), f) == reasons.end())
        reasons.push_back(f);
    log("  " + whose + ": " + std::to_string(failed.size()) + " run(s) failed, first: " + failed.front());
  }
  static constexpr std::size_t kKeptFailures = 5;

  const Cand* cand_of(const std::string& n) const {
    for (const auto& c : cands_)
      if (c.e->name == n) return &c;
    return nullptr;
  }

  // The candidates: the declared faults and the catalogue's effects (or
  // either alone), narrowed to the options' `faults`.
  Catalogue candidates(const std::string& catalogue_file, const Registry& registry) const {
    if (!opt_.declared_faults && catalogue_file.empty())
      throw InputError(SourceLocation{"--effects", 0, 0}, "", "", "no candidates: give a catalogue or use the declared faults");
    Catalogue cat;
    if (opt_.declared_faults) {
      std::map<std::string, std::pair<double, double>> range;
      std::vector<std::string> per_run;
      for (const auto& run : eng_.runs) {
        for (std::size_t s = 0; s < run.signals.size(); ++s)
          for (double y : run.y[s]) {
            auto [it, fresh] = range.try_emplace(run.signals[s], y, y);
            it->second.first = std::min(it->second.first, y);
            it->second.second = std::max(it->second.second, y);
          }
        for (const auto& op : run.operating_point) per_run.push_back(op.name());
      }
      std::vector<MeasuredSignal> signals;
      for (const Probe& p : eng_.base_probes())
        if (range.count(p.name)) signals.push_back({p.name, range[p.name].second - range[p.name].first, p.unit});
      cat = declared_faults(eng_.base(), registry, signals, per_run);
    }
    if (!catalogue_file.empty()) cat = merge_catalogues(std::move(cat), load_catalogue(catalogue_file, eng_.base(), registry));
    if (!opt_.faults.empty()) cat = narrow_catalogue(std::move(cat), opt_.faults);
    return cat;
  }

  // A run's operating point would override the re-calibrated value: a
  // top-level parameter becomes a factor on each run's own value; a
  // COMPONENT.PARAMETER a run sets is refused (a factor would need the
  // netlist to write it through a top-level parameter).
  void recalibrate_each_runs_values() {
    for (auto& e : cat_.effects)
      for (const auto& run : eng_.runs)
        for (const auto& op : run.operating_point) {
          if (e.recalibrates.empty() || op.name() != e.recalibrates) continue;
          if (e.recalibrates.find('.') != std::string::npos)
            throw InputError(e.where, "", op.name(),
                             "recalibrate: '" + op.name() + "' is set by the operating point of run '" + run.name +
                                 "', so it cannot be re-calibrated (write it as a top-level parameter the runs set: "
                                 "then it is re-calibrated as one factor on every run's value)");
          recalibrate_each_runs_value(e);
        }
  }

  // The operating-point parameters the next run may set: those the runs
  // vary, over the span they cover, and --experiment's, over its range (a
  // run without a value has the model's).
  std::vector<NextRunSetting> experiment_axes() const {
    const Netlist& nl = eng_.base();
    std::vector<NextRunSetting> axes;
    auto value_in = [&](const MeasuredRun& run, const std::string& name) {
      for (const auto& op : run.operating_point)
        if (op.name() == name && op.si) return *op.si;
      return nl.parameter(name)->si_value;
    };
    for (const auto& run : eng_.runs)
      for (const auto& op : run.operating_point) {
        if (!op.si) continue;  // a component's setting (a replayed file): not an axis
        if (std::any_of(axes.begin(), axes.end(), [&](const auto& a) { return a.name == op.name(); })) continue;
        NextRunSetting a;
        a.name = op.name();
        a.lower = INFINITY;
        a.upper = -INFINITY;
        a.unit = units::si_unit_name(nl.parameter(op.name())->dim);
        for (const auto& r : eng_.runs) a.lower = std::min(a.lower, value_in(r, a.name)), a.upper = std::max(a.upper, value_in(r, a.name));
        if (a.upper > a.lower) axes.push_back(a);
      }
    std::vector<std::string> given;
    for (const auto& spec : opt_.experiments) {
      NextRunSetting a = experiment_range(spec);
      if (std::find(given.begin(), given.end(), a.name) != given.end())
        throw InputError(SourceLocation{"--experiment", 0, 0}, "", a.name,
                         "--experiment " + spec + ": '" + a.name + "' is given twice; give each parameter once");
      given.push_back(a.name);
      const auto same = std::find_if(axes.begin(), axes.end(), [&](const auto& x) { return x.name == a.name; });
      if (same != axes.end()) *same = a;
      else axes.push_back(a);
    }
    return axes;
  }

  // --experiment NAME=LOW:HIGH: a top-level parameter of the model that no
  // candidate re-calibrates, its bounds SI numbers or quantities of its
  // dimension, LOW < HIGH.
  NextRunSetting experiment_range(const std::string& spec) const {
    const Netlist& nl = eng_.base();
    const SourceLocation where{"--experiment", 0, 0};
    const auto eq = spec.find('='), colon = spec.find(':', eq == std::string::npos ? 0 : eq);
    if (eq == std::string::npos || eq == 0 || colon == std::string::npos || spec.find(':', colon + 1) != std::string::npos)
      throw InputError(where, "", "", "--experiment " + spec + ": expected NAME=LOW:HIGH, e.g. p_supply=4bar:7bar");
    NextRunSetting a;
    a.name = trim(spec.substr(0, eq));
    const TopParameter* tp = nl.parameter(a.name);
    if (!tp) {
      std::string names;
      for (const auto& t : nl.parameters) names += (names.empty() ? "" : ", ") + t.name;
      throw InputError(where, "", a.name,
                       "--experiment " + spec + ": the model has no top-level parameter '" + a.name +
                           "' (top-level parameters: " + (names.empty() ? "none" : names) + ")");
    }
    for (const auto& e : cat_.effects)
      if (e.recalibrates == a.name)
        throw InputError(where, "", a.name,
                         "--experiment " + spec + ": '" + a.name + "' is re-calibrated by the catalogue, so a run cannot set it");
    a.unit = units::si_unit_name(tp->dim);
    auto bound = [&](const std::string& text) {
      units::Quantity q{};
      try {
        q = units::parse_quantity(trim(text), nl.gas.p_ambient);
      } catch (const units::ParseError& e) {
        throw InputError(where, "", a.name, "--experiment " + spec + ": cannot read '" + text + "': " + e.what());
      }
      if (q.had_unit && !(q.dim == tp->dim))
        throw InputError(where, "", a.name,
                         "--experiment " + spec + ": '" + text + "' is not in " + a.unit + " (" + tp->dim.to_string() + ")");
      return q;
    };
    const std::string low = spec.substr(eq + 1, colon - eq - 1), high = spec.substr(colon + 1);
    a.lower = bound(low).si_value;
    a.upper = bound(high).si_value;
    if (!(a.upper > a.lower))
      throw InputError(where, "", a.name, "--experiment " + spec + ": HIGH must be greater than LOW");
    // Shown in the unit the range was given in.
    const std::string t = trim(low);
    std::size_t used = 0;
    try {
      (void)std::stod(t, &used);
    } catch (const std::exception&) {
      used = t.size();
    }
    if (const std::string unit = trim(t.substr(used)); !unit.empty()) {
      const units::DisplayUnit d = units::display_unit(unit, tp->dim, nl.gas.p_ambient);
      a.shown_unit = d.unit;
      a.shown_scale = d.scale;
      a.shown_offset = d.offset;
    }
    return a;
  }

  // The runs, the noise each signal shows (median over runs), the signals'
  // units and the phases.
  void describe_data() {
    for (const auto& r : eng_.runs)
      (r.role == Role::calibration ? rep_.calibration_runs : rep_.validation_runs).push_back(r.name);
    std::map<std::string, std::vector<double>> sig;
    for (const auto& r : eng_.runs)
      for (std::size_t s = 0; s < r.signals.size(); ++s) sig[r.signals[s]].push_back(r.sigma[s]);
    for (auto& [name, v] : sig) {
      std::sort(v.begin(), v.end());
      rep_.noise.emplace_back(name, v[v.size() / 2]);
    }
    for (const Probe& p : eng_.base_probes()) rep_.signal_units.emplace_back(p.name, p.unit);
    log(fmt("diagnose: %g runs, ", eng_.runs.size()) + std::to_string(cat_.effects.size()) + " candidate effects, " +
        std::to_string(opt_.threads) + " threads");
    eng_.compute_phases(cat_.phases);
    rep_.phase_names = eng_.phase_names;
    cal_ = eng_.layout(Role::calibration);
    val_ = eng_.layout(Role::validation);
  }

  // Where: the unpatched model's gap, and the windows whose residuals are
  // significant against the noise (chi-square of each window: under "model
  // right" the normalised residuals are white with unit variance).
  void where() {
    base_model_ = eng_.model({});
    const std::size_t mark = eng_.failure_count();
    r_cal0_ = eng_.residuals({base_model_}, cal_)[0];
    r_val0_ = eng_.residuals({base_model_}, val_)[0];
    keep_failures(mark, rep_.base_failed_runs, rep_.base_run_failures, "the unpatched model");
    r_cal_cur_ = r_cal0_;
    r_val_cur_ = r_val0_;
    rep_.calibration_before = eng_.gaps(r_cal0_, cal_);
    rep_.validation_before = eng_.gaps(r_val0_, val_);
    log(fmt("base model: validation gap %.3g (noise = 1), calibration gap %.3g  [%.1f s]",
            rep_.validation_before.total.rms, rep_.calibration_before.total.rms, elapsed()));
    significant_windows(eng_.runs, cal_, r_cal0_, rep_.windows);
    significant_windows(eng_.runs, val_, r_val0_, rep_.windows);
    for (const auto& e : cat_.effects) {
      EffectResult er;
      er.name = e.name;
      er.description = e.description;
      er.component = e.component;
      er.fault = e.fault;
      er.setting = e.setting;
      er.unavailable = e.unavailable;
      for (const auto& p : e.parameters) {
        er.parameter_names.push_back(p.name);
        er.parameter_units.push_back(p.unit);
        er.parameter_nulls.push_back(p.null_value ? *p.null_value : NAN);
        er.parameter_differences.push_back(p.difference);
        er.values.push_back(p.null_value ? *p.null_value : p.initial);
      }
      if (!e.recalibrates.empty() && e.parameters.size() == 1) er.netlist_value = e.parameters[0].null_value;
      er.gap_before = er.gap_after = rep_.validation_before.total.rms;
      results_.push_back(er);
    }
  }

  // Screening: for an effect with a null, the share of the unpatched model's
  // calibration misfit that a Gauss-Newton step from the sensitivities would
  // remove, from the null (where the model is the unpatched one) and from the
  // initial values - a share of a far start's own large misfit says little
  // about the data. A structural switch has no point in its family that is
  // the unpatched model: the share of its own misfit at the initial values.
  // Returns (gain, effect index), best first.
  //
  // The sensitivities at the initial values cost a simulation per parameter
  // and run beyond the start's own; they are differenced only for the
  // kRescreened best (three times the fits, at least) by what the null's
  // linearisation and the start's own run tell: the null's gain, or the
  // chord's - the best point on the line through the unpatched model's
  // residuals and the start's. Those then have the better of the null's
  // gain and the start's, as every candidate had before the shortlist; the
  // others keep the better of the null's and the chord's. (On the
  // benchmarks no fitted effect ranked below 18th by that first look; by the
  // null's gain alone a needle's misadjustment ranked 28th:
  // docs/how-to/diagnose.md.)
  std::vector<std::pair<double, int>> screen() {
    const std::size_t n = cat_.effects.size();
    const double ssr_cal0 = ssr(r_cal0_);
    std::vector<double> gain(n, 0.0), at_null(n, 0.0);
    std::vector<std::pair<double, int>> by_first_look;  // the candidates with a start apart from their null
    for (std::size_t k = 0; k < n; ++k) {
      const Effect& e = cat_.effects[k];
      if (!e.unavailable.empty()) {
        log("  " + e.name + ": " + e.unavailable);
        continue;
      }
      gain[k] = first_look(k, ssr_cal0, at_null[k]);
      if (linearisation_starts(e).size() > 1) by_first_look.push_back({gain[k], static_cast<int>(k)});
      log(fmt("  screening %-2.0f ", k + 1) + e.name + fmt(": linearised improvement %.1f %%  [%.1f s]", 100 * gain[k], elapsed()));
    }
    std::stable_sort(by_first_look.begin(), by_first_look.end(), std::greater<>());
    const std::size_t shortlist = std::max<std::size_t>(kRescreened, 3 * static_cast<std::size_t>(std::max(opt_.screen_keep, 0)));
    for (std::size_t i = 0; i < by_first_look.size() && i < shortlist; ++i) {
      const int k = by_first_look[i].second;
      const Effect& e = cat_.effects[k];
      gain[k] = std::max(at_null[k], linearised_gain(k, e.initial_values(), ssr_cal0));
      log("  screening " + e.name + fmt(" from its initial values: linearised improvement %.1f %%  [%.1f s]", 100 * gain[k], elapsed()));
    }
    std::vector<std::pair<double, int>> screened;
    for (std::size_t k = 0; k < n; ++k)
      if (cat_.effects[k].unavailable.empty()) {
        results_[k].screening_improvement = gain[k];
        screened.push_back({gain[k], static_cast<int>(k)});
      }
    std::sort(screened.begin(), screened.end(), std::greater<>());
    return screened;
  }

  // Candidate k's first look: a structural switch's gain at its initial
  // values; else its null's (kept in `at_null`), or its chord's when that is
  // larger.
  double first_look(std::size_t k, double ssr_cal0, double& at_null) {
    const Effect& e = cat_.effects[k];
    const auto starts = linearisation_starts(e);
    if (e.null_values().size() != e.parameters.size()) return linearised_gain(k, starts[0], -1);
    at_null = linearised_gain(k, starts.back(), ssr_cal0);
    if (starts.size() == 1) return at_null;
    const std::size_t mark = eng_.failure_count();
    const auto r_start = eng_.residuals({eng_.model({EffectInstance{&e, starts[0]}})}, cal_)[0];
    keep_failures(mark, results_[k].failed_runs, results_[k].run_failures, e.name + " (screening)");
    return std::max(at_null, chord_gain(r_start));
  }

  // Candidate k's screening gain linearised at `values` against the misfit
  // `reference` (< 0: the start's own), at least 0; its failed runs kept.
  double linearised_gain(std::size_t k, const std::vector<double>& values, double reference) {
    const Effect& e = cat_.effects[k];
    const std::size_t mark = eng_.failure_count();
    const auto lin = eng_.linearise({EffectInstance{&e, values}}, cal_);
    keep_failures(mark, results_[k].failed_runs, results_[k].run_failures, e.name + " (screening)");
    return std::max(0.0, linear_gain(lin, reference >= 0 ? reference : ssr(lin.r)));
  }

  // The chord's gain: the share of the unpatched misfit a Gauss-Newton step
  // removes along the line through its residuals and `r` (a simulated point
  // of the effect's family that ran) - a linearisation at the null whose one
  // column is that chord.
  double chord_gain(const std::vector<double>& r) const {
    // A start the solver fails on is on no line with the unpatched model.
    if (r.size() != r_cal0_.size() || std::find(r.begin(), r.end(), kFailedResidual) != r.end()) return 0.0;
    Eigen::MatrixXd chord(static_cast<Eigen::Index>(r.size()), 1);
    for (std::size_t i = 0; i < r.size(); ++i) chord(static_cast<Eigen::Index>(i), 0) = r[i] - r_cal0_[i];
    const double share = fit::gauss_newton_share(chord, r_cal0_);
    return std::isfinite(share) ? share : 0.0;
  }

  // The best screened candidates, each calibrated alone and judged on the
  // validation runs.
  void fit_alone(const std::vector<std::pair<double, int>>& screened) {
    for (std::size_t q = 0; q < screened.size(); ++q) {
      const int k = screened[q].second;
      const Effect& e = cat_.effects[k];
      if (static_cast<int>(q) >= opt_.screen_keep || screened[q].first < 0.002) {
        results_[k].screened_out = true;
        continue;
      }
      const std::size_t mark = eng_.failure_count();
      auto f = eng_.fit({EffectInstance{&e, e.initial_values()}}, cal_, {}, opt_.max_iterations, true);
      const auto r_val = eng_.residuals({eng_.model(f.effects)}, val_)[0];
      keep_failures(mark, results_[k].failed_runs, results_[k].run_failures, e.name + " (fit)");
      judge(results_[k], f, r_val);
      log(fmt("  fit %-2.0f/%-2.0f ", q + 1, std::min<double>(screened.size(), opt_.screen_keep)) + e.name +
          fmt(": validation gap %.3g -> %.3g, dBIC %.3g", results_[k].gap_before, results_[k].gap_after,
              results_[k].delta_bic) +
          fmt("  (%.0f simulations) [%.1f s]", f.evaluations * cal_.runs.size(), elapsed()) +
          (results_[k].failed_validation_runs ? " - the solver failed on a validation run at the fitted values" : ""));
      cands_.push_back({&e, f, r_val});
    }
  }

  // Validation runs the solver failed on (their residuals are the sentinel).
  int failed_runs_in(const std::vector<double>& r_val) const {
    int n = 0;
    for (const auto& seg : val_.segments)
      if (seg.signal == 0 && seg.n > 0 && r_val[seg.offset] == kFailedResidual) ++n;
    return n;
  }

  void judge(EffectResult& er, const Engine::Fit& f, const std::vector<double>& r_val) const {
    er.values = f.effects[0].values;
    er.fit_evaluations = f.evaluations;
    er.validation_after = eng_.gaps(r_val, val_);
    er.gap_after = er.validation_after.total.rms;
    er.failed_validation_runs = failed_runs_in(r_val);
    const auto s = eng_.significance(r_val0_, r_val, val_, static_cast<int>(f.effects[0].values.size()));
    er.lr_eff = s.lr;
    er.delta_bic = s.delta_bic;
    er.p_value = s.p;
    er.n_eff = s.n_eff;
    er.significant = er.failed_validation_runs == 0 && s.delta_bic > opt_.significance_bic &&
                     !explains_the_data(rep_.validation_before, opt_) &&
                     practically_significant(rep_.validation_before, er.validation_after, opt_);
  }

  // Groups: effects the data cannot tell apart - near-collinear improvements
  // and neither fit practically better than the other on the validation
  // runs (in noise units, as an effect must be practically significant to
  // be named: between two form-mismatched explanations abundant data make
  // every difference "statistically" significant).
  void group() {
    for (auto& er : results_) {
      const Cand* a = cand_of(er.name);
      if (!a || !er.significant) continue;
      for (const auto& other : results_) {
        const Cand* b = cand_of(other.name);
        if (!b || b == a || !other.significant) continue;
        if (indistinguishable(r_val0_, {a->r_val, er.validation_after}, {b->r_val, other.validation_after}))
          er.group.push_back(other.name);
      }
    }
  }

  struct Outcome {  // a model's validation residuals and gaps
    const std::vector<double>& r_val;
    const GapTable& gap;
  };
  // Two models the data cannot tell apart, each improving on r_from.
  bool indistinguishable(const std::vector<double>& r_from, const Outcome& a, const Outcome& b) const {
    return improvement_cosine(r_from, a.r_val, b.r_val) > opt_.group_cosine &&
           !practically_significant(a.gap, b.gap, opt_) && !practically_significant(b.gap, a.gap, opt_);
  }
  bool indistinguishable(const std::vector<double>& r_from, const Step& a, const Step& b) const {
    return indistinguishable(r_from, {a.r_val, a.gap}, {b.r_val, b.gap});
  }

  // Cosine between two models' improvements (r_from - r_a, r_from - r_b).
  static double improvement_cosine(const std::vector<double>& r_from, const std::vector<double>& r_a,
                                   const std::vector<double>& r_b) {
    double ab = 0, aa = 0, bb = 0;
    for (std::size_t i = 0; i < r_from.size(); ++i) {
      const double da = r_from[i] - r_a[i], db = r_from[i] - r_b[i];
      ab += da * db, aa += da * da, bb += db * db;
    }
    return aa > 0 && bb > 0 ? ab / std::sqrt(aa * bb) : 0.0;
  }

  // Among effects of one component the runs cannot tell apart, a setting
  // turned off is named before a part of it that fails (FaultSpec::setting):
  // a flow control's needle is turned far more often than its check valve
  // leaks. Across components no such order holds (a rod seal wears as often
  // as a needle is turned), so there the better fit stays first. And within
  // one, unless the part's fit is clearly the better one on the validation
  // runs (Vuong's test of the two fits, z > 3): a group says neither is
  // practically better, not that the data are silent. Three standard
  // errors, not two: the residuals of two fits that both miss the truth's
  // form stay correlated beyond the whitening's AR(5), which inflates z.
  // The best-ranked such setting in er's group, or er itself.
  static constexpr double kClearlyBetter = 3.0;
  bool setting_first(const std::string& part, const std::vector<double>& r_part, const std::string& setting,
                     const std::vector<double>& r_setting) const {
    const double z = eng_.preference(r_part, r_setting, val_);
    const bool first = z < kClearlyBetter;
    log("  " + setting + (first ? " is named before " : " is not named before ") + part +
        fmt(" (a setting; the part's fit better by Vuong's z = %.2f)", z));
    return first;
  }
  const EffectResult& setting_before_part(const EffectResult& er) const {
    const Cand* c = cand_of(er.name);
    if (er.setting || !c) return er;
    for (int k : order_) {
      const EffectResult& o = results_[k];
      const Cand* oc = cand_of(o.name);
      if (o.setting && o.significant && oc && o.component == er.component &&
          std::find(er.group.begin(), er.group.end(), o.name) != er.group.end() &&
          setting_first(er.name, c->r_val, o.name, oc->r_val))
        return o;
    }
    return er;
  }
  std::vector<Step>::const_iterator setting_before_part(const std::vector<Step>& passed,
                                                        std::vector<Step>::const_iterator bs) const {
    if (bs->e->setting) return bs;
    for (auto it = passed.begin(); it != passed.end(); ++it)
      if (it->e->setting && it->e->component == bs->e->component && indistinguishable(r_val_cur_, *bs, *it) &&
          setting_first(bs->e->name, bs->r_val, it->e->name, it->r_val))
        return it;
    return bs;
  }

  // A verdict slot: the effect named, then those the data cannot tell apart
  // from it there, each with the effects it was fitted with (for the sensor
  // that would decide).
  void name_in_verdict(const std::vector<std::string>& group, SlotFits fits) {
    rep_.verdict.push_back(group[0]);
    rep_.verdict_groups.push_back(group);
    slot_fits_.push_back(std::move(fits));
  }

  // The best-ranked significant effect (a setting before a part of its
  // component); null: none is significant.
  const EffectResult* first_effect() const {
    for (int k : order_)
      if (results_[k].significant) return &setting_before_part(results_[k]);
    return nullptr;
  }

  // The verdict by forward selection from `first`: named, then effects added
  // while the data are not explained and one passes.
  void select_from(const EffectResult& first) {
    name_first_effect(first);
    while (static_cast<int>(rep_.verdict.size()) < opt_.max_effects &&
           !explains_the_data(eng_.gaps(r_val_cur_, val_), opt_) && add_effect()) {
    }
  }

  // What forward selection changes: the model chosen, its residuals, the
  // verdict, the effects dropped, and the first effect's polished values.
  struct Selection {
    std::vector<EffectInstance> chosen;
    std::vector<double> r_val, r_cal;
    std::vector<std::string> verdict;
    std::vector<std::vector<std::string>> groups;
    std::vector<SlotFits> slot_fits;
    std::set<std::string> dropped;
    std::vector<EffectResult> results;
  };
  Selection selection() const {
    return {chosen_, r_val_cur_, r_cal_cur_, rep_.verdict, rep_.verdict_groups, slot_fits_, dropped_, results_};
  }
  void restore(const Selection& s) {
    chosen_ = s.chosen, r_val_cur_ = s.r_val, r_cal_cur_ = s.r_cal;
    rep_.verdict = s.verdict, rep_.verdict_groups = s.groups;
    slot_fits_ = s.slot_fits, dropped_ = s.dropped, results_ = s.results;
  }
  static int parameter_count(const std::vector<EffectInstance>& model) {
    int n = 0;
    for (const auto& e : model) n += static_cast<int>(e.values.size());
    return n;
  }

  // Forward selection is greedy: a stand-in that fits best alone can take
  // the first slot from two effects that together explain the runs while
  // each alone leaves more than it (a wall heat fitted first for a cap
  // leak beside a heavier load; the mass and the leak together leave the
  // noise). When the verdict leaves the data unexplained, the selection is
  // run again from each of the next kOtherFirsts significant single fits
  // outside the first slot's group (re-screening fewer candidates:
  // worth_a_second_look), and a verdict that leaves clearly less - a
  // smaller validation gap, practically significant (on the whole set or
  // on a badly fitted signal) and, by BIC, for the parameters it adds - is
  // named instead. Only a diagnosis that cannot explain its runs pays.
  static constexpr int kOtherFirsts = 2;
  void try_other_first_effects(const Selection& before) {
    Selection best = selection();
    const std::vector<std::string> first_group = best.groups.at(0);
    int tried = 0;
    for (int k : order_) {
      const EffectResult& er = before.results[k];
      if (tried == kOtherFirsts) break;
      if (!er.significant || !cand_of(er.name) ||
          std::find(first_group.begin(), first_group.end(), er.name) != first_group.end())
        continue;
      ++tried;
      restore(before);
      alternative_ = true;
      log("  the verdict leaves the data unexplained: forward selection again, from " + er.name +
          fmt("  [%.1f s]", elapsed()));
      select_from(results_[k]);
      const GapTable gap_best = eng_.gaps(best.r_val, val_), gap_now = eng_.gaps(r_val_cur_, val_);
      const int added = std::max(0, parameter_count(chosen_) - parameter_count(best.chosen));
      const auto s = eng_.significance(best.r_val, r_val_cur_, val_, added);
      const bool better = failed_runs_in(r_val_cur_) == 0 && gap_now.total.rms < gap_best.total.rms &&
                          practically_significant(gap_best, gap_now, opt_) && s.delta_bic > opt_.significance_bic;
      log("  from " + er.name + fmt(": validation gap %.3g against %.3g", gap_now.total.rms, gap_best.total.rms) +
          (better ? ", clearly less: this verdict is named" : ", not clearly less"));
      if (better) best = selection();
    }
    restore(best);
    alternative_ = false;
  }

  // The first effect, polished alone with a second iteration budget, so that
  // a second effect is credited only for what the first cannot do (a joint
  // fit would otherwise also get the first effect's unfinished iterations).
  void name_first_effect(const EffectResult& first) {
    const Cand* best = cand_of(first.name);
    chosen_ = best->fit.effects;
    r_val_cur_ = best->r_val;
    r_cal_cur_ = best->fit.r_cal;
    log("  polishing " + best->e->name + fmt("  [%.1f s]", elapsed()));
    auto polished = eng_.fit(chosen_, cal_, r_cal_cur_, opt_.max_iterations);
    auto r_val_polished = ssr(polished.r_cal) < ssr(r_cal_cur_) ? eng_.residuals({eng_.model(polished.effects)}, val_)[0]
                                                                 : std::vector<double>{};
    // A polished model the solver fails on is not the verdict's: the single
    // fit, which ran, stays.
    if (!r_val_polished.empty() && failed_runs_in(r_val_polished) > 0)
      log("  the polished model fails on a validation run: the single fit is kept");
    if (!r_val_polished.empty() && failed_runs_in(r_val_polished) == 0) {
      chosen_ = polished.effects;
      r_cal_cur_ = polished.r_cal;
      r_val_cur_ = std::move(r_val_polished);
      for (auto& er : results_)
        if (er.name == best->e->name) {
          er.values = chosen_[0].values;
          er.validation_after = eng_.gaps(r_val_cur_, val_);
          er.gap_after = er.validation_after.total.rms;
        }
    }
    std::vector<std::string> group = {best->e->name};
    SlotFits fits;
    for (const auto& er : results_)
      if (er.name == best->e->name) group.insert(group.end(), er.group.begin(), er.group.end());
    for (const auto& n : group)
      if (const Cand* c = cand_of(n)) fits[n] = c->fit.effects;
    name_in_verdict(group, std::move(fits));
  }

  // Whether candidate k may join the current model: not chosen, not in
  // conflict with a chosen effect, not in a named group, not dropped.
  bool may_join(int k) const {
    const Effect* e = &cat_.effects[k];
    bool skip = false;
    for (const auto& ch : chosen_) skip = skip || ch.effect == e || effects_conflict(*ch.effect, *e);
    for (const auto& g : rep_.verdict_groups)
      for (const auto& n : g) skip = skip || n == e->name;
    return !skip && dropped_.count(e->name) == 0;
  }

  // The remaining candidates re-screened against the gap left, each added to
  // the current model: the linearised gain with every parameter free from its
  // null (where the added effect is a small change of the current model) and
  // from its initial values (a far start's step is judged on that start's own
  // misfit; the chosen effects' sensitivities are taken at the null, where
  // every candidate shares them - the candidate's start moves them to second
  // order), and the direct gain at its single fit (what one effect improves
  // alone says little about what it adds to another). The best, each with
  // the start that did best.
  //
  // The null's linearisation is simulated for every candidate; the start's,
  // which costs as much again, only for those that might need it: the
  // kRescreened best by the null's gain now, the kRescreened best by the
  // first screen's gain (whose start carried it there), and those fitted
  // alone. Both rankings are simulated, none is predicted: a shortlist from
  // the first screen's sensitivities alone misses effects whose timing the
  // chosen one moves (docs/benchmarks.md).
  std::vector<EffectInstance> rescreen() {
    eng_.anchor(chosen_);  // every candidate re-screened extends the chosen effects
    const double c0 = ssr(r_cal_cur_);
    int held = 0;  // the chosen effects' parameters: the first columns
    for (const auto& ch : chosen_) held += static_cast<int>(ch.effect->parameters.size());
    std::vector<int> open;
    for (int k : order_)
      if (may_join(k) && (!alternative_ || worth_a_second_look(k))) open.push_back(k);
    const auto with = [&](int k, const std::vector<double>& values) {
      auto m = chosen_;
      m.push_back({&cat_.effects[k], values});
      return m;
    };
    std::vector<std::optional<Engine::Linearisation>> at_null(open.size());
    std::vector<double> null_gain(open.size(), -INFINITY);
    for (std::size_t i = 0; i < open.size(); ++i)
      if (const auto starts = linearisation_starts(cat_.effects[open[i]]); starts.size() > 1) {
        at_null[i] = eng_.linearise(with(open[i], starts[1]), cal_);
        null_gain[i] = linear_gain(*at_null[i], c0);
      }
    const std::set<int> afresh = starts_worth_simulating(open, at_null, null_gain);
    std::vector<std::pair<double, EffectInstance>> gains;
    for (std::size_t i = 0; i < open.size(); ++i) {
      const int k = open[i];
      const Effect* e = &cat_.effects[k];
      const auto starts = linearisation_starts(*e);
      double gain = -INFINITY;
      EffectInstance from{e, starts[0]};
      const bool from_start = !at_null[i] || afresh.count(k) > 0 || cand_of(e->name) != nullptr;
      if (from_start) {
        auto at_start = eng_.linearise(with(k, starts[0]), cal_, at_null[i] ? held : 0);
        if (at_null[i]) {
          Eigen::MatrixXd J(at_start.J.rows(), held + at_start.J.cols());
          J << at_null[i]->J.leftCols(held), at_start.J;
          at_start.J = std::move(J);
        }
        gain = linear_gain(at_start, c0);
      }
      if (null_gain[i] > gain) gain = null_gain[i], from = EffectInstance{e, starts[1]};
      if (const Cand* c = cand_of(e->name)) {
        const double at_fit = ssr(eng_.residuals({eng_.model(with(k, c->fit.effects[0].values))}, cal_)[0]);
        if (1 - at_fit / c0 > gain) gain = 1 - at_fit / c0, from = c->fit.effects[0];
      }
      log("  re-screening " + e->name + fmt(" against the gap left: %.1f %%", 100 * gain) +
          (from_start ? "" : " (from its null)"));
      gains.push_back({gain, from});
    }
    std::stable_sort(gains.begin(), gains.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    // A flat screen says little about which candidate adds most: every one
    // within half the best gain is fitted (at least four, at most eight).
    std::vector<EffectInstance> out;
    for (std::size_t i = 0; i < gains.size() && i < 8; ++i)
      if (i < 4 || gains[i].first >= 0.5 * gains[0].first) out.push_back(gains[i].second);
    return out;
  }

  // The candidates (of `open`, with their null's linearisation and its gain
  // against the current misfit when they have a null) whose start is
  // linearised too: the kRescreened best by that gain, and the kRescreened
  // best by the first screen's gain.
  std::set<int> starts_worth_simulating(const std::vector<int>& open,
                                        const std::vector<std::optional<Engine::Linearisation>>& at_null,
                                        const std::vector<double>& null_gain) const {
    std::vector<std::pair<double, int>> by_null, by_first;
    for (std::size_t i = 0; i < open.size(); ++i) {
      if (!at_null[i]) continue;
      const double g = null_gain[i];
      by_null.push_back({std::isfinite(g) ? g : INFINITY, open[i]});
      by_first.push_back({results_[open[i]].screening_improvement, open[i]});
    }
    std::set<int> out;
    for (auto* list : {&by_null, &by_first}) {
      std::stable_sort(list->begin(), list->end(), [](const auto& a, const auto& b) { return a.first > b.first; });
      for (std::size_t i = 0; i < list->size() && i < kRescreened; ++i) out.insert((*list)[i].second);
    }
    return out;
  }
  static constexpr std::size_t kRescreened = 24;

  // A selection from another first effect is a second look, not a second
  // diagnosis: it re-screens only the candidates fitted alone and the
  // kRescreened best of the first screen (on a small circuit nearly all of
  // them; on a line of cylinders a fifth).
  bool worth_a_second_look(int k) const {
    if (cand_of(results_[k].name)) return true;
    int better = 0;
    for (const auto& er : results_) better += er.screening_improvement > results_[k].screening_improvement;
    return better < static_cast<int>(kRescreened);
  }

  // Forward selection: the re-screened candidates fitted jointly with the
  // chosen effects (their parameters free); the one that removes the most of
  // the validation gap among those that pass both gates against the current
  // model is added, grouped (as the first effect is) with every other that
  // passed with a near-collinear improvement and a fit not practically
  // different - two effects the data cannot tell apart in this slot are
  // reported as such, not one of them by a hair. False: none passes.
  bool add_effect() {
    const GapTable gap_cur = eng_.gaps(r_val_cur_, val_);
    std::vector<Step> passed;
    for (const auto& add : rescreen()) {
      const Effect* e = add.effect;
      auto start = chosen_;
      start.push_back(add);
      log("  forward selection: " + rep_.verdict.back() + " + " + e->name + fmt("  [%.1f s]", elapsed()));
      const std::size_t mark = eng_.failure_count();
      auto f = eng_.fit(start, cal_, {}, opt_.max_iterations, true);
      Step st{e, f, eng_.residuals({eng_.model(f.effects)}, val_)[0], {}};
      for (auto& er : results_)
        if (er.name == e->name) keep_failures(mark, er.failed_runs, er.run_failures, e->name + " (forward selection)");
      st.gap = eng_.gaps(st.r_val, val_);
      const auto s = eng_.significance(r_val_cur_, st.r_val, val_, static_cast<int>(e->parameters.size()));
      std::string why;
      const bool practical = practically_significant(gap_cur, st.gap, opt_, &why);
      log("    + " + e->name +
          fmt(": validation gap %.3g -> %.3g, dBIC %.3g", gap_cur.total.rms, st.gap.total.rms, s.delta_bic) +
          (practical ? ", removes enough of the gap of " + why : ", not practically significant"));
      if (failed_runs_in(st.r_val) > 0)
        log("    the solver fails on a validation run with it: not a fit");
      else if (s.delta_bic > opt_.significance_bic && practical && adds_its_own(st))
        passed.push_back(std::move(st));
    }
    if (passed.empty()) return false;
    const auto bs = setting_before_part(
        passed, std::min_element(passed.cbegin(), passed.cend(), [](const Step& a, const Step& b) {
          return a.gap.total.rms < b.gap.total.rms;
        }));
    std::vector<std::string> group = {bs->e->name};
    SlotFits fits = {{bs->e->name, bs->fit.effects}};
    for (const auto& other : passed)
      if (&other != &*bs && indistinguishable(r_val_cur_, *bs, other)) {
        group.push_back(other.e->name);
        fits[other.e->name] = other.fit.effects;
      }
    chosen_ = bs->fit.effects;
    r_val_cur_ = bs->r_val;
    r_cal_cur_ = bs->fit.r_cal;
    name_in_verdict(group, std::move(fits));
    drop_effects_without_their_own_share();
    return true;
  }

  // Every effect named before the last is re-tested in the joint fit: set
  // back to its null (the others at their joint values), is the model
  // significantly worse on the validation runs? An effect named first
  // because it mimicked a little of what the right one explains - a needle
  // at k = 1.00002 beside the leak - is not, and is dropped from the verdict
  // (the model without it, at the others' joint values, becomes the current
  // one). An effect without a null (a structural switch) stays.
  void drop_effects_without_their_own_share() {
    for (std::size_t i = 0; i + 1 < chosen_.size();) {
      const auto null = chosen_[i].effect->null_values();
      if (null.empty()) {
        ++i;
        continue;
      }
      auto without = chosen_;
      without[i].values = null;
      const auto r_without = eng_.residuals({eng_.model(without)}, val_)[0];
      const auto s = eng_.significance(r_without, r_val_cur_, val_, static_cast<int>(null.size()));
      if (failed_runs_in(r_without) > 0 || s.delta_bic > opt_.significance_bic) {
        ++i;
        continue;
      }
      log("  re-test: " + chosen_[i].effect->name +
          fmt(" adds nothing significant beside the others (dBIC %.3g against it at its null): dropped", s.delta_bic));
      const std::string name = chosen_[i].effect->name;
      dropped_.insert(name);
      without.erase(without.begin() + static_cast<long>(i));
      chosen_ = std::move(without);
      r_val_cur_ = r_without;
      r_cal_cur_ = eng_.residuals({eng_.model(chosen_)}, cal_)[0];
      const auto slot = std::find(rep_.verdict.begin(), rep_.verdict.end(), name) - rep_.verdict.begin();
      rep_.verdict.erase(rep_.verdict.begin() + slot);
      rep_.verdict_groups.erase(rep_.verdict_groups.begin() + slot);
      if (slot < static_cast<long>(slot_fits_.size())) slot_fits_.erase(slot_fits_.begin() + slot);
    }
  }

  // A joint fit may gain by re-fitting the chosen effects alone: the added
  // effect is credited only if setting it back to its null (the others kept
  // at their joint values) is significantly worse on the validation runs. Its
  // parameters' distance from the null says nothing about that: a small heat
  // transfer coefficient on a range up to 600 W/(m2*K) is not "no heat
  // transfer". A structural switch (no null) has no such reference.
  bool adds_its_own(const Step& st) {
    const auto null = st.e->null_values();
    if (null.empty()) return true;
    auto without = st.fit.effects;
    without.back().values = null;
    const auto r_without = eng_.residuals({eng_.model(without)}, val_)[0];
    const auto s = eng_.significance(r_without, st.r_val, val_, static_cast<int>(null.size()));
    if (s.delta_bic <= opt_.significance_bic)
      log(fmt("    its own share is not significant (dBIC %.3g against it at its null): not added", s.delta_bic));
    return s.delta_bic > opt_.significance_bic;
  }

  // Decimated traces of every validation run, measured against before and after.
  void traces() {
    const Model after = eng_.model(chosen_);
    for (int k : val_.runs) {
      const auto before_sim = eng_.simulate(base_model_, k);
      const auto after_sim = eng_.simulate(after, k);
      const auto& run = eng_.runs[k];
      const std::size_t stride = std::max<std::size_t>(1, run.t.size() / 400);
      for (std::size_t s = 0; s < run.signals.size(); ++s) {
        TracePlot tp;
        tp.run = run.name;
        tp.signal = run.signals[s];
        tp.phase_times = eng_.phase_times[k];
        for (std::size_t i = 0; i < run.t.size(); i += stride) {
          tp.t.push_back(run.t[i]);
          tp.measured.push_back(run.y[s][i]);
          tp.before.push_back(before_sim.empty() ? NAN : before_sim[s][i]);
          tp.after.push_back(after_sim.empty() ? NAN : after_sim[s][i]);
        }
        rep_.plots.push_back(std::move(tp));
      }
    }
  }

  // The verdict's values and gap, the traces, the ranking, which sensor
  // would decide, and what is left unexplained.
  void finish() {
    for (const auto& c : chosen_) rep_.final_values.emplace_back(c.effect->name, c.values);
    rep_.validation_after = eng_.gaps(r_val_cur_, val_);
    traces();
    rep_.effects = results_;
    std::sort(rep_.effects.begin(), rep_.effects.end(), [](const EffectResult& a, const EffectResult& b) {
      if ((a.rank == 0) != (b.rank == 0)) return a.rank != 0;
      return a.rank < b.rank;
    });
    rep_.sensors = decisive_sensors(eng_, rep_, slot_fits_);
    for (const auto& [names, fits] : rivals()) propose_next_run(names, fits);
    auto logger = [this](const std::string& s) { log(s); };
    if (!explains_the_data(rep_.validation_after, opt_))
      rep_.unexplained = leftover(eng_, eng_.model(chosen_), rep_, cal_, val_, r_cal_cur_, r_val_cur_, logger);
    rep_.seconds = elapsed();
    rep_.simulations = eng_.simulations;
    std::string v;
    for (const auto& n : rep_.verdict) v += (v.empty() ? "" : ", ") + n;
    log(fmt("verdict: [", 0) + v + fmt("]; validation gap %.3g -> %.3g; %.1f s", rep_.validation_before.total.rms,
                                       rep_.validation_after.total.rms, rep_.seconds) +
        fmt("; %.0f simulations", rep_.simulations) + fmt(", %.0f runs remembered", eng_.memo_hits()));
  }

  // Candidates the data cannot tell apart, each with the effects it was
  // fitted with: every verdict slot's group, and the verdict's first effect
  // with its runner-up (the best-ranked other fitted candidate) when
  // neither fit is practically better than the other on the validation runs.
  std::vector<std::pair<std::vector<std::string>, std::vector<std::vector<EffectInstance>>>> rivals() const {
    std::vector<std::pair<std::vector<std::string>, std::vector<std::vector<EffectInstance>>>> out;
    for (std::size_t i = 0; i < rep_.verdict_groups.size() && i < slot_fits_.size(); ++i) {
      std::pair<std::vector<std::string>, std::vector<std::vector<EffectInstance>>> r;
      for (const auto& n : rep_.verdict_groups[i])
        if (slot_fits_[i].count(n)) r.first.push_back(n), r.second.push_back(slot_fits_[i].at(n));
      if (r.first.size() >= 2) out.push_back(std::move(r));
    }
    if (rep_.verdict_groups.empty() || rep_.verdict_groups[0].size() > 1) return out;
    const Cand* first = cand_of(rep_.verdict[0]);
    if (!first) return out;
    const GapTable first_gap = eng_.gaps(first->r_val, val_);
    for (int k : order_) {
      const Cand* c = cand_of(results_[k].name);
      if (!c || c == first || results_[k].failed_validation_runs > 0) continue;
      const GapTable gap = eng_.gaps(c->r_val, val_);
      if (!practically_significant(gap, first_gap, opt_) && !practically_significant(first_gap, gap, opt_))
        out.push_back({{first->e->name, c->e->name}, {first->fit.effects, c->fit.effects}});
      break;
    }
    return out;
  }

  // The run that would tell `names` apart (framework/diagnose/next_run.hpp):
  // searched on the first run's span, sampling and signals.
  void propose_next_run(const std::vector<std::string>& names, const std::vector<std::vector<EffectInstance>>& fits) {
    if (axes_.empty() || eng_.runs.empty()) return;
    constexpr int kTemplate = 0;
    const MeasuredRun& tmpl = eng_.runs[kTemplate];
    std::vector<Model> models;
    for (const auto& f : fits) models.push_back(eng_.model(f));
    NextRunSearch s;
    for (const auto& a : axes_) s.axes.push_back({a.name, a.lower, a.upper});
    s.members = names;
    for (const auto& signal : tmpl.signals)
      for (const auto& [n, sigma] : rep_.noise)
        if (n == signal) s.sigma.push_back(sigma);
    for (const auto& run : eng_.runs) {
      std::vector<double> x;
      for (const auto& a : axes_) {
        double v = eng_.base().parameter(a.name)->si_value;
        for (const auto& op : run.operating_point)
          if (op.name() == a.name && op.si) v = *op.si;
        x.push_back(v);
      }
      s.measured_points.push_back(std::move(x));
    }
    s.simulate = [&](int member, const std::vector<double>& point) {
      return eng_.simulate(models[member], kTemplate, {}, setting(point));
    };
    s.threads = opt_.threads;
    log("  next run: searching where " + join(names) + " differ" + fmt("  [%.1f s]", elapsed()));
    const NextRunFound f = search_next_run(s);
    if (!f.found) {
      log(fmt("  next run: no point ran for every candidate (%.0f simulations failed)", f.failed));
      return;
    }
    NextRun n;
    n.effects = names;
    n.template_run = tmpl.name;
    for (std::size_t k = 0; k < axes_.size(); ++k) {
      n.operating_point.push_back(axes_[k]);
      n.operating_point.back().value = f.point[k];
    }
    n.separation = f.separation;
    n.separation_measured = f.separation_measured;
    n.effect_a = names[f.member_a];
    n.effect_b = names[f.member_b];
    n.signal = tmpl.signals[f.signal];
    n.decisive = f.separation >= 1.0 && f.separation > f.separation_measured;
    n.phase = n.decisive ? phase_of(f, kTemplate) : "";
    for (const auto& c : rep_.sensors)
      if ((c.effect_a == n.effect_a && c.effect_b == n.effect_b) || (c.effect_a == n.effect_b && c.effect_b == n.effect_a))
        n.sensor = sensor_clause(c);
    n.simulations = f.simulations;
    n.failed_simulations = f.failed;
    n.points = f.points;
    log("  next run: " + next_run_sentence(n) + fmt(" (%.0f points, %.0f simulations", n.points, n.simulations) +
        fmt(", %.0f failed)  [%.1f s]", n.failed_simulations, elapsed()));
    rep_.next_runs.push_back(std::move(n));
  }

  Setting setting(const std::vector<double>& point) const {
    Setting at;
    for (std::size_t k = 0; k < axes_.size(); ++k) at.emplace_back(axes_[k].name, point[k]);
    return at;
  }

  // The phase holding most of the separating signal's difference (one run
  // of the unpatched model there); empty with a single phase.
  std::string phase_of(const NextRunFound& f, int tmpl) {
    if (eng_.phase_names.size() < 2) return "";
    const std::vector<int> ph = eng_.phases_at(tmpl, setting(f.point));
    std::vector<double> by_phase(eng_.phase_names.size(), 0.0);
    for (std::size_t i = 0; i < ph.size() && i < f.d2.size(); ++i)
      if (ph[i] >= 0) by_phase[ph[i]] += f.d2[i];
    const auto most = std::max_element(by_phase.begin(), by_phase.end());
    return *most > 0 ? eng_.phase_names[most - by_phase.begin()] : "";
  }

  static std::string join(const std::vector<std::string>& names) {
    std::string out;
    for (std::size_t i = 0; i < names.size(); ++i) out += (i ? (i + 1 == names.size() ? " and " : ", ") : "") + names[i];
    return out;
  }

  const std::chrono::steady_clock::time_point t_start_ = std::chrono::steady_clock::now();
  const DiagnoseOptions& opt_;
  Engine eng_;
  Catalogue cat_;
  DiagnosisReport rep_;
  Layout cal_, val_;
  Model base_model_;
  std::vector<double> r_cal0_, r_val0_, r_cal_cur_, r_val_cur_;
  std::vector<EffectResult> results_;
  std::vector<Cand> cands_;
  std::vector<SlotFits> slot_fits_;  // per verdict slot, parallel to rep_.verdict_groups
  std::vector<int> order_;
  std::vector<EffectInstance> chosen_;
  std::set<std::string> dropped_;  // named, then dropped on re-test: not offered again
  bool alternative_ = false;       // selecting from another first effect (try_other_first_effects)
  std::vector<NextRunSetting> axes_;  // what the next run may set (experiment_axes())
};

}  // namespace

DiagnosisReport diagnose(const std::string& model_file, const std::string& runs_dir,
                         const std::string& catalogue_file, const Registry& base, const DiagnoseOptions& opt) {
  return Diagnosis(model_file, runs_dir, catalogue_file, base, opt).run();
}

}  // namespace pneumo::diagnose
