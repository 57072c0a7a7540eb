// `pneumo plot --steps x_A,x_B [--step-column step]` (documented in the
// README and examples/sequences.md) is registered on the CLI and writes the
// displacement-step diagram; --steps and --columns are refused together.
#include <gtest/gtest.h>

#include <filesystem>

#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

const std::string kSequence =
    "t [s],step [1],x_A [m],x_B [m]\n"
    "0,1,0,0\n0.5,1,0.1,0\n1,2,0.1,0.1\n1.5,3,0.05,0.1\n2,4,0,0\n";

TEST(PlotSteps, WritesTheStepDiagram) {
  TempDir dir;
  const std::string csv = dir.write("r.csv", kSequence);
  const auto [status, out] =
      run_cli("plot '" + csv + "' --steps x_A,x_B --step-column step -o '" + (dir.path() / "d").string() + "'");
  ASSERT_EQ(status, 0) << out;
  EXPECT_GT(std::filesystem::file_size(dir.path() / "d.svg"), 0u);
  EXPECT_GT(std::filesystem::file_size(dir.path() / "d.png"), 0u);
}

TEST(PlotSteps, StepsAndColumnsTogetherAreRefused) {
  TempDir dir;
  const std::string csv = dir.write("r.csv", kSequence);
  const auto [status, out] =
      run_cli("plot '" + csv + "' --steps x_A --columns x_B -o '" + (dir.path() / "d").string() + "'");
  EXPECT_EQ(status, 2) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "d.svg"));
}

}  // namespace
}  // namespace pneumo
