#include "framework/solver/failure_report.hpp"

#include <idas/idas.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace pneumo {

namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// The indices of the `k` largest entries of `score` above `floor`, largest first.
std::vector<int> largest(const std::vector<double>& score, std::size_t k, double floor) {
  std::vector<int> idx(score.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::stable_sort(idx.begin(), idx.end(), [&](int a, int b) { return score[a] > score[b]; });
  std::vector<int> out;
  for (int i : idx)
    if (out.size() < k && score[i] > floor) out.push_back(i);
  return out;
}

std::string listed(const std::vector<std::string>& items) {
  std::string s;
  for (std::size_t i = 0; i < items.size(); ++i) s += (i ? "; " : "") + items[i];
  return s;
}

// The equations a component rejects at (t, y, yp): residuals not finite.
std::string rejected_rows(UserData& u, N_Vector y, N_Vector yp, double t) {
  const System& s = u.eval->system();
  std::vector<double> F(s.size(), 0.0);
  const double* py = u.physical_y(y);
  if (u.eval->residual(t, py, u.disturbed_yp(t, y, yp), F.data()) == 0) return "";
  std::vector<std::string> rows;
  for (int r = 0; r < s.size() && rows.size() < 3; ++r)
    if (!std::isfinite(F[r])) rows.push_back(s.row_name(r));
  return rows.empty() ? " A component rejects the last state (a pressure, mass or temperature <= 0)."
                      : " Not finite at the last state: " + listed(rows) + ".";
}

// A junction without volume holds no gas: its pressure is where the flows
// through it balance, and two restrictions whose flows bend back on
// themselves (a regulator's supply path throttled shut as its outlet rises,
// fed backwards from a charged chamber) can leave no balance nearby - the
// volume of the line that joins them in reality gives the pressure a state.
std::string junction_hint(const System& s, int unknown) {
  const auto j = s.junction_pressures();
  const auto is = [unknown](const std::vector<int>& v) { return std::find(v.begin(), v.end(), unknown) != v.end(); };
  if (!is(j.unguessed) && !is(j.guessed)) return "";
  return " " + s.variable_names()[unknown] +
         " is a junction without volume, set only by the flows through it: draw the line there as a volume (a "
         "few mm3 will do) to give its pressure a state.";
}

// The weighted local error of IDA's last step per unknown; empty when IDA
// cannot tell it.
std::vector<double> weighted_errors(void* ida, N_Vector y) {
  std::vector<double> w;
  N_Vector ewt = N_VClone(y), ele = N_VClone(y);
  if (ewt && ele && IDAGetErrWeights(ida, ewt) == IDA_SUCCESS && IDAGetEstLocalErrors(ida, ele) == IDA_SUCCESS) {
    w.resize(NV_LENGTH_S(y));
    for (std::size_t i = 0; i < w.size(); ++i) w[i] = std::abs(NV_Ith_S(ele, i) * NV_Ith_S(ewt, i));
  }
  if (ewt) N_VDestroy(ewt);
  if (ele) N_VDestroy(ele);
  return w;
}

}  // namespace

std::string junction_failure_hint(void* ida, const System& s, N_Vector y) {
  const std::vector<int> worst = largest(weighted_errors(ida, y), 1, 0.0);
  return worst.empty() ? "" : junction_hint(s, worst[0]);
}

std::string step_failure_report(void* ida, UserData& u, N_Vector y, N_Vector yp, double t,
                                const std::vector<EventLogEntry>& events) {
  const System& s = u.eval->system();
  std::string out;
  const std::vector<double> w = weighted_errors(ida, y);
  std::vector<std::string> names;
  const std::vector<int> worst = largest(w, 3, 0.0);
  for (int i : worst) names.push_back(s.variable_names()[i] + " (" + number(w[i]) + ")");
  if (!names.empty()) out += " Largest weighted error (1 = the tolerance): " + listed(names) + ".";
  if (!worst.empty()) out += junction_hint(s, worst[0]);
  out += rejected_rows(u, y, yp, t);
  if (!events.empty()) {
    const auto& e = events.back();
    out += " Last event: t = " + number(e.t) + " s (" + number(t - e.t) + " s before), " + e.component + ": " +
           e.message + ".";
  }
  return out;
}

std::string start_failure_report(UserData& u, N_Vector y, N_Vector yp, double t) {
  const System& s = u.eval->system();
  const int n = s.size();
  if (n == 0 || n > 3000) return "";  // the dense matrices below: n^2 numbers
  std::vector<double> py(u.physical_y(y), u.physical_y(y) + n), pyp(u.physical_yp(yp), u.physical_yp(yp) + n);
  std::vector<double> dFdy, dFdyp, F(n, 0.0);
  u.eval->jacobian_parts(t, py.data(), pyp.data(), dFdy, dFdyp);
  u.eval->residual(t, py.data(), pyp.data(), F.data());
  // The consistent-value problem's matrix: algebraic unknowns by y,
  // differential ones by y', each column in its unknown's nominal unit.
  const auto& id = s.differential();
  auto m = [&](int r, int c) {
    return std::abs(id[c] != 0.0 ? dFdyp[std::size_t(r) * n + c] : dFdy[std::size_t(r) * n + c]) * s.nominal()[c];
  };
  std::vector<std::string> free_vars, empty_rows, off_rows;
  std::vector<double> off(n, 0.0);
  for (int c = 0; c < n; ++c) {
    double col = 0.0;
    for (int r = 0; r < n; ++r) col = std::max(col, m(r, c));
    if (col == 0.0 && free_vars.size() < 3) free_vars.push_back(s.variable_names()[c]);
  }
  for (int r = 0; r < n; ++r) {
    double row = 0.0;
    for (int c = 0; c < n; ++c) row = std::max(row, m(r, c));
    if (row == 0.0 && empty_rows.size() < 3) empty_rows.push_back(s.row_name(r));
    off[r] = row > 0.0 ? std::abs(F[r]) / row : std::abs(F[r]);  // in nominal units of its strongest unknown
    if (!std::isfinite(F[r])) off[r] = HUGE_VAL;
  }
  for (int r : largest(off, 2, 1e-6)) off_rows.push_back(s.row_name(r) + " (off by " + number(off[r]) + ")");
  std::string out;
  if (!free_vars.empty())
    out += " Nothing determines " + listed(free_vars) +
           " at the start: every equation of it is flat there (closed ports, a closed check valve, no volume); add "
           "a volume (a tube) at that node, or open a path that sets its pressure.";
  if (!empty_rows.empty()) out += " Equations that depend on no unknown at the start: " + listed(empty_rows) + ".";
  if (!off_rows.empty()) out += " Furthest from holding: " + listed(off_rows) + ".";
  return out;
}

}  // namespace pneumo
