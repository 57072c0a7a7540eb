#include "framework/diagnose/calibrate.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "framework/core/text.hpp"
#include "framework/core/units.hpp"
#include "framework/diagnose/engine.hpp"
#include "framework/diagnose/json_text.hpp"
#include "framework/diagnose/statistics.hpp"
#include "framework/fit/bounded_lm.hpp"
#include "framework/io/files.hpp"

namespace pneumo::diagnose {

namespace {

using engine::Engine;
using engine::Layout;

constexpr int kMaxArOrder = 5;
constexpr std::size_t kKeptFailures = 5;

const SourceLocation kFreeOption{"--free", 0, 0};

std::string si_text(double v) {
  std::ostringstream o;
  o.precision(17);
  o << v;
  return o.str();
}

// The dimension of the netlist parameter KEY, if the model has it (an
// unknown one is refused by recalibration() with the names it knows).
std::optional<units::Dimension> dimension_of_key(const std::string& key, const Netlist& nl, const Registry& reg) {
  const auto dot = key.find('.');
  if (dot == std::string::npos) {
    const TopParameter* tp = nl.parameter(key);
    return tp ? std::optional(tp->dim) : std::nullopt;
  }
  if (const ComponentDecl* c = nl.component(key.substr(0, dot)))
    if (const auto* entry = reg.find(c->type))
      if (const ParameterSpec* spec = entry->info->parameter(key.substr(dot + 1)))
        return units::dimension_of(spec->unit);
  return std::nullopt;
}

// A bound of --free: a factor ("0.5x") as recalibration() reads it, a
// quantity of the parameter's dimension or an SI number, as SI text.
std::string bound_text(const std::string& spec, const std::string& text, const std::optional<units::Dimension>& dim,
                       double p_ambient) {
  const std::string t = trim(text);
  if (t.empty()) throw InputError(kFreeOption, "", "", "--free " + spec + ": an empty bound (write NAME=LOW:HIGH)");
  if (t.back() == 'x') return t;
  units::Quantity q{};
  try {
    q = units::parse_quantity(t, p_ambient);
  } catch (const units::ParseError& e) {
    throw InputError(kFreeOption, "", "", "--free " + spec + ": cannot read '" + t + "': " + e.what());
  }
  if (q.had_unit && dim && !(q.dim == *dim))
    throw InputError(kFreeOption, "", "",
                     "--free " + spec + ": '" + t + "' is not in " + units::si_unit_name(*dim) + " (" +
                         dim->to_string() + ")");
  return si_text(q.si_value);
}

// A measured output's reading error, OUTPUT.offset | OUTPUT.gain |
// OUTPUT.lag (engine.hpp's measurement model), when KEY names one and no
// component has OUTPUT's name; it starts at its null.
std::optional<Effect> measurement_parameter(const std::string& key, const Engine& eng) {
  const auto dot = key.find('.');
  if (dot == std::string::npos) return std::nullopt;
  const std::string output = key.substr(0, dot);
  if (eng.base().component(output)) return std::nullopt;
  MeasuredSignal signal{output, 0, ""};
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& run : eng.runs)
    for (std::size_t s = 0; s < run.signals.size(); ++s)
      if (run.signals[s] == output)
        for (double y : run.y[s]) lo = std::min(lo, y), hi = std::max(hi, y);
  if (!(hi >= lo)) return std::nullopt;  // not measured
  signal.span = hi - lo;
  for (const Probe& p : eng.base_probes())
    if (p.name == output) signal.unit = p.unit;
  const Netlist& nl = eng.base();
  for (Effect& e : measurement_faults(signal, kFreeOption, nl.simulation.t_end - nl.simulation.t_start))
    if (e.name == key) {
      e.parameters[0].initial = *e.parameters[0].null_value;
      return e;
    }
  return std::nullopt;
}

// --free NAME[=LOW:HIGH] -> the effect that sets the parameter.
Effect free_parameter(const std::string& spec, const Engine& eng) {
  const Netlist& nl = eng.base();
  const auto eq = spec.find('=');
  const std::string key = trim(spec.substr(0, eq));
  if (key.empty()) throw InputError(kFreeOption, "", "", "--free '" + spec + "': expected NAME or NAME=LOW:HIGH");
  std::optional<Effect> reading = measurement_parameter(key, eng);
  std::string lower, upper;
  if (eq != std::string::npos) {
    const std::string range = spec.substr(eq + 1);
    const auto colon = range.find(':');
    if (colon == std::string::npos || range.find(':', colon + 1) != std::string::npos)
      throw InputError(kFreeOption, "", key, "--free " + spec + ": expected NAME=LOW:HIGH, e.g. F_C=1N:20N or C=0.5x:2x");
    const auto dim = reading ? std::optional(units::dimension_of(reading->parameters[0].unit))
                             : dimension_of_key(key, nl, eng.registry());
    lower = bound_text(spec, range.substr(0, colon), dim, nl.gas.p_ambient);
    upper = bound_text(spec, range.substr(colon + 1), dim, nl.gas.p_ambient);
  }
  if (!reading) return recalibration(key, lower, upper, nl, eng.registry(), "--free " + spec);
  EffectParameter& p = reading->parameters[0];
  if (!lower.empty()) {
    if (lower.back() == 'x' || upper.back() == 'x')
      throw InputError(kFreeOption, "", key, "--free " + spec + ": give a reading's " + p.name + " range as values, not factors");
    p.lower = std::stod(lower), p.upper = std::stod(upper);
  }
  if (!(p.lower < p.upper)) throw InputError(kFreeOption, "", key, "--free " + spec + ": LOW must be below HIGH");
  if (p.log_scale && p.lower <= 0) throw InputError(kFreeOption, "", key, "--free " + spec + ": a gain's range must stay above 0");
  p.initial = std::clamp(p.initial, p.lower, p.upper);
  reading->description = "reading error " + key;
  return *reading;
}

std::vector<Effect> free_parameters(const CalibrateOptions& opt, const Engine& eng) {
  if (opt.free.empty())
    throw InputError(kFreeOption, "", "", "name at least one parameter to fit: --free NAME or --free NAME=LOW:HIGH");
  std::vector<Effect> out;
  std::set<std::string> seen;
  for (const auto& spec : opt.free) {
    Effect e = free_parameter(spec, eng);
    if (!seen.insert(e.name).second) throw InputError(kFreeOption, "", e.name, "--free: '" + e.name + "' is given twice");
    for (const auto& run : eng.runs)
      for (const auto& op : run.operating_point)
        if (op.name() == e.recalibrates)
          throw InputError(kFreeOption, "", op.name(),
                           "--free: '" + op.name() + "' is set by the operating point of run '" + run.name +
                               "', so no single value can be fitted; fix it there or leave it out of --free");
    out.push_back(std::move(e));
  }
  return out;
}

std::vector<EffectInstance> with_values(const std::vector<Effect>& effects, const std::vector<double>& values) {
  std::vector<EffectInstance> inst;
  for (std::size_t i = 0; i < effects.size(); ++i) inst.push_back({&effects[i], {values[i]}});
  return inst;
}

// A step into the range from `v`, one thousandth of it (on the parameter's
// own scale).
double inward_step(const EffectParameter& p, double v) {
  double h = p.log_scale ? v * (std::exp(1e-3 * std::log(p.upper / p.lower)) - 1) : 1e-3 * (p.upper - p.lower);
  return v + h > p.upper ? -h : h;
}

struct Uncertainty {
  std::vector<double> se;
  std::vector<std::vector<double>> correlation;
  double scale = 0;
};

// Generalised least squares at the fit: each run's signal whitened by the
// AR(p) model of its own residuals, J likewise; covariance s^2 (Jw'Jw)^-1
// with s^2 the whitened residual variance. Directions the data do not
// determine (eigenvalues below 1e-10 of the largest) give NaN to the
// parameters they involve.
// `J` is taken per unit of `scale` (each parameter's magnitude), so that
// the eigenvalues compare parameters of any unit.
Uncertainty uncertainty(const std::vector<double>& r, std::vector<std::vector<double>> J, const std::vector<double>& scale,
                        const Layout& L) {
  const int p = static_cast<int>(J.size());
  for (int i = 0; i < p; ++i)
    for (double& x : J[i]) x *= scale[i];
  Eigen::MatrixXd JtJ = Eigen::MatrixXd::Zero(p, p);
  double ssr = 0;
  long n = 0;
  for (const auto& seg : L.segments) {
    const auto a = fit_ar(&r[seg.offset], seg.n, kMaxArOrder);
    const auto rw = whitened(&r[seg.offset], seg.n, a);
    std::vector<std::vector<double>> jw;
    for (const auto& col : J) jw.push_back(whitened(&col[seg.offset], seg.n, a));
    for (std::size_t t = 0; t < rw.size(); ++t) {
      ssr += rw[t] * rw[t];
      for (int i = 0; i < p; ++i)
        for (int j = 0; j < p; ++j) JtJ(i, j) += jw[i][t] * jw[j][t];
    }
    n += static_cast<long>(rw.size());
  }
  Uncertainty u;
  u.scale = std::sqrt(ssr / std::max<long>(1, n - p));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(JtJ);
  const Eigen::VectorXd lam = es.eigenvalues();
  const Eigen::MatrixXd V = es.eigenvectors();
  const double tol = 1e-10 * std::max(lam.maxCoeff(), 0.0);
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(p, p);
  std::vector<bool> undetermined(p, false);
  for (int k = 0; k < p; ++k) {
    if (lam[k] > tol && lam[k] > 0) {
      cov += V.col(k) * V.col(k).transpose() / lam[k];
    } else {
      for (int i = 0; i < p; ++i)
        if (std::abs(V(i, k)) > 0.1) undetermined[i] = true;
    }
  }
  cov *= u.scale * u.scale;
  for (int i = 0; i < p; ++i)
    for (int j = 0; j < p; ++j) cov(i, j) *= scale[i] * scale[j];
  u.se.resize(p);
  u.correlation.assign(p, std::vector<double>(p, NAN));
  for (int i = 0; i < p; ++i) u.se[i] = undetermined[i] ? NAN : std::sqrt(cov(i, i));
  for (int i = 0; i < p; ++i)
    for (int j = 0; j < p; ++j)
      if (!undetermined[i] && !undetermined[j]) u.correlation[i][j] = cov(i, j) / (u.se[i] * u.se[j]);
  return u;
}

Gap gap_of(const std::vector<double>& r) {
  Gap g;
  g.ssr = ssr_of(r.data(), r.size());
  g.n = static_cast<long>(r.size());
  g.rms = g.n ? std::sqrt(g.ssr / g.n) : 0.0;
  return g;
}

double rms_of(const double* r, std::size_t n) { return n ? std::sqrt(ssr_of(r, n) / n) : 0.0; }

// The unit a pneumatic engineer reads a parameter of `dim` in when the
// netlist's `display:` names none ("" keeps SI).
std::string engineering_unit(units::Dimension dim) {
  namespace d = units::dims;
  if (dim == d::sonic_conductance) return "dm3/(s*bar)";
  if (dim == d::length) return "mm";
  if (dim == d::pressure) return "bar";
  if (dim == d::temperature) return "degC";
  if (dim == d::area) return "mm2";
  if (dim == d::volume) return "L";
  return "";
}

// Per run and signal: the gaps before and after and the traces (the
// simulated signal recovered from the residual; NaN where the run failed).
void describe(const Engine& eng, const Layout& L, const std::vector<double>& before, const std::vector<double>& after,
              const std::vector<Probe>& probes, CalibrationReport& rep) {
  for (const auto& seg : L.segments) {
    const MeasuredRun& run = eng.runs[seg.run];
    const double sigma = run.sigma[seg.signal];
    RunSignalGap g;
    g.run = run.name;
    g.signal = run.signals[seg.signal];
    g.role = run.role;
    g.sigma = sigma;
    units::DisplayUnit display;
    for (const Probe& pr : probes)
      if (pr.name == g.signal) g.unit = pr.unit, display = pr.display;
    if (display.unit.empty()) {
      const units::Dimension dim = units::dimension_of(g.unit);
      if (const std::string u = engineering_unit(dim); !u.empty())
        display = units::display_unit(u, dim, eng.base().gas.p_ambient);
    }
    g.rms_before = rms_of(&before[seg.offset], seg.n);
    g.rms_after = rms_of(&after[seg.offset], seg.n);
    g.rms_before_si = g.rms_before * sigma;
    g.rms_after_si = g.rms_after * sigma;
    g.shown_unit = display.unit.empty() ? g.unit : units::difference_unit(display.unit);
    g.shown_scale = display.unit.empty() ? 1.0 : display.scale;
    rep.gaps.push_back(g);
    CalibrationTrace tr{run.name, g.signal, g.unit, display, run.t, run.y[seg.signal], {}, {}};
    for (std::size_t i = 0; i < seg.n; ++i) {
      auto sim = [&](double r) { return r == engine::kFailedResidual ? NAN : run.y[seg.signal][i] - r * sigma; };
      tr.before.push_back(sim(before[seg.offset + i]));
      tr.after.push_back(sim(after[seg.offset + i]));
    }
    rep.traces.push_back(std::move(tr));
  }
}

void show_in_habitual_unit(CalibratedParameter& c, const Netlist& nl) {
  const units::Dimension dim = units::dimension_of(c.unit);
  std::string unit = nl.display_unit_for(dim);
  // Only where the parameter is in the quantity's own SI unit: a friction
  // slope in N/Pa is not an area to show in mm2.
  static const std::set<std::string> plain = {"m", "Pa", "K", "m2", "m3", "m3/(s*Pa)"};
  if (unit.empty() && plain.count(c.unit)) unit = engineering_unit(dim);
  // A reading's offset is a difference: bar, not bar g.
  if (c.reading) unit = units::difference_unit(unit);
  if (unit.empty()) {
    c.shown_unit = c.unit;
    return;
  }
  const units::DisplayUnit d = units::display_unit(unit, dim, nl.gas.p_ambient);
  c.shown_unit = unit;
  c.shown_scale = d.scale;
  c.shown_offset = d.offset;
}

bool on_bound(const EffectParameter& p, double v) {
  const double u = fit::ScaledBound{p.lower, p.upper, p.log_scale}.to_u(v);
  return u < 1e-6 || u > 1 - 1e-6;
}

void log_line(const CalibrateOptions& opt, const std::string& s);

// An early long step can throw a parameter onto a bound where the runs do
// not see it (a critical pressure ratio above every ratio the runs reach:
// its sensitivity is zero there), a flat face the fit cannot leave. Such
// parameters start again from their netlist values, the others from the
// fit; the better fit is kept (at most twice).
Engine::Fit fit_with_restarts(Engine& eng, const std::vector<Effect>& effects, const std::vector<double>& start,
                              const Layout& cal, const std::vector<double>& r0, const CalibrateOptions& opt) {
  Engine::Fit best = eng.fit(with_values(effects, start), cal, r0, opt.max_iterations);
  for (int attempt = 0; attempt < 2; ++attempt) {
    std::vector<double> again;
    bool restart = false;
    for (std::size_t i = 0; i < effects.size(); ++i) {
      const double v = best.effects[i].values[0];
      const bool parked = on_bound(effects[i].parameters[0], v) && !on_bound(effects[i].parameters[0], start[i]);
      again.push_back(parked ? start[i] : v);
      restart = restart || parked;
    }
    if (!restart) break;
    log_line(opt, "calibrate: a parameter stopped on its bound; fitting again from its netlist value");
    Engine::Fit next = eng.fit(with_values(effects, again), cal, {}, opt.max_iterations);
    next.evaluations += best.evaluations;
    if (ssr_of(next.r_cal.data(), next.r_cal.size()) >= ssr_of(best.r_cal.data(), best.r_cal.size())) {
      best.evaluations = next.evaluations;
      break;
    }
    best = std::move(next);
  }
  return best;
}

void log_line(const CalibrateOptions& opt, const std::string& s) {
  if (opt.progress) std::cerr << s << std::endl;
}

}  // namespace

CalibrationReport calibrate(const std::string& model_file, const std::string& runs_dir, const Registry& base,
                            const CalibrateOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  DiagnoseOptions dopt;
  dopt.threads = std::max(1, opt.threads);
  dopt.sets = opt.sets;
  dopt.progress = opt.progress;
  Engine eng(model_file, base, dopt);
  eng.runs = load_runs(runs_dir, eng.base(), eng.base_probes(), eng.registry(), RunRoles::validation_optional);
  const std::vector<Effect> effects = free_parameters(opt, eng);
  // One phase, the whole run: calibration reports per run and signal.
  eng.phase_names = {"run"};
  for (const auto& run : eng.runs) eng.phases.push_back(std::vector<int>(run.t.size(), 0));
  const Layout cal = eng.layout(Role::calibration), val = eng.layout(Role::validation);
  if (cal.runs.empty())
    throw InputError(SourceLocation{runs_dir, 0, 0}, "", "role",
                     "no calibration run: give at least one run file 'role: calibration' (the default)");

  CalibrationReport rep;
  rep.model_file = model_file;
  rep.runs_dir = runs_dir;
  std::vector<double> start;
  for (const auto& e : effects) start.push_back(e.parameters[0].initial);
  const engine::Model start_model = eng.model(with_values(effects, start));
  const std::vector<double> r0 = eng.residuals({start_model}, cal)[0];
  log_line(opt, "calibrate: " + std::to_string(effects.size()) + " parameter(s) on " + std::to_string(cal.runs.size()) +
                    " calibration run(s); gap " + rounded(gap_of(r0).rms, 4) + " (noise = 1)");
  const Engine::Fit fit = fit_with_restarts(eng, effects, start, cal, r0, opt);
  std::vector<double> value;
  for (const auto& inst : fit.effects) value.push_back(inst.values[0]);
  rep.evaluations = fit.evaluations;

  // Sensitivities at the fit, one step into the range per parameter.
  std::vector<engine::Model> stepped;
  std::vector<double> steps;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    auto v = value;
    steps.push_back(inward_step(effects[i].parameters[0], value[i]));
    v[i] += steps.back();
    stepped.push_back(eng.model(with_values(effects, v)));
  }
  const auto r_step = eng.residuals(stepped, cal);
  std::vector<std::vector<double>> J(effects.size(), std::vector<double>(cal.size));
  for (std::size_t i = 0; i < effects.size(); ++i)
    for (std::size_t s = 0; s < cal.size; ++s) J[i][s] = (r_step[i][s] - fit.r_cal[s]) / steps[i];
  std::vector<double> magnitude;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    const EffectParameter& p = effects[i].parameters[0];
    magnitude.push_back(std::max(std::abs(value[i]), 1e-3 * (p.upper - p.lower)));
  }
  const Uncertainty unc = uncertainty(fit.r_cal, J, magnitude, cal);
  rep.correlation = unc.correlation;
  rep.residual_scale = unc.scale;

  const Netlist& nl = eng.base();
  for (std::size_t i = 0; i < effects.size(); ++i) {
    const EffectParameter& p = effects[i].parameters[0];
    CalibratedParameter c;
    c.name = effects[i].name;
    c.reading = effects[i].recalibrates.empty();
    c.unit = p.unit;
    c.start = p.initial;
    c.value = value[i];
    c.lower = p.lower;
    c.upper = p.upper;
    c.standard_error = unc.se[i];
    c.at_bound = on_bound(p, value[i]);
    show_in_habitual_unit(c, nl);
    rep.parameters.push_back(c);
  }

  rep.calibration_before = gap_of(r0);
  rep.calibration_after = gap_of(fit.r_cal);
  describe(eng, cal, r0, fit.r_cal, eng.base_probes(), rep);
  if (!val.runs.empty()) {
    const auto rv = eng.residuals({start_model, eng.model(fit.effects)}, val);
    rep.validation_before = gap_of(rv[0]);
    rep.validation_after = gap_of(rv[1]);
    describe(eng, val, rv[0], rv[1], eng.base_probes(), rep);
  }
  const auto failed = eng.failures_since(0);
  rep.failed_runs = static_cast<long>(failed.size());
  for (const auto& f : failed)
    if (rep.run_failures.size() < kKeptFailures) rep.run_failures.push_back(f);
  rep.simulations = eng.simulations;
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return rep;
}

namespace {

std::string with_unit(double v, int digits, const std::string& unit) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return unit.empty() || unit == "1" ? buf : buf + (" " + unit);
}

std::string shown_text(const CalibratedParameter& c, double si) { return with_unit(c.shown(si), 5, c.shown_unit); }
// A spread (standard error) is shown on the unit's scale alone.
std::string spread_text(const CalibratedParameter& c, double si) {
  return std::isfinite(si) ? with_unit(si / c.shown_scale, 2, units::difference_unit(c.shown_unit))
                           : "not determined by the data";
}

std::string role_name(Role r) { return r == Role::calibration ? "calibration" : "validation"; }

}  // namespace

std::string calibration_summary(const CalibrationReport& rep) {
  std::ostringstream o;
  for (const auto& c : rep.parameters) {
    o << c.name << " = " << shown_text(c, c.value) << " +- " << spread_text(c, c.standard_error)
      << " (1 standard error; netlist " << shown_text(c, c.start) << ", range " << shown_text(c, c.lower) << " .. "
      << shown_text(c, c.upper) << ")";
    if (c.at_bound) o << " - AT ITS BOUND: the range, not the data, holds it";
    o << "\n";
  }
  for (std::size_t i = 0; i < rep.parameters.size(); ++i)
    for (std::size_t j = i + 1; j < rep.parameters.size(); ++j)
      o << "correlation " << rep.parameters[i].name << " / " << rep.parameters[j].name << ": "
        << (std::isfinite(rep.correlation[i][j]) ? rounded(rep.correlation[i][j], 3) : std::string("undetermined")) << "\n";
  for (const auto& g : rep.gaps)
    o << role_name(g.role) << " run " << g.run << ", " << g.signal << ": RMS " << rounded(g.rms_before_si / g.shown_scale, 4)
      << " -> " << rounded(g.rms_after_si / g.shown_scale, 4) << " " << g.shown_unit << " (" << rounded(g.rms_before, 4) << " -> "
      << rounded(g.rms_after, 4) << " noise sd)\n";
  o << "calibration gap " << rounded(rep.calibration_before.rms, 4) << " -> " << rounded(rep.calibration_after.rms, 4)
    << " (noise = 1)";
  if (rep.validation_before.n)
    o << "; validation gap " << rounded(rep.validation_before.rms, 4) << " -> " << rounded(rep.validation_after.rms, 4);
  o << "\n" << rep.simulations << " simulations in " << rounded(rep.seconds, 3) << " s";
  if (rep.failed_runs) o << "; " << rep.failed_runs << " failed, first: " << rep.run_failures.front();
  o << "\n";
  return o.str();
}

std::string calibration_snippet(const CalibrationReport& rep) {
  std::ostringstream top, comps, reading;
  std::map<std::string, std::vector<const CalibratedParameter*>> by_component;
  for (const auto& c : rep.parameters) {
    const auto dot = c.name.find('.');
    if (c.reading)
      reading << "#   " << c.name << " = " << shown_text(c, c.value) << " +- " << spread_text(c, c.standard_error)
              << (c.at_bound ? ", at its bound" : "") << "\n";
    else if (dot == std::string::npos)
      top << "  " << c.name << ": " << shown_text(c, c.value) << "   # +- " << spread_text(c, c.standard_error)
          << (c.at_bound ? ", at its bound" : "") << "\n";
    else
      by_component[c.name.substr(0, dot)].push_back(&c);
  }
  for (const auto& [component, params] : by_component) {
    comps << "  " << component << ": {";
    std::string notes;
    for (std::size_t i = 0; i < params.size(); ++i) {
      const auto& c = *params[i];
      const std::string name = c.name.substr(c.name.find('.') + 1);
      comps << (i ? ", " : "") << name << ": " << shown_text(c, c.value);
      notes += (i ? "; " : "") + name + " +- " + spread_text(c, c.standard_error) + (c.at_bound ? ", at its bound" : "");
    }
    comps << "}   # merge into " << component << "'s line; " << notes << "\n";
  }
  std::string out = "# pneumo calibrate: " + rep.model_file + " fitted to " + rep.runs_dir + " (+- one standard error)\n";
  if (!top.str().empty()) out += "parameters:\n" + top.str();
  if (!comps.str().empty()) out += "components:\n" + comps.str();
  if (!reading.str().empty()) out += "# the readings' errors (not netlist values; the measured data carry them):\n" + reading.str();
  return out;
}

void write_calibration_json(const CalibrationReport& rep, const std::string& path) {
  using json::num;
  using json::str;
  std::ostringstream o;
  o << "{\n  \"model\": " << str(rep.model_file) << ",\n  \"runs\": " << str(rep.runs_dir) << ",\n  \"parameters\": [";
  for (std::size_t i = 0; i < rep.parameters.size(); ++i) {
    const auto& c = rep.parameters[i];
    o << (i ? "," : "") << "\n    {\"name\": " << str(c.name) << ", \"unit\": " << str(c.unit)
      << ", \"value\": " << num(c.value) << ", \"standard_error\": " << num(c.standard_error)
      << ", \"start\": " << num(c.start) << ", \"lower\": " << num(c.lower) << ", \"upper\": " << num(c.upper)
      << ", \"at_bound\": " << (c.at_bound ? "true" : "false") << ", \"shown_unit\": " << str(c.shown_unit)
      << ", \"shown_value\": " << num(c.shown(c.value)) << "}";
  }
  o << "\n  ],\n  \"correlation\": [";
  for (std::size_t i = 0; i < rep.correlation.size(); ++i) {
    o << (i ? ", " : "") << "[";
    for (std::size_t j = 0; j < rep.correlation[i].size(); ++j) o << (j ? ", " : "") << num(rep.correlation[i][j]);
    o << "]";
  }
  o << "],\n  \"residual_scale\": " << num(rep.residual_scale) << ",\n  \"gaps\": [";
  for (std::size_t i = 0; i < rep.gaps.size(); ++i) {
    const auto& g = rep.gaps[i];
    o << (i ? "," : "") << "\n    {\"run\": " << str(g.run) << ", \"signal\": " << str(g.signal)
      << ", \"role\": " << str(role_name(g.role)) << ", \"unit\": " << str(g.unit) << ", \"sigma\": " << num(g.sigma)
      << ", \"rms_before\": " << num(g.rms_before_si) << ", \"rms_after\": " << num(g.rms_after_si)
      << ", \"gap_before\": " << num(g.rms_before) << ", \"gap_after\": " << num(g.rms_after) << "}";
  }
  o << "\n  ],\n  \"calibration_gap\": {\"before\": " << num(rep.calibration_before.rms)
    << ", \"after\": " << num(rep.calibration_after.rms) << "},\n  \"validation_gap\": ";
  if (rep.validation_before.n)
    o << "{\"before\": " << num(rep.validation_before.rms) << ", \"after\": " << num(rep.validation_after.rms) << "}";
  else
    o << "null";
  o << ",\n  \"simulations\": " << rep.simulations << ",\n  \"failed_runs\": " << rep.failed_runs
    << ",\n  \"run_failures\": [";
  for (std::size_t i = 0; i < rep.run_failures.size(); ++i) o << (i ? ", " : "") << str(rep.run_failures[i]);
  o << "],\n  \"seconds\": " << num(rep.seconds) << "\n}\n";
  write_text_atomic(path, o.str());
}

}  // namespace pneumo::diagnose
