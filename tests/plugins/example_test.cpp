// The out-of-tree example (examples/custom_component), as a user gets it:
// the ctest fixture plugin_example installed this build into a prefix and
// built the example against it with find_package(pneumo)
// (install_and_build.cmake). Here the INSTALLED `pneumo` runs the example's
// netlist, which loads the example's plugin, and the result is checked
// against the closed form of an isothermal tank leaking through a laminar
// seal gap into the atmosphere (p0):
//   dm/dt = -K (p^2 - p0^2)/(R T), m = p V/(R T), K = pi d h^3/(24 mu L)
//   => (p - p0)/(p + p0) = (p_start - p0)/(p_start + p0) exp(-2 p0 K t / V).
// The numbers come from the netlist itself.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "framework/io/results.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;

const fs::path kWork = PNEUMO_EXAMPLE_WORK;
const fs::path kPneumo = kWork / "prefix" / "bin" / "pneumo";
const fs::path kNetlist = kWork / "build" / "seal_leakage.yaml";

int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string slurp(const fs::path& p) {
  std::stringstream s;
  s << std::ifstream(p).rdbuf();
  return s.str();
}

double parameter(const Netlist& nl, const std::string& name) {
  const TopParameter* p = nl.parameter(name);
  if (!p) throw std::runtime_error("the example netlist has no parameter " + name);
  return p->si_value;
}

TEST(PluginExample, InstalledPneumoRunsThePluginAndTheTankDrainsAsTheClosedFormSays) {
  const fs::path out = kWork / "run" / "seal.csv";
  fs::create_directories(out.parent_path());
  // From another directory: the plugin path is resolved from the netlist's.
  const std::string cmd = "cd / && '" + kPneumo.string() + "' simulate '" + kNetlist.string() + "' -o '" +
                          out.string() + "' > '" + (kWork / "run" / "log.txt").string() + "' 2>&1";
  ASSERT_EQ(run(cmd), 0) << cmd << "\n" << slurp(kWork / "run" / "log.txt");

  const Netlist nl = load_netlist(kNetlist.string());
  const double V = parameter(nl, "V_tank"), p_start = parameter(nl, "p_start"), T_wall = parameter(nl, "T_wall");
  const double d = parameter(nl, "d_seal"), h = parameter(nl, "h_gap"), L = parameter(nl, "L_seal");
  const double mu = parameter(nl, "mu_air");
  const double p0 = nl.gas.p_ambient;
  const double K = std::numbers::pi * d * h * h * h / (24.0 * mu * L);
  const double u0 = (p_start - p0) / (p_start + p0);

  const ResultsTable table = read_csv(out.string());
  ASSERT_GE(table.rows.size(), 100u);
  const int p_col = table.column("p"), T_col = table.column("T");
  ASSERT_GE(p_col, 0);
  ASSERT_GE(T_col, 0);
  double worst_p = 0.0, worst_T = 0.0;
  for (const auto& row : table.rows) {
    const double u = u0 * std::exp(-2.0 * p0 * K * row[0] / V);
    const double p = p0 * (1.0 + u) / (1.0 - u);
    worst_p = std::max(worst_p, std::abs(row[p_col] - p) / p);
    worst_T = std::max(worst_T, std::abs(row[T_col] - T_wall));
  }
  // The wall conductance (1e4 W/K against the gas's ~0.5 J/K) keeps the
  // gas within a few mK of the wall; the pressure then follows the
  // isothermal closed form to well within 1e-4.
  EXPECT_LT(worst_T, 0.02) << "the tank is not isothermal, the closed form does not apply";
  EXPECT_LT(worst_p, 1e-4) << "worst relative pressure error against the closed form";
  // The run covers most of the decay: from 6 bar to about 1.23 bar.
  const double p_end = table.rows.back()[p_col];
  EXPECT_LT(p_end, 1.3e5);
  EXPECT_GT(p_end, p0);
  std::cout << "seal leakage: worst relative pressure error " << worst_p << ", worst |T - T_wall| " << worst_T
            << " K, p(t_end) = " << p_end << " Pa\n";
}

TEST(PluginExample, InstalledPneumoDescribesThePluginsComponent) {
  const fs::path out = kWork / "run" / "components.txt";
  fs::create_directories(out.parent_path());
  const std::string cmd = "'" + kPneumo.string() + "' components --plugin '" +
                          (kWork / "build" / "seal_leakage.so").string() + "' seal_leakage > '" + out.string() +
                          "' 2>&1";
  ASSERT_EQ(run(cmd), 0) << slurp(out);
  const std::string text = slurp(out);
  for (const char* s : {"seal_leakage", "d [m] required", "h [m] required", "L [m] required"})
    EXPECT_NE(text.find(s), std::string::npos) << s << " not in:\n" << text;
}

}  // namespace
}  // namespace pneumo
