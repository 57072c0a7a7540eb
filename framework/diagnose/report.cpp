// report.json and a self-contained report.html (inline SVG, no network).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "framework/core/text.hpp"
#include "framework/core/units.hpp"
#include "framework/io/results.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "framework/diagnose/json_text.hpp"
#include "framework/diagnose/unexplained.hpp"

namespace pneumo::diagnose {

namespace {

using json::num;
using json::str;

std::string html(const std::string& s) { return markup_escaped(s); }

// Phase shading, repeated when there are more phases.
const char* const kShade[] = {"#f4f4f4", "#fff4e0", "#eef6ff", "#ffecec", "#eefbee", "#f6eeff"};
const char* shade(std::size_t p) { return kShade[p % 6]; }

std::string gap_json(const GapTable& g, const std::vector<std::string>& phases) {
  std::ostringstream o;
  const double tot = g.total.ssr > 0 ? g.total.ssr : 1;
  o << "{\"total\": " << num(g.total.rms) << ", \"by_signal\": {";
  for (std::size_t s = 0; s < g.signals.size(); ++s) {
    o << (s ? ", " : "") << str(g.signals[s]) << ": {\"gap\": " << num(g.by_signal[s].rms)
      << ", \"share\": " << num(g.by_signal[s].ssr / tot) << ", \"by_phase\": {";
    for (std::size_t p = 0; p < phases.size(); ++p)
      o << (p ? ", " : "") << str(phases[p]) << ": {\"gap\": " << num(g.by_phase[s][p].rms)
        << ", \"share\": " << num(g.by_phase[s][p].ssr / tot) << ", \"samples\": " << g.by_phase[s][p].n << "}";
    o << "}}";
  }
  o << "}, \"by_phase\": {";
  for (std::size_t p = 0; p < phases.size(); ++p)
    o << (p ? ", " : "") << str(phases[p]) << ": {\"gap\": " << num(g.phase_total[p].rms)
      << ", \"share\": " << num(g.phase_total[p].ssr / tot) << "}";
  o << "}}";
  return o.str();
}

// Gaps are RMS residuals over a noise level estimated to about 10 %: two digits.
std::string gap(double v) { return rounded(v, 2); }

// How the report shows a quantity of an SI unit: bar, mm, degC, cm3,
// dm3/(s*bar), ms; other units as they are. A `difference` (a noise level)
// takes no offset (K, not degC). Pressures in the model are absolute.
struct Shown {
  std::string label;
  double scale = 1, offset = 0;
  double operator()(double si) const { return (si - offset) / scale; }
};

Shown shown(const std::string& si_unit, bool difference = false) {
  static const std::vector<std::pair<units::Dimension, std::string>> kEngineering = {
      {units::dims::pressure, "bar"}, {units::dims::length, "mm"},   {units::dims::temperature, "degC"},
      {units::dims::volume, "cm3"},   {units::dims::time, "ms"},     {units::dims::sonic_conductance, "dm3/(s*bar)"}};
  try {
    const units::Unit u = units::parse_unit(si_unit);
    if (u.scale != 1 || u.affine() || u.dim.dimensionless()) return {si_unit};
    for (const auto& [dim, name] : kEngineering) {
      if (u.dim != dim) continue;
      if (difference && dim == units::dims::temperature) return {"K"};
      const units::Unit e = units::parse_unit(name);
      return {dim == units::dims::pressure && !difference ? "bar abs" : name, e.scale, difference ? 0.0 : e.offset};
    }
  } catch (const units::ParseError&) {
  }
  return {si_unit};
}

// Whether an effect's parameter j is a difference of its quantity: one
// whose null is 0 (an offset, a leak, a delay) is an amount - a pressure
// offset in bar, not bar abs; a temperature offset in K, not degC - and a
// pressure difference re-calibrated (a cracking pressure) is one.
bool is_difference(const EffectResult& e, std::size_t j) {
  return (j < e.parameter_nulls.size() && e.parameter_nulls[j] == 0) ||
         (j < e.parameter_differences.size() && e.parameter_differences[j]);
}

std::string unit_of(const DiagnosisReport& r, const std::string& signal) {
  for (const auto& [n, u] : r.signal_units)
    if (n == signal) return u;
  return "";
}

double noise_of(const DiagnosisReport& r, const std::string& signal) {
  for (const auto& [n, v] : r.noise)
    if (n == signal) return v;
  return NAN;
}

// Axis ticks at 1, 2 or 5 times a power of ten, about `want` of them.
std::vector<double> ticks(double lo, double hi, int want, int* decimals) {
  const double raw = (hi - lo) / want, mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag, step = (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
  *decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
  std::vector<double> out;
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + 1e-9 * step; v += step) out.push_back(v);
  return out;
}

std::string fixed(double v, int decimals) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, std::fabs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

// Tick marks, grid lines and labels of one axis. `horizontal`: the time axis.
void axis(std::ostringstream& o, bool horizontal, double lo, double hi, int want, const std::function<double(double)>& at,
          double from, double to) {
  int dec = 0;
  for (double v : ticks(lo, hi, want, &dec)) {
    const double c = at(v);
    if (horizontal)
      o << "<line x1=\"" << c << "\" y1=\"" << from << "\" x2=\"" << c << "\" y2=\"" << to
        << "\" stroke=\"#e4e4e4\"/><text x=\"" << c << "\" y=\"" << to + 14
        << "\" font-size=\"11\" text-anchor=\"middle\">" << fixed(v, dec) << "</text>\n";
    else
      o << "<line x1=\"" << from << "\" y1=\"" << c << "\" x2=\"" << to << "\" y2=\"" << c
        << "\" stroke=\"#e4e4e4\"/><text x=\"" << from - 4 << "\" y=\"" << c + 4
        << "\" font-size=\"11\" text-anchor=\"end\">" << fixed(v, dec) << "</text>\n";
  }
}

// One validation run and signal: measured against simulated in the signal's
// engineering unit (top) and the residuals in noise units (bottom, the band
// is +-1 noise sd, where a model that explains the data stays), phases shaded.
std::string svg_plot(const TracePlot& p, const std::vector<std::string>& phases, const Shown& u, double sigma) {
  const double W = 580, l = 64, r = 12, t = 24, h1 = 180, h2 = sigma > 0 ? 80 : 0, top2 = t + h1 + 10, b = 36;
  const double H = top2 + h2 + b;
  double t0 = p.t.front(), t1 = p.t.back(), lo = INFINITY, hi = -INFINITY, R = 2;
  for (const auto* v : {&p.measured, &p.before, &p.after})
    for (double y : *v)
      if (std::isfinite(y)) lo = std::min(lo, u(y)), hi = std::max(hi, u(y));
  if (!(hi > lo)) hi = lo + 1;
  const double pad = 0.05 * (hi - lo);
  lo -= pad, hi += pad;
  std::vector<double> res_before, res_after;
  for (std::size_t i = 0; i < p.t.size(); ++i) {
    res_before.push_back((p.measured[i] - p.before[i]) / sigma);
    res_after.push_back((p.measured[i] - p.after[i]) / sigma);
    for (double z : {res_before.back(), res_after.back()})
      if (std::isfinite(z)) R = std::max(R, 1.05 * std::fabs(z));
  }
  auto X = [&](double x) { return l + (x - t0) / (t1 - t0) * (W - l - r); };
  auto Y = [&](double y) { return t + (hi - y) / (hi - lo) * h1; };
  auto Z = [&](double z) { return top2 + (R - z) / (2 * R) * h2; };
  std::ostringstream o;
  o << "<svg class=\"trace\" data-run=\"" << html(p.run) << "\" data-signal=\"" << html(p.signal)
    << "\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << W << " " << H << "\">\n";
  for (std::size_t ph = 0; ph + 1 < p.phase_times.size() && ph < phases.size(); ++ph) {
    const double a = X(std::max(t0, p.phase_times[ph])), c = X(std::min(t1, p.phase_times[ph + 1]));
    if (c > a) o << "<rect x=\"" << a << "\" y=\"" << t << "\" width=\"" << c - a << "\" height=\"" << top2 + h2 - t
                 << "\" fill=\"" << shade(ph) << "\"><title>" << html(phases[ph]) << "</title></rect>\n";
  }
  axis(o, true, t0, t1, 6, X, t, top2 + h2);
  axis(o, false, lo, hi, 5, Y, l, W - r);
  auto line = [&](const std::vector<double>& v, const std::function<double(double)>& at, const char* color,
                  const char* cls, double width) {
    o << "<polyline class=\"" << cls << "\" fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << width
      << "\" points=\"";
    for (std::size_t i = 0; i < v.size(); ++i)
      if (std::isfinite(v[i])) o << rounded(X(p.t[i]), 5) << "," << rounded(at(v[i]), 5) << " ";
    o << "\"/>\n";
  };
  const auto shown_value = [&](double si) { return Y(u(si)); };
  line(p.measured, shown_value, "#999", "measured", 2.5);
  line(p.before, shown_value, "#d62728", "before", 1.2);
  line(p.after, shown_value, "#1f77b4", "after", 1.2);
  o << "<rect x=\"" << l << "\" y=\"" << t << "\" width=\"" << W - l - r << "\" height=\"" << h1
    << "\" fill=\"none\" stroke=\"#888\"/>\n";
  if (h2 > 0) {
    axis(o, false, -R, R, 4, Z, l, W - r);
    o << "<rect x=\"" << l << "\" y=\"" << Z(1) << "\" width=\"" << W - l - r << "\" height=\"" << Z(-1) - Z(1)
      << "\" fill=\"#999\" fill-opacity=\"0.35\"/>\n";
    line(res_before, Z, "#d62728", "residual-before", 1);
    line(res_after, Z, "#1f77b4", "residual-after", 1);
    o << "<rect x=\"" << l << "\" y=\"" << top2 << "\" width=\"" << W - l - r << "\" height=\"" << h2
      << "\" fill=\"none\" stroke=\"#888\"/><text x=\"" << l + 4 << "\" y=\"" << top2 + 11
      << "\" font-size=\"10\" fill=\"#555\">residual / noise</text>\n";
  }
  o << "<text x=\"" << (l + W - r) / 2 << "\" y=\"" << H - 4 << "\" font-size=\"11\" text-anchor=\"middle\">t [s]</text>";
  o << "<text x=\"" << l << "\" y=\"" << t - 8 << "\" font-size=\"12\"><tspan font-weight=\"bold\">" << html(p.signal)
    << "</tspan> [" << html(u.label) << "], " << html(p.run) << "</text>\n</svg>\n";
  return o.str();
}

// Validation gap per phase and in total, before and after the verdict, as
// RMS residual over noise on one linear axis (the dashed line: noise = 1),
// so that the after bars show what is left, not a share of a shrunken total.
std::string svg_phase_bars(const DiagnosisReport& r) {
  std::vector<std::string> names = r.phase_names;
  std::vector<std::pair<double, double>> v;
  for (std::size_t p = 0; p < names.size() && p < r.validation_before.phase_total.size(); ++p)
    v.push_back({r.validation_before.phase_total[p].rms,
                 p < r.validation_after.phase_total.size() ? r.validation_after.phase_total[p].rms : NAN});
  names.resize(v.size());
  names.push_back("all phases");
  v.push_back({r.validation_before.total.rms, r.validation_after.total.rms});
  double hi = 1.2;
  for (const auto& [b, a] : v) hi = std::max({hi, std::isfinite(b) ? b : 0.0, std::isfinite(a) ? a : 0.0});
  hi *= 1.08;
  const double W = 900, l = 120, r_margin = 60, bar = 13, group = 2 * bar + 12, t = 20;
  const double H = t + group * v.size() + 34;
  auto X = [&](double g) { return l + g / hi * (W - l - r_margin); };
  std::ostringstream o;
  o << "<svg id=\"phase-bars\" xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << W << " " << H
    << "\" style=\"max-width:" << W << "px\">\n";
  axis(o, true, 0, hi, 8, X, t, H - 34);
  for (std::size_t p = 0; p < v.size(); ++p) {
    const double y = t + p * group + 4;
    o << "<text x=\"" << l - 6 << "\" y=\"" << y + bar + 4 << "\" font-size=\"12\" text-anchor=\"end\""
      << (p + 1 == v.size() ? " font-weight=\"bold\"" : "") << ">" << html(names[p]) << "</text>";
    const double vals[2] = {v[p].first, v[p].second};
    for (int k = 0; k < 2; ++k) {
      if (!std::isfinite(vals[k])) continue;
      const double yy = y + k * bar, w = X(vals[k]) - l;
      o << "<rect class=\"phase-bar " << (k ? "after" : "before") << "\" x=\"" << l << "\" y=\"" << yy
        << "\" width=\"" << std::max(w, 1.0) << "\" height=\"" << bar - 1 << "\" fill=\"" << (k ? "#1f77b4" : "#d62728")
        << "\"><title>" << html(names[p]) << ", " << (k ? "after" : "before") << ": " << gap(vals[k])
        << "</title></rect><text x=\"" << l + w + 4 << "\" y=\"" << yy + bar - 3 << "\" font-size=\"11\">"
        << gap(vals[k]) << "</text>\n";
    }
  }
  o << "<line x1=\"" << X(1) << "\" y1=\"" << t << "\" x2=\"" << X(1) << "\" y2=\"" << H - 34
    << "\" stroke=\"#333\" stroke-dasharray=\"4,3\"/><text x=\"" << X(1) << "\" y=\"" << t - 6
    << "\" font-size=\"11\" text-anchor=\"middle\">noise</text>\n<text x=\"" << (l + W - r_margin) / 2 << "\" y=\"" << H - 4
    << "\" font-size=\"11\" text-anchor=\"middle\">validation gap: RMS of (measured - simulated) / noise</text>\n</svg>\n";
  return o.str();
}

// A next run's setting in the unit --experiment gave, else the report's
// engineering unit, three digits: "z_EC = 0.1 rev", "p_supply = 6.5 bar abs".
std::string setting_text(const NextRunSetting& s) {
  if (!s.shown_unit.empty())
    return s.name + " = " + rounded((s.value - s.shown_offset) / s.shown_scale, 3) + " " + s.shown_unit;
  const Shown u = shown(s.unit);
  return s.name + " = " + rounded(u(s.value), 3) + (u.label.empty() || u.label == "1" ? "" : " " + u.label);
}

std::string settings_text(const NextRun& n) {
  std::string out;
  for (const auto& s : n.operating_point) out += (out.empty() ? "" : ", ") + setting_text(s);
  return out;
}

}  // namespace

std::string next_run_sentence(const NextRun& n) {
  if (!n.decisive)
    return "no run within the ranges searched tells " + n.effect_a + " from " + n.effect_b + " (at best " +
           rounded(n.separation, 2) + " noise sd apart, at " + settings_text(n) + ")" +
           (n.sensor.empty() ? "" : "; " + n.sensor);
  return "to tell " + n.effect_a + " from " + n.effect_b + ", run at " + settings_text(n) + ": " +
         rounded(n.separation, 2) + " noise sd apart in " + n.signal +
         (n.phase.empty() ? "" : ", mostly during " + n.phase) + " (" + rounded(n.separation_measured, 2) +
         " at the measured runs' points)" + (n.sensor.empty() ? "" : "; or " + n.sensor);
}

// The missing term's form (form.hpp), when one was found and simulated.
std::string form_clause(const DiagnosisReport& r) {
  if (!r.unexplained || !r.unexplained->form) return "";
  const FormFinding& f = *r.unexplained->form;
  if (!f.confirmed || f.terms.empty()) return "";
  return std::string("; ") + (f.beats_shape ? "its form: " : "a lead on its form: ") + f.formula + " (gap then " +
         rounded(f.gap_after, 2) + ")";
}

namespace {
// The report's result for the effect named `effect` (null: none).
const EffectResult* find_effect(const DiagnosisReport& r, const std::string& effect) {
  for (const auto& e : r.effects)
    if (e.name == effect) return &e;
  return nullptr;
}

// The diagnosis names a setting before a part of the same component it is
// grouped with (diagnose.cpp); the page says so only where that happened.
bool setting_before_own_part(const DiagnosisReport& r, const std::vector<std::string>& group) {
  const EffectResult* first = find_effect(r, group[0]);
  if (!first || !first->setting || first->component.empty()) return false;
  for (std::size_t j = 1; j < group.size(); ++j) {
    const EffectResult* other = find_effect(r, group[j]);
    if (other && !other->setting && other->component == first->component) return true;
  }
  return false;
}
}  // namespace

std::string verdict_sentence(const DiagnosisReport& r) {
  std::string named;
  for (const auto& v : r.verdict) named += (named.empty() ? "" : ", then ") + v;
  const std::string left = rounded(r.validation_after.total.rms, 2);
  if (named.empty())
    return r.unexplained ? "none: no candidate effect explains the gap of " + left +
                               " times the noise (validation gap " + left + ", noise = 1)" + form_clause(r)
                         : "none needed: the model explains the data within noise (validation gap " + left +
                               ", noise = 1)";
  std::string next;
  const auto decisive = std::find_if(r.next_runs.begin(), r.next_runs.end(), [](const NextRun& n) { return n.decisive; });
  if (decisive != r.next_runs.end()) {
    const NextRun& n = *decisive;
    next = "; a run at " + settings_text(n) + " would tell " + n.effect_a + " from " + n.effect_b + " (" +
           rounded(n.separation, 2) + " noise sd apart in " + n.signal + ")";
  }
  return named + (r.unexplained ? "; a gap of " + left + " times the noise remains unexplained"
                                : "; the validation gap is then " + left + " (noise = 1)") + form_clause(r) + next;
}

void write_report_json(const DiagnosisReport& r, const std::string& path) {
  std::ostringstream o;
  o << "{\n\"model\": " << str(r.model_file) << ",\n\"catalogue\": " << str(r.catalogue_file)
    << ",\n\"runs\": " << str(r.runs_dir) << ",\n\"verdict_sentence\": " << str(verdict_sentence(r))
    << ",\n\"verdict\": [";
  for (std::size_t i = 0; i < r.verdict.size(); ++i) o << (i ? ", " : "") << str(r.verdict[i]);
  o << "],\n\"verdict_groups\": [";
  for (std::size_t i = 0; i < r.verdict_groups.size(); ++i) {
    o << (i ? ", " : "") << "[";
    for (std::size_t j = 0; j < r.verdict_groups[i].size(); ++j) o << (j ? ", " : "") << str(r.verdict_groups[i][j]);
    o << "]";
  }
  o << "],\n\"verdict_parameters\": {";
  for (std::size_t i = 0; i < r.final_values.size(); ++i) {
    o << (i ? ", " : "") << str(r.final_values[i].first) << ": [";
    for (std::size_t j = 0; j < r.final_values[i].second.size(); ++j) o << (j ? ", " : "") << num(r.final_values[i].second[j]);
    o << "]";
  }
  o << "},\n\"calibration_runs\": [";
  for (std::size_t i = 0; i < r.calibration_runs.size(); ++i) o << (i ? ", " : "") << str(r.calibration_runs[i]);
  o << "],\n\"validation_runs\": [";
  for (std::size_t i = 0; i < r.validation_runs.size(); ++i) o << (i ? ", " : "") << str(r.validation_runs[i]);
  o << "],\n\"noise\": {";
  for (std::size_t i = 0; i < r.noise.size(); ++i) o << (i ? ", " : "") << str(r.noise[i].first) << ": " << num(r.noise[i].second);
  o << "},\n\"signal_units\": {";
  for (std::size_t i = 0; i < r.signal_units.size(); ++i)
    o << (i ? ", " : "") << str(r.signal_units[i].first) << ": " << str(r.signal_units[i].second);
  o << "},\n\"unpatched_model_failed_runs\": " << r.base_failed_runs << ",\n\"unpatched_model_run_failures\": [";
  for (std::size_t i = 0; i < r.base_run_failures.size(); ++i) o << (i ? ", " : "") << str(r.base_run_failures[i]);
  o << "],\n\"gap_unit\": \"RMS of (measured - simulated)/noise; 1 = the noise level\",";
  o << "\n\"where\": {\"validation_before\": " << gap_json(r.validation_before, r.phase_names)
    << ",\n  \"validation_after\": " << gap_json(r.validation_after, r.phase_names)
    << ",\n  \"calibration_before\": " << gap_json(r.calibration_before, r.phase_names) << ",\n  \"significant_windows\": [";
  for (std::size_t i = 0; i < r.windows.size(); ++i) {
    const auto& w = r.windows[i];
    o << (i ? ",\n    " : "\n    ") << "{\"run\": " << str(w.run) << ", \"signal\": " << str(w.signal)
      << ", \"t_start\": " << num(w.t0) << ", \"t_end\": " << num(w.t1) << ", \"gap\": " << num(w.rms)
      << ", \"z\": " << num(w.z) << "}";
  }
  o << "]},\n\"effects\": [";
  for (std::size_t i = 0; i < r.effects.size(); ++i) {
    const auto& e = r.effects[i];
    o << (i ? ",\n  " : "\n  ") << "{\"name\": " << str(e.name) << ", \"rank\": " << e.rank;
    if (!e.component.empty())
      o << ", \"component\": " << str(e.component) << ", \"fault\": " << str(e.fault)
        << ", \"setting\": " << (e.setting ? "true" : "false");
    o << ", \"description\": " << str(e.description);
    if (!e.unavailable.empty()) o << ", \"status\": " << str(e.unavailable);
    else if (e.screened_out && e.failed_runs)
      o << ", \"status\": \"screened out: " << e.failed_runs << " run(s) of it failed\"";
    else if (e.screened_out) o << ", \"status\": \"screened out (linearised improvement too small)\"";
    else if (e.failed_validation_runs)
      o << ", \"status\": \"fitted; the solver failed on " << e.failed_validation_runs
        << " validation run(s) at the fitted values\"";
    else o << ", \"status\": \"fitted\"";
    o << ", \"parameters\": {";
    for (std::size_t j = 0; j < e.parameter_names.size(); ++j)
      o << (j ? ", " : "") << str(e.parameter_names[j]) << ": {\"value\": " << num(e.values[j])
        << ", \"unit\": " << str(e.parameter_units[j])
        << (j < e.parameter_nulls.size() && std::isfinite(e.parameter_nulls[j]) ? ", \"null\": " + num(e.parameter_nulls[j])
                                                                                 : "")
        << (e.netlist_value ? ", \"netlist_value\": " + num(*e.netlist_value) : "")
        << (is_difference(e, j) ? ", \"difference\": true" : "") << "}";
    o << "}, \"validation_gap_before\": " << num(e.gap_before) << ", \"validation_gap_after\": " << num(e.gap_after)
      << ", \"screening_improvement\": " << num(e.screening_improvement) << ", \"significance\": {\"significant\": "
      << (e.significant ? "true" : "false") << ", \"lr_effective\": " << num(e.lr_eff)
      << ", \"n_effective\": " << num(e.n_eff) << ", \"delta_bic\": " << num(e.delta_bic)
      << ", \"p_value\": " << num(e.p_value) << "}, \"group\": [";
    for (std::size_t j = 0; j < e.group.size(); ++j) o << (j ? ", " : "") << str(e.group[j]);
    o << "]";
    if (e.failed_runs) {
      o << ", \"failed_runs\": " << e.failed_runs << ", \"run_failures\": [";
      for (std::size_t j = 0; j < e.run_failures.size(); ++j) o << (j ? ", " : "") << str(e.run_failures[j]);
      o << "]";
    }
    if (!e.unavailable.empty() || e.screened_out) o << "}";
    else o << ", \"where_after\": " << gap_json(e.validation_after, r.phase_names) << "}";
  }
  o << "],\n\"sensors\": [";
  for (std::size_t i = 0; i < r.sensors.size(); ++i) {
    const auto& c = r.sensors[i];
    o << (i ? ",\n  " : "\n  ") << "{\"effects\": [" << str(c.effect_a) << ", " << str(c.effect_b)
      << "], \"measured_best\": {\"signal\": " << str(c.measured_signal)
      << ", \"separation\": " << num(c.measured_separation) << "}, \"best\": [";
    for (std::size_t j = 0; j < c.best.size(); ++j)
      o << (j ? ", " : "") << "{\"quantity\": " << str(c.best[j].quantity) << ", \"unit\": " << str(c.best[j].unit)
        << ", \"sigma\": " << num(c.best[j].sigma) << ", \"separation\": " << num(c.best[j].separation) << "}";
    o << "], \"run_failures\": [";
    for (std::size_t j = 0; j < c.run_failures.size(); ++j) o << (j ? ", " : "") << str(c.run_failures[j]);
    o << "]}";
  }
  o << "],\n\"next_run\": [";
  for (std::size_t i = 0; i < r.next_runs.size(); ++i) {
    const auto& n = r.next_runs[i];
    o << (i ? ",\n  " : "\n  ") << "{\"effects\": [";
    for (std::size_t j = 0; j < n.effects.size(); ++j) o << (j ? ", " : "") << str(n.effects[j]);
    o << "], \"operating_point\": {";
    for (std::size_t j = 0; j < n.operating_point.size(); ++j) {
      const auto& p = n.operating_point[j];
      o << (j ? ", " : "") << str(p.name) << ": {\"value\": " << num(p.value) << ", \"unit\": " << str(p.unit)
        << ", \"searched\": [" << num(p.lower) << ", " << num(p.upper) << "], \"shown\": " << str(setting_text(p)) << "}";
    }
    o << "}, \"template_run\": " << str(n.template_run) << ", \"separation\": " << num(n.separation)
      << ", \"separation_measured\": " << num(n.separation_measured) << ", \"closest\": [" << str(n.effect_a) << ", "
      << str(n.effect_b) << "], \"signal\": " << str(n.signal) << ", \"phase\": " << str(n.phase)
      << ", \"decisive\": " << (n.decisive ? "true" : "false") << ", \"sentence\": " << str(next_run_sentence(n)) << ", \"points\": " << n.points
      << ", \"simulations\": " << n.simulations << ", \"failed_simulations\": " << n.failed_simulations << "}";
  }
  o << "],\n\"unexplained\": " << unexplained_json(r.unexplained, num, str);
  o << ",\n\"seconds\": " << num(r.seconds) << ",\n\"simulations\": " << r.simulations << "\n}\n";
  write_text_atomic(path, o.str());
}

namespace {

// A fitted parameter in its engineering unit, three digits (the report gives
// no confidence interval that would say more).
std::string parameter(double si, const std::string& unit, bool difference = false) {
  const Shown u = shown(unit, difference);
  return rounded(u(si), 3) + (u.label.empty() || u.label == "1" ? "" : " " + u.label);
}

// An effect's parameter j at `si`: one whose null is 0 (an offset, a leak,
// a delay) is an amount, shown as a difference (is_difference).
std::string effect_parameter(const EffectResult& e, std::size_t j, double si) {
  return parameter(si, e.parameter_units[j], is_difference(e, j));
}

// A re-calibrated value beside the netlist's: " (netlist 0.35 dm3/(s*bar), +1.1 %)" -
// whether the data ask for a setting off by a tolerance or by a factor.
std::string from_netlist(double si, const std::optional<double>& netlist, const std::string& unit,
                         bool difference) {
  if (!netlist || *netlist == 0) return "";
  const double pct = 100 * (si / *netlist - 1);
  return " (netlist " + parameter(*netlist, unit, difference) + ", " + (pct >= 0 ? "+" : "") + rounded(pct, 2) + " %)";
}

// A value beside its null: " (null 1, +32 %)", or " (null 0)" where no
// relative change means anything.
std::string from_null(double si, double null, const std::string& unit) {
  if (!std::isfinite(null)) return "";
  if (null == 0) return " (null 0)";
  const double pct = 100 * (si / null - 1);
  return " (null " + parameter(null, unit) + ", " + (pct >= 0 ? "+" : "") + rounded(pct, 2) + " %)";
}

// A verdict slot's values at the verdict's joint fit - what the verdict
// model was simulated with, not the effect's single fit: " = 0.357
// dm3/(s*bar) (netlist 0.35 dm3/(s*bar), +2.2 %)" for a re-calibration,
// ": k = 1.32 (null 1, +32 %), C = ..." for an effect.
std::string recalibrated(const DiagnosisReport& r, std::size_t slot) {
  const std::string& name = r.verdict_groups[slot][0];
  for (const auto& e : r.effects) {
    if (e.name != name) continue;
    for (const auto& [n, values] : r.final_values) {
      if (n != name) continue;
      if (e.netlist_value && values.size() == 1)
        return " = " + effect_parameter(e, 0, values[0]) +
               from_netlist(values[0], e.netlist_value, e.parameter_units[0], is_difference(e, 0));
      std::string out;
      for (std::size_t j = 0; j < values.size() && j < e.parameter_names.size(); ++j)
        out += (j ? ", " : ": ") + e.parameter_names[j] + " = " + effect_parameter(e, j, values[j]) +
               (j < e.parameter_nulls.size() ? from_null(values[j], e.parameter_nulls[j], e.parameter_units[j]) : "");
      return out;
    }
  }
  return "";
}

// p-values below what the effective sample size can mean are shown as a bound.
std::string p_value(double p) { return p < 1e-4 ? "&lt; 0.0001" : rounded(p, 2); }

std::string share(double part, double total) {
  const double pct = 100 * part / (total > 0 ? total : 1);
  return pct < 0.1 ? "&lt; 0.1 %" : rounded(pct, 2) + " %";
}

std::string file_name(const std::string& path) {
  return "<code title=\"" + html(path) + "\">" + html(std::filesystem::path(path).filename().string()) + "</code>";
}

// The validation gap by phase and signal: bars, table, shares, windows.
void gap_section(std::ostream& o, const DiagnosisReport& r) {
  o << "<h2>Gap by phase and signal (validation runs)</h2>\n"
    << "<p class=\"legend\"><span style=\"color:#d62728\">&#9632; unpatched model</span>"
       "<span style=\"color:#1f77b4\">&#9632; with the verdict's effects</span></p>\n"
    << svg_phase_bars(r);
  o << "<table id=\"gap-table\"><tr><th rowspan=\"2\">signal</th><th rowspan=\"2\">noise (1 sd)</th>";
  for (const auto& p : r.phase_names) o << "<th colspan=\"2\">" << html(p) << "</th>";
  o << "<th colspan=\"2\">all phases</th><th rowspan=\"2\">share of the gap before</th></tr>\n<tr>";
  for (std::size_t p = 0; p <= r.phase_names.size(); ++p) o << "<th>before</th><th>after</th>";
  o << "</tr>\n";
  for (std::size_t s = 0; s < r.validation_before.signals.size(); ++s) {
    const std::string& name = r.validation_before.signals[s];
    const double sigma = noise_of(r, name);
    const Shown du = shown(unit_of(r, name), true);
    const bool has_after = s < r.validation_after.by_signal.size();
    o << "<tr><td class=\"l\">" << html(name) << "</td><td>" << rounded(du(sigma), 2) << " " << html(du.label) << "</td>";
    for (std::size_t p = 0; p < r.phase_names.size(); ++p)
      o << "<td>" << gap(r.validation_before.by_phase[s][p].rms) << "</td><td>"
        << (has_after ? gap(r.validation_after.by_phase[s][p].rms) : "") << "</td>";
    o << "<td><b>" << gap(r.validation_before.by_signal[s].rms) << "</b></td><td><b>"
      << (has_after ? gap(r.validation_after.by_signal[s].rms) : "") << "</b></td><td>"
      << share(r.validation_before.by_signal[s].ssr, r.validation_before.total.ssr) << "</td></tr>\n";
  }
  o << "</table>\n<p id=\"phase-shares\" class=\"note\">Share of the squared validation gap by phase, before:";
  for (std::size_t p = 0; p < r.phase_names.size(); ++p)
    o << " " << html(r.phase_names[p]) << " "
      << share(r.validation_before.phase_total[p].ssr, r.validation_before.total.ssr)
      << (p + 1 < r.phase_names.size() ? ";" : ".");
  o << " Gaps are RMS residuals in units of each signal's noise, which the data show themselves.</p>\n";
  o << "<details><summary>" << r.windows.size()
    << " time windows with residuals significant against the noise (unpatched model, all runs)</summary>\n"
       "<table id=\"windows\"><tr><th>run</th><th>signal</th><th>from [s]</th><th>to [s]</th><th>gap</th></tr>\n";
  for (std::size_t i = 0; i < r.windows.size() && i < 60; ++i)
    o << "<tr><td class=\"l\">" << html(r.windows[i].run) << "</td><td class=\"l\">" << html(r.windows[i].signal)
      << "</td><td>" << fixed(r.windows[i].t0, 3) << "</td><td>" << fixed(r.windows[i].t1, 3) << "</td><td>"
      << gap(r.windows[i].rms) << "</td></tr>\n";
  o << "</table></details>\n";
}

// Every candidate: rank, status, fitted values, gaps, significance, group.
void ranking_section(std::ostream& o, const DiagnosisReport& r) {
  o << "<h2>Ranking of candidate effects</h2>\n<table id=\"ranking\"><tr><th>rank</th><th>effect</th><th>status</th>"
       "<th>fitted parameters</th><th>gap before</th><th>gap after</th><th>&Delta;BIC (eff.)</th><th>p</th>"
       "<th>significant</th><th>indistinguishable from</th></tr>\n";
  for (const auto& e : r.effects) {
    bool present = false;
    for (const auto& v : r.verdict) present = present || v == e.name;
    o << "<tr class=\"effect" << (present ? " present" : "") << "\"><td>" << (e.rank ? std::to_string(e.rank) : "-")
      << "</td><td class=\"l\">" << html(e.name) << "</td><td class=\"l w\">"
      << html(!e.unavailable.empty() ? e.unavailable
              : e.screened_out && e.failed_runs ? "screened out: " + std::to_string(e.failed_runs) +
                                                      " run(s) failed, first: " + e.run_failures.front()
              : e.screened_out        ? "screened out"
              : e.failed_validation_runs ? "fitted; solver failed on " + std::to_string(e.failed_validation_runs) +
                                               " validation run(s)"
                                         : "fitted")
      << "</td><td class=\"l\">";
    const bool fitted = e.unavailable.empty() && !e.screened_out;
    for (std::size_t j = 0; fitted && j < e.parameter_names.size(); ++j)
      o << html(e.parameter_names[j]) << " = " << html(effect_parameter(e, j, e.values[j]))
        << html(from_netlist(e.values[j], e.netlist_value, e.parameter_units[j], is_difference(e, j))) << "<br>";
    o << "</td><td>" << gap(e.gap_before) << "</td><td>" << (fitted ? gap(e.gap_after) : "") << "</td><td>"
      << (fitted ? fixed(std::round(e.delta_bic), 0) : "") << "</td><td>" << (fitted ? p_value(e.p_value) : "")
      << "</td><td>" << (e.significant ? "yes" : "no") << "</td><td class=\"l w\">";
    for (const auto& g : e.group) o << html(g) << " ";
    o << "</td></tr>\n";
  }
  o << "</table>\n";
}

}  // namespace

void write_report_html(const DiagnosisReport& r, const std::string& path) {
  std::ostringstream o;
  o << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>pneumo diagnosis</title>\n"
       "<style>body{font-family:sans-serif;max-width:1140px;margin:1em auto;padding:0 10px;line-height:1.35}"
       "table{border-collapse:collapse;max-width:100%}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right;"
       "vertical-align:top;white-space:nowrap}th,td.w{white-space:normal}th{background:#eee}td.l{text-align:left}tr.present{background:#e8f4e8}"
       ".legend span{margin-right:1.2em}code{overflow-wrap:anywhere}svg{max-width:100%;height:auto}"
       ".traces{display:grid;grid-template-columns:repeat(auto-fill,minmax(520px,1fr));gap:6px}"
       "p.note{color:#555;font-size:90%}#ranking td{white-space:normal}</style></head><body>\n";
  o << "<h1>Sim-to-real gap diagnosis</h1>\n<p>Model " << file_name(r.model_file) << ", runs "
    << file_name(r.runs_dir) << " (calibration";
  for (const auto& n : r.calibration_runs) o << " " << html(n);
  o << "; validation";
  for (const auto& n : r.validation_runs) o << " " << html(n);
  o << "), catalogue " << file_name(r.catalogue_file) << "; " << r.simulations << " simulations in "
    << rounded(r.seconds, 2) << " s.</p>\n";
  o << "<h2>Verdict</h2>\n<p id=\"verdict\">";
  if (r.verdict.empty()) o << html(verdict_sentence(r)) << ".";
  for (std::size_t i = 0; i < r.verdict_groups.size(); ++i) {
    o << (i ? "; then " : "") << "<b>" << html(r.verdict_groups[i][0]) << "</b>" << html(recalibrated(r, i));
    if (r.verdict_groups[i].size() > 1) {
      o << " (indistinguishable from";
      for (std::size_t j = 1; j < r.verdict_groups[i].size(); ++j)
        o << (j > 1 ? ", " : " ") << html(r.verdict_groups[i][j]);
      if (setting_before_own_part(r, r.verdict_groups[i]))
        o << "; a setting turned off is named before a part of the same component that fails";
      o << ")";
    }
  }
  o << "</p>\n<p>Validation gap (RMS of residual / noise; 1 = the noise level): before <b>"
    << gap(r.validation_before.total.rms) << "</b>, after <b>" << gap(r.validation_after.total.rms) << "</b>.</p>\n";
  for (const auto& c : r.sensors)
    if (!c.best.empty()) o << "<p class=\"sensor\">To tell them apart: " << html(sensor_sentence(c)) << ".</p>\n";
  for (const auto& n : r.next_runs)
    o << "<p class=\"next-run\">" << (n.decisive ? "The next run: " : "") << html(next_run_sentence(n)) << ".</p>\n";
  o << unexplained_html(r.unexplained, html);

  gap_section(o, r);
  ranking_section(o, r);
  o << "<h2>Measured against simulated (validation runs)</h2>\n<p class=\"legend\">"
       "<span style=\"color:#999\">&#9644; measured</span><span style=\"color:#d62728\">&#9644; unpatched model</span>"
       "<span style=\"color:#1f77b4\">&#9644; model with the verdict's effects</span>shading: phases";
  for (std::size_t p = 0; p < r.phase_names.size(); ++p)
    o << " <span style=\"background:" << shade(p) << ";padding:0 4px\">" << html(r.phase_names[p]) << "</span>";
  o << "</p>\n<div class=\"traces\">\n";
  for (const auto& p : r.plots) o << svg_plot(p, r.phase_names, shown(unit_of(r, p.signal)), noise_of(r, p.signal));
  o << "</div>\n</body></html>\n";
  write_text_atomic(path, o.str());
}

}  // namespace pneumo::diagnose
