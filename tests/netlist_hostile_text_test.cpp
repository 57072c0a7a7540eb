// Netlist texts as editors and hostile inputs write them (issue #29): the
// reader accepts what is only an encoding detail and refuses, at the line,
// what would otherwise be silently misread.
//
// What is asserted:
//  * a UTF-8 byte order mark and old Mac line ends (CR alone) read exactly
//    like the plain text: the same parameter values and line numbers;
//  * YAML nested thousands deep is an error at its line saying "nested too
//    deeply", not "bad file";
//  * a second YAML document is refused at its '---' line (it was ignored);
//  * a device named as the netlist (/dev/zero) is refused, not read forever;
//  * output and metric names that would break a CSV header (comma, quote,
//    line break) are refused at their line;
//  * metric windows: a time before the run, a window whose from is after its
//    to, a key given twice and a division by a constant zero are refused at
//    the metric's line.
#include <gtest/gtest.h>

#include <string>

#include "framework/core/error.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo {
namespace {

const std::string kTank = R"(parameters:
  p_source: 2 bar
components:
  source: {type: pressure_source, p: p_source}
  valve:  {type: iso6358_throttle, C: 0.4 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 1 L}
connections:
  - [source.port, valve.a]
  - [valve.b, tank.port]
outputs: {p: tank.p}
)";

// The message of the InputError that parsing `text` throws ("" if none), and its line.
std::pair<std::string, int> refusal(const std::string& text) {
  try {
    (void)parse_netlist(text, "hostile.yaml");
  } catch (const InputError& e) {
    return {e.what(), e.where().line};
  }
  return {"", 0};
}

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

TEST(NetlistHostileText, ByteOrderMarkIsNotPartOfTheFirstKey) {
  const Netlist nl = parse_netlist("\xEF\xBB\xBF" + kTank, "bom.yaml");
  ASSERT_NE(nl.parameter("p_source"), nullptr);
  EXPECT_EQ(nl.parameter("p_source")->si_value, 2e5);
  EXPECT_EQ(nl.components.at(2).where.line, 6);
}

TEST(NetlistHostileText, CarriageReturnLineEndsReadLikeNewlines) {
  std::string cr = kTank;
  for (auto& c : cr)
    if (c == '\n') c = '\r';
  const Netlist nl = parse_netlist(cr, "cr.yaml");
  ASSERT_NE(nl.parameter("p_source"), nullptr);
  EXPECT_EQ(nl.parameter("p_source")->si_value, 2e5);
  ASSERT_EQ(nl.components.size(), 3u);
  EXPECT_EQ(nl.components.at(2).where.line, 6);
  EXPECT_EQ(nl.connections.size(), 2u);
}

TEST(NetlistHostileText, DeepNestingIsALocatedError) {
  const auto [message, line] = refusal(kTank + "title: " + std::string(5000, '[') + std::string(5000, ']') + "\n");
  EXPECT_TRUE(has(message, "nested too deeply")) << message;
  EXPECT_FALSE(has(message, "bad file")) << message;
  EXPECT_EQ(line, 11) << message;
}

TEST(NetlistHostileText, ASecondDocumentIsRefusedAtItsMarker) {
  const auto [message, line] = refusal(kTank + "---\ncomponents:\n  other: {type: volume, V: 2 L}\n");
  EXPECT_TRUE(has(message, "second YAML document")) << message;
  EXPECT_EQ(line, 11) << message;
  // A trailing marker with nothing after it holds no content to lose.
  EXPECT_NO_THROW((void)parse_netlist(kTank + "---\n", "end.yaml"));
}

TEST(NetlistHostileText, NamesThatBreakACsvHeaderAreRefused) {
  for (const std::string name : {"\"p,A\"", "'say \"hi\"'", "\"p\\nA\""}) {
    const auto [message, line] = refusal(kTank + "metrics:\n  " + name + ": {max: p}\n");
    EXPECT_TRUE(has(message, "heads a column")) << name << ": " << message;
    EXPECT_EQ(line, 12) << message;
    std::string outputs = kTank;
    outputs.replace(outputs.find("outputs: {p: tank.p}"), 20, "outputs: {p: tank.p, " + name + ": tank.T}");
    const auto [out_message, out_line] = refusal(outputs);
    EXPECT_TRUE(has(out_message, "heads a column")) << name << ": " << out_message;
    EXPECT_EQ(out_line, 10) << out_message;
  }
}

TEST(NetlistHostileText, MetricWindowsAndArithmeticAreChecked) {
  const struct {
    std::string metric, message;
  } cases[] = {
      {"bad: {max: p, from: -1 s}", "before the run starts"},
      {"bad: {value: p, at: -0.5 s}", "before the run starts"},
      {"bad: {max: p, from: 2 s, to: 1 s}", "is after to"},
      {"bad: {max: p, from: 1 s, from: 2 s}", "'from' is given twice"},
      {"bad: {expr: ok / 0}", "division by zero"},
      {"bad: {expr: ok / (2 - 2*1)}", "division by zero"},
  };
  for (const auto& c : cases) {
    const auto [message, line] = refusal(kTank + "metrics:\n  ok: {max: p}\n  " + c.metric + "\n");
    EXPECT_TRUE(has(message, c.message)) << c.metric << ": " << message;
    EXPECT_EQ(line, 13) << c.metric << ": " << message;
  }
  // Windows that are fine stay fine.
  EXPECT_NO_THROW((void)parse_netlist(kTank + "metrics:\n  ok: {max: p, from: 0 s, to: 1 s}\n  r: {expr: ok / 2}\n",
                                      "ok.yaml"));
}

TEST(NetlistHostileText, ADeviceIsRefusedNotReadForever) {
  try {
    (void)load_netlist("/dev/zero");
    ADD_FAILURE() << "/dev/zero was read as a netlist";
  } catch (const InputError& e) {
    EXPECT_TRUE(has(e.what(), "not a regular file")) << e.what();
  }
}

}  // namespace
}  // namespace pneumo
