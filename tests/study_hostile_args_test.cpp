// Study and fit command lines given hostile arguments (issue #29): each is
// refused with exit status 2 and a message naming what to change, or runs
// with memory proportional to the work it does.
//
// What is asserted:
//  * a parameter given twice (two grids, a samples header, --param, --design
//    with --uncertain) is refused naming it, where one copy was ignored;
//  * a samples file with a byte order mark reads its first column; a device
//    as the samples file is refused, not read forever;
//  * optimize: --pareto with one objective (was SIGSEGV), -j 0 (printed
//    DBL_MAX in 300 digits), a constraint in parentheses (was blamed on
//    --robust), --at outside the design range (was reported as found) are
//    refused; an infeasible problem names the violated constraint and by how
//    much; --max-evaluations 2e7 stays within 150 MB (DIRECT allocated for
//    the whole budget: about 450 MB at 2e7, 12 GB at 2e9);
//  * sweep and sensitivity with every run failed exit non-zero with the reason;
//  * fit refuses data where the measured quantity is constant, and data
//    whose squares overflow.
#include <gtest/gtest.h>

#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/study/optimize.hpp"
#include "framework/study/parameters.hpp"
#include "tests/test_support.hpp"

extern char** environ;

namespace pneumo::study {
namespace {

using namespace test_support;

const std::string kRig = std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml";

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(StudyHostileArgs, AParameterGivenTwiceIsRefusedNamingIt) {
  const Netlist nl = load_netlist(kRig);
  const Registry& reg = builtin_registry();
  EXPECT_TRUE(has(refusal([&] { (void)grid_design(nl, reg, {"z_EC=1:2:2", "z_EC=3:4:2"}); }),
                  "--grid: 'z_EC' is given twice"));
  EXPECT_TRUE(has(refusal([&] { (void)grid_design(nl, reg, {"cylinder.friction_scale=1:2:2", "z_EC=1:2:2",
                                                            "cylinder.friction_scale=3:4:2"}); }),
                  "'cylinder.friction_scale' is given twice"));
  EXPECT_TRUE(has(refusal([&] { (void)parse_ranges(nl, reg, {"m_load=1kg:2kg", "m_load=3kg:4kg"}); }),
                  "--param: 'm_load' is given twice"));
  TempDir dir;
  const std::string samples = dir.write("s.csv", "z_EC,m_load,z_EC\n1,2,3\n");
  const std::string header = refusal([&] { (void)samples_design(nl, reg, samples); });
  EXPECT_TRUE(has(header, samples + ":1:1")) << header;
  EXPECT_TRUE(has(header, "'z_EC' is given twice")) << header;
  const auto [rc, out] = run_cli("optimize '" + kRig + "' -q -o '" + (dir.path() / "o.yaml").string() +
                                 "' --design m_load=2kg:5kg --minimize v_impact --uncertain m_load=uniform:2kg:5kg");
  EXPECT_EQ(rc, 2) << out;
  EXPECT_TRUE(has(out, "--design and --uncertain: 'm_load' is given twice")) << out;
}

TEST(StudyHostileArgs, SamplesFileWithByteOrderMarkOrThatIsADevice) {
  const Netlist nl = load_netlist(kRig);
  TempDir dir;
  const Design d = samples_design(nl, builtin_registry(), dir.write("bom.csv", "\xEF\xBB\xBFz_EC,m_load [kg]\r\n1.5,3\r\n"));
  ASSERT_EQ(d.parameters.size(), 2u);
  EXPECT_EQ(d.parameters[0].name, "z_EC");
  ASSERT_EQ(d.samples.size(), 1u);
  EXPECT_EQ(d.samples[0][1], 3.0);
  EXPECT_TRUE(has(refusal([&] { (void)samples_design(nl, builtin_registry(), "/dev/zero"); }), "not a regular file"));
}

TEST(StudyHostileArgs, GridsTooLargeToPlanAreRefusedBeforeAllocating) {
  const Netlist nl = load_netlist(kRig);
  EXPECT_TRUE(has(refusal([&] { (void)grid_design(nl, builtin_registry(), {"z_EC=1:2:2000000000"}); }),
                  "COUNT must be a whole number from 1 to"));
  EXPECT_TRUE(has(refusal([&] {
                    (void)grid_design(nl, builtin_registry(), {"z_EC=1:2:100000", "m_load=1kg:2kg:100000"});
                  }),
                  "the full factorial grid has 1e+10 runs"));
}

class OptimizeCli : public ::testing::Test {
 protected:
  std::pair<int, std::string> optimize(const std::string& args) {
    return run_cli("optimize '" + kRig + "' -q -o '" + (dir_.path() / "o.yaml").string() + "' " + args);
  }
  TempDir dir_;
};

TEST_F(OptimizeCli, ParetoWithOneObjectiveIsRefused) {
  const auto [rc, out] = optimize("--design z_EC=0:6 --minimize v_impact --pareto");
  EXPECT_EQ(rc, 2) << out;
  EXPECT_TRUE(has(out, "--pareto trades two objectives")) << out;
}

TEST_F(OptimizeCli, ZeroThreadsSaysTheRange) {
  const auto [rc, out] = optimize("--design z_EC=0:6 --minimize v_impact -j 0");
  EXPECT_EQ(rc, 2) << out;
  EXPECT_TRUE(has(out, "give a whole number from 1 to 4096")) << out;
  EXPECT_LT(out.size(), 300u) << out;
}

TEST_F(OptimizeCli, AConstraintInParenthesesIsBlamedOnItself) {
  const auto [rc, out] = optimize("--design z_EC=0:6 --minimize v_impact --constraint '(t_cushion)<=0.1s'");
  EXPECT_EQ(rc, 2) << out;
  EXPECT_TRUE(has(out, "--constraint (t_cushion)<=0.1s")) << out;
  EXPECT_FALSE(has(out, "--robust")) << out;
  const auto [rc2, out2] = optimize("--design z_EC=0:6 --minimize v_impact --constraint 'median(t_cushion)<=0.1s'");
  EXPECT_EQ(rc2, 2) << out2;
  EXPECT_TRUE(has(out2, "unknown statistic 'median'")) << out2;
}

TEST_F(OptimizeCli, ADesignOutsideTheRangeIsNotReportedAsFound) {
  const auto [rc, out] = optimize("--design z_EC=0:6 --minimize v_impact --at z_EC=9");
  EXPECT_EQ(rc, 2) << out;
  EXPECT_TRUE(has(out, "--at z_EC=9: outside the --design range of z_EC (0 to 6)")) << out;
  const auto [rc2, out2] = optimize("--design z_EC=0:6 --minimize v_impact --at z_EC=1 --at z_EC=2");
  EXPECT_EQ(rc2, 2) << out2;
  EXPECT_TRUE(has(out2, "z_EC is given 2 times")) << out2;
}

// t_cushion falls as the throttle opens wider; at most 1 us cannot be met.
TEST(OptimizeInfeasible, NamesTheViolatedConstraintAndByHowMuch) {
  TempDir dir;
  const auto [rc, out] = run_cli("optimize '" + kRig + "' -o '" + (dir.path() / "o.yaml").string() +
                                 "' --design z_EC=0.5:6 --minimize v_impact --constraint 't_cushion<=1us' "
                                 "--max-evaluations 12 --algorithm cobyla");
  EXPECT_EQ(rc, 1) << out;
  EXPECT_TRUE(has(out, "no feasible design found")) << out;
  EXPECT_TRUE(has(out, "the least infeasible design evaluated: z_EC = ")) << out;
  EXPECT_TRUE(has(out, "constraint t_cushion<=1us violated: t_cushion is ")) << out;
  EXPECT_TRUE(has(out, " beyond the limit")) << out;
}

// Peak resident memory (kB) of `pneumo ARGS`, or -1.
long peak_kb(const std::vector<std::string>& args) {
  std::vector<std::string> all{PNEUMO_BINARY};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, PNEUMO_BINARY, nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) return -1;
  return usage.ru_maxrss;
}

TEST(OptimizeMemory, FollowsTheWorkNotTheEvaluationLimit) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "under AddressSanitizer the peak memory is its shadow and quarantine, not pneumo's";
#endif
  TempDir dir;
  const long kb = peak_kb({"optimize", kRig, "-q", "-o", (dir.path() / "o.yaml").string(), "--design", "z_EC=0:6",
                           "--minimize", "v_impact", "--max-evaluations", "2e7"});
  ASSERT_GT(kb, 0) << "the optimisation failed";
  EXPECT_LT(kb, 150 * 1024) << "peak memory " << kb << " kB";
  const std::string result = read_file(dir.path() / "o.yaml");
  EXPECT_TRUE(has(result, "found: true")) << result;
}

TEST(StudyAllRunsFailed, SweepAndSensitivityExitNonZeroWithTheReason) {
  TempDir dir;
  // A negative load mass fails every run when the netlist is elaborated.
  const auto [rc, out] = run_cli("sweep '" + kRig + "' --grid 'm_load=-2kg:-1kg:2' --metrics v_impact -q -o '" +
                                 (dir.path() / "s.csv").string() + "'");
  EXPECT_EQ(rc, 1) << out;
  EXPECT_TRUE(has(out, "every run failed")) << out;
  EXPECT_TRUE(has(out, "is out of range")) << out;
  const auto [rc2, out2] = run_cli("sensitivity '" + kRig + "' --param 'm_load=-2kg:-1kg' --trajectories 2 "
                                   "--metrics v_impact -q -o '" + (dir.path() / "i.csv").string() + "'");
  EXPECT_EQ(rc2, 1) << out2;
  EXPECT_TRUE(has(out2, "every run failed, there are no indices")) << out2;
  EXPECT_TRUE(has(out2, "is out of range")) << out2;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "i.csv"));
}

TEST(FitHostileData, ConstantOrOverflowingDataAreRefused) {
  TempDir dir;
  const std::string constant = dir.write("c.csv", "v [m/s],p_A [bar_rel],p_B [bar_rel],F [N]\n"
                                                  "0.1,5,4,20\n0.2,5,4,20\n0.3,5,4,20\n0.4,5,4,20\n0.5,5,4,20\n"
                                                  "0.6,5,4,20\n0.7,5,4,20\n0.8,5,4,20\n0.9,5,4,20\n1.0,5,4,20\n");
  const auto [rc, out] = run_cli("fit friction '" + constant + "' --model eq4");
  EXPECT_EQ(rc, 2) << out;
  EXPECT_TRUE(has(out, "'F' has the same value in every row: a constant force leaves nothing to fit")) << out;
  std::string big = "v [m/s],p_A [bar_rel],p_B [bar_rel],F [N]\n";
  for (int i = 1; i <= 10; ++i) big += std::to_string(0.1 * i) + ",5,4," + std::to_string(i) + "e300\n";
  const auto [rc2, out2] = run_cli("fit friction '" + dir.write("b.csv", big) + "' --model eq4");
  EXPECT_EQ(rc2, 2) << out2;
  EXPECT_TRUE(has(out2, "the fit overflowed")) << out2;
}

}  // namespace
}  // namespace pneumo::study
