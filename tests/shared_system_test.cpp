// One assembled System, several integrations: the System holds the
// structure and reductions and no run's state (the modes and the
// evaluator's scratch are each integration's Evaluator), so that threads
// run one System at the same time and each gets what a run alone gets.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <thread>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo {
namespace {

double largest(const ResultsTable& t, const std::string& column) {
  const int c = t.column(column);
  double m = -1e300;
  for (const auto& row : t.rows) m = std::max(m, row[c]);
  return m;
}

// The basic cushioning rig (100 mm stroke, the piston ending at the head):
// four integrations of one System at once, two threads each running it
// twice, against one run alone. A System that kept the modes or the
// residual's cache of a run would hand one thread's valve position or
// expanded unknowns to the other.
TEST(SharedSystem, ThreadsIntegrateOneSystemAsEachRunAlone) {
  const Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml");
  const System system(elaborate(nl, builtin_registry()));
  const SolverOptions options = solver_options(nl.simulation);
  const RunResult alone = run_system(system, options);
  ASSERT_TRUE(alone.solver.ok) << alone.solver.message;
  // The piston strokes 100 mm to the head (0.1 mm short of the stop at most).
  EXPECT_GT(largest(alone.table, "x"), 0.0999);
  EXPECT_LT(largest(alone.table, "x"), 0.1 + 2e-4);  // the stop gives by less than 0.2 mm

  std::vector<RunResult> runs(4);
  std::vector<std::thread> threads;
  for (int k = 0; k < 2; ++k)
    threads.emplace_back([&, k] {
      for (int i = 0; i < 2; ++i) runs[2 * k + i] = run_system(system, options);
    });
  for (auto& t : threads) t.join();
  for (const auto& r : runs) {
    ASSERT_TRUE(r.solver.ok) << r.solver.message;
    EXPECT_EQ(r.solver.stats.steps, alone.solver.stats.steps);
    ASSERT_EQ(r.table.rows.size(), alone.table.rows.size());
    for (std::size_t i = 0; i < r.table.rows.size(); ++i) ASSERT_EQ(r.table.rows[i], alone.table.rows[i]) << "row " << i;
  }
}

}  // namespace
}  // namespace pneumo
