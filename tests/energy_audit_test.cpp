// The cushioning energy audit (framework/analysis/energy_audit) on the basic
// rig, in the three regimes of paper [1], and through the command line.
//
// What is asserted:
//  * the audit balances: energy in (kinetic energy at entry + driving work)
//    equals the sum of where it went, to 1e-4 of the input (the issue asks
//    for 1 %; the accounts are solver-integrated, so the residual is the
//    solver's error);
//  * the kinetic energy at entry is 1/2 M v^2 with M = 3.7 kg and v the
//    entry speed the independent reference gives (0.410 m/s at 5 bar);
//  * the regimes distribute it as physics says: at 0.1 rev the piston never
//    touches the stop (no end-stop term) and compressing the cushion gas takes
//    the largest share; at 6 rev the needle throttle is wide open, the gas
//    escapes instead of being compressed (throttle dissipation >> compression)
//    and the stop absorbs energy on impact;
//  * with wall heat switched on, heat leaves the (compression-heated) cushion
//    gas and the audit still balances;
//  * the CLI prints the audit, writes it as YAML and keeps the audit's
//    accounts out of the results CSV.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "components/builtin.hpp"
#include "framework/analysis/energy_audit.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

using namespace test_support;

std::string rig_path() { return std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml"; }

double term(const std::vector<AuditTerm>& terms, const std::string& name) {
  for (const auto& t : terms)
    if (t.name == name) return t.joules;
  ADD_FAILURE() << "no audit term " << name;
  return NAN;
}

EnergyAudit audit_of(Netlist nl) {
  Circuit circuit = elaborate(nl, builtin_registry());
  const auto plans = prepare_energy_audit(nl, circuit);
  const RunResult r = run_circuit(std::move(circuit), solver_options(nl.simulation));
  EXPECT_TRUE(r.solver.ok) << r.solver.message;
  const auto audits = energy_audit(plans, r);
  EXPECT_EQ(audits.size(), 1u);
  std::ostringstream s;
  print_audit(audits.at(0), s);
  std::cout << s.str();
  return audits.at(0);
}

EnergyAudit rig_audit(double z_EC) {
  Netlist nl = load_netlist(rig_path());
  apply_override(nl, "z_EC=" + std::to_string(z_EC));
  return audit_of(nl);
}

void expect_balanced(const EnergyAudit& a) {
  ASSERT_TRUE(a.opened);
  EXPECT_GT(a.total_in, 0.0);
  EXPECT_LT(std::abs(a.residual()), 1e-4 * a.total_in);
}

TEST(EnergyAudit, OverdampedCushionAbsorbsByCompression) {
  const EnergyAudit a = rig_audit(0.1);
  expect_balanced(a);
  // Entry speed of the reference at 5 bar (tests/cushion_rig_test: 0.410 m/s);
  // the moving mass is the 3.7 kg load on the cylinder's flange.
  EXPECT_NEAR(a.speed_at_open, 0.410, 0.003);
  EXPECT_NEAR(term(a.in, "kinetic_energy_at_entry"), 0.5 * 3.7 * a.speed_at_open * a.speed_at_open, 1e-12);
  EXPECT_EQ(term(a.out, "end_stop"), 0.0);  // stops before the head
  const double compression = term(a.out, "cushion_gas_compression");
  for (const auto& t : a.out)
    if (t.name != "cushion_gas_compression") EXPECT_GT(compression, t.joules) << t.name;
  EXPECT_EQ(term(a.out, "heat_to_walls"), 0.0);  // adiabatic rig
}

TEST(EnergyAudit, WideOpenThrottleLetsTheGasEscapeAndTheStopTakesTheImpact) {
  const EnergyAudit a = rig_audit(6.0);
  expect_balanced(a);
  EXPECT_GT(term(a.out, "cushion_throttle_dissipation"), 10.0 * std::abs(term(a.out, "cushion_gas_compression")));
  EXPECT_GT(term(a.out, "end_stop"), 0.05);  // J; the impact at ~0.39 m/s brings ~0.28 J
}

TEST(EnergyAudit, MediumOpeningBalances) {
  const EnergyAudit a = rig_audit(1.5);
  expect_balanced(a);
  // Friction work over the window is bounded by the friction force at the
  // highest speed (the entry speed: the cushion only decelerates) times the
  // distance travelled (at most the 20 mm cushion plus the stop's give):
  // Annex B row 5.14 bar_rel, |F| = b + (FS - FC) exp(-v/vS) + kv v^a.
  const double v = a.speed_at_open;
  const double F_max = 2.776 + (25.05 - 4.31) * std::exp(-v / 0.004033) + 128.7 * std::pow(v, 0.6843);
  EXPECT_GT(term(a.out, "friction"), 0.0);
  EXPECT_LT(term(a.out, "friction"), F_max * 0.0201);
}

TEST(EnergyAudit, WallHeatLeavesTheCompressedGasAndTheAuditStillBalances) {
  std::string y = read_file(rig_path());
  const std::string anchor = "\nconnections:";
  const auto pos = y.find(anchor);
  ASSERT_NE(pos, std::string::npos);
  y.insert(pos,
           "\n  wall_cap: {type: thermal_mass, C: 30 J/K, T0: 293.15 K}\n"
           "  wall_A:   {type: thermal_mass, C: 30 J/K, T0: 293.15 K}");
  const auto cyl = y.find("type: cushioned_cylinder");
  ASSERT_NE(cyl, std::string::npos);
  y.insert(y.find('\n', cyl) + 1, "    wall_alpha: 300 W/(m2*K)\n");
  const auto con = y.find(anchor) + anchor.size();
  y.insert(y.find('\n', con) + 1, "  - [cylinder.heat_cap, wall_cap.port]\n  - [cylinder.heat_A, wall_A.port]\n");
  Netlist nl = parse_netlist(y, "cushion_rig_wall_heat.yaml");
  apply_override(nl, "z_EC=0.1");
  const EnergyAudit a = audit_of(nl);
  expect_balanced(a);
  EXPECT_GT(term(a.out, "heat_to_walls"), 1e-3);  // J, the gas is hotter than the wall
}

TEST(EnergyAudit, CliPrintsAndWritesTheAuditAndKeepsTheCsvClean) {
  const auto dir = std::filesystem::temp_directory_path() / "pneumo_audit_test";
  std::filesystem::create_directories(dir);
  const std::string csv = (dir / "rig.csv").string(), yaml = (dir / "audit.yaml").string(),
                    log = (dir / "log.txt").string();
  const std::string cmd = std::string(PNEUMO_BINARY) + " simulate " + rig_path() + " -o " + csv +
                          " --energy-audit " + yaml + " > " + log + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << read_file(log);
  const std::string out = read_file(log);
  EXPECT_NE(out.find("energy audit of cylinder"), std::string::npos) << out;
  EXPECT_NE(out.find("balance: in"), std::string::npos);
  const std::string audit = read_file(yaml);
  for (const char* key : {"component: cylinder", "kinetic_energy_at_entry:", "cushion_throttle_dissipation:",
                          "end_stop:", "residual_relative:"})
    EXPECT_NE(audit.find(key), std::string::npos) << key;
  const std::string header = read_file(csv).substr(0, read_file(csv).find('\n'));
  EXPECT_EQ(header.find("audit."), std::string::npos) << header;
  EXPECT_NE(header.find("p_EC"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(yaml + ".writing"));
  // A netlist where no component declares an audit is bad input for it.
  const std::string tank = std::string(PNEUMO_SOURCE_DIR) + "/netlists/tank_filling.yaml";
  const std::string bad = std::string(PNEUMO_BINARY) + " simulate " + tank + " -o " + (dir / "t.csv").string() +
                          " --energy-audit " + (dir / "t.yaml").string() + " > " + log + " 2>&1";
  const int status = std::system(bad.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_NE(read_file(log).find("declares an energy audit"), std::string::npos) << read_file(log);
}

}  // namespace
}  // namespace pneumo

#include "framework/study/sweep.hpp"

namespace pneumo {
namespace {

// Issue #23: on the full rig at this operating point the audit's
// quadratures, when they steered the step size, drove IDA to a 3e-10 s step
// at the impact and the run failed only because it was audited. The audit
// now integrates on the trajectory's own steps: the audited run succeeds,
// and closes.
TEST(EnergyAudit, AuditingNeverTurnsAGoodRunIntoAFailure) {
  Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig_full.yaml");
  for (const char* s : {"p_supply=716666.66666666663", "m_load=5.6444444444444439", "z_EC=2"}) apply_override(nl, s);
  const auto metrics = study::select_metrics(nl, builtin_registry(), {"v_impact", "E_compression", "audit_residual"});
  const study::RunRecord r = study::run_one(nl, builtin_registry(), {}, {}, metrics);
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_GT(r.metrics[0], 0.0);
  EXPECT_LT(std::abs(r.metrics[2]), 1e-4);
}

}  // namespace
}  // namespace pneumo
