// The component authors' test kit (framework/testkit) must catch the
// mistakes it is there for: a component whose equations lose a derivative
// (a value() cast on a state), one that loses mass, one that heats the gas
// passing through it. Each defect is a text parameter of one linear flow
// resistance m = G (p_a - p_b); without a defect the kit passes it.
#include <gtest/gtest.h>

#include "components/builtin.hpp"
#include "framework/testkit/testkit.hpp"

namespace pneumo {
namespace {

class Laminar final : public ComponentT<Laminar> {
 public:
  enum class Defect { none, drops_derivative, loses_mass, heats_gas };
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "kit_laminar";
    i.description = "linear flow resistance with selectable defects (test kit test)";
    i.parameters = {ParameterSpec::scalar("G", "kg/(s*Pa)", "conductance").positive(),
                    ParameterSpec::text("defect", {"none", "drops_derivative", "loses_mass", "heats_gas"},
                                        "the mistake to make", "none")};
    i.ports = {{"a", Domain::pneumatic, Causality::acausal, "a"}, {"b", Domain::pneumatic, Causality::acausal, "b"}};
    return i;
  }
  explicit Laminar(const Construction& c) : ComponentT(c), G_(c.params["G"]) {
    const std::string& d = c.params.text("defect");
    defect_ = d == "drops_derivative" ? Defect::drops_derivative
              : d == "loses_mass"     ? Defect::loses_mass
              : d == "heats_gas"      ? Defect::heats_gas
                                      : Defect::none;
  }
  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto a = e.gas_port(0), b = e.gas_port(1);
    // The derivative with respect to p_b lost: Newton still converges, the
    // residual is right, only the Jacobian is wrong.
    const T p_b = defect_ == Defect::drops_derivative ? T(value(b.p)) : b.p;
    r[0] = a.m_flow - G_ * (a.p - p_b);
    r[1] = defect_ == Defect::loses_mass ? T(a.m_flow + 1.01 * b.m_flow) : T(a.m_flow + b.m_flow);
    const double dT = defect_ == Defect::heats_gas ? 5.0 : 0.0;
    r[2] = a.T_out - b.T_in - dT;
    r[3] = b.T_out - a.T_in - dT;
  }

 private:
  double G_;
  Defect defect_;
};

const Registry& registry() {
  static const Registry r = testkit::with_builtin([](Registry& reg) { reg.add<Laminar>(); });
  return r;
}

std::string circuit(const std::string& defect) {
  return "components:\n"
         "  a: {type: volume, V: 1 L, p0: 6 bar, T0: 320 K}\n"
         "  r: {type: kit_laminar, G: 1e-8 kg/(s*Pa), defect: " + defect + "}\n"
         "  b: {type: volume, V: 1 L, p0: 1 bar, T0: 280 K}\n"
         "connections:\n  - [a.port, r.a]\n  - [r.b, b.port]\n"
         "simulation: {t_end: 2 s, rtol: 1e-8, atol: 1e-8, output_interval: 20 ms}\n";
}

bool all_passed(const std::vector<testkit::JacobianCheck>& checks) {
  for (const auto& c : checks)
    if (!c.passed()) return false;
  return true;
}

TEST(TestKit, JacobianCheckPassesACorrectComponentAndCatchesALostDerivative) {
  const auto good = testkit::check_jacobian(circuit("none"), registry(), 0.05);
  ASSERT_EQ(good.size(), 2u);
  for (const auto& c : good) EXPECT_TRUE(c.passed()) << c.report();

  const auto bad = testkit::check_jacobian(circuit("drops_derivative"), registry(), 0.05);
  EXPECT_FALSE(all_passed(bad));
  // The lost entry is d(flow residual)/d(p_b) = G: AD says 0 where the
  // finite difference gives 1e-8 kg/(s Pa), a scaled error far above 1e-5
  // (measured ~170).
  EXPECT_GT(bad.front().worst, 1.0) << bad.front().report();
  EXPECT_NE(bad.front().worst_where.find("AD 0"), std::string::npos) << bad.front().report();
}

TEST(TestKit, ConservationCheckCatchesLostMassAndCreatedEnergy) {
  const std::vector<testkit::Balance> balances = {testkit::mass_of({"a", "b"}), testkit::energy_of({"a", "b"})};
  const auto good = testkit::check_conservation(circuit("none"), registry(), balances);
  ASSERT_EQ(good.size(), 2u);
  for (const auto& c : good) EXPECT_TRUE(c.passed(1e-12)) << c.report();

  // 1 % of the flow vanishes between a and b: about 1 % of the mass that
  // moved is lost, ~2.6e-3 of the total (measured).
  const auto lossy = testkit::check_conservation(circuit("loses_mass"), registry(), balances);
  EXPECT_FALSE(lossy[0].passed(1e-6)) << lossy[0].report();
  EXPECT_GT(lossy[0].worst, 1e-3) << lossy[0].report();

  // Gas heated by 5 K in passing: mass is kept, energy is not (measured
  // +0.59 % by t_end).
  const auto heating = testkit::check_conservation(circuit("heats_gas"), registry(), balances);
  EXPECT_TRUE(heating[0].passed(1e-12)) << heating[0].report();
  EXPECT_FALSE(heating[1].passed(1e-6)) << heating[1].report();
  EXPECT_GT(heating[1].final_value, heating[1].initial);
}

}  // namespace
}  // namespace pneumo
