#include "framework/run/run.hpp"

namespace pneumo {

SolverOptions solver_options(const SimulationSettings& s) {
  SolverOptions o;
  static_cast<SimulationSettings&>(o) = s;
  return o;
}

RunResult run_system(System& system, const SolverOptions& options) {
  RunResult out;
  const auto& probes = system.circuit().probes;
  out.table.names.push_back("t");
  out.table.units.push_back("s");
  out.table.display.emplace_back();
  // Integral outputs are IDAS quadratures; the others are sampled.
  Quadratures quad;
  std::vector<double> integrals;
  quad.values = &integrals;
  std::vector<int> slot(probes.size(), -1);
  for (std::size_t i = 0; i < probes.size(); ++i) {
    const auto& p = probes[i];
    out.table.names.push_back(p.name);
    out.table.units.push_back(p.unit);
    out.table.display.push_back(p.display);
    if (p.integral) {
      slot[i] = static_cast<int>(quad.integrands.size());
      quad.integrands.push_back(p);
      quad.integrands.back().integral = false;
      // As for the states: the tolerance's fraction of the typical magnitude
      // of the integral's unit (J, kg, ...).
      quad.atol.push_back(options.atol * nominal_floor(p.unit));
    }
  }
  // The sampled outputs, evaluated together (one observe_all per component).
  std::vector<Probe> sampled;
  std::vector<int> sampled_column;
  for (std::size_t i = 0; i < probes.size(); ++i)
    if (slot[i] < 0) {
      sampled.push_back(probes[i]);
      sampled_column.push_back(static_cast<int>(i) + 1);
    }
  const ProbeSet sampled_set = system.probe_set(sampled);
  std::vector<double> values(sampled.size());
  const OutputFn output = [&](double t, const double* y, const double* yp) {
    std::vector<double> row(probes.size() + 1);
    row[0] = t;
    system.probe_all(sampled_set, t, y, yp, values.data());
    for (std::size_t i = 0; i < sampled.size(); ++i) row[sampled_column[i]] = values[i];
    for (std::size_t i = 0; i < probes.size(); ++i)
      if (slot[i] >= 0) row[i + 1] = integrals[slot[i]];
    out.table.add_row(std::move(row));
  };
  SolverOptions opt = options;
  opt.outputs_read_yp = sampled_set.reads_yp;
  out.solver = simulate(system, opt, output, quad.integrands.empty() ? nullptr : &quad);
  return out;
}

RunResult run_simulation(const Netlist& netlist, const Registry& registry) {
  System system(elaborate(netlist, registry));
  return run_system(system, solver_options(netlist.simulation));
}

}  // namespace pneumo
