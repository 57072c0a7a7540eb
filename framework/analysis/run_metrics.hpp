// The netlist's metrics (`metrics:`, MetricDecl) of a finished run: scalar
// results defined from its output columns, its tagged events
// (COMPONENT.TAG), integrals the solver computed, energy audit terms and
// arithmetic of other metrics. A metric whose event never happened is NaN,
// not an error.
#pragma once

#include <string>
#include <vector>

#include "framework/analysis/energy_audit.hpp"
#include "framework/model/circuit.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo {

// The netlist metrics that the metrics marked in `wanted` depend on,
// themselves included (expressions name other metrics).
std::vector<bool> metric_closure(const Netlist& netlist, std::vector<bool> wanted);
// True if any of the marked metrics reads an energy audit.
bool metrics_read_audit(const Netlist& netlist, const std::vector<bool>& marked);
// Adds the outputs the marked integral metrics read (hidden columns "metric.NAME").
void add_metric_outputs(Netlist& netlist, const std::vector<bool>& marked);
// Removes those columns from a results table.
void drop_metric_columns(ResultsTable& table);

// The SI dimension of each netlist metric (expressions: from what they name).
std::vector<units::Dimension> metric_dimensions(const Netlist& netlist, const Circuit& circuit);
// The unit each netlist metric is shown in (values stay SI; DisplayUnit::shown
// converts): its declared `unit:`, else the unit its output is shown in, else
// SI. From the circuit's outputs (elaborated with add_metric_outputs() for
// every integral metric). Throws InputError naming the metric when a declared
// unit or a crossing level does not fit the metric's dimension.
std::vector<units::DisplayUnit> metric_units(const Netlist& netlist, const Circuit& circuit);

// Values of the marked metrics (NaN for the others). `audits`: the run's
// energy audits if any marked metric reads one.
std::vector<double> evaluate_metrics(const Netlist& netlist, const std::vector<bool>& marked, const RunResult& run,
                                     const std::vector<EnergyAudit>& audits);

// Why each metric of `values` (evaluate_metrics' result) that is NaN is
// undefined - "event cylinder.cushion_in did not happen", "p_A never rose
// through 5 bar within the window" - so that a user reading `nan` learns
// what the run did not do; "" for the defined ones.
std::vector<std::string> undefined_metric_reasons(const Netlist& netlist, const std::vector<double>& values,
                                                  const RunResult& run);

}  // namespace pneumo
