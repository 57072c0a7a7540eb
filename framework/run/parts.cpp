#include "framework/run/parts.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

namespace pneumo {

namespace {

int root_of(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Part p's value of column c at merged time t, when p has no row at t:
// linear in t between its rows i - 1 and i (its last row if it has none
// after t, its first if none before).
double between_rows(const std::vector<std::vector<double>>& rows, std::size_t i, double t, std::size_t c) {
  if (i == 0) return rows.front()[c];
  if (i >= rows.size()) return rows.back()[c];
  const auto& a = rows[i - 1];
  const auto& b = rows[i];
  const double w = (t - a[0]) / (b[0] - a[0]);
  return a[c] + w * (b[c] - a[c]);
}

void add_stats(SolverStats& sum, const SolverStats& s) {
  sum.steps += s.steps;
  sum.residual_evals += s.residual_evals;
  sum.jacobian_evals += s.jacobian_evals;
  sum.jacobian_recombinations += s.jacobian_recombinations;
  sum.recombined_retries += s.recombined_retries;
  sum.nonlinear_iterations += s.nonlinear_iterations;
  sum.nonlinear_failures += s.nonlinear_failures;
  sum.linear_setups += s.linear_setups;
  sum.lu += s.lu;
  sum.seconds_residual += s.seconds_residual;
  sum.seconds_jacobian += s.seconds_jacobian;
  sum.seconds_total += s.seconds_total;
  sum.error_test_failures += s.error_test_failures;
  sum.root_evals += s.root_evals;
  sum.reinitialisations += s.reinitialisations;
  sum.pattern_misses += s.pattern_misses;
  sum.variables += s.variables;
  sum.netlist_variables += s.netlist_variables;
  sum.explicit_variables += s.explicit_variables;
  sum.nonzeros += s.nonzeros;
  sum.part_steps_max = std::max(sum.part_steps_max, s.steps);
}

}  // namespace

std::vector<std::vector<int>> independent_parts(const Circuit& circuit) {
  const int n = static_cast<int>(circuit.components.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& c : circuit.connections)
    for (std::size_t k = 1; k < c.ports.size(); ++k) {
      const int a = root_of(parent, c.ports[0].component), b = root_of(parent, c.ports[k].component);
      parent[std::max(a, b)] = std::min(a, b);  // the root stays the part's first component
    }
  std::vector<std::vector<int>> parts;
  std::vector<int> part_of(n, -1);
  for (int i = 0; i < n; ++i) {
    const int r = root_of(parent, i);
    if (part_of[r] < 0) {
      part_of[r] = static_cast<int>(parts.size());
      parts.emplace_back();
    }
    parts[part_of[r]].push_back(i);
  }
  return parts;
}

std::vector<Circuit> split_circuit(Circuit&& circuit, const std::vector<std::vector<int>>& parts,
                                   std::vector<std::vector<int>>& column_of) {
  const std::size_t n = circuit.components.size();
  std::vector<int> part_of(n), local(n);
  std::vector<Circuit> out(parts.size());
  column_of.assign(parts.size(), {0});
  for (std::size_t p = 0; p < parts.size(); ++p) {
    out[p].gas = circuit.gas;
    for (const int i : parts[p]) {
      part_of[i] = static_cast<int>(p);
      local[i] = static_cast<int>(out[p].components.size());
      out[p].components.push_back(std::move(circuit.components[i]));
      if (static_cast<std::size_t>(i) < circuit.component_where.size())
        out[p].component_where.push_back(circuit.component_where[i]);
    }
  }
  for (auto& c : circuit.connections) {
    Circuit& to = out[part_of[c.ports.front().component]];
    for (auto& port : c.ports) port.component = local[port.component];
    to.connections.push_back(std::move(c));
  }
  for (std::size_t k = 0; k < circuit.probes.size(); ++k) {
    Probe probe = circuit.probes[k];
    const int p = part_of[probe.component];
    probe.component = local[probe.component];
    out[p].probes.push_back(std::move(probe));
    column_of[p].push_back(static_cast<int>(k) + 1);
  }
  return out;
}

void merge_parts(std::vector<PartRun>& parts, ResultsTable header, SolverResult& solver, ResultsTable& table) {
  table = std::move(header);
  table.rows.clear();
  solver = SolverResult{};
  solver.ok = true;
  solver.t_reached = std::numeric_limits<double>::infinity();
  double t_last = std::numeric_limits<double>::infinity();
  for (const auto& part : parts) {
    add_stats(solver.stats, part.solver.stats);
    solver.t_reached = std::min(solver.t_reached, part.solver.t_reached);
    if (!part.solver.ok && solver.ok) {
      solver.ok = false;
      solver.message = part.solver.message;
    }
    t_last = std::min(t_last, part.table.rows.empty() ? -std::numeric_limits<double>::infinity()
                                                      : part.table.rows.back()[0]);
    solver.events.insert(solver.events.end(), part.solver.events.begin(), part.solver.events.end());
    solver.warnings.insert(solver.warnings.end(), part.solver.warnings.begin(), part.solver.warnings.end());
  }
  solver.stats.parts = static_cast<int>(parts.size());
  std::stable_sort(solver.events.begin(), solver.events.end(),
                   [](const EventLogEntry& a, const EventLogEntry& b) { return a.t < b.t; });

  std::vector<std::size_t> next(parts.size(), 0), count(parts.size());
  const std::size_t width = table.names.size();
  for (;;) {
    double t = std::numeric_limits<double>::infinity();
    for (std::size_t p = 0; p < parts.size(); ++p)
      if (next[p] < parts[p].table.rows.size()) t = std::min(t, parts[p].table.rows[next[p]][0]);
    if (!(t <= t_last)) break;
    std::size_t rows_at_t = 0;
    for (std::size_t p = 0; p < parts.size(); ++p) {
      const auto& rows = parts[p].table.rows;
      count[p] = 0;
      while (next[p] + count[p] < rows.size() && rows[next[p] + count[p]][0] == t) ++count[p];
      rows_at_t = std::max(rows_at_t, count[p]);
    }
    for (std::size_t j = 0; j < rows_at_t; ++j) {
      std::vector<double> row(width);
      row[0] = t;
      for (std::size_t p = 0; p < parts.size(); ++p) {
        const auto& rows = parts[p].table.rows;
        const auto& cols = parts[p].column_of;
        for (std::size_t c = 1; c < cols.size(); ++c)
          row[cols[c]] = count[p] > 0 ? rows[next[p] + std::min(j, count[p] - 1)][c] : between_rows(rows, next[p], t, c);
      }
      table.add_row(std::move(row));
    }
    for (std::size_t p = 0; p < parts.size(); ++p) next[p] += count[p];
  }
}

}  // namespace pneumo
