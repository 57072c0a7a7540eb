// report.json and a self-contained report.html (inline SVG, no network).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "framework/io/results.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "framework/diagnose/unexplained.hpp"

namespace pneumo::diagnose {

namespace {

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string str(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\', o += c;
    else if (c == '\n') o += "\\n";
    else if (static_cast<unsigned char>(c) < 0x20) o += ' ';
    else o += c;
  }
  return o + "\"";
}

std::string html(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else if (c == '"') o += "&quot;";
    else o += c;
  }
  return o;
}

// Phase colours, repeated when there are more phases: shading (light) and bars.
const char* const kShade[] = {"#f4f4f4", "#fff4e0", "#eef6ff", "#ffecec", "#eefbee", "#f6eeff"};
const char* const kColour[] = {"#bbb", "#f0a030", "#4c8fd6", "#d64c4c", "#4cb04c", "#9b6bd6"};
const char* shade(std::size_t p) { return kShade[p % 6]; }
const char* colour(std::size_t p) { return kColour[p % 6]; }

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

std::string svg_plot(const TracePlot& p, const std::vector<std::string>& phases) {
  const double W = 560, H = 220, l = 60, r = 10, t = 10, b = 30;
  double t0 = p.t.front(), t1 = p.t.back(), lo = INFINITY, hi = -INFINITY;
  for (const auto* v : {&p.measured, &p.before, &p.after})
    for (double y : *v)
      if (std::isfinite(y)) lo = std::min(lo, y), hi = std::max(hi, y);
  if (!(hi > lo)) hi = lo + 1;
  const double pad = 0.05 * (hi - lo);
  lo -= pad, hi += pad;
  auto X = [&](double x) { return l + (x - t0) / (t1 - t0) * (W - l - r); };
  auto Y = [&](double y) { return t + (hi - y) / (hi - lo) * (H - t - b); };
  std::ostringstream o;
  o << "<svg class=\"trace\" data-run=\"" << html(p.run) << "\" data-signal=\"" << html(p.signal)
    << "\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H << "\" viewBox=\"0 0 " << W
    << " " << H << "\">\n";
  for (std::size_t ph = 0; ph + 1 < p.phase_times.size() && ph < phases.size(); ++ph) {
    const double a = X(p.phase_times[ph]), c = X(p.phase_times[ph + 1]);
    if (c > a) o << "<rect x=\"" << a << "\" y=\"" << t << "\" width=\"" << c - a << "\" height=\"" << H - t - b
                 << "\" fill=\"" << shade(ph) << "\"><title>" << html(phases[ph]) << "</title></rect>\n";
  }
  o << "<rect x=\"" << l << "\" y=\"" << t << "\" width=\"" << W - l - r << "\" height=\"" << H - t - b
    << "\" fill=\"none\" stroke=\"#888\"/>\n";
  auto line = [&](const std::vector<double>& v, const char* color, const char* cls, double width) {
    o << "<polyline class=\"" << cls << "\" fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << width
      << "\" points=\"";
    for (std::size_t i = 0; i < v.size(); ++i)
      if (std::isfinite(v[i])) o << num(X(p.t[i])) << "," << num(Y(v[i])) << " ";
    o << "\"/>\n";
  };
  line(p.measured, "#999", "measured", 2.5);
  line(p.before, "#d62728", "before", 1.2);
  line(p.after, "#1f77b4", "after", 1.2);
  o << "<text x=\"" << l << "\" y=\"" << H - 8 << "\" font-size=\"11\">" << num(t0) << " s</text>";
  o << "<text x=\"" << W - r - 40 << "\" y=\"" << H - 8 << "\" font-size=\"11\">" << num(t1) << " s</text>";
  o << "<text x=\"2\" y=\"" << t + 10 << "\" font-size=\"11\">" << num(hi) << "</text>";
  o << "<text x=\"2\" y=\"" << H - b << "\" font-size=\"11\">" << num(lo) << "</text>";
  o << "<text x=\"" << l + 8 << "\" y=\"" << t + 14 << "\" font-size=\"12\">" << html(p.run) << ": "
    << html(p.signal) << "</text>\n</svg>\n";
  return o.str();
}

std::string svg_phase_bars(const DiagnosisReport& r) {
  // Share of the squared validation gap by phase: before (top) and after (bottom).
  const double W = 560, H = 90;
  std::ostringstream o;
  o << "<svg id=\"phase-bars\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H << "\">\n";
  const double before = r.validation_before.total.ssr > 0 ? r.validation_before.total.ssr : 1;
  int row = 0;
  for (const GapTable* g : {&r.validation_before, &r.validation_after}) {
    double x = 70;
    const double scale = (W - 80) * (row == 0 ? 1.0 : std::min(1.0, g->total.ssr / before)) /
                         (g->total.ssr > 0 ? g->total.ssr : 1);
    o << "<text x=\"0\" y=\"" << 25 + row * 35 << "\" font-size=\"12\">" << (row ? "after" : "before") << "</text>";
    for (std::size_t p = 0; p < r.phase_names.size() && p < g->phase_total.size(); ++p) {
      const double w = g->phase_total[p].ssr * scale;
      o << "<rect class=\"phase-bar\" x=\"" << x << "\" y=\"" << 10 + row * 35 << "\" width=\"" << w
        << "\" height=\"22\" fill=\"" << colour(p) << "\"><title>" << html(r.phase_names[p]) << ": "
        << num(100 * g->phase_total[p].ssr / (g->total.ssr > 0 ? g->total.ssr : 1)) << " %</title></rect>";
      x += w;
    }
    ++row;
  }
  o << "</svg>\n";
  return o.str();
}

}  // namespace

void write_report_json(const DiagnosisReport& r, const std::string& path) {
  std::ostringstream o;
  o << "{\n\"model\": " << str(r.model_file) << ",\n\"catalogue\": " << str(r.catalogue_file)
    << ",\n\"runs\": " << str(r.runs_dir) << ",\n\"verdict\": [";
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
  o << "},\n\"gap_unit\": \"RMS of (measured - simulated)/noise; 1 = within noise\",";
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
    if (!e.unavailable.empty()) o << ", \"status\": " << str(e.unavailable);
    else if (e.screened_out) o << ", \"status\": \"screened out (linearised improvement too small)\"";
    else if (e.failed_validation_runs)
      o << ", \"status\": \"fitted; the solver failed on " << e.failed_validation_runs
        << " validation run(s) at the fitted values\"";
    else o << ", \"status\": \"fitted\"";
    o << ", \"parameters\": {";
    for (std::size_t j = 0; j < e.parameter_names.size(); ++j)
      o << (j ? ", " : "") << str(e.parameter_names[j]) << ": {\"value\": " << num(e.values[j])
        << ", \"unit\": " << str(e.parameter_units[j]) << "}";
    o << "}, \"validation_gap_before\": " << num(e.gap_before) << ", \"validation_gap_after\": " << num(e.gap_after)
      << ", \"screening_improvement\": " << num(e.screening_improvement) << ", \"significance\": {\"significant\": "
      << (e.significant ? "true" : "false") << ", \"lr_effective\": " << num(e.lr_eff)
      << ", \"n_effective\": " << num(e.n_eff) << ", \"delta_bic\": " << num(e.delta_bic)
      << ", \"p_value\": " << num(e.p_value) << "}, \"group\": [";
    for (std::size_t j = 0; j < e.group.size(); ++j) o << (j ? ", " : "") << str(e.group[j]);
    o << "]";
    if (!e.unavailable.empty() || e.screened_out) o << "}";
    else o << ", \"where_after\": " << gap_json(e.validation_after, r.phase_names) << "}";
  }
  o << "],\n\"unexplained\": " << unexplained_json(r.unexplained, num, str);
  o << ",\n\"seconds\": " << num(r.seconds) << ",\n\"simulations\": " << r.simulations << "\n}\n";
  write_text_atomic(path, o.str());
}

void write_report_html(const DiagnosisReport& r, const std::string& path) {
  std::ostringstream o;
  o << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>pneumo diagnosis</title>\n"
       "<style>body{font-family:sans-serif;max-width:1200px;margin:1em auto}table{border-collapse:collapse}"
       "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#eee}td.l{text-align:left}"
       "tr.present{background:#e8f4e8}.legend span{margin-right:1em}</style></head><body>\n";
  o << "<h1>Sim-to-real gap diagnosis</h1>\n<p>Model <code>" << html(r.model_file) << "</code>, runs <code>"
    << html(r.runs_dir) << "</code>, catalogue <code>" << html(r.catalogue_file) << "</code>; " << r.simulations
    << " simulations in " << num(r.seconds) << " s.</p>\n";
  o << "<h2>Verdict</h2>\n<p id=\"verdict\">";
  if (r.verdict.empty()) o << "No effect needed: the model explains the data within the noise (or no candidate helps significantly).";
  for (std::size_t i = 0; i < r.verdict_groups.size(); ++i) {
    o << (i ? "; then " : "") << "<b>" << html(r.verdict_groups[i][0]) << "</b>";
    if (r.verdict_groups[i].size() > 1) {
      o << " (indistinguishable from";
      for (std::size_t j = 1; j < r.verdict_groups[i].size(); ++j) o << " " << html(r.verdict_groups[i][j]);
      o << ")";
    }
  }
  o << "</p>\n<p>Validation gap (RMS of residual / noise; 1 = within noise): before <b>"
    << num(r.validation_before.total.rms) << "</b>, after <b>" << num(r.validation_after.total.rms) << "</b>.</p>\n";
  o << "<h2>Gap by signal and phase (validation runs)</h2>\n" << svg_phase_bars(r) << "<div class=\"legend\">";
  for (std::size_t p = 0; p < r.phase_names.size(); ++p)
    o << "<span style=\"color:" << colour(p) << "\">" << html(r.phase_names[p]) << "</span>";
  o << "</div>\n<table id=\"gap-table\"><tr><th>signal</th><th>noise</th>";
  for (const auto& p : r.phase_names) o << "<th>" << html(p) << " before</th><th>after</th>";
  o << "<th>total before</th><th>after</th></tr>\n";
  for (std::size_t s = 0; s < r.validation_before.signals.size(); ++s) {
    double sigma = NAN;
    for (const auto& [n, v] : r.noise)
      if (n == r.validation_before.signals[s]) sigma = v;
    o << "<tr><td class=\"l\">" << html(r.validation_before.signals[s]) << "</td><td>" << num(sigma) << "</td>";
    for (std::size_t p = 0; p < r.phase_names.size(); ++p)
      o << "<td>" << num(r.validation_before.by_phase[s][p].rms) << "</td><td>"
        << (s < r.validation_after.by_phase.size() ? num(r.validation_after.by_phase[s][p].rms) : "") << "</td>";
    o << "<td>" << num(r.validation_before.by_signal[s].rms) << "</td><td>"
      << (s < r.validation_after.by_signal.size() ? num(r.validation_after.by_signal[s].rms) : "") << "</td></tr>\n";
  }
  o << "</table>\n<p id=\"phase-shares\">Share of the squared validation gap by phase, before:";
  for (std::size_t p = 0; p < r.phase_names.size(); ++p)
    o << " " << html(r.phase_names[p]) << " "
      << num(100 * r.validation_before.phase_total[p].ssr /
             (r.validation_before.total.ssr > 0 ? r.validation_before.total.ssr : 1))
      << " %" << (p + 1 < r.phase_names.size() ? ";" : ".");
  o << " By signal:";
  for (std::size_t s = 0; s < r.validation_before.signals.size(); ++s)
    o << " " << html(r.validation_before.signals[s]) << " "
      << num(100 * r.validation_before.by_signal[s].ssr /
             (r.validation_before.total.ssr > 0 ? r.validation_before.total.ssr : 1))
      << " %" << (s + 1 < r.validation_before.signals.size() ? ";" : ".");
  o << "</p>\n<details><summary>" << r.windows.size()
    << " time windows with residuals significant against the noise (unpatched model, all runs)</summary>\n"
       "<table id=\"windows\"><tr><th>run</th><th>signal</th><th>from [s]</th><th>to [s]</th><th>gap</th></tr>\n";
  for (std::size_t i = 0; i < r.windows.size() && i < 60; ++i)
    o << "<tr><td class=\"l\">" << html(r.windows[i].run) << "</td><td class=\"l\">" << html(r.windows[i].signal)
      << "</td><td>" << num(r.windows[i].t0) << "</td><td>" << num(r.windows[i].t1) << "</td><td>"
      << num(r.windows[i].rms) << "</td></tr>\n";
  o << "</table></details>\n";
  o << unexplained_html(r.unexplained, html);
  o << "<h2>Ranking of candidate effects</h2>\n<table id=\"ranking\"><tr><th>rank</th><th>effect</th><th>status</th>"
       "<th>parameters</th><th>gap before</th><th>gap after</th><th>&Delta;BIC (eff.)</th><th>p</th>"
       "<th>significant</th><th>indistinguishable from</th></tr>\n";
  for (const auto& e : r.effects) {
    bool present = false;
    for (const auto& v : r.verdict) present = present || v == e.name;
    o << "<tr class=\"effect" << (present ? " present" : "") << "\"><td>" << (e.rank ? std::to_string(e.rank) : "-")
      << "</td><td class=\"l\">" << html(e.name) << "</td><td class=\"l\">"
      << html(!e.unavailable.empty() ? e.unavailable
              : e.screened_out        ? "screened out"
              : e.failed_validation_runs ? "fitted; solver failed on " + std::to_string(e.failed_validation_runs) +
                                               " validation run(s)"
                                         : "fitted")
      << "</td><td class=\"l\">";
    for (std::size_t j = 0; j < e.parameter_names.size(); ++j)
      o << html(e.parameter_names[j]) << " = " << num(e.values[j]) << " " << html(e.parameter_units[j]) << "<br>";
    o << "</td><td>" << num(e.gap_before) << "</td><td>" << num(e.gap_after) << "</td><td>" << num(e.delta_bic)
      << "</td><td>" << num(e.p_value) << "</td><td>" << (e.significant ? "yes" : "no") << "</td><td class=\"l\">";
    for (const auto& g : e.group) o << html(g) << " ";
    o << "</td></tr>\n";
  }
  o << "</table>\n<h2>Measured against simulated (validation runs)</h2>\n<p class=\"legend\">"
       "<span style=\"color:#999\">&#9644; measured</span><span style=\"color:#d62728\">&#9644; model before</span>"
       "<span style=\"color:#1f77b4\">&#9644; model with the verdict's effects</span>; shading: phases.</p>\n";
  for (const auto& p : r.plots) o << svg_plot(p, r.phase_names);
  o << "</body></html>\n";
  write_text_atomic(path, o.str());
}

}  // namespace pneumo::diagnose
