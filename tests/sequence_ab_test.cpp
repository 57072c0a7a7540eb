// netlists/sequence_ab.yaml (and assembly_line.yaml): cylinders switched by their limit switches
// through the sequencer A+ B+ B- A-.
//  * Order: the chain's steps follow each other in the notation's order, each
//    entered at the instant (and just after, in the log) the limit switch of
//    the previous movement closes - not at a time read off an earlier run.
//  * Motion: when B+ starts, A is extended and B still retracted; when A-
//    starts, B is back.
//  * cycle_time (start signal to A0) falls as the supply pressure rises.
//  * Display units: the barg columns are the SI pressures less the ambient.
//  * Newton matrix reuse: the same events as fresh matrices, about their steps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "framework/io/plot.hpp"
#include "framework/analysis/run_metrics.hpp"

namespace pneumo {
namespace {

const std::string kNetlist = std::string(PNEUMO_SOURCE_DIR) + "/netlists/sequence_ab.yaml";

RunResult run_ab(const std::vector<std::string>& sets = {}) {
  Netlist nl = load_netlist(kNetlist);
  for (const auto& s : sets) apply_override(nl, s);
  return run_simulation(nl, builtin_registry());
}

int index_of(const RunResult& r, const std::string& component, const std::string& tag, double after = -1.0) {
  for (std::size_t i = 0; i < r.solver.events.size(); ++i) {
    const auto& e = r.solver.events[i];
    if (e.component == component && e.tag == tag && e.t > after) return static_cast<int>(i);
  }
  return -1;
}

double at(const RunResult& r, const std::string& column, double t) {
  const int c = r.table.column(column);
  for (const auto& row : r.table.rows)
    if (row[0] >= t) return row[c];
  return std::nan("");
}

TEST(SequenceAB, StepsFollowTheNotationEachTriggeredByItsLimitSwitch) {
  const RunResult r = run_ab();
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const auto& ev = r.solver.events;
  // Sequencer step k and the limit switch whose closing must trigger it.
  const std::vector<std::pair<std::string, std::string>> chain = {
      {"cycle_start", "start"}, {"step_2", "a1"}, {"step_3", "b1"}, {"step_4", "b0"}, {"cycle_end", "a0"}};
  int previous = -1;
  for (const auto& [tag, trigger] : chain) {
    const int i = index_of(r, "seq", tag);
    ASSERT_GE(i, 0) << "no sequencer event " << tag;
    EXPECT_GT(i, previous) << tag << " out of order";
    previous = i;
    // The trigger's event is at the same instant, logged before the step.
    const int j = index_of(r, trigger, trigger == "start" ? "step" : "on", ev[i].t - 1e-9);
    ASSERT_GE(j, 0) << "no event of " << trigger << " at t = " << ev[i].t;
    EXPECT_LT(j, i) << tag;
    EXPECT_EQ(ev[j].t, ev[i].t) << tag << " not at the instant " << trigger << " switched";
  }
  const double t_B_plus = ev[index_of(r, "seq", "step_2")].t;
  const double t_A_minus = ev[index_of(r, "seq", "step_4")].t;
  EXPECT_GT(at(r, "x_A", t_B_plus), 0.099 - 1e-9);  // A extended (switch closes 1 mm before the stop)
  EXPECT_LT(at(r, "x_B", t_B_plus), 1e-4);    // B not yet moved
  EXPECT_LT(at(r, "x_B", t_A_minus), 0.0011); // B back within its switch window
  EXPECT_GT(at(r, "x_A", t_A_minus), 0.099);  // A still out
  // Each cylinder travels its full stroke once.
  EXPECT_EQ(index_of(r, "a1", "on", ev[index_of(r, "seq", "cycle_end")].t), -1);
}

TEST(SequenceAB, CycleTimeFallsAsSupplyPressureRises) {
  double previous = INFINITY;
  for (const char* p : {"4 bar", "5 bar", "6 bar", "7 bar"}) {
    Netlist nl = load_netlist(kNetlist);
    apply_override(nl, std::string("p_supply=") + p);
    const RunResult r = run_simulation(nl, builtin_registry());
    ASSERT_TRUE(r.solver.ok) << r.solver.message;
    int k = -1;
    for (std::size_t i = 0; i < nl.metrics.size(); ++i)
      if (nl.metrics[i].name == "cycle_time") k = static_cast<int>(i);
    ASSERT_GE(k, 0) << "netlist metric cycle_time";
    std::vector<bool> marked(nl.metrics.size(), false);
    marked[k] = true;
    const double t_cycle = evaluate_metrics(nl, marked, r, {})[k];
    std::printf("p_supply %s (absolute): cycle_time %.4f s\n", p, t_cycle);
    ASSERT_FALSE(std::isnan(t_cycle)) << p;
    // The metric is the time from the start signal to A's retracted switch.
    EXPECT_NEAR(t_cycle, r.solver.events[index_of(r, "a0", "on", 0.2)].t - 0.1, 1e-12) << p;
    EXPECT_LT(t_cycle, previous) << p;
    previous = t_cycle;
  }
}

// Newton matrix reuse (SolverOptions::jacobian_reuse) changes only the
// matrix the Newton iteration uses, not the equations: the same events in
// the same order at the same times (within the integration error), and,
// since an iteration that fails on a recombined matrix is retried on a fresh
// one at the same step instead of cutting the step, about the steps of
// fresh matrices (measured 2,834 against 2,812; cutting the step took
// 3,054, +8.6 %).
TEST(SequenceAB, NewtonMatrixReuseKeepsTheEventsAndStepsOfFreshMatrices) {
  const RunResult reuse = run_ab();
  const RunResult fresh = run_ab({"simulation.jacobian_reuse=false"});
  ASSERT_TRUE(reuse.solver.ok) << reuse.solver.message;
  ASSERT_TRUE(fresh.solver.ok) << fresh.solver.message;
  const SolverStats& s = reuse.solver.stats;
  EXPECT_GT(s.jacobian_recombinations, 0);
  EXPECT_GT(s.recombined_retries, 0) << "no Newton iteration failed on a recombined matrix: nothing retried";
  EXPECT_EQ(fresh.solver.stats.recombined_retries, 0);
  std::printf("steps %ld with reuse (%ld recombined, %ld retried), %ld with fresh matrices\n", s.steps,
              s.jacobian_recombinations, s.recombined_retries, fresh.solver.stats.steps);
  EXPECT_LE(s.steps, 1.03 * fresh.solver.stats.steps);
  ASSERT_EQ(reuse.solver.events.size(), fresh.solver.events.size());
  for (std::size_t i = 0; i < fresh.solver.events.size(); ++i) {
    const auto& a = reuse.solver.events[i];
    const auto& b = fresh.solver.events[i];
    EXPECT_EQ(a.component + "." + a.tag, b.component + "." + b.tag) << "event " << i;
    EXPECT_NEAR(a.t, b.t, 1e-4) << "event " << i << ": " << b.component << "." << b.tag;
  }
}

TEST(SequenceAB, BargColumnsAreSIPressureLessAmbient) {
  const RunResult r = run_ab({"t_start=0.05 s"});
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const std::string path = testing::TempDir() + "sequence_ab_units.csv";
  write_csv_atomic(path, r.table);
  const ResultsTable shown = read_csv(path);
  const int c = shown.column("p_cap_A");
  ASSERT_GE(c, 0);
  EXPECT_EQ(shown.units[c], "barg");
  EXPECT_EQ(shown.units[shown.column("x_A")], "mm");  // the netlist's display: length
  for (std::size_t k = 0; k < r.table.rows.size(); k += 97)
    EXPECT_NEAR(shown.rows[k][shown.column("x_A")], 1e3 * r.table.rows[k][r.table.column("x_A")], 1e-6);
  for (std::size_t k = 0; k < r.table.rows.size(); k += 97)
    EXPECT_NEAR(shown.rows[k][c], (r.table.rows[k][c] - 101325.0) / 1e5, 1e-8);
  std::remove(path.c_str());
}

// The displacement-step diagram is drawn from the results file (gnuplot);
// without the sequencer's step column it says what to add.
TEST(SequenceAB, StepDiagramIsDrawnAndNeedsTheStepColumn) {
  const RunResult r = run_ab();
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const std::string dir = testing::TempDir() + "sequence_ab_plot/";
  std::filesystem::create_directories(dir);
  write_csv_atomic(dir + "ab.csv", r.table);
  plot_step_diagram(dir + "ab.csv", dir + "steps", {"x_A", "x_B"}, "step");
  EXPECT_GT(std::filesystem::file_size(dir + "steps.png"), 1000u);
  EXPECT_FALSE(std::filesystem::exists(dir + "steps.steps.csv"));  // its data file is cleaned up
  try {
    plot_step_diagram(dir + "ab.csv", dir + "bad", {"x_A"}, "v_A");
    ADD_FAILURE() << "a column that is not the step was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("SEQ.step"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

// netlists/assembly_line.yaml: six cylinders, two of them (D, E) moving in
// one step. The chain completes and prints its takt; in the parallel step
// both leave their retracted switches before the step ends, and the step
// ends only when the slower of the two has arrived (D1 after E1).
TEST(AssemblyLine, RunsItsChainWithAParallelStepAndPrintsTheTakt) {
  const RunResult r = run_simulation(load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/assembly_line.yaml"),
                                     builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  const auto& ev = r.solver.events;
  const int step4 = index_of(r, "seq", "step_4"), step5 = index_of(r, "seq", "step_5");
  const int end = index_of(r, "seq", "cycle_end");
  ASSERT_GE(step4, 0);
  ASSERT_GE(step5, 0);
  ASSERT_GE(end, 0);
  for (const char* sw : {"d0", "e0"}) {
    const int off = index_of(r, sw, "off", ev[step4].t - 1e-9);
    ASSERT_GE(off, 0) << sw;
    EXPECT_LT(ev[off].t, ev[step5].t) << sw << " still retracted when step 5 began";
  }
  const int d1 = index_of(r, "d1", "on", ev[step4].t), e1 = index_of(r, "e1", "on", ev[step4].t);
  ASSERT_GE(d1, 0);
  ASSERT_GE(e1, 0);
  EXPECT_LT(ev[e1].t, ev[d1].t);        // the small stamp arrives first ...
  EXPECT_EQ(ev[d1].t, ev[step5].t);     // ... the press's arrival ends the step
  EXPECT_NE(ev[end].message.find("cycle time"), std::string::npos) << ev[end].message;
  std::printf("assembly line takt: %.4f s (%s)\n", ev[end].t - ev[index_of(r, "seq", "cycle_start")].t,
              ev[end].message.c_str());
}

}  // namespace
}  // namespace pneumo
