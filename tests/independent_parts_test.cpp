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
#include "tests/test_support.hpp"

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

// n insulated volumes (different V, p0, T0), each through a throttle of
// its own to one junction: a node of n pneumatic ports. Beyond 32 ports the
// stream mixing reads the other groups' sums instead of every port (the 64
// locals a block holds); the gas must keep its total mass (to rounding, as
// at three ports in conservation_test) and internal energy (the smoothed
// mixing weights: 1e-6, as there), and end at the energy balance's common
// pressure sum(p V) / sum(V).
struct Junction {
  std::string text;
  double m0 = 0, U0 = 0, p_end = 0;
};

Junction junction_of(int n) {
  const GasModel air;
  Junction j;
  std::string comps, conns, outs, node = "  - [";
  double pv = 0, v = 0;
  for (int k = 0; k < n; ++k) {
    const std::string t = "t" + std::to_string(k), th = "v" + std::to_string(k);
    const double V = 1e-4 * (1 + k % 5), p0 = 1e5 * (1 + k % 7), T0 = 260.0 + 10.0 * (k % 9);
    comps += "  " + t + ": {type: volume, V: " + test_support::num(V) + " m3, p0: " + test_support::num(p0) +
             " Pa, T0: " + test_support::num(T0) + " K}\n";
    comps += "  " + th + ": {type: iso6358_throttle, C: " + test_support::num(0.05 + 0.01 * (k % 4)) +
             " dm3/(s*bar), b: 0.3}\n";
    conns += "  - [" + t + ".port, " + th + ".a]\n";
    node += (k ? ", " : "") + th + ".b";
    outs += "  m" + std::to_string(k) + ": " + t + ".m\n  U" + std::to_string(k) + ": " + t + ".U\n  p" +
            std::to_string(k) + ": " + t + ".p\n";
    j.m0 += p0 * V / (air.R * T0);
    j.U0 += p0 * V / (air.kappa - 1.0);
    pv += p0 * V;
    v += V;
  }
  j.p_end = pv / v;
  j.text = "components:\n" + comps + "connections:\n" + conns + node + "]\noutputs:\n" + outs +
           "simulation: {t_end: 30 s, rtol: 1e-8, atol: 1e-8, output_interval: 0.5 s}\n";
  return j;
}

TEST(IndependentParts, AJunctionOf64PortsConservesMassAndEnergy) {
  const int n = 64;
  const Junction j = junction_of(n);
  const RunResult r = test_support::run_text(j.text, "junction.yaml");
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  double worst_m = 0, worst_U = 0;
  for (const auto& row : r.table.rows) {
    double m = 0, U = 0;
    for (int k = 0; k < n; ++k) {
      m += row[r.table.column("m" + std::to_string(k))];
      U += row[r.table.column("U" + std::to_string(k))];
    }
    worst_m = std::max(worst_m, test_support::rel_err(m, j.m0));
    worst_U = std::max(worst_U, test_support::rel_err(U, j.U0));
  }
  EXPECT_LT(worst_m, 1e-12);
  // The volumes' upwinding moves no heat at zero flow, the node's mixing
  // weights stay eps / 2 there (framework/assembly): between the two, 1.5e-6.
  EXPECT_LT(worst_U, 2e-6);
  for (int k = 0; k < n; ++k)
    EXPECT_LT(test_support::rel_err(r.table.rows.back()[r.table.column("p" + std::to_string(k))], j.p_end), 1e-5)
        << "volume " << k;
}

// 273 ports: a mix would read 65 variables in any grouping (17 groups of
// up to 17); an input error naming the connection's line, not an overrun.
TEST(IndependentParts, ANodeOfMoreThan272PneumaticPortsIsAnInputErrorAtItsConnection) {
  const Netlist nl = parse_netlist(junction_of(273).text, "junction.yaml");
  try {
    System system(elaborate(nl, builtin_registry()));
    FAIL() << "a node of 273 pneumatic ports was assembled";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().file, "junction.yaml");
    EXPECT_EQ(e.where().line, 2 * 273 + 2 + 273 + 1) << e.what();  // components, "connections:", the tanks' lines
    EXPECT_NE(std::string(e.what()).find("joins 273 ports"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("at most 272 pneumatic ports"), std::string::npos) << e.what();
  }
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
