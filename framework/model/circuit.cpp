#include "framework/model/circuit.hpp"

namespace pneumo {

namespace {
struct Named {
  const char* name;
  const char* unit;
};
// Variable names and units per domain, in the local layout order.
const std::vector<Named>& domain_variables(Domain d) {
  static const std::vector<Named> pneumatic{{"p", "Pa"}, {"m_flow", "kg/s"}, {"T_out", "K"}, {"T_in", "K"}};
  static const std::vector<Named> thermal{{"T", "K"}, {"Q", "W"}};
  static const std::vector<Named> translational{{"s", "m"}, {"f", "N"}, {"v", "m/s"}};
  static const std::vector<Named> signal{{"value", "1"}};
  switch (d) {
    case Domain::pneumatic: return pneumatic;
    case Domain::thermal: return thermal;
    case Domain::translational: return translational;
    case Domain::signal: return signal;
  }
  return signal;
}
}  // namespace

bool is_entering_stream_temperature(const std::string& local_variable) {
  const std::string tail = ".T_in";
  return local_variable.size() > tail.size() &&
         local_variable.compare(local_variable.size() - tail.size(), tail.size(), tail) == 0;
}

std::vector<std::string> local_variable_names(const Component& c) {
  std::vector<std::string> out;
  for (const auto& p : c.info().ports)
    for (const auto& v : domain_variables(p.domain)) out.push_back(p.name + "." + v.name);
  for (const auto& v : c.info().variables) out.push_back(v.name);
  return out;
}

std::vector<std::string> local_variable_units(const Component& c) {
  std::vector<std::string> out;
  for (const auto& p : c.info().ports)
    for (const auto& v : domain_variables(p.domain)) out.push_back(v.unit);
  for (const auto& v : c.info().variables) out.push_back(v.unit);
  return out;
}

Probe find_probe(const Circuit& circuit, int component, const std::string& quantity) {
  const Component& comp = *circuit.components[component];
  Probe probe;
  probe.component = component;
  const auto& obs = comp.info().observables;
  for (std::size_t i = 0; i < obs.size(); ++i)
    if (obs[i].name == quantity) {
      probe.kind = Probe::Kind::observable;
      probe.index = static_cast<int>(i);
      probe.unit = obs[i].unit;
    }
  if (probe.index < 0) {
    const auto names = local_variable_names(comp);
    const auto units = local_variable_units(comp);
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == quantity) probe.index = static_cast<int>(i), probe.unit = units[i];
  }
  // A signal port by its name alone (source.y for the value of port y).
  if (probe.index < 0) {
    const int port = comp.info().port_index(quantity);
    if (port >= 0 && comp.info().ports[port].domain == Domain::signal) {
      probe.index = comp.port_offset(port);
      probe.unit = local_variable_units(comp)[probe.index];
    }
  }
  return probe;
}

}  // namespace pneumo
