// A run that succeeds but leaves a step chain waiting says so (issue #30: a
// limit switch outside the stroke made a sequence stall with exit 0, a
// metric of nan and no word).
#include <gtest/gtest.h>

#include <string>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "test_support.hpp"

namespace pneumo {
namespace {

using test_support::read_file;
using test_support::replace_once;
using test_support::run_cli;
using test_support::TempDir;

const std::string kSequence = std::string(PNEUMO_SOURCE_DIR) + "/netlists/sequence_ab.yaml";

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// A's extended switch at 160 mm, beyond its 100 mm stroke: step 1 (A+)
// never ends.
std::string switch_beyond_the_stroke() {
  return replace_once(read_file(kSequence), "a1:      {type: limit_switch, position: 100 mm}",
                      "a1:      {type: limit_switch, position: 160 mm}");
}

TEST(StallWarnings, ASequenceWaitingForASwitchBeyondTheStrokeNamesTheStepAndTheSwitch) {
  const Netlist nl = parse_netlist(switch_beyond_the_stroke(), "stalled.yaml");
  const RunResult r = run_simulation(nl, builtin_registry());
  ASSERT_TRUE(r.solver.ok) << r.solver.message;
  ASSERT_EQ(r.solver.warnings.size(), 1u);
  const std::string& w = r.solver.warnings[0];
  EXPECT_TRUE(has(w, "seq: the cycle did not end: step 1 (")) << w;
  EXPECT_TRUE(has(w, "waiting for A1")) << w;
  // The chain started at the start signal and never left step 1.
  bool step_2 = false;
  for (const auto& e : r.solver.events) step_2 |= e.component == "seq" && e.tag == "step_2";
  EXPECT_FALSE(step_2);
}

TEST(StallWarnings, ACompletedCycleSaysNothingAndTheCommandLinePrintsTheStall) {
  const RunResult fine = run_simulation(load_netlist(kSequence), builtin_registry());
  ASSERT_TRUE(fine.solver.ok) << fine.solver.message;
  EXPECT_TRUE(fine.solver.warnings.empty()) << fine.solver.warnings[0];

  TempDir dir;
  const std::string path = dir.write("stalled.yaml", switch_beyond_the_stroke());
  const auto [status, out] = run_cli("simulate '" + path + "' -o '" + (dir.path() / "s.csv").string() + "'");
  EXPECT_EQ(status, 0) << out;
  EXPECT_TRUE(has(out, "pneumo: warning: seq: the cycle did not end: step 1")) << out;
}

}  // namespace
}  // namespace pneumo
