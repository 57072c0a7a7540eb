// TEMPORARY debug harness (cushion rig helper) - will be deleted.
#include <gtest/gtest.h>
#include <cmath>
#include <cstdio>
#include <iostream>
#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
namespace pneumo {
TEST(ZZTmpCushionDebug, Probe) {
  Netlist nl = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml");
  apply_override(nl, "p_supply=7e5"); apply_override(nl, "z_EC=0.1");
  System sys(elaborate(nl, builtin_registry()));
  SolverOptions o = solver_options(nl.simulation);
  const int n = sys.size();
  std::vector<double> ty, y(n), yp(n); double tl = 0;
  std::vector<std::vector<double>> Y, YP; std::vector<double> T;
  SolverResult r = simulate(sys, o, [&](double t, const double* a, const double* b) {
    T.push_back(t); Y.emplace_back(a, a + n); YP.emplace_back(b, b + n); });
  std::cout << r.message << "\n";
  const auto& names = sys.variable_names();
  y = Y.back(); yp = YP.back(); tl = T.back();
  std::vector<double> F(n), F2(n);
  int rc = sys.residual(tl, y.data(), yp.data(), F.data());
  std::printf("t=%.9g rc=%d\n", tl, rc);
  for (int i = 0; i < n; ++i) std::printf("%3d %-28s y=% .10e yp=% .6e nom=%g diff=%g F=% .3e\n", i, names[i].c_str(), y[i], yp[i], sys.nominal()[i], sys.differential()[i], F[i]);
  std::vector<double> Jy, Jyp; sys.jacobian_parts(tl, y.data(), yp.data(), Jy, Jyp);
  double worst = 0;
  for (int j = 0; j < n; ++j) {
    const double h = 1e-7 * std::max(std::abs(y[j]), sys.nominal()[j]);
    auto yy = y; yy[j] += h; sys.residual(tl, yy.data(), yp.data(), F2.data());
    auto yy2 = y; yy2[j] -= h; std::vector<double> F3(n); sys.residual(tl, yy2.data(), yp.data(), F3.data());
    for (int i = 0; i < n; ++i) {
      const double fd = (F2[i] - F3[i]) / (2 * h);
      const double an = Jy[i * n + j];
      const double scale = std::abs(fd) + std::abs(an);
      if (std::abs(fd - an) > 1e-4 * scale + 1e-9) std::printf("J mismatch d r%d / d %s: an=%g fd=%g\n", i, names[j].c_str(), an, fd);
    }
  }
}
}
