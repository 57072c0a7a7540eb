#include "framework/study/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

namespace pneumo::study {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kEntryEvent = "enters the cushioning zone";
constexpr const char* kImpactEvent = "impact on the cap-end stop";

// Time of the first logged event whose message contains `text`; NaN if none.
double event_time(const RunResult& r, const char* text) {
  for (const auto& e : r.solver.events)
    if (e.message.find(text) != std::string::npos) return e.t;
  return kNaN;
}

// Value of column `name` at time t: the first row at or after t (event rows
// are emitted exactly at the event time), interpolated otherwise.
double value_at(const RunResult& r, const std::string& name, double t) {
  const int c = r.table.column(name);
  const auto& rows = r.table.rows;
  if (c < 0 || rows.empty() || std::isnan(t)) return kNaN;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (rows[k][0] < t) continue;
    if (rows[k][0] == t || k == 0) return rows[k][c];
    const double w = (t - rows[k - 1][0]) / (rows[k][0] - rows[k - 1][0]);
    return rows[k - 1][c] + w * (rows[k][c] - rows[k - 1][c]);
  }
  return kNaN;
}

double extreme(const RunResult& r, const std::string& name, double from, bool highest) {
  const int c = r.table.column(name);
  if (c < 0 || std::isnan(from)) return kNaN;
  double best = highest ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  bool any = false;
  for (const auto& row : r.table.rows) {
    if (row[0] < from) continue;
    best = highest ? std::max(best, row[c]) : std::min(best, row[c]);
    any = true;
  }
  return any ? best : kNaN;
}

// A metric that is one term of the first audited cylinder's energy audit
// (NaN if the piston never entered the cushioning zone).
Metric audit_metric(const char* name, const char* unit, const char* description, bool in, const char* term) {
  Metric m{name, unit, description, {}, nullptr};
  m.from_audit = [in, term](const CushionAudit& a) {
    if (!a.entered) return kNaN;
    for (const auto& t : in ? a.in : a.out)
      if (t.name == term) return t.joules;
    return kNaN;
  };
  return m;
}

std::vector<Metric> builtin_metrics() {
  std::vector<Metric> m = {
      {"t_cushion", "s", "time in the cushioning zone: cushion entry event to the first cap-end impact", {"x"},
       [](const RunResult& r) { return event_time(r, kImpactEvent) - event_time(r, kEntryEvent); }},
      {"v_impact", "m/s", "piston velocity at the first cap-end impact", {"v"},
       [](const RunResult& r) { return value_at(r, "v", event_time(r, kImpactEvent)); }},
      {"p_EC_peak", "Pa", "highest cushion pressure from the cushion entry on", {"p_EC"},
       [](const RunResult& r) { return extreme(r, "p_EC", event_time(r, kEntryEvent), true); }},
      {"T_EC_min", "K", "lowest cushion-volume temperature over the run", {"T_EC"},
       [](const RunResult& r) { return extreme(r, "T_EC", -std::numeric_limits<double>::infinity(), false); }},
      {"T_EC_max", "K", "highest cushion-volume temperature over the run", {"T_EC"},
       [](const RunResult& r) { return extreme(r, "T_EC", -std::numeric_limits<double>::infinity(), true); }},
      {"t_move", "s", "total movement time: first logged event (valve command) to the first cap-end impact", {"x"},
       [](const RunResult& r) {
         return r.solver.events.empty() ? kNaN : event_time(r, kImpactEvent) - r.solver.events.front().t;
       }},
      {"cycle_time", "s",
       "first cycle of a step chain: from its event tagged cycle_start to the next tagged cycle_end (needs the "
       "sequencer's step as output 'step')",
       {"step"},
       [](const RunResult& r) {
         double start = kNaN;
         for (const auto& e : r.solver.events) {
           if (std::isnan(start) && e.tag == "cycle_start") start = e.t;
           else if (!std::isnan(start) && e.tag == "cycle_end") return e.t - start;
         }
         return kNaN;
       }},
      audit_metric("E_kin_entry", "J", "kinetic energy at cushion entry", true, "kinetic_energy_at_entry"),
      audit_metric("E_drive_cushion", "J", "driving work during cushioning", true, "driving_work"),
      audit_metric("E_compression", "J", "compression of the cushion gas", false, "cushion_gas_compression"),
      audit_metric("E_throttle", "J", "flow work through the cushion throttle / bore opening", false,
                   "cushion_throttle_dissipation"),
      audit_metric("E_friction_cushion", "J", "friction while cushioning", false, "friction"),
      audit_metric("E_stop", "J", "absorbed by the end stop", false, "end_stop"),
  };
  Metric closure{"audit_residual", "1", "closure of the energy audit, (in - out) / in", {}, nullptr};
  closure.from_audit = [](const CushionAudit& a) {
    return a.entered && a.total_in != 0 ? a.residual() / a.total_in : kNaN;
  };
  m.push_back(std::move(closure));
  return m;
}

std::vector<Metric>& catalogue() {
  static std::vector<Metric> m = builtin_metrics();
  return m;
}

std::mutex& catalogue_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace

const std::vector<Metric>& metric_catalogue() { return catalogue(); }

void register_metric(Metric m) {
  std::lock_guard<std::mutex> lock(catalogue_mutex());
  catalogue().push_back(std::move(m));
}

bool needs_audit(const std::vector<const Metric*>& metrics) {
  return std::any_of(metrics.begin(), metrics.end(), [](const Metric* m) { return bool(m->from_audit); });
}

std::vector<double> compute_metrics(const std::vector<const Metric*>& metrics, const Netlist& nl,
                                    const RunResult& run) {
  std::vector<CushionAudit> audits;
  if (needs_audit(metrics)) audits = energy_audit(nl, run);
  std::vector<double> out;
  for (const auto* m : metrics)
    out.push_back(m->from_audit ? (audits.empty() ? kNaN : m->from_audit(audits.front())) : m->compute(run));
  return out;
}

std::vector<const Metric*> available_metrics(const Netlist& nl) {
  const bool has_cylinder = std::any_of(nl.components.begin(), nl.components.end(),
                                        [](const ComponentDecl& c) { return c.type == "cushioned_cylinder"; });
  std::vector<const Metric*> out;
  for (const auto& m : metric_catalogue()) {
    if (m.from_audit && !has_cylinder) continue;
    bool ok = true;
    for (const auto& need : m.needs)
      ok &= std::any_of(nl.outputs.begin(), nl.outputs.end(), [&](const OutputDecl& o) { return o.name == need; });
    if (ok) out.push_back(&m);
  }
  return out;
}

std::vector<const Metric*> select_metrics(const Netlist& nl, const std::vector<std::string>& names) {
  const auto avail = available_metrics(nl);
  if (names.empty()) return avail;
  std::vector<const Metric*> out;
  for (const auto& n : names) {
    const auto it = std::find_if(avail.begin(), avail.end(), [&](const Metric* m) { return m->name == n; });
    if (it == avail.end()) {
      std::string list;
      for (const auto* m : avail) list += (list.empty() ? "" : ", ") + m->name;
      throw InputError(SourceLocation{nl.file, 1, 1}, "", "",
                       "metric '" + n + "' is not available for this netlist (available: " +
                           (list.empty() ? "none - the metrics need outputs named x, v, p_EC, T_EC" : list) + ")");
    }
    out.push_back(*it);
  }
  return out;
}

}  // namespace pneumo::study
