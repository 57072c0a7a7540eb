#include "friction_experiment.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "components/builtin.hpp"
#include "framework/run/run.hpp"

namespace pneumo::examples {

namespace {

constexpr double kPi = 3.14159265358979323846;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

ComponentDecl& component(Netlist& nl, const std::string& name) {
  for (auto& c : nl.components)
    if (c.name == name) return c;
  throw InputError(SourceLocation{nl.file, 1, 1}, name, "", "the friction test needs a component '" + name + "'");
}

// A scalar parameter of the cylinder in SI, read as the netlist gives it.
double cylinder_parameter(const Netlist& nl, const ComponentDecl& cyl, const std::string& name) {
  const auto* entry = builtin_registry().find(cyl.type);
  for (const auto& spec : entry->info->parameters)
    if (spec.name == name)
      for (const auto& [k, node] : cyl.parameters)
        if (k == name) return parameter_value(nl, cyl, spec, node);
  throw InputError(cyl.where, cyl.name, name, "the friction test needs this parameter");
}

}  // namespace

std::vector<FrictionTestSupply> annex_b_supplies() {
  return {{2.07, "annexB_2.07"},   {3.127, "annexB_3.127"}, {4.115, "annexB_4.115"}, {5.14, "annexB_5.14"},
          {6.13, "annexB_6.13"},   {7.085, "annexB_7.085"}, {8.075, "annexB_8.075"}};
}

std::vector<double> meter_out_openings(int n, double C_min, double C_max) {
  std::vector<double> c;
  for (int i = 0; i < n; ++i)
    c.push_back(n == 1 ? C_min : C_min * std::pow(C_max / C_min, double(i) / (n - 1)));
  return c;
}

std::vector<FrictionTestPoint> run_friction_test(const FrictionTestOptions& o) {
  const Netlist base = load_netlist(o.netlist);
  Netlist probe = base;
  const ComponentDecl& cyl = component(probe, "cylinder");
  const double bore = cylinder_parameter(base, cyl, "bore"), rod = cylinder_parameter(base, cyl, "rod");
  const double plug = cylinder_parameter(base, cyl, "plug_diameter");
  const double stroke = cylinder_parameter(base, cyl, "stroke");
  const double L = cylinder_parameter(base, cyl, "cushion_length");
  const double A_B = kPi * bore * bore / 4, A_R = kPi * rod * rod / 4, A_A = A_B - A_R;
  const double A_CP = kPi * plug * plug / 4;
  const double p_amb = base.gas.p_ambient;
  const double x_end = stroke - L - o.cushion_margin;
  const auto* m_par = base.parameter("m_load");
  if (!m_par) throw InputError(SourceLocation{base.file, 1, 1}, "", "m_load", "the friction test needs parameter m_load");
  const double m = m_par->si_value;
  // Meter-out choked: v ~ C rho_ref R T / A_B, independent of the pressure.
  const double v_per_C = 1e-8 * base.gas.rho_ref * base.gas.R * base.gas.T_ambient / A_B;

  std::vector<FrictionTestPoint> out;
  for (const auto& s : o.supplies) {
    for (const double C : o.openings) {
      Netlist nl = base;
      apply_override(nl, "p_supply=" + num(p_amb + s.p0_bar_rel * 1e5));
      apply_override(nl, "C_MO=" + num(C * 1e-8));
      const double p_s = p_amb + s.p0_bar_rel * 1e5;
      apply_override(nl, "p_cap0=" + num((p_s * A_A + p_amb * A_R) / A_B));
      for (auto& [k, node] : component(nl, "cylinder").parameters)
        if (k == "friction") {
          node.shape = ValueDecl::Shape::scalar;
          node.text = s.preset;
        }
      const double v_est = std::min(v_per_C * C, 1.0);
      nl.simulation.t_end = 0.2 + 1.3 * x_end / v_est;
      nl.simulation.output_interval = std::clamp((x_end - o.x_begin) / v_est / 400, 2e-4, 5e-3);
      const RunResult run = run_simulation(nl, builtin_registry());
      // Only the main stroke up to the window's end is needed: a run that
      // fails later (in the cushioning zone or at the cap) still has it.
      const bool passed_window = !run.table.rows.empty() && run.table.rows.back()[run.table.column("x")] > x_end;
      if (!run.solver.ok && !passed_window)
        throw std::runtime_error("friction test p0 = " + num(s.p0_bar_rel) + " bar_rel, C_MO = " + num(C) +
                                 " dm3/(s*bar): " + run.solver.message);
      const auto& t = run.table;
      const int ct = t.column("t"), cx = t.column("x"), cv = t.column("v"), cA = t.column("p_A");
      const int cEC = t.column("p_EC"), cch = t.column("p_ch"), cF = t.column("F_friction");
      if (cx < 0 || cv < 0 || cA < 0 || cEC < 0 || cch < 0 || cF < 0)
        throw InputError(SourceLocation{base.file, 1, 1}, "", "",
                         "the friction test needs outputs x, v, p_A, p_EC, p_ch, F_friction");
      std::vector<double> v, pA, pB, F, Fm;
      for (std::size_t i = 1; i + 1 < t.rows.size(); ++i) {
        const auto& r = t.rows[i];
        if (r[cx] < o.x_begin || r[cx] > x_end) continue;
        const double a = (t.rows[i + 1][cv] - t.rows[i - 1][cv]) / (t.rows[i + 1][ct] - t.rows[i - 1][ct]);
        const double pressure_force = r[cA] * A_A + p_amb * A_R - r[cEC] * (A_B - A_CP) - r[cch] * A_CP;
        v.push_back(r[cv]);
        pA.push_back(r[cA]);
        pB.push_back(r[cEC]);
        F.push_back(pressure_force - m * a);
        Fm.push_back(-r[cF]);
      }
      if (v.size() < 10)
        throw std::runtime_error("friction test p0 = " + num(s.p0_bar_rel) + " bar_rel, C_MO = " + num(C) +
                                 " dm3/(s*bar): only " + std::to_string(v.size()) +
                                 " samples in the quasi-static window (the piston did not get there in time)");
      FrictionTestPoint p;
      p.failed_after_window = !run.solver.ok;
      p.p0_bar_rel = s.p0_bar_rel;
      p.C_MO = C;
      p.v = median(v);
      p.p_A = median(pA);
      p.p_B = median(pB);
      p.F = median(F);
      p.F_model = median(Fm);
      const auto [vmin, vmax] = std::minmax_element(v.begin(), v.end());
      p.v_spread = (*vmax - *vmin) / p.v;
      p.samples = static_cast<int>(v.size());
      if (p.v_spread > o.max_v_spread)
        throw std::runtime_error("friction test p0 = " + num(s.p0_bar_rel) + " bar_rel, C_MO = " + num(C) +
                                 " dm3/(s*bar): the speed varies by " + num(100 * p.v_spread) +
                                 " % over the window - not quasi-static (stick-slip below the Stribeck minimum, "
                                 "or still accelerating); choose other openings");
      out.push_back(p);
    }
  }
  return out;
}

void write_friction_points(const std::string& path, const std::vector<FrictionTestPoint>& pts) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << "# simulated friction test of paper [1] (examples/friction_test): medians over the quasi-static window\n"
    << "p0 [bar_rel],C_MO [dm3/(s*bar)],v [m/s],p_A [Pa],p_B [Pa],F [N],F_model [N],v_spread [1]\n";
  for (const auto& p : pts)
    f << num(p.p0_bar_rel) << "," << num(p.C_MO) << "," << num(p.v) << "," << num(p.p_A) << "," << num(p.p_B) << ","
      << num(p.F) << "," << num(p.F_model) << "," << num(p.v_spread) << "\n";
}

}  // namespace pneumo::examples
