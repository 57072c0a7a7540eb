// Where a patched model departs from the unpatched model's run
// (framework/diagnose/departure.hpp), on the sequence A+ B+ B- A-
// (netlists/sequence_ab.yaml): cylinder B rests against its cap-end stop
// until A has extended, so what only acts on B's motion - the mass it
// moves, the needle its exhaust passes through - leaves the run as it is
// until B's valve switches; the patched run resumed there is the patched
// model's own run, event for event and row for row within the integration's
// error. A leak across A's piston, open between a chamber at the supply
// pressure and one at the atmosphere from the start, departs at once.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "components/builtin.hpp"
#include "framework/diagnose/departure.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

std::string sequence_text() {
  std::ifstream in(std::string(PNEUMO_SOURCE_DIR) + "/netlists/sequence_ab.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The sequence with `extra` inserted after `after`'s line.
Netlist sequence(const std::string& after = "", const std::string& extra = "") {
  std::string s = sequence_text();
  if (!after.empty()) {
    const auto at = s.find(after);
    s.insert(s.find('\n', at) + 1, extra);
  }
  return parse_netlist(s, "sequence_ab.yaml");
}

struct Assembled {
  explicit Assembled(const Netlist& nl)
      : options(solver_options(nl.simulation)),
        system(elaborate(nl, builtin_registry()), assembly_options(options)) {}
  SolverOptions options;
  System system;
};

std::vector<double> every(double dt, double t_end) {
  std::vector<double> t;
  for (int i = 0; i * dt <= t_end + 1e-12; ++i) t.push_back(i * dt);
  return t;
}

// The first (or last) time the component raised the tagged event.
double event_time(const RunResult& r, const std::string& component, const std::string& tag, bool last = false) {
  double t = -1;
  for (const auto& e : r.solver.events)
    if (e.component == component && e.tag == tag) {
      t = e.t;
      if (!last) break;
    }
  return t;
}
// When cylinder `c`'s retracted switch closed last: its return.
double back(const RunResult& r, const std::string& c) { return event_time(r, c, "on", true); }

class Departure : public ::testing::Test {
 protected:
  Departure() : unpatched(sequence()) {
    Resumption keep{every(0.01, unpatched.options.t_end), nullptr};
    keep.in_passing = true;
    kept = run_assembled(unpatched.system, unpatched.options, keep);
  }
  Assembled unpatched;
  RunResult kept;
};

TEST_F(Departure, WhatActsOnlyOnBsMotionDepartsAfterAsStrokeAndBeforeBMovesAndResumesAsItsOwnRun) {
  ASSERT_TRUE(kept.solver.ok) << kept.solver.message;
  const double a_extended = event_time(kept, "a1", "on"), b_leaves = event_time(kept, "cyl_B", "left_retracted");
  ASSERT_GT(a_extended, 0.1);
  ASSERT_GT(b_leaves, a_extended);

  for (const std::string name : {"B three times as heavy", "B's exhaust needle turned"}) {
    Netlist nl = sequence();
    if (name == "B three times as heavy") set_si_value(nl, ParameterPath::parse("load_B.m"), 6.0);
    else set_si_value(nl, ParameterPath::parse("flow_B_rod.C"), 1.5 * 0.15e-3 / 1e5);
    const Assembled patched(nl);
    const long j = diagnose::last_checkpoint_before_departure(unpatched.system, patched.system, kept,
                                                              unpatched.options);
    ASSERT_GE(j, 0) << name;
    const double t_j = kept.checkpoints[j].t;
    // Nothing of B moves before A is out; the mass and the needle act from
    // B's valve switching, at A's extended switch, at the latest when B leaves.
    EXPECT_GE(t_j, a_extended - 0.01) << name;
    EXPECT_LT(t_j, b_leaves) << name;

    const RunResult own = run_assembled(patched.system, patched.options);
    const RunResult resumed =
        run_assembled(patched.system, patched.options, {{}, &kept.checkpoints[j], &kept.table});
    ASSERT_TRUE(own.solver.ok && resumed.solver.ok) << name;
    // The patched model differs: B's return ends elsewhere than unpatched.
    const double b_back = back(own, "b0");
    EXPECT_GT(std::abs(b_back - back(kept, "b0")), 1e-3) << name;
    EXPECT_NEAR(back(resumed, "b0"), b_back, 1e-4) << name;
    EXPECT_NEAR(back(resumed, "a0"), back(own, "a0"), 1e-4) << name;
    const int x_B = own.table.column("x_B");
    for (const auto& row : resumed.table.rows)
      EXPECT_NEAR(row[x_B], test_support::value_at(own, x_B, row[0]), 5e-5) << name << ", t = " << row[0];  // 0.05 mm
  }
}

// A limit switch set 2 mm short (its root function moved from the start):
// the run is the unpatched one while neither switch position is reached,
// and departs before the first of the two is.
TEST_F(Departure, ALimitSwitchSetShortDepartsBeforeEitherPositionIsReached) {
  ASSERT_TRUE(kept.solver.ok) << kept.solver.message;
  Netlist nl = sequence();
  set_si_value(nl, ParameterPath::parse("b1.position"), 0.048);
  const Assembled patched(nl);
  const long j = diagnose::last_checkpoint_before_departure(unpatched.system, patched.system, kept, unpatched.options);
  ASSERT_GE(j, 0);
  const RunResult own = run_assembled(patched.system, patched.options);
  ASSERT_TRUE(own.solver.ok) << own.solver.message;
  const double short_on = event_time(own, "b1", "on"), set_on = event_time(kept, "b1", "on");
  ASSERT_GT(short_on, 0);
  ASSERT_LT(short_on, set_on);  // the short switch closes first
  EXPECT_LT(kept.checkpoints[j].t, short_on);
  EXPECT_GT(kept.checkpoints[j].t, event_time(kept, "cyl_B", "left_retracted"));  // B was on its way

  const RunResult resumed = run_assembled(patched.system, patched.options, {{}, &kept.checkpoints[j], &kept.table});
  ASSERT_TRUE(resumed.solver.ok) << resumed.solver.message;
  EXPECT_NEAR(event_time(resumed, "b1", "on"), short_on, 1e-4);
  EXPECT_NEAR(back(resumed, "a0"), back(own, "a0"), 1e-4);
}

TEST_F(Departure, ALeakAcrossAPistonBetweenSupplyAndAtmosphereDepartsAtTheStart) {
  ASSERT_TRUE(kept.solver.ok) << kept.solver.message;
  Netlist nl = sequence();
  set_si_value(nl, ParameterPath::parse("load_B.m"), 6.0);
  const Assembled heavier(nl);
  ASSERT_GE(diagnose::last_checkpoint_before_departure(unpatched.system, heavier.system, kept, unpatched.options), 1);

  const Netlist leaking = sequence("    p0_rod: p_supply               # at rest", "    fault_piston_leak_C: 0.01 dm3/(s*bar)\n");
  const Assembled patched(leaking);
  EXPECT_EQ(diagnose::last_checkpoint_before_departure(unpatched.system, patched.system, kept, unpatched.options), -1);
}

}  // namespace
}  // namespace pneumo
