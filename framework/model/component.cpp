#include "framework/model/component.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <vector>

#include "framework/core/units.hpp"

namespace pneumo {

const char* domain_name(Domain d) {
  switch (d) {
    case Domain::pneumatic: return "pneumatic";
    case Domain::thermal: return "thermal";
    case Domain::translational: return "translational";
    case Domain::signal: return "signal";
  }
  return "?";
}

int port_width(Domain d) {
  switch (d) {
    case Domain::pneumatic: return 4;  // p, m_flow, T_out, T_in
    case Domain::thermal: return 2;    // T, Q
    case Domain::translational: return 3;  // s, f, v
    case Domain::signal: return 1;     // value
  }
  return 0;
}

int port_equations(Domain d, Causality c) {
  switch (d) {
    case Domain::pneumatic: return 2;  // m_flow and T_out
    case Domain::thermal: return 1;    // Q
    case Domain::translational: return 1;  // f
    case Domain::signal: return c == Causality::output ? 1 : 0;
  }
  return 0;
}

static std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

namespace {

// What is plausible in a pneumatic drive, by dimension (SI): at most
// `ceiling` in magnitude, never negative where physics says so, and for a
// parameter that must be positive at least `floor`. A value outside is a
// typing slip (1e308 Pa, 9.2e18 dm3/(s*bar), 1e-320 Pa), which the solver
// would only report as "cannot find consistent initial values".
struct Plausible {
  units::Dimension dim;
  double floor, ceiling;
  bool non_negative;
};

const Plausible* plausible_for(const std::string& unit) {
  using namespace units::dims;
  static const std::vector<Plausible> table = {
      {pressure, 1.0, 1e8, false},                 // 1 Pa .. 1000 bar
      {volume, 1e-12, 1e2, true},                  // m3
      {length, 1e-9, 1e3, false},                  // m
      {area, 1e-14, 1e2, false},                   // m2 (also N/bar friction slopes)
      {mass, 1e-9, 1e6, true},                     // kg
      {temperature, 1.0, 5000.0, true},            // K
      {time, 1e-12, 1e7, false},                   // s
      {sonic_conductance, 1e-20, 1e-3, true},      // m3/(s*Pa): up to 1e5 dm3/(s*bar)
      {force, 1e-12, 1e8, false},                  // N
      {velocity, 1e-12, 1e3, false},               // m/s
      {mass_flow, 1e-15, 1e9, false},              // kg/s, also damping N*s/m
      {{.kg = 1, .s = -2}, 1e-9, 1e12, false},     // stiffness N/m
      {energy, 1e-12, 1e12, false},                // J
      {power, 1e-12, 1e9, false},                  // W
      {{.m = 2, .kg = 1, .s = -2, .K = -1}, 1e-9, 1e9, true},  // heat capacity J/K
      {{.kg = 1, .s = -3, .K = -1}, 1e-9, 1e6, true},         // heat transfer coefficient W/(m2*K)
  };
  units::Dimension d;
  try {
    d = units::dimension_of(unit);
  } catch (const units::ParseError&) {
    return nullptr;
  }
  for (const auto& p : table)
    if (p.dim == d) return &p;
  return nullptr;
}

struct Bounds {
  double lo, hi;
  bool lo_open, hi_open;
};

// The spec's own range narrowed to what is plausible for its unit.
Bounds bounds_of(const ParameterSpec& s) {
  Bounds b{s.min, s.max, s.min_exclusive, s.max_exclusive};
  const Plausible* p = plausible_for(s.unit);
  if (!p) return b;
  if (b.lo == 0 && b.lo_open) b = {p->floor, b.hi, false, b.hi_open};  // positive: at least the floor
  const double lo = p->non_negative ? 0.0 : -p->ceiling;
  if (lo > b.lo) b.lo = lo, b.lo_open = false;
  if (p->ceiling < b.hi) b.hi = p->ceiling, b.hi_open = false;
  return b;
}

}  // namespace

std::string ParameterSpec::range_text() const {
  const Bounds b = bounds_of(*this);
  const bool lo = std::isfinite(b.lo), hi = std::isfinite(b.hi);
  if (!lo && !hi) return "any value";
  if (lo && !hi) return std::string(b.lo_open ? "> " : ">= ") + num(b.lo);
  if (!lo && hi) return std::string(b.hi_open ? "< " : "<= ") + num(b.hi);
  return std::string(b.lo_open ? "(" : "[") + num(b.lo) + ", " + num(b.hi) + (b.hi_open ? ")" : "]");
}

std::string ParameterSpec::default_text_of_scalar() const {
  if (ambient_default == Ambient::pressure) return "ambient pressure";
  if (ambient_default == Ambient::temperature) return "ambient temperature";
  std::ostringstream o;
  if (default_value) o << *default_value;
  return o.str();
}

bool ParameterSpec::in_range(double v) const {
  if (!std::isfinite(v)) return false;
  const Bounds b = bounds_of(*this);
  if (b.lo_open ? !(v > b.lo) : !(v >= b.lo)) return false;
  if (b.hi_open ? !(v < b.hi) : !(v <= b.hi)) return false;
  return true;
}

int ComponentInfo::port_index(const std::string& n) const {
  for (std::size_t i = 0; i < ports.size(); ++i)
    if (ports[i].name == n) return static_cast<int>(i);
  return -1;
}

const ParameterSpec* ComponentInfo::parameter(const std::string& n) const {
  for (const auto& p : parameters)
    if (p.name == n) return &p;
  return nullptr;
}

bool EventSpec::matches(const std::string& t) const {
  const bool numbered = tag.size() > 2 && tag.compare(tag.size() - 2, 2, "_K") == 0;
  if (!numbered) return t == tag;
  const std::size_t stem = tag.size() - 1;  // "step_"
  return t.size() > stem && t.compare(0, stem, tag, 0, stem) == 0 &&
         std::all_of(t.begin() + static_cast<std::ptrdiff_t>(stem), t.end(), [](char c) { return c >= '0' && c <= '9'; });
}

bool ComponentInfo::raises(const std::string& t) const {
  return std::any_of(events.begin(), events.end(), [&](const EventSpec& e) { return e.matches(t); });
}

std::string ComponentInfo::event_list() const {
  std::string s;
  for (const auto& e : events) s += (s.empty() ? "" : ", ") + e.tag;
  return s.empty() ? "none" : s;
}

namespace {
bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }
bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](double x, double y) { return same_bits(x, y); });
}
bool same_bits(const Table& a, const Table& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](const auto& x, const auto& y) { return same_bits(x, y); });
}
template <class V>
bool same_bits(const std::map<std::string, V>& a, const std::map<std::string, V>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](const auto& x, const auto& y) { return x.first == y.first && same_bits(x.second, y.second); });
}
}  // namespace

bool ParameterValues::same_bits(const ParameterValues& other) const {
  return pneumo::same_bits(scalars_, other.scalars_) && pneumo::same_bits(tables_, other.tables_) &&
         texts_ == other.texts_;
}

double ParameterValues::scalar(const std::string& name) const {
  auto it = scalars_.find(name);
  if (it == scalars_.end()) throw ParameterError(name, "scalar parameter '" + name + "' has no value");
  return it->second;
}
const Table& ParameterValues::table(const std::string& name) const {
  auto it = tables_.find(name);
  if (it == tables_.end()) throw ParameterError(name, "table parameter '" + name + "' has no value");
  return it->second;
}
const std::string& ParameterValues::text(const std::string& name) const {
  auto it = texts_.find(name);
  if (it == texts_.end()) throw ParameterError(name, "text parameter '" + name + "' has no value");
  return it->second;
}
bool ParameterValues::has(const std::string& name) const {
  return scalars_.count(name) || tables_.count(name) || texts_.count(name);
}

void require_increasing(const Table& table, const std::string& parameter, const std::string& what) {
  for (std::size_t k = 1; k < table.size(); ++k)
    if (!(table[k][0] > table[k - 1][0]))
      throw ParameterError(parameter, what + " must increase (row " + std::to_string(k + 1) + ")");
}

void StartValues::fix_var(int k, double v) { set(c_.internal_offset() + k, v, Kind::fixed); }
void StartValues::guess_var(int k, double v) { set(c_.internal_offset() + k, v, Kind::guess); }
void StartValues::guess_pressure(int port, double p) { set(c_.port_offset(port), p, Kind::guess); }
void StartValues::guess_temperature(int port, double T) {
  const int o = c_.port_offset(port);
  if (c_.info().ports[port].domain == Domain::pneumatic) {
    set(o + 2, T, Kind::guess);
  } else {
    set(o, T, Kind::guess);
  }
}
void StartValues::fix_position(int port, double s) { set(c_.port_offset(port), s, Kind::fixed); }
void StartValues::guess_position(int port, double s) { set(c_.port_offset(port), s, Kind::guess); }
void StartValues::fix_velocity(int port, double v) { set(c_.port_offset(port) + 2, v, Kind::fixed); }

Component::Component(const Construction& c) : name_(c.name), info_(c.info) {
  int offset = 0;
  for (const auto& p : info_->ports) {
    port_offset_.push_back(offset);
    offset += port_width(p.domain);
    n_equations_ += port_equations(p.domain, p.causality);
  }
  internal_offset_ = offset;
  n_local_ = offset + static_cast<int>(info_->variables.size());
  n_equations_ += static_cast<int>(info_->variables.size());
}

}  // namespace pneumo
