// Forward selection is greedy: the effect that fits best alone takes the
// verdict's first slot. Two faults together can each fit worse alone than
// a stand-in does; when the verdict then leaves the runs unexplained, the
// selection is run again from the next single fits (diagnose.cpp,
// try_other_first_effects). Runs generated here from a truth with two
// faults in forms of their own, plus sensor noise.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>

#include "components/builtin.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

// netlists/quick_exhaust_cylinder.yaml: a single-acting cylinder behind a
// quick-exhaust valve, meter-in on a 3/2 valve; runs set p_supply.
const std::string kQuickExhaust = read_file(fs::path(PNEUMO_SOURCE_DIR) / "netlists" / "quick_exhaust_cylinder.yaml");

// Runs of `truth` at supply 5 and 7 bar g (calibration) and 6 bar g
// (validation), with noise 0.05 mm on x and 3 kPa on p_cap.
void make_runs(const fs::path& dir, const std::string& truth) {
  std::mt19937 rng(41);
  const std::vector<NoisySignal> signals = {{"x", 5e-5}, {"p_cap", 3e3}};
  write_measured_run(dir, "cal1", "calibration", truth, "p_supply", 601325, signals, rng);
  write_measured_run(dir, "cal2", "calibration", truth, "p_supply", 801325, signals, rng);
  write_measured_run(dir, "val", "validation", truth, "p_supply", 701325, signals, rng);
}

// A worn piston seal venting the cap chamber (a laminar-ish gap of 0.0235
// dm3/(s*bar) to the atmosphere, not the declared fault's conductance) and a
// workpiece that makes the load 3.07 times as heavy. Alone, the cylinder's
// wall heat fits best (24.4 -> 10.7 x noise; the mass alone leaves 13.9, the
// leak 19.2); beside it the mass leaves 5.3 and the leak no longer screens:
// the verdict was the wall heat and the mass, flagged unexplained. From the
// mass, the leak is found.
TEST(DiagnoseSelection, TwoFaultsEachWorseAloneThanAStandInAreFoundFromTheNextFirstEffect) {
  std::string truth = kQuickExhaust;
  truth.replace(truth.find("m: 1.5 kg"), 9, "m: 4.605 kg");
  truth.replace(truth.find("connections:"), 12,
                "  seal_gap: {type: iso6358_throttle, C: 0.0235 dm3/(s*bar), b: 0.05}\n"
                "  leak_air: {type: atmosphere}\n"
                "connections:\n  - [cyl.cap, seal_gap.a]\n  - [seal_gap.b, leak_air.port]");
  TempDir dir;
  const std::string model = dir.write("qev.yaml", kQuickExhaust);
  make_runs(dir.path() / "runs", truth);
  diagnose::DiagnoseOptions opt;
  opt.declared_faults = true;
  opt.faults = {"cyl.wall_heat",  "load.mass_off", "cyl.piston_seal_leak", "x.lag", "silencer.misadjusted",
                "cyl.friction_running"};
  std::string log;
  opt.log = [&](const std::string& line) { log += line + "\n"; };
  const auto rep = diagnose::diagnose(model, (dir.path() / "runs").string(), "", builtin_registry(), opt);
  std::cout << "validation gap " << rep.validation_before.total.rms << " -> " << rep.validation_after.total.rms
            << ", verdict:";
  for (const auto& v : rep.verdict) std::cout << " " << v;
  std::cout << "\n";
  // The greedy first pick was the stand-in, and the search went on from another.
  EXPECT_NE(log.find("forward selection again, from load.mass_off"), std::string::npos) << log;
  ASSERT_EQ(rep.verdict.size(), 2u);
  EXPECT_NE(std::find(rep.verdict.begin(), rep.verdict.end(), "load.mass_off"), rep.verdict.end());
  EXPECT_NE(std::find(rep.verdict.begin(), rep.verdict.end(), "cyl.piston_seal_leak"), rep.verdict.end());
  EXPECT_GT(rep.validation_before.total.rms, 10.0);
  EXPECT_LT(rep.validation_after.total.rms, 1.5);
  for (const auto& [name, values] : rep.final_values)
    if (name == "load.mass_off") EXPECT_NEAR(values[0], 3.07, 0.3);
}

}  // namespace
}  // namespace pneumo
