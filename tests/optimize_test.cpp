// pneumo optimize (issue #20) on the basic cushion rig.
//
// What is asserted:
//  * minimising the impact velocity over the cushion throttle opening z_EC
//    with the time in the cushioning zone at most 0.1 s: the optimum is at
//    least as good (within 2 %) as the best feasible point of a 400-point
//    grid sweep, in fewer runs than the grid, and it meets the constraint;
//  * robust design: over loads uniform in 2-8 kg and supplies in 4-7 bar
//    (the same Latin hypercube samples for every design), minimising the 95 %
//    quantile of the impact velocity with the mean time in the cushioning
//    zone at most 0.1 s gives a lower 95 % quantile than the nominal optimum
//    evaluated on the same samples;
//  * a resumed optimisation takes every run from its journal and ends at the
//    same optimum;
//  * bad arguments (unknown parameter, empty range, unknown metric, unknown
//    distribution) are errors naming the argument, exit status 2.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "components/builtin.hpp"
#include "framework/study/optimize.hpp"
#include "framework/study/sweep.hpp"
#include "tests/test_support.hpp"

namespace pneumo::study {
namespace {

using namespace test_support;

const std::string kRig = std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml";

OptimizeProblem nominal_problem(const Netlist& nl) {
  OptimizeProblem p;
  p.design = parse_design(nl, builtin_registry(), {"z_EC=0:6"});
  p.objectives = {"v_impact"};
  p.constraints = {parse_constraint(select_metrics(nl, builtin_registry(), {}), "t_cushion<=0.1s")};
  return p;
}

OptimizeOptions quiet(const std::string& journal = "") {
  OptimizeOptions o;
  o.threads = 2;
  o.progress = false;
  o.journal = journal;
  return o;
}

TEST(Optimize, BeatsA400PointGridInFewerRuns) {
  const Netlist nl = load_netlist(kRig);
  const OptimizeResult r = optimize(load_model(kRig, builtin_registry()), nominal_problem(nl), quiet());
  ASSERT_TRUE(r.found) << r.best.reason;
  const double v_opt = r.best.robust[0], t_opt = r.best.robust[1];

  TempDir dir;
  const Design d = grid_design(nl, builtin_registry(), {"z_EC=0:6:400"});
  SweepOptions so;
  so.threads = 2;
  so.progress = false;
  so.metrics = {"v_impact", "t_cushion"};
  const auto s = run_sweep(load_model(kRig, builtin_registry()), d, (dir.path() / "grid.csv").string(), so, process_communicator());
  ASSERT_TRUE(s.complete);
  double v_grid = std::numeric_limits<double>::infinity();
  for (const auto& rec : s.records)
    if (rec.ok && rec.metrics[1] <= 0.1) v_grid = std::min(v_grid, rec.metrics[0]);
  std::cout << "optimum v_impact " << v_opt << " m/s at z_EC " << r.best.x[0] << " (" << r.runs
            << " runs); best feasible of the 400-point grid " << v_grid << " m/s\n";
  EXPECT_LE(v_opt, 1.02 * v_grid);
  EXPECT_LE(t_opt, 0.1 * (1 + 1e-6));
  EXPECT_LT(r.runs, 400);
}

TEST(Optimize, RobustDesignHasALowerQuantileThanTheNominalOneOnTheSameSamples) {
  const Netlist nl = load_netlist(kRig);
  const OptimizeResult nominal = optimize(load_model(kRig, builtin_registry()), nominal_problem(nl), quiet());
  ASSERT_TRUE(nominal.found);
  OptimizeProblem p = nominal_problem(nl);
  p.uncertain = {parse_uncertain(nl, builtin_registry(), "m_load=uniform:2kg:8kg"),
                 parse_uncertain(nl, builtin_registry(), "p_supply=uniform:4bar:7bar")};
  p.robust = parse_robust("quantile:0.95");
  p.constraints = {parse_constraint(select_metrics(nl, builtin_registry(), {}), "mean(t_cushion)<=0.1s")};
  p.samples = 24;
  const OptimizeResult robust = optimize(load_model(kRig, builtin_registry()), p, quiet());
  ASSERT_TRUE(robust.found) << robust.best.reason;
  const OptimizeResult nominal_on_samples = evaluate_design(load_model(kRig, builtin_registry()), p, quiet(), nominal.best.x);
  std::cout << "q95 v_impact: robust " << robust.best.robust[0] << " m/s at z_EC " << robust.best.x[0]
            << ", nominal optimum " << nominal_on_samples.best.robust[0] << " m/s at z_EC " << nominal.best.x[0] << "\n";
  EXPECT_LT(robust.best.robust[0], nominal_on_samples.best.robust[0]);
  EXPECT_EQ(robust.best.metric[0].size(), 24u);  // every sample ran
}

TEST(Optimize, ResumedOptimisationReadsItsJournal) {
  TempDir dir;
  const std::string journal = (dir.path() / "opt.journal").string();
  const Netlist nl = load_netlist(kRig);
  const OptimizeResult first = optimize(load_model(kRig, builtin_registry()), nominal_problem(nl), quiet(journal));
  const OptimizeResult again = optimize(load_model(kRig, builtin_registry()), nominal_problem(nl), quiet(journal));
  EXPECT_GT(first.runs, 0);
  EXPECT_EQ(again.runs, 0);
  EXPECT_EQ(again.runs_resumed, first.runs);
  EXPECT_EQ(again.best.x, first.best.x);
}

TEST(Optimize, BadArgumentsAreErrorsNamingThem) {
  TempDir dir;
  const std::string base = std::string(PNEUMO_BINARY) + " optimize " + kRig + " -q -o " +
                           (dir.path() / "r.yaml").string() + " ";
  const struct {
    std::string args, message;
  } cases[] = {
      {"--design no_such=0:1 --minimize v_impact", "no_such"},
      {"--design z_EC=3:3 --minimize v_impact", "HIGH must be greater than LOW"},
      {"--design z_EC=0:6 --minimize v_fast", "v_fast"},
      {"--design z_EC=0:6 --minimize v_impact --uncertain m_load=weibull:1:2", "unknown distribution 'weibull'"},
      {"--design z_EC=0:6 --minimize v_impact --constraint 't_nothing<=1s'", "unknown metric 't_nothing'"},
      {"--design cylinder.stroke=-1m:1m --minimize v_impact", "valid range"},
  };
  for (const auto& c : cases) {
    const std::string log = (dir.path() / "log.txt").string();
    const int status = std::system((base + c.args + " > " + log + " 2>&1").c_str());
    EXPECT_EQ(WEXITSTATUS(status), 2) << c.args;
    EXPECT_NE(read_file(log).find(c.message), std::string::npos) << c.args << ": " << read_file(log);
  }
}

}  // namespace
}  // namespace pneumo::study
