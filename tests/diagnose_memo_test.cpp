// The diagnosis's memo of simulated runs (framework/diagnose/memo.hpp): a
// run is given back as it was kept, and beyond the budget of stored values
// the least recently used runs are forgotten - never the one just asked for.
#include <gtest/gtest.h>

#include "framework/diagnose/memo.hpp"

namespace pneumo::diagnose {
namespace {

Signals run_of(double v) { return {{v, v + 1}, {v + 2, v + 3}}; }  // two signals, four values

TEST(SignalMemo, ForgetsTheLeastRecentlyUsedBeyondItsBudget) {
  SignalMemo memo(12);  // three runs of four values
  memo.keep("a", run_of(1));
  memo.keep("b", run_of(5));
  memo.keep("c", run_of(9));
  ASSERT_TRUE(memo.find("a"));  // a used again: b is now the oldest
  EXPECT_EQ(*memo.find("a"), run_of(1));
  memo.keep("d", run_of(13));
  EXPECT_FALSE(memo.find("b"));
  EXPECT_EQ(*memo.find("c"), run_of(9));
  EXPECT_EQ(*memo.find("d"), run_of(13));
  EXPECT_EQ(*memo.find("a"), run_of(1));
  EXPECT_EQ(memo.hits(), 5u);
  memo.keep("huge", Signals{std::vector<double>(13, 0.0)});  // more than the whole budget: not kept
  EXPECT_FALSE(memo.find("huge"));
  EXPECT_TRUE(memo.find("a"));
}

}  // namespace
}  // namespace pneumo::diagnose
