// Expressions (framework/core/expression.hpp) of hostile size: deep nesting
// and very long sums are refused with a located message or evaluated
// exactly, never crash the process by exhausting the stack (issue #29).
//
// What is asserted:
//  * 30,000 nested parentheses, or a long run of signs, are refused naming
//    the nesting limit and the column where it was passed;
//  * an expression longer than the stated length is refused, saying so;
//  * a 49,999-term sum just under the length limit evaluates to its exact
//    count, and 200 nested parentheses (the limit) still evaluate;
//  * a division by a part that is always zero is refused at its '/';
//  * through a netlist metric the same refusals are errors at the metric's
//    file:line, and the message does not echo the whole expression.
#include <gtest/gtest.h>

#include <string>

#include "framework/core/error.hpp"
#include "framework/core/expression.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo {
namespace {

std::string nested(std::size_t depth, const std::string& inner) {
  return std::string(depth, '(') + inner + std::string(depth, ')');
}

TEST(ExpressionLimits, DeepNestingIsRefusedAtItsColumn) {
  try {
    (void)Expression(nested(30000, "1"));
    ADD_FAILURE() << "30,000 nested parentheses were accepted";
  } catch (const ExpressionError& e) {
    EXPECT_NE(std::string(e.what()).find("nested more than 200"), std::string::npos) << e.what();
    EXPECT_EQ(e.column, Expression::kMaxDepth + 1) << e.what();
  }
  EXPECT_THROW((void)Expression(std::string(30000, '-') + "1"), ExpressionError);
  // At the limit the value is still computed, signs included.
  EXPECT_EQ(Expression(nested(Expression::kMaxDepth, "2*3")).evaluate([](const std::string&) { return 0.0; }), 6.0);
  EXPECT_EQ(Expression(std::string(Expression::kMaxDepth, '-') + "5").evaluate([](const std::string&) { return 0.0; }),
            5.0);
}

TEST(ExpressionLimits, LongSumsAreEvaluatedOrRefusedByLength) {
  std::string sum = "x";
  for (int k = 1; k < 49999; ++k) sum += "+x";
  ASSERT_LE(sum.size(), Expression::kMaxLength);
  const Expression e(sum);
  EXPECT_EQ(e.names().size(), 1u);
  EXPECT_EQ(e.evaluate([](const std::string&) { return 1.0; }), 49999.0);

  std::string huge = "1";
  for (int k = 1; k < 200000; ++k) huge += "+1";
  try {
    (void)Expression(huge);
    ADD_FAILURE() << "a 400,000-character expression was accepted";
  } catch (const ExpressionError& err) {
    EXPECT_NE(std::string(err.what()).find("at most 100000"), std::string::npos) << err.what();
  }
}

TEST(ExpressionLimits, DivisionByAConstantZeroIsRefusedAtTheOperator) {
  try {
    (void)Expression("a + b / (3 - 3)");
    ADD_FAILURE() << "accepted";
  } catch (const ExpressionError& e) {
    EXPECT_EQ(e.column, 6u) << e.what();
    EXPECT_NE(std::string(e.what()).find("division by zero"), std::string::npos) << e.what();
  }
  // A divisor that depends on a name may be zero only in some runs: allowed.
  EXPECT_EQ(Expression("a / (b - 1)").evaluate([](const std::string& n) { return n == "a" ? 6.0 : 4.0; }), 2.0);
}

TEST(ExpressionLimits, NetlistMetricWithDeepExpressionIsALocatedError) {
  const std::string head = R"(components:
  source: {type: pressure_source, p: 2 bar}
  valve:  {type: iso6358_throttle, C: 0.4 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 1 L}
connections:
  - [source.port, valve.a]
  - [valve.b, tank.port]
outputs: {p: tank.p}
metrics:
  ok: {max: p}
)";
  try {
    (void)parse_netlist(head + "  deep: {expr: \"" + nested(30000, "ok") + "\"}\n", "deep.yaml");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 11) << e.what();
    EXPECT_EQ(e.parameter(), "metrics.deep");
    EXPECT_NE(std::string(e.what()).find("nested more than"), std::string::npos) << e.what();
    EXPECT_LT(std::string(e.what()).size(), 600u) << "the message echoes the whole expression";
  }
}

}  // namespace
}  // namespace pneumo
