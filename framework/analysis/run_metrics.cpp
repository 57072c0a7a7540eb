#include "framework/analysis/run_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "framework/core/expression.hpp"

namespace pneumo {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
const std::string kPrefix = "metric.";

using Kind = MetricDecl::Kind;

int index_of(const Netlist& nl, const std::string& name) {
  for (std::size_t i = 0; i < nl.metrics.size(); ++i)
    if (nl.metrics[i].name == name) return static_cast<int>(i);
  return -1;
}

// Time of the n-th event COMPONENT.TAG; NaN if it did not happen.
double event_time(const RunResult& r, const std::string& component, const std::string& tag, int n) {
  for (const auto& e : r.solver.events)
    if (e.component == component && e.tag == tag && --n == 0) return e.t;
  return kNaN;
}

double event_time(const RunResult& r, const std::string& reference) {
  const auto dot = reference.find('.');
  return event_time(r, reference.substr(0, dot), reference.substr(dot + 1), 1);
}

double time_of(const RunResult& r, const TimeRef& ref) {
  return ref.is_event() ? event_time(r, ref.component, ref.tag, ref.occurrence) : ref.t;
}

// Value of a column at time t: the first row at or after t (event rows are
// written exactly at the event), interpolated otherwise.
double value_at(const ResultsTable& tab, int c, double t) {
  const auto& rows = tab.rows;
  if (c < 0 || rows.empty() || std::isnan(t)) return kNaN;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (rows[k][0] < t) continue;
    if (rows[k][0] == t || k == 0) return rows[k][c];
    const double w = (t - rows[k - 1][0]) / (rows[k][0] - rows[k - 1][0]);
    return rows[k - 1][c] + w * (rows[k][c] - rows[k - 1][c]);
  }
  return kNaN;
}

double extreme(const ResultsTable& tab, int c, double from, double to, bool highest) {
  if (c < 0 || std::isnan(from) || std::isnan(to)) return kNaN;
  double best = highest ? -kInf : kInf;
  bool any = false;
  for (const auto& row : tab.rows) {
    if (row[0] < from || row[0] > to) continue;
    best = highest ? std::max(best, row[c]) : std::min(best, row[c]);
    any = true;
  }
  return any ? best : kNaN;
}

// Time of the n-th crossing of `level` in `direction` between rows (linear
// in between), within [from, to].
double crossing(const ResultsTable& tab, int c, double level, int direction, int n, double from, double to) {
  if (c < 0 || std::isnan(from) || std::isnan(to)) return kNaN;
  const auto& rows = tab.rows;
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const double a = rows[k - 1][c] - level, b = rows[k][c] - level;
    const bool rising = a < 0 && b >= 0, falling = a > 0 && b <= 0;
    if (!((direction >= 0 && rising) || (direction <= 0 && falling))) continue;
    const double t = rows[k - 1][0] + (rows[k][0] - rows[k - 1][0]) * a / (a - b);
    if (t < from || t > to) continue;
    if (--n == 0) return t;
  }
  return kNaN;
}

double audit_value(const std::vector<EnergyAudit>& audits, const std::string& reference) {
  const auto dot = reference.find('.');
  const std::string component = reference.substr(0, dot), term = reference.substr(dot + 1);
  for (const auto& a : audits) {
    if (a.component != component) continue;
    if (!a.opened) return kNaN;
    if (term == "residual") return a.total_in != 0 ? a.residual() / a.total_in : kNaN;
    for (const auto* side : {&a.in, &a.out})
      for (const auto& t : *side)
        if (t.name == term) return t.joules;
  }
  return kNaN;
}

class MetricEvaluator {
 public:
  MetricEvaluator(const Netlist& nl, const RunResult& run, const std::vector<EnergyAudit>& audits)
      : nl_(nl), run_(run), audits_(audits), values_(nl.metrics.size(), kNaN), done_(nl.metrics.size(), false) {}

  double value(int i) {
    if (!done_[i]) {
      values_[i] = compute(nl_.metrics[i]);
      done_[i] = true;
    }
    return values_[i];
  }

 private:
  double compute(const MetricDecl& m) {
    const ResultsTable& tab = run_.table;
    const double t0 = tab.rows.empty() ? kNaN : tab.rows.front()[0];
    const double t1 = tab.rows.empty() ? kNaN : tab.rows.back()[0];
    const double from = m.from ? time_of(run_, *m.from) : -kInf;
    const double to = m.to ? time_of(run_, *m.to) : kInf;
    const int c = tab.column(m.output);
    switch (m.kind) {
      case Kind::max: return extreme(tab, c, from, to, true);
      case Kind::min: return extreme(tab, c, from, to, false);
      case Kind::value: return value_at(tab, c, time_of(run_, *m.at));
      case Kind::final_value: return c < 0 || tab.rows.empty() ? kNaN : tab.rows.back()[c];
      case Kind::crossing: return crossing(tab, c, m.level.si_value, m.direction, m.occurrence, from, to);
      case Kind::event_time: return time_of(run_, m.event);
      case Kind::integral: {
        const int q = tab.column(kPrefix + m.name);
        return value_at(tab, q, std::min(to, t1)) - value_at(tab, q, std::max(from, t0));
      }
      case Kind::audit: return audit_value(audits_, m.output);
      case Kind::expression:
        return Expression(m.expression).evaluate([&](const std::string& n) {
          const int i = index_of(nl_, n);
          return i >= 0 ? value(i) : event_time(run_, n);
        });
    }
    return kNaN;
  }

  const Netlist& nl_;
  const RunResult& run_;
  const std::vector<EnergyAudit>& audits_;
  std::vector<double> values_;
  std::vector<bool> done_;
};

}  // namespace

namespace {

int event_count(const RunResult& r, const std::string& component, const std::string& tag) {
  int n = 0;
  for (const auto& e : r.solver.events) n += e.component == component && e.tag == tag;
  return n;
}

// "" if `ref` names a time the run reached, else why it does not.
std::string missing_time(const RunResult& r, const TimeRef& ref) {
  if (!ref.is_event()) return "";
  const int n = event_count(r, ref.component, ref.tag);
  if (n >= ref.occurrence) return "";
  const std::string name = ref.component + "." + ref.tag;
  return n == 0 ? "event " + name + " did not happen"
                : "event " + name + " happened " + std::to_string(n) + " time" + (n > 1 ? "s" : "") + ", not " +
                      std::to_string(ref.occurrence);
}

// A level in the unit its column is shown in ("5 barg"), so the reason
// reads as the netlist was written.
std::string level_text(const ResultsTable& tab, int c, double si) {
  const units::DisplayUnit d = tab.shown_as(static_cast<std::size_t>(c));
  std::ostringstream s;
  s << std::setprecision(6) << d.shown(si) << (d.unit.empty() || d.unit == "1" ? "" : " " + d.unit);
  return s.str();
}

std::string reason(const Netlist& nl, const std::vector<double>& values, const RunResult& run, const MetricDecl& m) {
  for (const auto* ref : {m.from ? &*m.from : nullptr, m.to ? &*m.to : nullptr, m.at ? &*m.at : nullptr,
                          m.kind == Kind::event_time ? &m.event : nullptr})
    if (ref)
      if (std::string why = missing_time(run, *ref); !why.empty()) return why;
  const ResultsTable& tab = run.table;
  const int c = tab.column(m.output);
  const std::string window = m.from || m.to ? " within its window" : "";
  switch (m.kind) {
    case Kind::max:
    case Kind::min: return "no sample of " + m.output + window;
    case Kind::value: return "the run ended before that time";
    case Kind::crossing: {
      if (c < 0) break;
      const char* how = m.direction > 0 ? " never rose through " : m.direction < 0 ? " never fell through " : " never crossed ";
      return m.output + how + level_text(tab, c, m.level.si_value) + window +
             (m.occurrence > 1 ? " " + std::to_string(m.occurrence) + " times" : "");
    }
    case Kind::audit: return "the energy audit of " + m.output.substr(0, m.output.find('.')) + " did not open";
    case Kind::expression:
      for (const auto& n : Expression(m.expression).names()) {
        const int j = index_of(nl, n);
        if (j >= 0 && std::isnan(values[j])) return "it uses " + n + ", which is undefined";
        if (j < 0 && n.find('.') != std::string::npos && std::isnan(event_time(run, n)))
          return "event " + n + " did not happen";
      }
      return "the expression has no value there (a division by zero or a root of a negative number)";
    default: break;
  }
  return "the run gave it no value";
}

}  // namespace

std::vector<std::string> undefined_metric_reasons(const Netlist& nl, const std::vector<double>& values,
                                                  const RunResult& run) {
  std::vector<std::string> out(nl.metrics.size());
  for (std::size_t i = 0; i < nl.metrics.size() && i < values.size(); ++i)
    if (std::isnan(values[i])) out[i] = reason(nl, values, run, nl.metrics[i]);
  return out;
}

std::vector<bool> metric_closure(const Netlist& nl, std::vector<bool> wanted) {
  wanted.resize(nl.metrics.size(), false);
  for (bool grew = true; grew;) {
    grew = false;
    for (std::size_t i = 0; i < nl.metrics.size(); ++i) {
      if (!wanted[i] || nl.metrics[i].kind != Kind::expression) continue;
      for (const auto& n : Expression(nl.metrics[i].expression).names()) {
        const int j = index_of(nl, n);
        if (j >= 0 && !wanted[j]) wanted[j] = grew = true;
      }
    }
  }
  return wanted;
}

bool metrics_read_audit(const Netlist& nl, const std::vector<bool>& marked) {
  for (std::size_t i = 0; i < nl.metrics.size() && i < marked.size(); ++i)
    if (marked[i] && nl.metrics[i].kind == Kind::audit) return true;
  return false;
}

void add_metric_outputs(Netlist& nl, const std::vector<bool>& marked) {
  for (std::size_t i = 0; i < nl.metrics.size() && i < marked.size(); ++i) {
    const MetricDecl& m = nl.metrics[i];
    if (!marked[i] || m.kind != Kind::integral) continue;
    const auto dot = m.output.find('.');
    nl.outputs.push_back({kPrefix + m.name, m.output.substr(0, dot), m.output.substr(dot + 1), m.where, true, "", {}});
  }
}

void drop_metric_columns(ResultsTable& table) { table.drop_columns(kPrefix); }

namespace {

// The SI dimension of each metric; expressions from the metrics they name.
std::vector<units::Dimension> dimensions_of(const Netlist& nl, const std::map<std::string, const Probe*>& probe) {
  std::vector<units::Dimension> out;
  auto output_dim = [&](const std::string& name) {
    const auto it = probe.find(name);
    return it == probe.end() ? units::Dimension{} : units::dimension_of(it->second->unit);
  };
  for (const auto& m : nl.metrics) {
    switch (m.kind) {
      case Kind::max:
      case Kind::min:
      case Kind::value:
      case Kind::final_value: out.push_back(output_dim(m.output)); break;
      case Kind::crossing: {
        const units::Dimension d = output_dim(m.output);
        if (m.level.had_unit && !(m.level.dim == d))
          throw InputError(m.where, "", "metrics." + m.name,
                           "metric '" + m.name + "': the level has dimension " + m.level.dim.to_string() +
                               " but output '" + m.output + "' is in " + units::si_unit_name(d));
        out.push_back(units::dims::time);
        break;
      }
      case Kind::event_time: out.push_back(units::dims::time); break;
      case Kind::integral: out.push_back(output_dim(kPrefix + m.name)); break;
      case Kind::audit:
        out.push_back(m.output.substr(m.output.find('.') + 1) == "residual" ? units::dims::none : units::dims::energy);
        break;
      case Kind::expression: out.push_back(units::dims::none); break;
    }
  }
  // Expressions name other metrics, declared before or after them (no cycles:
  // checked when read), so as many passes as metrics settle every dimension.
  for (std::size_t pass = 0; pass < nl.metrics.size(); ++pass)
    for (std::size_t i = 0; i < nl.metrics.size(); ++i) {
      const MetricDecl& m = nl.metrics[i];
      if (m.kind != Kind::expression) continue;
      const auto d = Expression(m.expression).dimension([&](const std::string& n) {
        const int j = index_of(nl, n);
        return j >= 0 ? out[j] : units::dims::time;  // otherwise an event COMPONENT.TAG
      });
      if (!d && !m.unit.empty() && pass + 1 == nl.metrics.size())
        throw InputError(m.where, "", "metrics." + m.name,
                         "metric '" + m.name + "': the expression adds values of different dimensions, so unit '" +
                             m.unit + "' cannot be checked; make each sum one kind of quantity");
      out[i] = d.value_or(units::dims::none);
    }
  return out;
}

}  // namespace

std::vector<units::Dimension> metric_dimensions(const Netlist& nl, const Circuit& circuit) {
  std::map<std::string, const Probe*> probe;
  for (const auto& p : circuit.probes) probe[p.name] = &p;
  return dimensions_of(nl, probe);
}

std::vector<units::DisplayUnit> metric_units(const Netlist& nl, const Circuit& circuit) {
  std::map<std::string, const Probe*> probe;
  for (const auto& p : circuit.probes) probe[p.name] = &p;
  const std::vector<units::Dimension> dims = dimensions_of(nl, probe);
  std::vector<units::DisplayUnit> out;
  for (std::size_t i = 0; i < nl.metrics.size(); ++i) {
    const MetricDecl& m = nl.metrics[i];
    const bool of_output = m.kind == Kind::max || m.kind == Kind::min || m.kind == Kind::value || m.kind == Kind::final_value;
    if (m.unit.empty() && of_output && probe.count(m.output) && !probe[m.output]->display.unit.empty()) {
      out.push_back(probe[m.output]->display);  // the unit the output is shown in
      continue;
    }
    // Without a unit of its own, a metric that is not an output's value is
    // shown in `display:`'s unit for its dimension, read as a difference.
    const std::string unit = m.unit.empty() ? units::difference_unit(nl.display_unit_for(dims[i])) : m.unit;
    try {
      out.push_back(units::display_unit(unit, dims[i], nl.gas.p_ambient));
    } catch (const std::exception& e) {  // ParseError was caught when reading; a dimension that does not fit
      throw InputError(m.where, "", "metrics." + m.name,
                       "metric '" + m.name + "': unit " + e.what() + "; give a unit of " + units::si_unit_name(dims[i]) +
                           " or leave unit out");
    }
  }
  return out;
}

std::vector<double> evaluate_metrics(const Netlist& nl, const std::vector<bool>& marked, const RunResult& run,
                                     const std::vector<EnergyAudit>& audits) {
  MetricEvaluator ev(nl, run, audits);
  std::vector<double> out(nl.metrics.size(), kNaN);
  for (std::size_t i = 0; i < nl.metrics.size() && i < marked.size(); ++i)
    if (marked[i]) out[i] = ev.value(static_cast<int>(i));
  return out;
}

}  // namespace pneumo
