// A run kept at some times and another resumed from one of its checkpoints
// (run/run.hpp: Resumption): the resumed run is the same trajectory from
// there on - the same events in the same order at the same times, the same
// positions within the integration's error - and carries the integrals
// over: on the sequence A+ B+ B- A- (netlists/sequence_ab.yaml, whose
// sequencer and limit switches hold modes across the checkpoint), the
// integral of cylinder A's velocity from t_start stays its displacement
// x_A - x_A(0).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

Netlist sequence_with_travel() {
  const std::string file = std::string(PNEUMO_SOURCE_DIR) + "/netlists/sequence_ab.yaml";
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const auto at = s.find("\noutputs:\n");
  s.insert(at + 10, "  travel_A: {integral: cyl_A.v}\n");
  return parse_netlist(s, file);
}

RunResult run(const Netlist& nl, const Resumption& r = {}, long max_total_steps = 0) {
  SolverOptions o = solver_options(nl.simulation);
  o.threads = 1;
  o.max_total_steps = max_total_steps;
  return run_circuit(elaborate(nl, builtin_registry()), o, r);
}

TEST(Resume, ACheckpointedRunGoesOnAsTheWholeRunWithItsModesAndIntegrals) {
  const Netlist nl = sequence_with_travel();
  const RunResult whole = run(nl);
  ASSERT_TRUE(whole.solver.ok) << whole.solver.message;
  const RunResult kept = run(nl, {{0.3, 0.9}, nullptr});
  ASSERT_TRUE(kept.solver.ok) << kept.solver.message;
  ASSERT_EQ(kept.checkpoints.size(), 2u);
  EXPECT_DOUBLE_EQ(kept.checkpoints[1].t, 0.9);

  const RunResult resumed = run(nl, {{}, &kept.checkpoints[1]});
  ASSERT_TRUE(resumed.solver.ok) << resumed.solver.message;
  ASSERT_FALSE(resumed.table.rows.empty());
  EXPECT_GT(resumed.table.rows.front()[0], 0.9);
  EXPECT_DOUBLE_EQ(resumed.table.rows.back()[0], whole.table.rows.back()[0]);

  // The events after the checkpoint, in the same order at the same times.
  std::vector<EventLogEntry> after;
  for (const auto& e : whole.solver.events)
    if (e.t > 0.9) after.push_back(e);
  ASSERT_GE(after.size(), 5u);  // B-, A- and the cycle's end are still to come
  ASSERT_EQ(resumed.solver.events.size(), after.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_EQ(resumed.solver.events[i].component, after[i].component) << i;
    EXPECT_EQ(resumed.solver.events[i].tag, after[i].tag) << i;
    EXPECT_NEAR(resumed.solver.events[i].t, after[i].t, 1e-4) << i;
  }

  const int x_A = resumed.table.column("x_A"), x_B = resumed.table.column("x_B"),
            travel = resumed.table.column("travel_A");
  const double x_A0 = whole.table.rows.front()[x_A];
  for (const auto& row : resumed.table.rows) {
    EXPECT_NEAR(row[x_A], test_support::value_at(whole, x_A, row[0]), 5e-5) << "t = " << row[0];  // 0.05 mm
    EXPECT_NEAR(row[x_B], test_support::value_at(whole, x_B, row[0]), 5e-5) << "t = " << row[0];
    EXPECT_NEAR(row[travel], row[x_A] - x_A0, 5e-5) << "t = " << row[0];
  }
}

// A budget of steps in all (what the diagnosis gives a disturbed run, a
// multiple of the kept run's): within it the resumed run is the one without
// a budget, row for row; past it the run stops there with the budget named,
// its rows up to where it stopped.
TEST(Resume, AResumedRunBoundedInStepsStopsWhereTheBudgetRunsOut) {
  const Netlist nl = sequence_with_travel();
  const RunResult kept = run(nl, {{0.3}, nullptr});
  ASSERT_EQ(kept.checkpoints.size(), 1u);
  const RunResult free = run(nl, {{}, &kept.checkpoints[0]});
  ASSERT_TRUE(free.solver.ok) << free.solver.message;
  const long steps = free.solver.stats.steps;
  ASSERT_GT(steps, 100);

  const RunResult within = run(nl, {{}, &kept.checkpoints[0]}, 2 * steps);
  ASSERT_TRUE(within.solver.ok) << within.solver.message;
  ASSERT_EQ(within.table.rows.size(), free.table.rows.size());
  for (std::size_t i = 0; i < free.table.rows.size(); ++i) EXPECT_EQ(within.table.rows[i], free.table.rows[i]) << i;

  const RunResult short_of = run(nl, {{}, &kept.checkpoints[0]}, steps / 2);
  EXPECT_FALSE(short_of.solver.ok);
  EXPECT_NE(short_of.solver.message.find("IDA_TOO_MUCH_WORK (" + std::to_string(steps / 2) + " steps in all)"),
            std::string::npos)
      << short_of.solver.message;
  EXPECT_LE(short_of.solver.stats.steps, steps / 2);
  ASSERT_FALSE(short_of.table.rows.empty());
  const double t_end = free.table.rows.back()[0];
  EXPECT_GT(short_of.table.rows.back()[0], 0.3);
  EXPECT_LT(short_of.table.rows.back()[0], t_end);
  EXPECT_NEAR(short_of.solver.t_reached, short_of.table.rows.back()[0], 1e-9);
}

// Checkpoints taken in passing (read off the interpolant at output rows):
// the run is the one kept nowhere, row for row, and a run resumed from one
// goes on as the whole run does.
TEST(Resume, CheckpointsTakenInPassingLeaveTheRunAsItIsAndResumeAsStoppedOnes) {
  const Netlist nl = sequence_with_travel();
  const RunResult whole = run(nl);
  Resumption passing{{0.3, 0.9}, nullptr};
  passing.in_passing = true;
  const RunResult kept = run(nl, passing);
  ASSERT_TRUE(whole.solver.ok && kept.solver.ok);
  ASSERT_EQ(kept.table.rows.size(), whole.table.rows.size());
  for (std::size_t i = 0; i < whole.table.rows.size(); ++i) EXPECT_EQ(kept.table.rows[i], whole.table.rows[i]) << i;
  EXPECT_EQ(kept.solver.stats.steps, whole.solver.stats.steps);
  ASSERT_EQ(kept.checkpoints.size(), 2u);
  EXPECT_GE(kept.checkpoints[1].t, 0.9);
  EXPECT_LT(kept.checkpoints[1].t, 0.9 + nl.simulation.output_interval + 1e-12);

  const RunResult resumed = run(nl, {{}, &kept.checkpoints[1]});
  ASSERT_TRUE(resumed.solver.ok) << resumed.solver.message;
  std::vector<EventLogEntry> after;
  for (const auto& e : whole.solver.events)
    if (e.t > kept.checkpoints[1].t) after.push_back(e);
  ASSERT_GE(after.size(), 5u);
  ASSERT_EQ(resumed.solver.events.size(), after.size());
  for (std::size_t i = 0; i < after.size(); ++i) EXPECT_NEAR(resumed.solver.events[i].t, after[i].t, 1e-4) << i;
  const int x_A = resumed.table.column("x_A"), travel = resumed.table.column("travel_A");
  const double x_A0 = whole.table.rows.front()[x_A];
  for (const auto& row : resumed.table.rows) {
    EXPECT_NEAR(row[x_A], test_support::value_at(whole, x_A, row[0]), 5e-5) << "t = " << row[0];
    EXPECT_NEAR(row[travel], row[x_A] - x_A0, 5e-5) << "t = " << row[0];
  }
}

TEST(Resume, ACheckpointOfAnotherCircuitIsRefused) {
  const Netlist nl = sequence_with_travel();
  RunResult kept = run(nl, {{0.3}, nullptr});
  ASSERT_EQ(kept.checkpoints.size(), 1u);
  kept.checkpoints[0].parts[0].y.pop_back();
  EXPECT_THROW(run(nl, {{}, &kept.checkpoints[0]}), std::invalid_argument);
}

}  // namespace
}  // namespace pneumo
