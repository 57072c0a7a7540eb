// The one netlist-edit API (framework/netlist/netlist.hpp): a value set by
// path acts in the run as if the netlist had written it, and its errors point
// at the place the value came from (the netlist's line, or a catalogue's).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "components/builtin.hpp"
#include "framework/core/error.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo {
namespace {

const Netlist& tank_filling() {
  static const Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/tank_filling.yaml");
  return nl;
}

double final_mass(const Netlist& nl) {
  const RunResult r = run_simulation(nl, builtin_registry());
  EXPECT_TRUE(r.solver.ok) << r.solver.message;
  return r.table.rows.back()[r.table.column("m")];
}

// Adiabatic filling of a rigid tank from p2, T_in (the netlist's header):
// m_end = p1 V / (R T1) + (p2 - p1) V / (kappa R T_in).
double closed_form_mass(double p1, double T1) {
  const double R = 287.05, kappa = 1.4, V = 1e-3, p2 = 2e5, T_in = 273.15;
  return p1 * V / (R * T1) + (p2 - p1) * V / (kappa * R * T_in);
}

TEST(NetlistEdit, ValueOfReadsWhatTheNetlistWritesAndNothingForADefault) {
  const Netlist& nl = tank_filling();
  const ValueDecl* p0 = value_of(nl, {"tank", "p0"});
  ASSERT_NE(p0, nullptr);
  EXPECT_EQ(p0->text, "1 bar");
  EXPECT_EQ(p0->where.line, 17);
  EXPECT_EQ(value_of(nl, {"tank", "wall_alpha"}), nullptr);  // left at its default
  EXPECT_EQ(value_of(nl, {"no_such_tank", "p0"}), nullptr);
}

TEST(NetlistEdit, AComponentValueSetAsWrittenFillsTheTankAsTheClosedFormSays) {
  Netlist nl = tank_filling();
  set_value(nl, {"tank", "p0"}, "1.5 bar", "--set tank.p0=1.5 bar");
  EXPECT_EQ(value_of(nl, {"tank", "p0"})->given_by, "--set tank.p0=1.5 bar");
  EXPECT_NEAR(final_mass(nl), closed_form_mass(1.5e5, 293.15), 1e-4 * closed_form_mass(1.5e5, 293.15));
}

TEST(NetlistEdit, AnSiNumberFromAStudyActsAsTheWrittenValue) {
  Netlist nl = tank_filling();
  set_si_value(nl, {"tank", "T0"}, 313.15);
  EXPECT_EQ(*value_of(nl, {"tank", "T0"})->si, 313.15);
  EXPECT_NEAR(final_mass(nl), closed_form_mass(1e5, 313.15), 1e-4 * closed_form_mass(1e5, 313.15));
}

TEST(NetlistEdit, AValueFromACatalogueKeepsItsLineForItsErrors) {
  Netlist nl = tank_filling();
  ValueDecl v;
  v.text = "5 N";
  v.where = {"faults.yaml", 7, 12};
  set_value(nl, {"tank", "V"}, v);
  try {
    elaborate(nl, builtin_registry());
    FAIL() << "a volume in newtons was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("faults.yaml:7:12"), std::string::npos) << e.what();
  }
  ValueDecl elsewhere;
  elsewhere.text = "1 L";
  elsewhere.where = {"faults.yaml", 9, 3};
  EXPECT_THROW(set_value(nl, {"no_such_tank", "V"}, elsewhere), InputError);
}

}  // namespace
}  // namespace pneumo
