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

}  // namespace pneumo
