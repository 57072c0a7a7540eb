// One simulation run from a netlist: elaborate, assemble, integrate, and
// collect the netlist's outputs into a results table.
#pragma once

#include <memory>

#include "framework/assembly/system.hpp"
#include "framework/io/results.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/solver/ida_solver.hpp"

namespace pneumo {

// A run's state at one instant, part by part (run_circuit's independent
// parts; one for a System).
struct RunCheckpoint {
  double t = 0.0;
  std::vector<Checkpoint> parts;
};

struct RunResult {
  SolverResult solver;
  ResultsTable table;
  std::vector<RunCheckpoint> checkpoints;  // at Resumption::keep_at, as far as the run got
};

// A run kept at some times, or resumed from where one of the same circuit
// was kept. A program's (the diagnosis: a disturbance that is zero until
// some time need not integrate what comes before it again).
struct Resumption {
  std::vector<double> keep_at;  // ascending
  const RunCheckpoint* from = nullptr;
  // The kept run's table (same options but the disturbances): given, the
  // resumed run's table is whole - the kept rows up to the checkpoint, then
  // its own - and a part no disturbance reaches is not integrated again,
  // its rows all the kept run's. Without it, the rows start after `from`.
  const ResultsTable* kept = nullptr;
  // keep_at's checkpoints taken as the run passes them, at output rows,
  // without stopping there (Integration::keep_in_passing): the run is the
  // one kept nowhere, step for step.
  bool in_passing = false;
};

SolverOptions solver_options(const SimulationSettings& s);

// Throws InputError / StructureError for bad input; solver failures are
// reported in RunResult::solver (ok == false) with the rows computed so far.
RunResult run_simulation(const Netlist& netlist, const Registry& registry);
// One integration of `system` (an Evaluator of its own): Systems are not
// changed by a run, so threads may run one System at the same time.
RunResult run_system(const System& system, const SolverOptions& options, const Resumption& resumption = {});
// A circuit of one part: as run_system on its System. Of several
// independent parts (framework/run/parts.hpp): each part assembled and
// integrated by a System and an IDA of its own, on options.threads threads,
// the results merged (merge_parts; the table's columns as the whole
// circuit's: "t", then its probes in order). Assembly errors of the parts
// are thrown as the first part's in component order.
RunResult run_circuit(Circuit circuit, const SolverOptions& options, const Resumption& resumption = {});
// A circuit of one part assembled beforehand (assembly_options(options)):
// as run_circuit, without assembling it again - a program that runs one
// circuit many times, with other disturbances, on threads that share it.
RunResult run_assembled(const System& system, const SolverOptions& options, const Resumption& resumption = {});
// The assembly options run_circuit assembles with: a steady start's
// settling needs the rest-heat rows (Evaluator::set_resting).
AssemblyOptions assembly_options(const SolverOptions& options);

}  // namespace pneumo
