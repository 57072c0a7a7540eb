// Scalar metrics of one run, computed from its outputs (the netlist's
// `outputs:` columns) and its event log. Each metric says which outputs it
// needs; a study asks only for metrics the netlist can provide.
//
// Cushioning metrics (netlists/cushion_rig.yaml: outputs x, v, p_EC, T_EC of
// the cushioned cylinder; its events "enters the cushioning zone" and
// "impact on the cap-end stop"):
//   t_cushion  [s]    time in the cushioning zone: from the cushion entry event
//                     to the first cap-end impact event
//   v_impact   [m/s]  piston velocity at the first cap-end impact
//   p_EC_peak  [Pa]   highest cushion pressure from the cushion entry on
//   T_EC_min   [K]    lowest cushion-volume temperature over the run
//   T_EC_max   [K]    highest cushion-volume temperature over the run
//   t_move     [s]    total movement time: from the first logged event (the
//                     valve command step) to the first cap-end impact
// Sequence metric (a netlist with a sequencer and its step as output 'step'):
//   cycle_time [s]    first cycle: from the event tagged cycle_start (the
//                     start signal) to the next tagged cycle_end
// A metric whose event never happens (e.g. the piston never reaches the cap
// by t_end) is NaN ("nan" in the results), not an error.
//
// Energy audit metrics (framework/analysis/energy_audit; available when the
// netlist has a cushioned_cylinder - the run then carries the audit's
// solver-integrated accounts; the first cylinder is audited), J unless said:
//   E_kin_entry       kinetic energy at cushion entry
//   E_drive_cushion   driving work during cushioning (rod-side gas, ambient)
//   E_compression     compression of the cushion gas
//   E_throttle        flow work through the cushion throttle / bore opening
//   E_friction_cushion  friction while cushioning
//   E_stop            absorbed by the end stop
//   audit_residual [1]  (in - out) / in, the audit's closure
//
// Extension point: register_metric() adds further metrics - names, units and
// a function of the run (or of the audit) - and they then appear in sweeps
// and sensitivity studies like the others.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "framework/analysis/energy_audit.hpp"
#include "framework/run/run.hpp"

namespace pneumo::study {

struct Metric {
  std::string name;
  std::string unit;
  std::string description;
  std::vector<std::string> needs;  // output columns used
  std::function<double(const RunResult&)> compute;
  // Set instead of `compute` for energy audit metrics.
  std::function<double(const CushionAudit&)> from_audit = nullptr;
};

// True if any of the metrics needs the energy audit (the run must then be
// prepared with prepare_energy_audit()).
bool needs_audit(const std::vector<const Metric*>& metrics);
// Values of the metrics for a finished run of netlist `nl` (prepared for the
// audit if needs_audit()).
std::vector<double> compute_metrics(const std::vector<const Metric*>& metrics, const Netlist& nl,
                                    const RunResult& run);

// All metrics known (built-in cushioning metrics plus registered ones).
const std::vector<Metric>& metric_catalogue();
void register_metric(Metric m);

// The metrics whose needed outputs the netlist provides, in catalogue order.
std::vector<const Metric*> available_metrics(const Netlist& netlist);
// Look up by name; throws InputError listing the available names.
std::vector<const Metric*> select_metrics(const Netlist& netlist, const std::vector<std::string>& names);

}  // namespace pneumo::study
