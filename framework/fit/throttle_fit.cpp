#include "framework/fit/throttle_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <stdexcept>

#include "framework/fit/least_squares_impl.hpp"

namespace pneumo::fit {

namespace {

constexpr double kCUnit = 1e-8;  // 1 dm3/(s*bar) in m3/(s*Pa)

// Flow function of components/iso6358_flow.hpp with b a fitted unknown.
template <class T>
T phi(double r, const T& b, double r_lam) {
  using std::sqrt;
  if (r <= r_lam) {
    const T x = (r - b) / (1.0 - b);
    if (r <= b) return T(1.0);  // choked, where b is not seen by the data point
    return sqrt(1.0 - x * x);
  }
  const T x_lam = (r_lam - b) / (1.0 - b);
  return sqrt(1.0 - x_lam * x_lam) * (1.0 - r) / (1.0 - r_lam);
}

struct ThrottleResidual {
  ThrottlePoint pt;
  double rho_ref, T_ref, r_lam, scale;
  template <class T>
  bool operator()(T const* const* params, T* res) const {
    const T C = params[0][0] * kCUnit;
    const T m = C * rho_ref * pt.p1 * std::sqrt(T_ref / pt.T1) * phi(pt.p2 / pt.p1, params[1][0], r_lam);
    res[0] = (m - pt.m_flow) / scale;
    return true;
  }
};

std::string g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

double iso6358_flow(const ThrottlePoint& p, double C, double b, const GasModel& gas, double r_lam) {
  return C * gas.rho_ref * p.p1 * std::sqrt(gas.T_ref / p.T1) * phi(p.p2 / p.p1, b, r_lam);
}

FitReport fit_throttle(const std::vector<ThrottlePoint>& points, const GasModel& gas) {
  if (points.empty()) throw std::invalid_argument("too few points: no data points");
  // Initial C from the point with the lowest pressure ratio (nearest to choked).
  const auto lowest = *std::min_element(points.begin(), points.end(), [](const auto& a, const auto& b) {
    return a.p2 / a.p1 < b.p2 / b.p1;
  });
  const double C0 = lowest.m_flow / (gas.rho_ref * lowest.p1 * std::sqrt(gas.T_ref / lowest.T1)) / kCUnit;
  int subsonic = 0;
  for (const auto& p : points) subsonic += p.p2 / p.p1 > 0.55;
  if (subsonic < 2)
    throw std::invalid_argument("too few points: b needs at least two subsonic points (p2/p1 > 0.55), the data have " +
                                std::to_string(subsonic));
  const FitParameter C = bounded_parameter("C", "dm3/(s*bar)", C0, 0.0, 1e6);
  const FitParameter b = bounded_parameter("b", "1", 0.4, 0.0, 0.99);
  double scale = 0;
  for (const auto& p : points) scale = std::max(scale, p.m_flow);
  std::vector<ThrottleResidual> res;
  std::vector<double> obs;
  for (const auto& p : points) {
    res.push_back({p, gas.rho_ref, gas.T_ref, 0.999, scale});
    obs.push_back(p.m_flow);
  }
  return detail::solve({C, b}, res, obs, scale);
}

NeedleFit fit_needle_throttle(const std::vector<ThrottlePoint>& points, const GasModel& gas) {
  std::map<double, std::vector<ThrottlePoint>> groups;
  for (const auto& p : points) groups[p.z].push_back(p);
  if (groups.size() < 2)
    throw std::invalid_argument("too few openings: C(z) and b(C) need points at two or more openings z, the data have " +
                                std::to_string(groups.size()));
  NeedleFit f;
  for (const auto& [z, pts] : groups) {
    try {
      f.per_opening.push_back(fit_throttle(pts, gas));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("opening z = " + g(z) + ": " + e.what());
    }
    f.z.push_back(z);
    f.C_max = std::max(f.C_max, f.per_opening.back().value("C"));
  }
  // b = b0 + slope * C/C_max: ordinary least squares (linear, closed form).
  const std::size_t n = f.z.size();
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& r : f.per_opening) {
    const double x = r.value("C") / f.C_max, y = r.value("b");
    sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  const double den = n * sxx - sx * sx;
  f.b_slope = den > 0 ? (n * sxy - sx * sy) / den : 0.0;
  f.b0 = (sy - f.b_slope * sx) / n;
  double rss = 0, tss = 0;
  for (const auto& r : f.per_opening) {
    const double x = r.value("C") / f.C_max, y = r.value("b");
    rss += std::pow(y - f.b0 - f.b_slope * x, 2);
    tss += std::pow(y - sy / n, 2);
  }
  f.b_line_r2 = tss > 0 ? 1 - rss / tss : 1.0;
  return f;
}

std::vector<ThrottlePoint> throttle_points(const DataTable& d, bool* has_z) {
  const std::string why = "ISO 6358 throttle fit";
  const int c1 = d.require("p1", "upstream pressure, " + why);
  const int c2 = d.require("p2", "downstream pressure, " + why);
  const int cm = d.require("m_flow", "mass flow, " + why);
  const int cT = d.column("T1");
  const int cz = d.column("z");
  if (has_z) *has_z = cz >= 0;
  std::vector<ThrottlePoint> pts;
  for (std::size_t i = 0; i < d.rows.size(); ++i) {
    const auto& r = d.rows[i];
    ThrottlePoint p;
    p.p1 = r[c1];
    p.p2 = r[c2];
    p.m_flow = r[cm];
    if (cT >= 0) p.T1 = r[cT];
    if (cz >= 0) p.z = r[cz];
    p.line = d.lines[i];
    if (!(p.p1 > 0 && p.p2 > 0))
      throw InputError(d.where(i), "", "", "pressures must be positive (absolute; write 'p1 [bar_rel]' for gauge)");
    if (!(p.p2 < p.p1))
      throw InputError(d.where(i), "", "", "p2 must be below p1 (flow from p1 to p2)");
    if (!(p.m_flow > 0)) throw InputError(d.where(i), "", "", "column 'm_flow': the mass flow p1 -> p2 must be positive");
    if (!(p.T1 > 0)) throw InputError(d.where(i), "", "", "column 'T1': temperature must be positive (K)");
    pts.push_back(p);
  }
  return pts;
}

std::string throttle_yaml(const FitReport& r, const std::string& header) {
  std::ostringstream o;
  std::istringstream h(header);
  std::string line;
  while (std::getline(h, line)) o << "# " << line << "\n";
  o << "# ISO 6358 fit to " << r.points << " points: R2 " << g(r.r2) << "\n";
  o << "type: iso6358_throttle\nC: " << g(r.value("C")) << " dm3/(s*bar)\nb: " << g(r.value("b")) << "\n";
  return o.str();
}

std::string needle_throttle_yaml(const NeedleFit& f, const std::string& header) {
  std::ostringstream o;
  std::istringstream h(header);
  std::string line;
  while (std::getline(h, line)) o << "# " << line << "\n";
  o << "# needle throttle: C and b per opening, b = b0 + slope C/C_max (R2 of the line " << g(f.b_line_r2)
    << ")\n# Paste into the cylinder's parameters (cushion needle throttle).\ncushion_C_of_z:\n";
  for (std::size_t i = 0; i < f.z.size(); ++i)
    o << "  - [" << g(f.z[i]) << ", " << g(f.per_opening[i].value("C")) << " dm3/(s*bar)]   # b = "
      << g(f.per_opening[i].value("b")) << ", R2 " << g(f.per_opening[i].r2) << "\n";
  o << "cushion_b0: " << g(f.b0) << "\ncushion_b_slope: " << g(f.b_slope) << "\n";
  return o.str();
}

}  // namespace pneumo::fit
