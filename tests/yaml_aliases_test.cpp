// YAML aliases: a few kilobytes of anchors and aliases can stand for
// billions of values. A 21 KB netlist of tables repeated by aliases made
// `pneumo simulate` take 23.8 GB and 75 s before it said anything (the
// netlist fuzzer's out-of-memory in CI); such a file is refused at once.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "components/builtin.hpp"
#include "framework/core/error.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo {
namespace {

// `valves` valves sharing one schedule table of `rows` aliased rows of `cells` numbers.
std::string amplified(int valves, int rows, int cells) {
  std::string row = "[";
  for (int c = 0; c < cells; ++c) row += c ? ",0.001" : "0.001";
  row += "]";
  std::string table = "&t [&r " + row;
  for (int r = 1; r < rows; ++r) table += ", *r";
  table += "]";
  std::string s = "components:\n";
  for (int v = 0; v < valves; ++v)
    s += "  v" + std::to_string(v) + ": {type: directional_valve_32, C: 1 dm3/(s*bar), schedule: " +
         (v == 0 ? table : std::string("*t")) + "}\n";
  return s;
}

TEST(YamlAliases, AnAliasAmplifiedNetlistIsRefusedAtOnce) {
  const std::string text = amplified(200, 1500, 300);  // 21 KB for 90 million values
  ASSERT_LT(text.size(), 30000u);
  const auto start = std::chrono::steady_clock::now();
  try {
    (void)parse_netlist(text, "amplified.yaml");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("amplified.yaml:1:1"), std::string::npos) << what;
    EXPECT_NE(what.find("aliases"), std::string::npos) << what;
    EXPECT_NE(what.find("500000"), std::string::npos) << what;
  }
  // Counting stops at the limit: far below the seconds the expansion took.
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
}

TEST(YamlAliases, ASelfReferentialAliasIsRefusedNotFollowedForever) {
  EXPECT_THROW((void)parse_netlist("title: demo\ncomponents: &c\n  a: [*c]\n", "cycle.yaml"), InputError);
}

// Aliases used as people use them - one schedule shared by a few valves - still work.
TEST(YamlAliases, ModestSharingStillElaborates) {
  const std::string text =
      "components:\n"
      "  a: {type: directional_valve_32, C: 1 dm3/(s*bar), schedule: &s [[0.1, 1], [0.5, 0]]}\n"
      "  b: {type: directional_valve_32, C: 1 dm3/(s*bar), schedule: *s}\n"
      "  c: {type: directional_valve_32, C: 1 dm3/(s*bar), schedule: *s}\n";
  const Netlist nl = parse_netlist(text, "shared.yaml");
  ASSERT_EQ(nl.components.size(), 3u);
  EXPECT_NO_THROW((void)elaborate(nl, builtin_registry()));
}

// yaml-cpp reads a NUL byte as the start of endless empty documents.
TEST(YamlAliases, ANulByteIsRefusedAtItsLineNotReadForever) {
  const std::string text = std::string("title: demo\ncomponents:\n  a: {type: vol") + '\0' + "ume}\n";
  try {
    (void)parse_netlist(text, "binary.yaml");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("binary.yaml:3:16"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("NUL"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pneumo
