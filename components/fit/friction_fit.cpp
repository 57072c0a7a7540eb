#include "components/fit/friction_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>

#include "framework/fit/least_squares_impl.hpp"

namespace pneumo::fit {

using components::FrictionCoefficients;
using components::FrictionPressure;

namespace {

// The three laws over coefficient accessor c(i), same order as the defaults.
template <class T, class C>
T model_force(FrictionModel m, const C& c, double v, double p) {
  const double av = std::abs(v);
  using std::exp;
  using std::pow;
  // |v|^a with a fitted: v = 0 contributes 0 (pow(0, a) has no derivative in a).
  auto pw = [&](const T& a) { return av > 0 ? T(pow(av, a)) : T(0.0); };
  switch (m) {
    case FrictionModel::eq4:  // FC, FS, vS, kv, a, kp
      return c(0) + c(5) * p + (c(1) - c(0)) * exp(-av / c(2)) + c(3) * pw(c(4));
    case FrictionModel::eq7:  // b, FS, FC, vS, kv, a
      return c(0) + (c(1) - c(2)) * exp(-av / c(3)) + c(4) * pw(c(5));
    case FrictionModel::eq8:  // b0, b1, FS0, FS1, FC, vS, kv0, kv1, a
      return c(0) + c(1) * p + (c(2) + c(3) * p - c(4)) * exp(-av / c(5)) + (c(6) + c(7) * p) * pw(c(8));
  }
  return T(0.0);
}

// What a point's measured force is compared with: the law's magnitude, or,
// with a load-cell offset F0 (the last coefficient), the signed force
// sign(v) law + F0 (F measured positive along the motion).
template <class T, class C>
T point_force(FrictionModel m, bool offset, int k, const C& c, const FrictionPoint& pt) {
  const T law = model_force<T>(m, c, pt.v, pt.p_bar);
  return offset ? (pt.v < 0 ? -law : law) + c(k - 1) : law;
}

double observed(bool offset, const FrictionPoint& pt) { return offset ? pt.F : std::abs(pt.F); }

struct FrictionResidual {
  FrictionModel model;
  bool offset;
  int k;
  FrictionPoint pt;
  template <class T>
  bool operator()(T const* const* params, T* r) const {
    r[0] = point_force<T>(model, offset, k, [&](int i) { return params[i][0]; }, pt) - observed(offset, pt);
    return true;
  }
};

bool has_offset(FrictionModel m, const std::vector<FitParameter>& params) {
  return params.size() == default_friction_parameters(m).size() + 1 && params.back().name == "F0";
}

std::size_t index_of(const std::vector<FitParameter>& params, const std::string& name) {
  std::size_t i = 0;
  while (params[i].name != name) ++i;
  return i;
}

// Values from lo to hi (log-spaced if `log`), or the held value when fixed.
// (Unbounded: a decade either side of the initial value.)
std::vector<double> grid(const FitParameter& p, int n, bool log) {
  if (p.fixed) return {p.initial};
  double lo = p.lower, hi = p.upper;
  if (!std::isfinite(lo) || !std::isfinite(hi) || (log && hi <= 0)) {
    const double s = std::max(std::abs(p.initial), 1e-12);
    lo = std::max(lo, log ? s / 10 : p.initial - 10 * s);
    hi = std::min(hi, log ? s * 10 : p.initial + 10 * s);
  }
  if (log) lo = std::max(lo, hi * 1e-4);
  std::vector<double> g;
  for (int i = 0; i < n; ++i) {
    const double f = double(i) / (n - 1);
    g.push_back(log ? lo * std::pow(hi / lo, f) : lo + f * (hi - lo));
  }
  return g;
}

// Starting values: the given ones and the three best of a grid. Every law
// is linear in all its coefficients but vS and a (and F0 too): on a grid of (vS, a) the others follow
// from one linear least-squares solve (the model's columns are found by
// evaluating it, so no law is written twice), clamped to their bounds. The
// best grid point starts the nonlinear fit near the global minimum instead
// of where the paper's initial values happen to lie - far from it on data
// whose speeds (mm/s) are far from where kv is defined (1 m/s), where the
// solver crawls along the kv-a valley without converging. At most ~2000
// points (every n-th) are used: a start needs no more.
std::vector<std::vector<FitParameter>> separable_starts(FrictionModel m, bool offset,
                                                        const std::vector<FrictionPoint>& all,
                                                        const std::vector<FitParameter>& params) {
  const int k = static_cast<int>(params.size());
  const std::size_t ivs = index_of(params, "vS"), ia = index_of(params, "a");
  std::vector<int> lin;
  for (int j = 0; j < k; ++j)
    if (!params[j].fixed && j != int(ivs) && j != int(ia)) lin.push_back(j);
  std::vector<FrictionPoint> pts;
  const std::size_t step = std::max<std::size_t>(1, all.size() / 2000);
  for (std::size_t i = 0; i < all.size(); i += step) pts.push_back(all[i]);
  const int n = static_cast<int>(pts.size());
  std::vector<double> x(k);
  for (int j = 0; j < k; ++j) x[j] = params[j].initial;
  auto force = [&](const FrictionPoint& pt) {
    return point_force<double>(m, offset, k, [&](int i) { return x[i]; }, pt);
  };
  auto rss = [&] {
    double s = 0;
    for (const auto& pt : pts) s += std::pow(force(pt) - observed(offset, pt), 2);
    return s;
  };
  std::vector<std::pair<double, std::vector<double>>> found;  // (RSS, values) per grid point
  Eigen::MatrixXd A(n, lin.size());
  Eigen::VectorXd y(n), f0(n);
  for (double vs : grid(params[ivs], 12, true))
    for (double a : grid(params[ia], 10, false)) {
      x[ivs] = vs, x[ia] = a;
      for (int j : lin) x[j] = 0;
      for (int i = 0; i < n; ++i) f0(i) = force(pts[i]);  // the part that is not linear
      for (std::size_t c = 0; c < lin.size(); ++c) {
        x[lin[c]] = 1;
        for (int i = 0; i < n; ++i) A(i, c) = force(pts[i]) - f0(i);
        x[lin[c]] = 0;
      }
      for (int i = 0; i < n; ++i) y(i) = observed(offset, pts[i]) - f0(i);
      const Eigen::VectorXd sol = A.colPivHouseholderQr().solve(y);
      for (std::size_t c = 0; c < lin.size(); ++c)
        x[lin[c]] = std::isfinite(sol(c)) ? std::clamp(sol(c), params[lin[c]].lower, params[lin[c]].upper)
                                          : params[lin[c]].initial;
      if (const double s = rss(); std::isfinite(s)) found.emplace_back(s, x);
    }
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::vector<FitParameter>> starts{params};  // the given values, then the best 3 grid points
  for (std::size_t i = 0; i < found.size() && i < 3; ++i) {
    starts.push_back(params);
    for (int j = 0; j < k; ++j) starts.back()[j].initial = found[i].second[j];
  }
  return starts;
}

FitParameter par(const char* name, const char* unit, double init, double lo, double hi, const char* note = "") {
  return bounded_parameter(name, unit, init, lo, hi, note);
}

FitParameter fixed(FitParameter p) {
  p.fixed = true;
  return p;
}

std::string g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

FrictionModel parse_friction_model(const std::string& t) {
  if (t == "eq4") return FrictionModel::eq4;
  if (t == "eq7") return FrictionModel::eq7;
  if (t == "eq8") return FrictionModel::eq8;
  throw std::invalid_argument("unknown friction model '" + t + "' (eq4, eq7 or eq8)");
}

std::string friction_model_name(FrictionModel m) {
  switch (m) {
    case FrictionModel::eq4: return "eq4";
    case FrictionModel::eq7: return "eq7";
    case FrictionModel::eq8: return "eq8";
  }
  return "";
}

FrictionPressure parse_friction_pressure(const std::string& t) {
  if (t == "pAB-") return FrictionPressure::ab_minus;
  if (t == "pAB+") return FrictionPressure::ab_plus;
  if (t == "pEC") return FrictionPressure::ec;
  if (t == "none") return FrictionPressure::none;
  throw std::invalid_argument("unknown friction pressure '" + t + "' (pAB-, pAB+ or pEC)");
}

std::string friction_pressure_name(FrictionPressure p) {
  switch (p) {
    case FrictionPressure::none: return "none";
    case FrictionPressure::ab_minus: return "pAB-";
    case FrictionPressure::ab_plus: return "pAB+";
    case FrictionPressure::ec: return "pEC";
  }
  return "";
}

std::vector<FitParameter> default_friction_parameters(FrictionModel m, bool offset) {
  auto params = default_friction_parameters(m);
  if (offset) params.push_back(par("F0", "N", 0, -1000, 1000, "force offset (load cell), not friction"));
  return params;
}

std::vector<FitParameter> default_friction_parameters(FrictionModel m) {
  const char* fc_note = "only FS-FC is identifiable";
  switch (m) {
    case FrictionModel::eq4:
      return {par("FC", "N", 5, 2, 200, "lower bound 2 N as Annex A"),
              par("FS", "N", 20, 0, 500),
              par("vS", "m/s", 0.004, 0.001, 0.1, "lower bound 1 mm/s as Annex A"),
              par("kv", "N", 100, 0, 5000, "force at 1 m/s"),
              par("a", "1", 0.7, 0.1, 2),
              par("kp", "N/bar", 5, -200, 200)};
    case FrictionModel::eq7:
      return {par("b", "N", 3, -100, 200),
              par("FS", "N", 25, -100, 500),
              fixed(par("FC", "N", 5, -1e9, 1e9, fc_note)),
              par("vS", "m/s", 0.004, 0.0002, 0.1),
              par("kv", "N", 100, 0, 5000, "force at 1 m/s"),
              par("a", "1", 0.7, 0.1, 2)};
    case FrictionModel::eq8:
      return {par("b0", "N", 0, -100, 200),
              par("b1", "N/bar", 0, -100, 100),
              par("FS0", "N", 20, -100, 500),
              par("FS1", "N/bar", 0, -100, 100),
              fixed(par("FC", "N", 5, -1e9, 1e9, fc_note)),
              par("vS", "m/s", 0.004, 0.0002, 0.1),
              par("kv0", "N", 100, -1000, 5000, "force at 1 m/s"),
              par("kv1", "N/bar", 0, -1000, 1000, "per bar, at 1 m/s"),
              par("a", "1", 0.7, 0.1, 2)};
  }
  return {};
}

double friction_model_force(FrictionModel m, const std::vector<double>& c, double v, double p_bar) {
  return model_force<double>(m, [&](int i) { return c.at(static_cast<std::size_t>(i)); }, v, p_bar);
}

double friction_rms(FrictionModel m, const FitReport& r, const std::vector<FrictionPoint>& points) {
  if (points.empty()) return NAN;
  const bool offset = has_offset(m, r.parameters);
  const std::vector<double> c = r.values();
  const int k = static_cast<int>(c.size());
  double s = 0;
  for (const auto& pt : points)
    s += std::pow(point_force<double>(m, offset, k, [&](int i) { return c[static_cast<std::size_t>(i)]; }, pt) -
                      observed(offset, pt),
                  2);
  return std::sqrt(s / static_cast<double>(points.size()));
}

FitReport fit_friction(FrictionModel m, const std::vector<FrictionPoint>& points, std::vector<FitParameter> params) {
  const bool offset = has_offset(m, params);
  if (params.size() != default_friction_parameters(m).size() && !offset)
    throw std::invalid_argument("coefficient list does not match model " + friction_model_name(m));
  check_parameters(params);
  if (offset) {
    // The offset model needs forces signed along the motion: refuse data
    // written the other way round rather than fit a negative friction.
    double along = 0;
    for (const auto& pt : points) along += pt.v < 0 ? -pt.F : pt.F;
    if (along < 0)
      throw std::invalid_argument(
          "with a force offset F is signed: positive along the motion (sign of v), but in these data F is mostly "
          "against v; negate the F column");
  }
  const int k = static_cast<int>(params.size());
  std::vector<FrictionResidual> res;
  std::vector<double> obs;
  for (const auto& pt : points) {
    res.push_back({m, offset, k, pt});
    obs.push_back(observed(offset, pt));
  }
  // The Stribeck term has local minima: the least RSS of four starts.
  FitReport best;
  bool have = false;
  for (const auto& start : separable_starts(m, offset, points, params)) {
    FitReport r = detail::solve(start, res, obs, 1.0);
    if (!have || r.rss < best.rss) best = std::move(r), have = true;
  }
  for (int j = 0; j < k; ++j) best.parameters[j].initial = params[j].initial;  // report the user's
  return best;
}

std::vector<FrictionPoint> friction_points(const DataTable& d, FrictionPressure pressure, double p_ambient) {
  const std::string why = "friction fit with pressure " + friction_pressure_name(pressure);
  const int cv = d.require("v", "piston speed, " + why);
  const int cF = d.require("F", "friction force, " + why);
  int ca = -1, cb = -1, cec = -1;
  if (pressure == FrictionPressure::ab_minus || pressure == FrictionPressure::ab_plus) {
    ca = d.require("p_A", "chamber pressure A, " + why);
    cb = d.require("p_B", "chamber pressure B, " + why);
  } else if (pressure == FrictionPressure::ec) {
    cec = d.require("p_EC", "cushion pressure, " + why);
  }
  std::vector<FrictionPoint> pts;
  for (std::size_t i = 0; i < d.rows.size(); ++i) {
    const auto& r = d.rows[i];
    FrictionPoint p;
    p.v = r[cv];  // signed: a force offset is told apart from friction by the direction
    p.F = r[cF];
    p.line = d.lines[i];
    if (p.v == 0)
      throw InputError(d.where(i), "", "",
                       "column 'v': speed 0 - friction at rest is not on the Stribeck curve; drop the row");
    switch (pressure) {
      case FrictionPressure::none: break;
      case FrictionPressure::ab_minus: p.p_bar = std::abs(r[ca] - r[cb]) / 1e5; break;
      case FrictionPressure::ab_plus: p.p_bar = (r[ca] + r[cb] - 2 * p_ambient) / 1e5; break;
      case FrictionPressure::ec: p.p_bar = (r[cec] - p_ambient) / 1e5; break;
    }
    pts.push_back(p);
  }
  return pts;
}

FrictionCoefficients friction_coefficients(FrictionModel m, const FitReport& r, FrictionPressure pressure) {
  FrictionCoefficients c;
  const auto v = r.values();
  switch (m) {
    case FrictionModel::eq4:  // FC, FS, vS, kv, a, kp
      c = FrictionCoefficients{v[0], v[5], v[1], 0, v[0], v[2], v[3], 0, v[4], pressure};
      break;
    case FrictionModel::eq7:  // b, FS, FC, vS, kv, a
      c = FrictionCoefficients{v[0], 0, v[1], 0, v[2], v[3], v[4], 0, v[5], FrictionPressure::none};
      break;
    case FrictionModel::eq8:
      c = FrictionCoefficients{v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], pressure};
      break;
  }
  return c;
}

std::string friction_preset_yaml(const FrictionCoefficients& c, const FitReport& r, FrictionModel m,
                                 bool cushion_zone, const std::string& header) {
  std::ostringstream o;
  std::istringstream h(header);
  std::string line;
  while (std::getline(h, line)) o << "# " << line << "\n";
  o << "# paper [1] " << friction_model_name(m) << " fitted to " << r.points << " points: RSS " << g(r.rss)
    << " N^2, R2 " << g(r.r2) << "\n"
    << "# general form (components/friction.hpp): |F| = b0 + b1 p + (FS0 + FS1 p - FC) exp(-|v|/vS)"
       " + (kv0 + kv1 p) |v|^a, p in bar\n"
    << "# Paste into the cylinder's parameters (friction law).\n";
  const std::string pre = cushion_zone ? "friction_cushion" : "friction";
  o << pre << ": custom\n";
  o << pre << "_pressure: " << friction_pressure_name(c.pressure) << "\n";
  o << pre << "_b0: " << g(c.b0) << " N\n";
  o << pre << "_b1: " << g(c.b1) << " N/bar\n";
  o << pre << "_FS0: " << g(c.FS0) << " N\n";
  o << pre << "_FS1: " << g(c.FS1) << " N/bar\n";
  o << pre << "_FC: " << g(c.FC) << " N\n";
  o << pre << "_vS: " << g(c.vS) << " m/s\n";
  o << pre << "_kv0: " << g(c.kv0) << " N       # force at |v| = 1 m/s\n";
  o << pre << "_kv1: " << g(c.kv1) << " N/bar\n";
  o << pre << "_a: " << g(c.a) << "\n";
  return o.str();
}

}  // namespace pneumo::fit
