// One simulation run from a netlist: elaborate, assemble, integrate, and
// collect the netlist's outputs into a results table.
#pragma once

#include <memory>

#include "framework/assembly/system.hpp"
#include "framework/io/results.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/solver/ida_solver.hpp"

namespace pneumo {

struct RunResult {
  SolverResult solver;
  ResultsTable table;
};

SolverOptions solver_options(const SimulationSettings& s);

// Throws InputError / StructureError for bad input; solver failures are
// reported in RunResult::solver (ok == false) with the rows computed so far.
RunResult run_simulation(const Netlist& netlist, const Registry& registry);
RunResult run_system(System& system, const SolverOptions& options);
// A circuit of one part: as run_system on its System. Of several
// independent parts (framework/run/parts.hpp): each part assembled and
// integrated by a System and an IDA of its own, on options.threads threads,
// the results merged (merge_parts; the table's columns as the whole
// circuit's: "t", then its probes in order). Assembly errors of the parts
// are thrown as the first part's in component order.
RunResult run_circuit(Circuit circuit, const SolverOptions& options);

}  // namespace pneumo
