#include "framework/study/metrics.hpp"

#include <algorithm>
#include <mutex>

#include "framework/analysis/run_metrics.hpp"

namespace pneumo::study {

namespace {

std::vector<Metric>& registered() {
  static std::vector<Metric> m;
  return m;
}

std::mutex& registered_mutex() {
  static std::mutex m;
  return m;
}

std::string description_of(const MetricDecl& m) {
  using K = MetricDecl::Kind;
  switch (m.kind) {
    case K::max: return "highest " + m.output;
    case K::min: return "lowest " + m.output;
    case K::value: return m.output + " at a moment";
    case K::final_value: return m.output + " at the end";
    case K::crossing: return "time " + m.output + " crosses its level";
    case K::event_time: return "time of " + m.event.component + "." + m.event.tag;
    case K::integral: return "integral of " + m.output;
    case K::audit: return "energy audit " + m.output;
    case K::expression: return m.expression;
  }
  return "";
}

}  // namespace

void register_metric(Metric m) {
  std::lock_guard<std::mutex> lock(registered_mutex());
  registered().push_back(std::move(m));
}

std::vector<Metric> available_metrics(const Netlist& nl, const Registry& registry) {
  std::vector<Metric> out;
  if (!nl.metrics.empty()) {
    Netlist with_outputs = nl;
    add_metric_outputs(with_outputs, std::vector<bool>(nl.metrics.size(), true));
    const Circuit circuit = elaborate(with_outputs, registry);
    const auto units = metric_units(nl, circuit);
    const auto dims = metric_dimensions(nl, circuit);
    for (std::size_t i = 0; i < nl.metrics.size(); ++i)
      out.push_back({nl.metrics[i].name, units[i].unit, description_of(nl.metrics[i]), {}, nullptr,
                     static_cast<int>(i), units[i], units::si_unit_name(dims[i])});
  }
  std::lock_guard<std::mutex> lock(registered_mutex());
  for (const auto& m : registered()) {
    const bool has_outputs = std::all_of(m.needs.begin(), m.needs.end(), [&](const std::string& need) {
      return std::any_of(nl.outputs.begin(), nl.outputs.end(), [&](const OutputDecl& o) { return o.name == need; });
    });
    const bool shadowed = std::any_of(out.begin(), out.end(), [&](const Metric& o) { return o.name == m.name; });
    if (!has_outputs || shadowed) continue;
    out.push_back(m);
    if (out.back().si_unit.empty()) out.back().si_unit = m.unit;
  }
  return out;
}

std::vector<Metric> select_metrics(const Netlist& nl, const Registry& registry, const std::vector<std::string>& names) {
  auto avail = available_metrics(nl, registry);
  if (names.empty()) return avail;
  std::vector<Metric> out;
  for (const auto& n : names) {
    const auto it = std::find_if(avail.begin(), avail.end(), [&](const Metric& m) { return m.name == n; });
    if (it == avail.end()) {
      std::string list;
      for (const auto& m : avail) list += (list.empty() ? "" : ", ") + m.name;
      throw InputError(SourceLocation{nl.file, 1, 1}, "", "",
                       "metric '" + n + "' is not available for this netlist (available: " +
                           (list.empty() ? "none - declare metrics in the netlist's 'metrics:' section" : list) + ")");
    }
    out.push_back(*it);
  }
  return out;
}

MetricPlan prepare_metrics(Netlist& nl, const std::vector<Metric>& metrics) {
  MetricPlan plan;
  std::vector<bool> wanted(nl.metrics.size(), false);
  for (const auto& m : metrics)
    if (m.netlist_index >= 0) wanted[m.netlist_index] = true;
  plan.netlist_marked = metric_closure(nl, wanted);
  plan.audit = metrics_read_audit(nl, plan.netlist_marked);
  add_metric_outputs(nl, plan.netlist_marked);
  return plan;
}

std::vector<AuditPlan> prepare_audits(const MetricPlan& plan, const Netlist& nl, Circuit& circuit) {
  return plan.audit ? prepare_energy_audit(nl, circuit) : std::vector<AuditPlan>{};
}

std::vector<double> compute_metrics(const std::vector<Metric>& metrics, const MetricPlan& plan,
                                    const std::vector<AuditPlan>& audit_plans, const Netlist& nl,
                                    const RunResult& run) {
  const std::vector<EnergyAudit> audits = plan.audit ? energy_audit(audit_plans, run) : std::vector<EnergyAudit>{};
  const std::vector<double> values = evaluate_metrics(nl, plan.netlist_marked, run, audits);
  std::vector<double> out;
  for (const auto& m : metrics) out.push_back(m.netlist_index >= 0 ? values[m.netlist_index] : m.compute(run));
  return out;
}

}  // namespace pneumo::study
