// Independent parts of a circuit: components joined by no connection,
// directly or through other components, share no equation, so each part can
// be integrated by its own IDA instance with a step size of its own, and
// their outputs merged onto one time base afterwards.
#pragma once

#include <vector>

#include "framework/io/results.hpp"
#include "framework/model/circuit.hpp"
#include "framework/solver/ida_solver.hpp"

namespace pneumo {

// The components of each part (ascending indices); parts ordered by their
// first component. Every connection (pneumatic, mechanical, thermal or
// signal) joins the components of its ports.
std::vector<std::vector<int>> independent_parts(const Circuit& circuit);

// One circuit per part: the components moved out of `circuit` in their
// order, the connections and probes of the part renumbered, the gas copied.
// `column_of[p][c]` is the column (t = 0) of the whole circuit's table that
// part p's column c fills.
std::vector<Circuit> split_circuit(Circuit&& circuit, const std::vector<std::vector<int>>& parts,
                                   std::vector<std::vector<int>>& column_of);

// One part's run, for merge_parts.
struct PartRun {
  SolverResult solver;
  ResultsTable table;
  std::vector<int> column_of;  // see split_circuit
};

// The whole circuit's table from its parts' tables (names, units and
// display of `header`, which has every column): a row for every row of
// every part, in time order. The j-th rows of several parts at one time t
// (their common output grid, simultaneous events) are one merged row. A
// part without a row at t contributes its value interpolated linearly in t
// between its rows before and after t (between two of its events it is
// continuous there); one with fewer rows at t repeats its last. A part's own
// rows keep its values bit for bit. Rows end at the earliest end of a part
// (a failed part stops them all). Events merge in time order (stable: parts
// in order at one time); the statistics add up, steps also as the largest
// of a part (SolverStats::part_steps_max).
void merge_parts(std::vector<PartRun>& parts, ResultsTable header, SolverResult& solver, ResultsTable& table);

}  // namespace pneumo
