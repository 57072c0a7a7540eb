// A study's runs prepared once (study::SweepRunner): the energy audit takes
// its plan from the circuit the run elaborated (one elaboration a run, not
// two), each run's audit follows that run's parameter values, and a sweep's
// metrics are those of a plain simulation of the same netlist with the same
// --set, to the last bit.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/analysis/energy_audit.hpp"
#include "framework/analysis/run_metrics.hpp"
#include "framework/study/sweep.hpp"

namespace pneumo {
namespace {

std::atomic<int> g_constructed{0};

// A piston braked by an adiabatic air spring, with an energy audit of the
// stroke into it; counts its constructions (one per elaboration).
class CountedAirSpring final : public ComponentT<CountedAirSpring> {
 public:
  static constexpr double kA = 1e-3, kV0 = 1e-4;  // m2, m3
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "test_counted_air_spring";
    i.description = "piston braked by an adiabatic air spring, counting its elaborations (test)";
    i.ports = {{"flange", Domain::translational, Causality::acausal, "piston"}};
    i.variables = {{"U", "J", "internal energy of the spring gas"}};
    i.observables = {{"s", "m", "piston position"}, {"v", "m/s", "piston velocity"}, {"U", "J", "gas energy"}};
    return i;
  }
  explicit CountedAirSpring(const Construction& c) : ComponentT(c) { ++g_constructed; }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto fl = e.flange(0);
    const GasModel& gas = e.gas();
    const T p = (gas.kappa - 1.0) * e.var(0) / (kV0 - kA * fl.s);
    r[0] = e.der(0) - p * kA * fl.v;         // dU = -p dV
    r[1] = fl.f - (p - gas.p_ambient) * kA;  // force of the gas and the ambient on the piston
  }
  void start(StartValues& s, const GasModel& gas) const override {
    s.fix_var(0, gas.p_ambient * kV0 / (gas.kappa - 1.0));
    s.fix_position(0, 0.0);
  }
  double observe(int k, const Eval<double>& e) const override {
    return k == 0 ? e.flange(0).s : k == 1 ? e.flange(0).v : e.var(0);
  }
  std::optional<EnergyAuditSpec> energy_audit(const GasModel& gas) const override {
    using K = EnergyTerm::Kinetic;
    EnergyAuditSpec a;
    a.title = "stroke into the air spring";
    a.closes_when_not_positive = "v";
    a.kinetic_port = "flange";
    a.terms = {{"kinetic_energy_at_start", "kinetic energy at the start", true, {}, {}, K::at_open},
               {"ambient_work", "work of the ambient pressure", true, {{"s", gas.p_ambient * kA}}, {}},
               {"compression", "internal energy gained by the gas", false, {{"U", 1.0}}, {}},
               {"kinetic_energy_at_end", "kinetic energy left", false, {}, {}, K::at_close}};
    return a;
  }
};

const char* kAirSpring = R"(
components:
  piston: {type: test_counted_air_spring}
  load:   {type: translational_mass, m: 2 kg, v0: 3 m/s}
connections:
  - [piston.flange, load.flange]
outputs: {s: piston.s}
metrics:
  E_in: {audit: piston.kinetic_energy_at_start}
  audit_residual: {audit: piston.residual}
simulation: {t_end: 0.2 s, output_interval: 0.5 ms}
)";

// Each run of a sweep over the load's mass elaborates the netlist once (the
// audit's plan comes from that circuit), and its audit is that run's: the
// kinetic energy that entered is m v0^2 / 2 of the run's own mass.
TEST(SweepPrepare, AuditPlanComesFromTheRunsOwnCircuit) {
  Registry reg = builtin_registry();
  reg.add<CountedAirSpring>();
  const Netlist nl = parse_netlist(kAirSpring, "air_spring.yaml");
  const auto metrics = study::select_metrics(nl, reg, {});
  ASSERT_EQ(metrics.size(), 2u);
  const study::StudyParameter mass = study::resolve_parameter(nl, reg, "load.m");
  const study::SweepRunner runner(nl, reg, {mass}, metrics);
  for (double m : {1.0, 2.0, 4.0}) {
    g_constructed = 0;
    const study::RunRecord r = runner.run({m});
    ASSERT_TRUE(r.ok) << r.reason;
    EXPECT_EQ(g_constructed.load(), 1) << "elaborations of the netlist in one run of m = " << m << " kg";
    EXPECT_NEAR(r.metrics[0], 0.5 * m * 3.0 * 3.0, 1e-9 * m);
    EXPECT_LT(std::abs(r.metrics[1]), 1e-4);  // the audit balances
  }
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// What `pneumo simulate --set ...` computes for the netlist's metrics
// (framework/cli/simulate.cpp): every metric, the audits' outputs added to
// the circuit, run_circuit.
std::vector<double> simulated_metrics(const std::vector<std::string>& sets) {
  Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml");
  for (const auto& s : sets) apply_override(nl, s);
  const std::vector<bool> all(nl.metrics.size(), true);
  add_metric_outputs(nl, all);
  Circuit circuit = elaborate(nl, builtin_registry());
  const auto plans = prepare_energy_audit(nl, circuit);
  const RunResult run = run_circuit(std::move(circuit), solver_options(nl.simulation));
  EXPECT_TRUE(run.solver.ok) << run.solver.message;
  return evaluate_metrics(nl, all, run, energy_audit(plans, run));
}

// A sweep's metrics, run by run, are bit for bit those of a plain
// simulation with the same values given by --set.
TEST(SweepPrepare, SweepEqualsPlainSimulateToTheLastBit) {
  const Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml");
  const Registry& reg = builtin_registry();
  const auto metrics = study::select_metrics(nl, reg, {});
  ASSERT_EQ(metrics.size(), nl.metrics.size());
  const std::vector<study::StudyParameter> params = {study::resolve_parameter(nl, reg, "m_load"),
                                                      study::resolve_parameter(nl, reg, "p_supply")};
  const study::SweepRunner runner(nl, reg, params, metrics);
  const std::vector<std::pair<std::string, std::string>> texts = {{"2.5", "6e5"}, {"5", "4.5e5"}, {"3.7", "5e5"}};
  for (const auto& [m, p] : texts) {
    const study::RunRecord r = runner.run({std::stod(m), std::stod(p)});
    ASSERT_TRUE(r.ok) << r.reason;
    const std::vector<double> plain = simulated_metrics({"m_load=" + m, "p_supply=" + p});
    ASSERT_EQ(r.metrics.size(), plain.size());
    for (std::size_t k = 0; k < plain.size(); ++k)
      EXPECT_TRUE(same_bits(r.metrics[k], plain[k]))
          << metrics[k].name << " at m_load=" << m << ", p_supply=" << p << ": sweep " << r.metrics[k]
          << ", simulate " << plain[k];
  }
}

}  // namespace
}  // namespace pneumo
