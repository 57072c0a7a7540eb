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
  // Integral outputs are IDAS quadratures; the others are sampled.
  Quadratures quad;
  std::vector<double> integrals;
  quad.values = &integrals;
  std::vector<int> slot(probes.size(), -1);
  for (std::size_t i = 0; i < probes.size(); ++i) {
    const auto& p = probes[i];
    out.table.names.push_back(p.name);
    out.table.units.push_back(p.unit);
    if (p.integral) {
      slot[i] = static_cast<int>(quad.integrands.size());
      quad.integrands.push_back(p);
      quad.integrands.back().integral = false;
      // As for the states: the tolerance's fraction of the typical magnitude
      // of the integral's unit (J, kg, ...).
      quad.atol.push_back(options.atol * nominal_floor(p.unit));
    }
  }
  const OutputFn output = [&](double t, const double* y, const double* yp) {
    std::vector<double> row;
    row.reserve(probes.size() + 1);
    row.push_back(t);
    for (std::size_t i = 0; i < probes.size(); ++i)
      row.push_back(slot[i] >= 0 ? integrals[slot[i]] : system.probe(probes[i], t, y, yp));
    out.table.add_row(std::move(row));
  };
  out.solver = simulate(system, options, output, quad.integrands.empty() ? nullptr : &quad);
  return out;
}

RunResult run_simulation(const Netlist& netlist, const Registry& registry) {
  System system(elaborate(netlist, registry));
  return run_system(system, solver_options(netlist.simulation));
}

}  // namespace pneumo
