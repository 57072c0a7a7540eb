#include "framework/fit/friction_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

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

struct FrictionResidual {
  FrictionModel model;
  double v, p, F;
  template <class T>
  bool operator()(T const* const* params, T* r) const {
    r[0] = model_force<T>(model, [&](int i) { return params[i][0]; }, v, p) - F;
    return true;
  }
};

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

FitReport fit_friction(FrictionModel m, const std::vector<FrictionPoint>& points, std::vector<FitParameter> params) {
  if (params.size() != default_friction_parameters(m).size())
    throw std::invalid_argument("coefficient list does not match model " + friction_model_name(m));
  std::vector<FrictionResidual> res;
  std::vector<double> obs;
  for (const auto& pt : points) {
    res.push_back({m, pt.v, pt.p_bar, pt.F});
    obs.push_back(pt.F);
  }
  // The Stribeck term makes the problem multimodal in vS (a small vS lets
  // exp(-|v|/vS) vanish at every point and the bias absorb it): start from
  // the given vS and from 1/3, 3 and 10 times it, keep the smallest RSS.
  std::size_t ivs = 0;
  while (params[ivs].name != "vS") ++ivs;
  FitReport best;
  bool have = false;
  const double vs0 = params[ivs].initial;
  for (double f : {1.0, 1.0 / 3.0, 3.0, 10.0}) {
    if (params[ivs].fixed && f != 1.0) break;
    auto start = params;
    start[ivs].initial = std::clamp(vs0 * f, start[ivs].lower, start[ivs].upper);
    FitReport r = detail::solve(start, res, obs, 1.0);
    r.parameters[ivs].initial = vs0;
    if (!have || r.rss < best.rss) best = std::move(r), have = true;
  }
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
    p.v = std::abs(r[cv]);
    p.F = std::abs(r[cF]);
    p.line = d.lines[i];
    if (p.v <= 0)
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
