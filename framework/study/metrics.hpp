// Scalar metrics of one run for studies (sweep, sensitivity): the metrics
// a netlist declares in `metrics:` (framework/analysis/run_metrics), plus
// metrics registered in code through register_metric() (a function of the
// run that needs some output columns). A study asks for metrics by name;
// the default is every metric the netlist provides.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "framework/analysis/energy_audit.hpp"
#include "framework/model/registry.hpp"
#include "framework/run/run.hpp"

namespace pneumo::study {

struct Metric {
  std::string name;
  std::string unit;  // what result files show the metric in (display.unit for netlist metrics)
  std::string description;
  std::vector<std::string> needs;                   // output columns used (registered metrics)
  std::function<double(const RunResult&)> compute;  // registered metrics
  int netlist_index = -1;                           // a metric of the netlist's `metrics:`
  units::DisplayUnit display;  // values are computed in SI (si_unit) and shown with display.shown()
  std::string si_unit;
};

// The metrics available for a netlist: its own, then the registered ones
// whose needed outputs it has. Elaborates the netlist once for the units.
std::vector<Metric> available_metrics(const Netlist& netlist, const Registry& registry);
// Look up by name (empty: all available); throws InputError listing the available names.
std::vector<Metric> select_metrics(const Netlist& netlist, const Registry& registry,
                                   const std::vector<std::string>& names);

// What a run must carry for the metrics: the hidden outputs and whether
// the energy audits are read. The same for every run of a study (it depends
// on the netlist's metric declarations, not on parameter values).
struct MetricPlan {
  std::vector<bool> netlist_marked;  // the netlist metrics to evaluate (with their dependencies)
  bool audit = false;
};
// Adds the outputs the metrics read to `netlist` (the study's copy).
MetricPlan prepare_metrics(Netlist& netlist, const std::vector<Metric>& metrics);
// The audits' plans of one run, their outputs added to its circuit
// (elaborated from the prepared netlist, not yet assembled); none unless
// the plan reads audits.
std::vector<AuditPlan> prepare_audits(const MetricPlan& plan, const Netlist& netlist, Circuit& circuit);
// Values of the metrics for a finished run of the prepared netlist.
std::vector<double> compute_metrics(const std::vector<Metric>& metrics, const MetricPlan& plan,
                                    const std::vector<AuditPlan>& audits, const Netlist& netlist,
                                    const RunResult& run);

void register_metric(Metric m);

}  // namespace pneumo::study
