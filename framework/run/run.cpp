#include "framework/run/run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <thread>

#include "framework/core/parallel.hpp"
#include "framework/run/parts.hpp"
#include "framework/solver/integration.hpp"

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

// The parts' checkpoints (each of one part) at each time all of them reached.
std::vector<RunCheckpoint> merge_checkpoints(std::vector<std::vector<RunCheckpoint>>& kept) {
  std::size_t n = SIZE_MAX;
  for (const auto& k : kept) n = std::min(n, k.size());
  std::vector<RunCheckpoint> out(kept.empty() ? 0 : n);
  for (std::size_t j = 0; j < out.size(); ++j) {
    out[j].t = kept[0][j].t;
    for (auto& k : kept) out[j].parts.push_back(std::move(k[j].parts[0]));
  }
  return out;
}

// Part `p`'s columns (column_of: split_circuit's) of a whole circuit's
// rows; those after `t` left out.
std::vector<std::vector<double>> part_rows(const ResultsTable& whole, const std::vector<int>& column_of, double t) {
  std::vector<std::vector<double>> out;
  for (const auto& row : whole.rows) {
    if (row[0] > t) break;
    std::vector<double> r(column_of.size());
    for (std::size_t c = 0; c < column_of.size(); ++c) r[c] = row[column_of[c]];
    out.push_back(std::move(r));
  }
  return out;
}

// A run resumed with the kept run's table: the kept rows up to the
// checkpoint (these columns of them), then its own.
void kept_rows_first(const Resumption& r, const std::vector<int>& columns, std::vector<std::vector<double>>& rows) {
  if (!r.from || !r.kept) return;
  auto out = part_rows(*r.kept, columns, r.from->t);
  out.insert(out.end(), std::make_move_iterator(rows.begin()), std::make_move_iterator(rows.end()));
  rows = std::move(out);
}

// Part p's run on its System (its disturbances already picked out): a
// resumed part no disturbance reaches is the kept run's rows.
PartRun run_part(const System& system, const SolverOptions& options, const Resumption& resumption, std::size_t p,
                 std::vector<int> column_of, std::vector<RunCheckpoint>& kept) {
  PartRun out;
  if (resumption.from && resumption.kept && options.disturbances.empty()) {
    out.table.rows = part_rows(*resumption.kept, column_of, INFINITY);
    out.solver.ok = true;
    out.solver.t_reached = out.table.rows.empty() ? resumption.from->t : out.table.rows.back()[0];
  } else {
    Resumption own{resumption.keep_at, nullptr};
    own.in_passing = resumption.in_passing;
    RunCheckpoint from;
    if (resumption.from) {
      from = {resumption.from->t, {resumption.from->parts[p]}};
      own.from = &from;
    }
    RunResult r = run_system(system, options, own);
    kept_rows_first(resumption, column_of, r.table.rows);
    out.solver = std::move(r.solver);
    out.table = std::move(r.table);
    kept = std::move(r.checkpoints);
  }
  out.column_of = std::move(column_of);
  return out;
}

}  // namespace

RunResult run_system(const System& system, const SolverOptions& options, const Resumption& resumption) {
  if (resumption.from && resumption.from->parts.size() != 1)
    throw std::invalid_argument("run_system: a checkpoint of " + std::to_string(resumption.from->parts.size()) + " parts");
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
  Evaluator eval(system);
  std::vector<double> values(sampled.size());
  const OutputFn output = [&](double t, const double* y, const double* yp) {
    std::vector<double> row(probes.size() + 1);
    row[0] = t;
    eval.probe_all(sampled_set, t, y, yp, values.data());
    for (std::size_t i = 0; i < sampled.size(); ++i) row[sampled_column[i]] = values[i];
    for (std::size_t i = 0; i < probes.size(); ++i)
      if (slot[i] >= 0) row[i + 1] = integrals[slot[i]];
    out.table.add_row(std::move(row));
  };
  SolverOptions opt = options;
  opt.outputs_read_yp = sampled_set.reads_yp;
  Integration integration(eval, opt, output, quad.integrands.empty() ? nullptr : &quad);
  if (resumption.in_passing) integration.keep_in_passing(resumption.keep_at);
  bool ok = resumption.from ? integration.resume(resumption.from->parts[0]) : integration.start();
  // One checkpoint a time kept (one at or before the start: the start's).
  for (double t : resumption.in_passing ? std::vector<double>{} : resumption.keep_at) {
    if (!ok || t > opt.t_end) break;
    ok = t <= integration.time() || integration.advance_to(t);
    if (!ok) break;
    out.checkpoints.push_back({integration.time(), {integration.checkpoint()}});
  }
  if (ok) integration.advance_to(opt.t_end);
  for (auto& c : integration.passed()) out.checkpoints.push_back({c.t, {std::move(c)}});
  out.solver = integration.finish();
  return out;
}


AssemblyOptions assembly_options(const SolverOptions& options) { return {.rest_heat = options.steady_start}; }

RunResult run_assembled(const System& system, const SolverOptions& options, const Resumption& resumption) {
  std::vector<int> columns(system.circuit().probes.size() + 1);
  std::iota(columns.begin(), columns.end(), 0);
  RunResult r = run_system(system, options, resumption);
  kept_rows_first(resumption, columns, r.table.rows);
  return r;
}

RunResult run_circuit(Circuit circuit, const SolverOptions& options, const Resumption& resumption) {
  const std::vector<std::vector<int>> parts = independent_parts(circuit);
  const AssemblyOptions assembly = assembly_options(options);
  if (parts.size() <= 1) return run_assembled(System(std::move(circuit), assembly), options, resumption);
  if (resumption.from && resumption.from->parts.size() != parts.size())
    throw std::invalid_argument("run_circuit: a checkpoint of " + std::to_string(resumption.from->parts.size()) +
                                " parts for a circuit of " + std::to_string(parts.size()));
  const ResultsTable header = table_header(circuit);
  std::vector<std::vector<int>> column_of;
  std::vector<Circuit> circuits = split_circuit(std::move(circuit), parts, column_of);
  std::vector<PartRun> runs(parts.size());
  // Each part's assembly error is kept, so that the one thrown does not
  // depend on the threads' timing.
  std::vector<std::exception_ptr> errors(parts.size());
  std::vector<std::size_t> disturbed(parts.size(), 0);
  std::vector<std::vector<RunCheckpoint>> kept(parts.size());
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
    runs[p] = run_part(*system, part_options, resumption, p, std::move(column_of[p]), kept[p]);
  });
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  if (std::accumulate(disturbed.begin(), disturbed.end(), std::size_t{0}) < options.disturbances.size())
    throw std::invalid_argument("a disturbance names an unknown that no part of the circuit has");
  RunResult out;
  merge_parts(runs, header, out.solver, out.table);
  out.checkpoints = merge_checkpoints(kept);
  return out;
}

RunResult run_simulation(const Netlist& netlist, const Registry& registry) {
  return run_circuit(elaborate(netlist, registry), solver_options(netlist.simulation));
}

}  // namespace pneumo
