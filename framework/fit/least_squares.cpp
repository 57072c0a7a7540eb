#include "framework/fit/least_squares.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace pneumo::fit {

namespace {
bool near(double a, double b) { return std::isfinite(b) && std::abs(a - b) <= 1e-6 * (std::abs(b) + 1e-9); }

std::string num(double v) {
  if (std::isnan(v)) return "-";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.5g", v);
  return buf;
}
std::string fixed5(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.5f", v);
  return buf;
}
}  // namespace

bool FitParameter::at_lower() const { return !fixed && near(value, lower); }
bool FitParameter::at_upper() const { return !fixed && near(value, upper); }

const FitParameter& FitReport::parameter(const std::string& name) const {
  for (const auto& p : parameters)
    if (p.name == name) return p;
  throw std::out_of_range("no fitted coefficient '" + name + "'");
}

std::vector<double> FitReport::values() const {
  std::vector<double> v;
  for (const auto& p : parameters) v.push_back(p.value);
  return v;
}

FitParameter bounded_parameter(const std::string& name, const std::string& unit, double initial, double lower,
                               double upper, const std::string& note) {
  FitParameter p;
  p.name = name;
  p.unit = unit;
  p.initial = initial;
  p.lower = lower;
  p.upper = upper;
  p.note = note;
  return p;
}

void set_parameter(std::vector<FitParameter>& params, const std::string& assignment, ParameterField field) {
  const auto eq = assignment.find('=');
  std::string known;
  for (const auto& p : params) known += (known.empty() ? "" : ", ") + p.name;
  if (eq == std::string::npos)
    throw std::invalid_argument("'" + assignment + "': expected NAME=VALUE with NAME one of " + known);
  const std::string name = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || std::isnan(v))
    throw std::invalid_argument("'" + assignment + "': '" + text + "' is not a number");
  for (auto& p : params) {
    if (p.name != name) continue;
    switch (field) {
      case ParameterField::initial: p.initial = v; break;
      case ParameterField::lower: p.lower = v; break;
      case ParameterField::upper: p.upper = v; break;
      case ParameterField::fixed:
        p.initial = v;
        p.fixed = true;
        break;
    }
    return;
  }
  throw std::invalid_argument("'" + assignment + "': no coefficient '" + name + "' in this model (" + known + ")");
}

void check_parameters(const std::vector<FitParameter>& params) {
  for (const auto& p : params) {
    if (!(p.lower <= p.upper))
      throw std::invalid_argument("coefficient '" + p.name + "': lower bound " + num(p.lower) +
                                  " is above the upper bound " + num(p.upper));
    if (!std::isfinite(p.initial))
      throw std::invalid_argument("coefficient '" + p.name + "': initial value is not finite");
    if (!p.fixed && (p.initial < p.lower || p.initial > p.upper))
      throw std::invalid_argument("coefficient '" + p.name + "': initial value " + num(p.initial) +
                                  " lies outside its bounds [" + num(p.lower) + ", " + num(p.upper) + "]");
  }
}

std::string format_report(const FitReport& r, const std::string& rss_unit) {
  std::ostringstream o;
  char line[256];
  std::snprintf(line, sizeof line, "  %-6s %-12s %12s %10s %10s %10s %10s  %s\n", "coeff", "unit", "value",
                "std.err", "initial", "lower", "upper", "");
  o << line;
  for (const auto& p : r.parameters) {
    std::string flag = p.fixed ? "fixed" : p.at_lower() ? "at lower bound" : p.at_upper() ? "at upper bound" : "";
    if (!p.note.empty()) flag += (flag.empty() ? "" : "; ") + p.note;
    std::snprintf(line, sizeof line, "  %-6s %-12s %12s %10s %10s %10s %10s  %s\n", p.name.c_str(), p.unit.c_str(),
                  num(p.value).c_str(), num(p.std_error).c_str(), num(p.initial).c_str(),
                  p.fixed ? "-" : num(p.lower).c_str(), p.fixed ? "-" : num(p.upper).c_str(), flag.c_str());
    o << line;
  }
  o << "  points " << r.points << ", free coefficients " << r.free_parameters << ", RSS " << num(r.rss) << " "
    << rss_unit << ", R2 " << fixed5(r.r2) << (r.converged ? "" : "  (NOT CONVERGED: ")
    << (r.converged ? "" : r.solver_message + ")") << "\n";
  return o.str();
}

}  // namespace pneumo::fit
