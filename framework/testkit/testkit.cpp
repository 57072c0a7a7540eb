#include "framework/testkit/testkit.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo::testkit {

Registry with_builtin(const std::function<void(Registry&)>& add) {
  Registry r = builtin_registry();
  if (add) add(r);
  return r;
}

namespace {

// Central differences of the residual against the AD part dF/dy (or dF/dy').
void compare_part(const Evaluator& eval, double t, const std::vector<double>& y0, const std::vector<double>& yp0,
                  bool wrt_yp, const std::vector<double>& J_ad, JacobianCheck& out) {
  const System& sys = eval.system();
  const int n = sys.size();
  std::vector<double> scale(n);
  const auto& base = wrt_yp ? yp0 : y0;
  for (int j = 0; j < n; ++j) scale[j] = std::max(std::abs(base[j]), sys.nominal()[j]);

  // J_fd column by column, plus the one-sided differences for the kink test.
  std::vector<double> Jc(static_cast<std::size_t>(n) * n), Jf(Jc.size()), Jb(Jc.size());
  std::vector<double> F0(n), Fp(n), Fm(n);
  eval.residual(t, y0.data(), yp0.data(), F0.data());
  for (int j = 0; j < n; ++j) {
    const double h = 1e-6 * scale[j];
    std::vector<double> y = y0, yp = yp0;
    auto& v = wrt_yp ? yp : y;
    v[j] = base[j] + h;
    eval.residual(t, y.data(), yp.data(), Fp.data());
    v[j] = base[j] - h;
    eval.residual(t, y.data(), yp.data(), Fm.data());
    for (int i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i) * n + j;
      Jc[k] = (Fp[i] - Fm[i]) / (2 * h);
      Jf[k] = (Fp[i] - F0[i]) / h;
      Jb[k] = (F0[i] - Fm[i]) / h;
    }
  }
  for (int i = 0; i < n; ++i) {
    double row = 0.0;
    for (int j = 0; j < n; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * n + j;
      row = std::max({row, std::abs(J_ad[k]) * scale[j], std::abs(Jc[k]) * scale[j]});
    }
    if (row == 0.0) continue;
    for (int j = 0; j < n; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * n + j;
      const double ad = J_ad[k] * scale[j], fd = Jc[k] * scale[j];
      if (ad == 0.0 && fd == 0.0) continue;
      const double denom = std::max(std::abs(ad), 1e-3 * row);
      // Forward and backward differences disagree by much more than their
      // O(h) truncation error: a kink lies inside the stencil.
      if (std::abs(Jf[k] - Jb[k]) * scale[j] > 1e-4 * denom) {
        ++out.kinks;
        continue;
      }
      ++out.compared;
      const double err = std::abs(ad - fd) / denom;
      if (err > out.worst) {
        out.worst = err;
        std::ostringstream w;
        w << (wrt_yp ? "dF/dy'" : "dF/dy") << " row " << i << ", " << (wrt_yp ? "der(" : "")
          << sys.variable_names()[j] << (wrt_yp ? ")" : "") << ": AD " << J_ad[k] << ", FD " << Jc[k];
        out.worst_where = w.str();
      }
    }
  }
}

// jacobian(cj) against the two parts on the pattern; zero outside it.
void check_assembled(const Evaluator& eval, double t, const std::vector<double>& y, const std::vector<double>& yp,
                     const std::vector<double>& dFdy, const std::vector<double>& dFdyp, JacobianCheck& out) {
  const System& sys = eval.system();
  const int n = sys.size();
  const double cj = 1e3;  // 1/h for a 1 ms step
  std::vector<double> values(sys.nnz());
  eval.jacobian(t, y.data(), yp.data(), cj, values.data());
  // Cumulative: misses during the evaluator's run count as well.
  out.pattern_misses = eval.pattern_misses();
  auto problem = [&](const std::string& s) {
    if (out.problems.size() < 10) out.problems.push_back(s);
  };
  std::vector<char> in_pattern(static_cast<std::size_t>(n) * n, 0);
  std::vector<double> row_max(n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * n + j;
      row_max[i] = std::max(row_max[i], std::abs(dFdy[k] + cj * dFdyp[k]));
    }
  for (int c = 0; c < n; ++c)
    for (long p = sys.col_ptr()[c]; p < sys.col_ptr()[c + 1]; ++p) {
      const int r = static_cast<int>(sys.row_idx()[p]);
      const std::size_t k = static_cast<std::size_t>(r) * n + c;
      in_pattern[k] = 1;
      const double expected = dFdy[k] + cj * dFdyp[k];
      if (std::abs(values[p] - expected) > 1e-12 * std::max(row_max[r], 1e-300)) {
        std::ostringstream s;
        s << "jacobian(cj) at (" << r << ", " << sys.variable_names()[c] << ") = " << values[p]
          << ", dF/dy + cj dF/dy' = " << expected;
        problem(s.str());
      }
    }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * n + j;
      if (!in_pattern[k] && (dFdy[k] != 0.0 || dFdyp[k] != 0.0))
        problem("nonzero derivative outside the sparsity pattern: row " + std::to_string(i) + ", " +
                sys.variable_names()[j]);
      // A variable whose derivative appears must be flagged differential for IDASetId.
      if (dFdyp[k] != 0.0 && sys.differential()[j] != 1.0)
        problem(sys.variable_names()[j] + " appears differentiated but is flagged algebraic");
    }
}

}  // namespace

bool JacobianCheck::passed(double tolerance) const {
  return worst < tolerance && compared > variables && kinks <= std::max(2, compared / 50) && pattern_misses == 0 &&
         problems.empty();
}

std::string JacobianCheck::report() const {
  std::ostringstream s;
  s << "Jacobian at t = " << t << " s: " << variables << " variables, " << compared << " entries compared, "
    << kinks << " skipped at kinks, worst scaled error " << worst;
  if (!worst_where.empty()) s << " (" << worst_where << ")";
  if (compared <= variables) s << "; too few entries compared";
  if (kinks > std::max(2, compared / 50)) s << "; too many kinks";
  if (pattern_misses) s << "; " << pattern_misses << " AD entries outside the structural pattern";
  for (const auto& p : problems) s << "\n  " << p;
  return s.str();
}

JacobianCheck check_jacobian_at(const Evaluator& eval, double t, const std::vector<double>& y,
                                const std::vector<double>& yp) {
  JacobianCheck out;
  out.t = t;
  out.variables = eval.system().size();
  std::vector<double> dFdy, dFdyp;
  eval.jacobian_parts(t, y.data(), yp.data(), dFdy, dFdyp);
  compare_part(eval, t, y, yp, false, dFdy, out);
  compare_part(eval, t, y, yp, true, dFdyp, out);
  check_assembled(eval, t, y, yp, dFdy, dFdyp, out);
  return out;
}

std::vector<JacobianCheck> check_jacobian(const System& system, const SolverOptions& options, double t_short) {
  struct Point {
    double t;
    std::vector<double> y, yp, modes;
  };
  std::vector<Point> points;
  SolverOptions opt = options;
  opt.t_end = opt.t_start + t_short;
  opt.output_interval = t_short;
  const int n = system.size();
  Evaluator eval(system);
  const SolverResult res = simulate(eval, opt, [&](double t, const double* y, const double* yp) {
    points.push_back({t, std::vector<double>(y, y + n), std::vector<double>(yp, yp + n), eval.modes()});
  });
  if (!res.ok) throw std::runtime_error("check_jacobian: the run to t = " + std::to_string(opt.t_end) +
                                        " s failed: " + res.message);
  if (points.size() < 2) throw std::runtime_error("check_jacobian: the run produced fewer than two points");
  std::vector<JacobianCheck> out;
  for (const Point* pt : {&points.front(), &points.back()}) {
    eval.modes() = pt->modes;
    out.push_back(check_jacobian_at(eval, pt->t, pt->y, pt->yp));
  }
  return out;
}

std::vector<JacobianCheck> check_jacobian(const std::string& netlist_yaml, const Registry& registry, double t_short,
                                          const std::string& name) {
  const Netlist netlist = parse_netlist(netlist_yaml, name);
  // Every component row and unknown, as the component wrote them: alias
  // elimination would fold a small circuit's rows into constants.
  AssemblyOptions all_unknowns;
  all_unknowns.eliminate_aliases = false;
  System system(elaborate(netlist, registry), all_unknowns);
  return check_jacobian(system, solver_options(netlist.simulation), t_short);
}

Balance mass_of(const std::vector<std::string>& volumes) {
  Balance b{"mass", {}};
  for (const auto& v : volumes) b.terms.push_back({v + ".m", 1.0});
  return b;
}

Balance energy_of(const std::vector<std::string>& volumes) {
  Balance b{"energy", {}};
  for (const auto& v : volumes) b.terms.push_back({v + ".U", 1.0});
  return b;
}

bool ConservationCheck::passed(double tolerance) const { return solver_ok && rows >= 2 && worst <= tolerance; }

std::string ConservationCheck::report() const {
  std::ostringstream s;
  s.precision(12);
  s << "total " << name << ": " << initial << " at the start, " << final_value << " at the end; worst relative drift "
    << worst << " at t = " << worst_t << " s over " << rows << " output rows";
  if (!solver_ok) s << "; the run failed: " << solver_message;
  return s.str();
}

std::vector<ConservationCheck> check_conservation(const std::string& netlist_yaml, const Registry& registry,
                                                  const std::vector<Balance>& balances, const std::string& name) {
  Netlist netlist = parse_netlist(netlist_yaml, name);
  // Each term becomes an extra output column of the run.
  std::vector<std::vector<std::string>> columns(balances.size());
  for (std::size_t b = 0; b < balances.size(); ++b)
    for (std::size_t k = 0; k < balances[b].terms.size(); ++k) {
      const std::string& ref = balances[b].terms[k].ref;
      const auto dot = ref.find('.');
      if (dot == std::string::npos)
        throw std::invalid_argument("check_conservation: term '" + ref + "' must be component.variable");
      OutputDecl o;
      o.name = "testkit_" + std::to_string(b) + "_" + std::to_string(k);
      o.component = ref.substr(0, dot);
      o.quantity = ref.substr(dot + 1);
      o.where = SourceLocation{name, 0, 0};
      netlist.outputs.push_back(o);
      columns[b].push_back(o.name);
    }
  const RunResult run = run_simulation(netlist, registry);
  std::vector<ConservationCheck> out;
  for (std::size_t b = 0; b < balances.size(); ++b) {
    ConservationCheck c;
    c.name = balances[b].name;
    c.solver_ok = run.solver.ok;
    c.solver_message = run.solver.message;
    c.rows = static_cast<int>(run.table.rows.size());
    for (std::size_t r = 0; r < run.table.rows.size(); ++r) {
      const auto& row = run.table.rows[r];
      double sum = 0.0;
      for (std::size_t k = 0; k < columns[b].size(); ++k)
        sum += balances[b].terms[k].factor * row[run.table.column(columns[b][k])];
      if (r == 0) c.initial = sum;
      c.final_value = sum;
      const double drift = std::abs(sum - c.initial) / std::abs(c.initial);
      if (drift > c.worst) c.worst = drift, c.worst_t = row[0];
    }
    out.push_back(c);
  }
  return out;
}

}  // namespace pneumo::testkit
