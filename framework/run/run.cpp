#include "framework/run/run.hpp"

namespace pneumo {

SolverOptions solver_options(const SimulationSettings& s) {
  SolverOptions o;
  o.t_start = s.t_start;
  o.t_end = s.t_end;
  o.rtol = s.rtol;
  o.atol = s.atol;
  o.output_interval = s.output_interval;
  o.max_step = s.max_step;
  return o;
}

RunResult run_system(System& system, const SolverOptions& options) {
  RunResult out;
  const auto& probes = system.circuit().probes;
  out.table.names.push_back("t");
  out.table.units.push_back("s");
  for (const auto& p : probes) {
    out.table.names.push_back(p.name);
    out.table.units.push_back(p.unit);
  }
  out.solver = simulate(system, options, [&](double t, const double* y, const double* yp) {
    std::vector<double> row;
    row.reserve(probes.size() + 1);
    row.push_back(t);
    for (const auto& p : probes) row.push_back(system.probe(p, t, y, yp));
    out.table.add_row(std::move(row));
  });
  return out;
}

RunResult run_simulation(const Netlist& netlist, const Registry& registry) {
  System system(elaborate(netlist, registry));
  return run_system(system, solver_options(netlist.simulation));
}

}  // namespace pneumo
