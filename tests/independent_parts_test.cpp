// Circuits of independent parts: copies of the cushion rig that share no
// connection are integrated apart (each part its own IDA) and must give
// each copy exactly the trajectory of the rig run alone - the physics of
// one copy does not depend on the others; copies joined through a shared
// component stay one part.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "benchmarks/copies_netlist.hpp"
#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/parts.hpp"
#include "framework/run/run.hpp"

namespace pneumo {
namespace {

const std::string kRigPath = std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml";
const char* const kZ[] = {"0.8 rev", "1.5 rev", "3 rev"};

std::string rig_text() {
  std::ifstream f(kRigPath);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string three_copies(const std::string& shared = "") {
  return pneumo_scale::copies_netlist(
      rig_text(), 3, [](int k, YAML::Node p) { p["z_EC"] = kZ[k]; }, shared);
}

RunResult rig_alone(int k) {
  Netlist nl = load_netlist(kRigPath);
  apply_override(nl, std::string("z_EC=") + kZ[k]);
  return run_simulation(nl, builtin_registry());
}

TEST(IndependentParts, SignalAndMechanicalConnectionsJoinComponentsIntoOnePartPerCopy) {
  const Circuit c = elaborate(parse_netlist(three_copies(), "copies.yaml"), builtin_registry());
  const auto parts = independent_parts(c);
  ASSERT_EQ(parts.size(), 3u);
  // valve_cmd reaches its copy only through a signal, the load only through
  // a flange: both belong to their copy's part.
  for (int k = 0; k < 3; ++k) {
    const auto& part = parts[k];
    for (const char* name : {"supply", "valve_cmd", "cylinder", "load", "exhaust"})
      EXPECT_NE(std::find(part.begin(), part.end(), c.find(pneumo_scale::copy_name(k, name))), part.end())
          << name << " of copy " << k;
    EXPECT_EQ(part.size(), 9u);
  }
}

TEST(IndependentParts, EachCopyIntegratedApartEqualsTheRigRunAlone) {
  const RunResult all = run_simulation(parse_netlist(three_copies(), "copies.yaml"), builtin_registry());
  ASSERT_TRUE(all.solver.ok) << all.solver.message;
  EXPECT_EQ(all.solver.stats.parts, 3);
  double impact[3] = {};
  for (int k = 0; k < 3; ++k) {
    const RunResult alone = rig_alone(k);
    ASSERT_TRUE(alone.solver.ok) << alone.solver.message;
    EXPECT_EQ(alone.solver.stats.parts, 1);
    // Every row of the rig alone is a row of the merged table, in order,
    // with the same x and p_EC.
    std::size_t j = 0;
    for (const auto& row : alone.table.rows) {
      while (j < all.table.rows.size() && all.table.rows[j][0] != row[0]) ++j;
      ASSERT_LT(j, all.table.rows.size()) << "copy " << k << ": no merged row at t = " << row[0];
      for (const char* out : {"x", "p_EC"}) {
        const double a = all.table.rows[j][all.table.column(pneumo_scale::copy_name(k, out))];
        const double b = row[alone.table.column(out)];
        ASSERT_LE(std::abs(a - b), 1e-9 * std::abs(b)) << out << " of copy " << k << " at t = " << row[0];
      }
      ++j;
    }
    // Its events, named after its own components, at the same times.
    std::size_t found = 0;
    for (const auto& ev : alone.solver.events)
      for (const auto& merged : all.solver.events)
        if (merged.t == ev.t && merged.component == pneumo_scale::copy_name(k, ev.component) &&
            merged.message == ev.message) {
          ++found;
          break;
        }
    EXPECT_EQ(found, alone.solver.events.size()) << "copy " << k;
    for (const auto& ev : alone.solver.events)
      if (ev.tag == "cap_impact" && impact[k] == 0.0) impact[k] = ev.t;
    EXPECT_GT(impact[k], 0.0) << "copy " << k << " reaches the cap end";
  }
  // The copies differ (a narrower cushion throttle brakes harder: the cap
  // end is reached later), so the comparison above could tell them apart.
  EXPECT_GT(impact[0], impact[1]);
  EXPECT_GT(impact[1], impact[2]);
  // Merged events are in time order.
  for (std::size_t i = 1; i < all.solver.events.size(); ++i)
    EXPECT_LE(all.solver.events[i - 1].t, all.solver.events[i].t);
}

TEST(IndependentParts, SerialAndThreadedRunsGiveTheSameTable) {
  const Netlist nl = parse_netlist(three_copies(), "copies.yaml");
  SolverOptions one = solver_options(nl.simulation), two = one;
  one.threads = 1;
  two.threads = 2;
  const RunResult a = run_circuit(elaborate(nl, builtin_registry()), one);
  const RunResult b = run_circuit(elaborate(nl, builtin_registry()), two);
  ASSERT_TRUE(a.solver.ok && b.solver.ok);
  EXPECT_EQ(a.table.rows, b.table.rows);
  EXPECT_EQ(a.solver.stats.steps, b.solver.stats.steps);
}

TEST(IndependentParts, CopiesOnOneSupplyAreOneCoupledPart) {
  const Netlist nl = parse_netlist(three_copies("supply"), "line.yaml");
  EXPECT_EQ(independent_parts(elaborate(nl, builtin_registry())).size(), 1u);
  const RunResult r = run_simulation(nl, builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  EXPECT_EQ(r.solver.stats.parts, 1);
  EXPECT_EQ(r.solver.stats.part_steps_max, r.solver.stats.steps);
}

// 32 copies on one supply join 33 pneumatic ports at the supply's node:
// its stream mixing would read 65 variables, past the 64 locals a block
// holds. An input error naming the connection's line, not an overrun.
TEST(IndependentParts, ANodeOfMoreThan32PneumaticPortsIsAnInputErrorAtItsConnection) {
  const std::string text = pneumo_scale::copies_netlist(rig_text(), 32, {}, "supply");
  const Netlist nl = parse_netlist(text, "line.yaml");
  EXPECT_EQ(independent_parts(elaborate(nl, builtin_registry())).size(), 1u);
  try {
    (void)run_simulation(nl, builtin_registry());
    FAIL() << "a node of 33 pneumatic ports was assembled";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().file, "line.yaml");
    EXPECT_GT(e.where().line, 0);
    EXPECT_NE(std::string(e.what()).find("joins 33 ports"), std::string::npos) << e.what();
  }
  // 16 copies (17 ports) assemble.
  EXPECT_NO_THROW(System(elaborate(parse_netlist(pneumo_scale::copies_netlist(rig_text(), 16, {}, "supply"), "l.yaml"),
                                   builtin_registry())));
}

// The merge on a hand-made pair of parts: x = 2 t in part 0 (an event at
// t = 0.25 adds a row, one at t = 0.5 two rows), y = 10 - t in part 1 (its
// grid rows only). Part 1's values at part 0's event times are the line
// through its neighbouring rows; at part 0's second row at 0.5 it repeats.
TEST(IndependentParts, MergeInterpolatesAPartBetweenItsOwnRows) {
  std::vector<PartRun> parts(2);
  parts[0].table.rows = {{0.0, 0.0}, {0.25, 0.5}, {0.5, 1.0}, {0.5, 1.5}, {1.0, 2.5}};
  parts[0].column_of = {0, 2};
  parts[0].solver.ok = true;
  parts[0].solver.t_reached = 1.0;
  parts[0].solver.stats.steps = 7;
  parts[1].table.rows = {{0.0, 10.0}, {0.5, 9.5}, {1.0, 9.0}};
  parts[1].column_of = {0, 1};
  parts[1].solver.ok = true;
  parts[1].solver.t_reached = 1.0;
  parts[1].solver.stats.steps = 3;
  ResultsTable header;
  header.names = {"t", "y", "x"};
  header.units = {"s", "m", "m"};
  header.display.resize(3);
  SolverResult solver;
  ResultsTable table;
  merge_parts(parts, header, solver, table);
  const std::vector<std::vector<double>> expected = {
      {0.0, 10.0, 0.0}, {0.25, 9.75, 0.5}, {0.5, 9.5, 1.0}, {0.5, 9.5, 1.5}, {1.0, 9.0, 2.5}};
  EXPECT_EQ(table.rows, expected);
  EXPECT_EQ(table.names, header.names);
  EXPECT_TRUE(solver.ok);
  EXPECT_EQ(solver.stats.steps, 10);
  EXPECT_EQ(solver.stats.part_steps_max, 7);
  EXPECT_EQ(solver.stats.parts, 2);
}

}  // namespace
}  // namespace pneumo
