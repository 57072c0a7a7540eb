#include "framework/model/component.hpp"

#include <cmath>
#include <sstream>

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

std::string ParameterSpec::range_text() const {
  const bool lo = std::isfinite(min), hi = std::isfinite(max);
  if (!lo && !hi) return "any value";
  if (lo && !hi) return std::string(min_exclusive ? "> " : ">= ") + num(min);
  if (!lo && hi) return std::string(max_exclusive ? "< " : "<= ") + num(max);
  return std::string(min_exclusive ? "(" : "[") + num(min) + ", " + num(max) +
         (max_exclusive ? ")" : "]");
}

bool ParameterSpec::in_range(double v) const {
  if (!std::isfinite(v)) return false;
  if (min_exclusive ? !(v > min) : !(v >= min)) return false;
  if (max_exclusive ? !(v < max) : !(v <= max)) return false;
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
