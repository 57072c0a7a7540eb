#include "framework/run/run.hpp"

#include <algorithm>
#include <exception>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <thread>

#include "framework/core/parallel.hpp"
#include "framework/run/parts.hpp"

namespace pneumo {

SolverOptions solver_options(const SimulationSettings& s) {
  SolverOptions o;
  static_cast<SimulationSettings&>(o) = s;
  return o;
}

namespace {

// "t" and every probe's column, no rows.
ResultsTable table_header(const Circuit& circuit) {
  ResultsTable t;
  t.names.push_back("t");
  t.units.push_back("s");
  t.display.emplace_back();
  for (const auto& p : circuit.probes) {
    t.names.push_back(p.name);
    t.units.push_back(p.unit);
    t.display.push_back(p.display);
  }
  return t;
}

}  // namespace

RunResult run_system(System& system, const SolverOptions& options) {
  RunResult out;
  const auto& probes = system.circuit().probes;
  out.table = table_header(system.circuit());
  // Integral outputs are IDAS quadratures; the others are sampled.
  Quadratures quad;
  std::vector<double> integrals;
  quad.values = &integrals;
  std::vector<int> slot(probes.size(), -1);
  for (std::size_t i = 0; i < probes.size(); ++i) {
    const auto& p = probes[i];
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


RunResult run_circuit(Circuit circuit, const SolverOptions& options) {
  const std::vector<std::vector<int>> parts = independent_parts(circuit);
  // A steady start's settling needs the rest-heat rows (System::set_resting).
  const AssemblyOptions assembly{.rest_heat = options.steady_start};
  if (parts.size() <= 1) {
    System system(std::move(circuit), assembly);
    return run_system(system, options);
  }
  const ResultsTable header = table_header(circuit);
  std::vector<std::vector<int>> column_of;
  std::vector<Circuit> circuits = split_circuit(std::move(circuit), parts, column_of);
  std::vector<PartRun> runs(parts.size());
  // Each part's assembly error is kept, so that the one thrown does not
  // depend on the threads' timing.
  std::vector<std::exception_ptr> errors(parts.size());
  std::vector<std::size_t> disturbed(parts.size(), 0);
  const int threads = options.threads > 0 ? options.threads
                                          : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  parallel_for(static_cast<long>(parts.size()), threads, [&](int, long p) {
    std::unique_ptr<System> system;
    try {
      system = std::make_unique<System>(std::move(circuits[p]), assembly);
    } catch (...) {
      errors[p] = std::current_exception();
      return;
    }
    // Each disturbance goes to the part whose System has its variable.
    SolverOptions part_options = options;
    const auto& names = system->variable_names();
    std::erase_if(part_options.disturbances, [&](const Disturbance& d) {
      return std::find(names.begin(), names.end(), d.variable) == names.end();
    });
    disturbed[p] = part_options.disturbances.size();
    RunResult r = run_system(*system, part_options);
    runs[p].solver = std::move(r.solver);
    runs[p].table = std::move(r.table);
    runs[p].column_of = std::move(column_of[p]);
  });
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  if (std::accumulate(disturbed.begin(), disturbed.end(), std::size_t{0}) < options.disturbances.size())
    throw std::invalid_argument("a disturbance names an unknown that no part of the circuit has");
  RunResult out;
  merge_parts(runs, header, out.solver, out.table);
  return out;
}

RunResult run_simulation(const Netlist& netlist, const Registry& registry) {
  return run_circuit(elaborate(netlist, registry), solver_options(netlist.simulation));
}

}  // namespace pneumo
