#include "framework/model/start_conflicts.hpp"

#include <cmath>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

namespace pneumo {

namespace {

// The fixed start values of one component's local variables (NaN: not fixed).
std::vector<double> fixed_starts(const Component& c, const GasModel& gas) {
  std::vector<double> values(c.n_local(), 0.0);
  std::vector<StartValues::Kind> kinds(c.n_local(), StartValues::Kind::none);
  StartValues sv(c, values.data(), kinds.data());
  c.start(sv, gas);
  for (int i = 0; i < c.n_local(); ++i)
    if (kinds[i] != StartValues::Kind::fixed) values[i] = std::nan("");
  return values;
}

std::string text(double v, const char* unit) {
  std::ostringstream s;
  s << v << " " << unit;
  return s.str();
}

}  // namespace

void check_start_conflicts(const Circuit& circuit) {
  // Translational ports by node: ports of connections sharing a port are one node.
  std::map<std::pair<int, int>, int> id;
  std::vector<PortId> ports;
  std::vector<int> parent, via;  // union-find; via: a connection of the node
  auto index = [&](PortId p) {
    auto [it, fresh] = id.try_emplace({p.component, p.port}, static_cast<int>(ports.size()));
    if (fresh) ports.push_back(p), parent.push_back(it->second), via.push_back(-1);
    return it->second;
  };
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (int k = 0; k < static_cast<int>(circuit.connections.size()); ++k) {
    const auto& conn = circuit.connections[k].ports;
    if (conn.empty()) continue;
    const auto& first = conn.front();
    if (circuit.components[first.component]->info().ports[first.port].domain != Domain::translational) continue;
    const int a = root(index(first));
    via[a] = k;
    for (const PortId& p : conn) {
      const int b = root(index(p));
      if (b != a) parent[b] = a;
    }
  }
  std::map<int, std::vector<double>> starts;  // by component
  auto fixed = [&](int c) -> const std::vector<double>& {
    auto it = starts.find(c);
    if (it == starts.end()) it = starts.emplace(c, fixed_starts(*circuit.components[c], circuit.gas)).first;
    return it->second;
  };
  // The first fixed value of each node's position (offset 0) and velocity (2).
  struct Seen {
    PortId by;
    double value;
  };
  std::map<std::pair<int, int>, Seen> seen;
  for (int i = 0; i < static_cast<int>(ports.size()); ++i) {
    const PortId p = ports[i];
    const Component& c = *circuit.components[p.component];
    if (c.info().ports[p.port].domain != Domain::translational) continue;  // a mismatch assembly reports
    for (const int offset : {0, 2}) {
      const double v = fixed(p.component)[c.port_offset(p.port) + offset];
      if (std::isnan(v)) continue;
      const int node = root(i);
      const auto [it, fresh] = seen.try_emplace({node, offset}, Seen{p, v});
      if (fresh || std::abs(it->second.value - v) <= 1e-6) continue;
      const char* unit = offset == 0 ? "m" : "m/s";
      const std::string what = offset == 0 ? "position" : "velocity";
      int k = via[node];
      for (int j = 0; j < static_cast<int>(ports.size()) && k < 0; ++j)
        if (root(j) == node) k = via[j];
      throw InputError(circuit.connections[k].where, c.name(), "",
                       "'" + circuit.port_name(it->second.by) + "' starts at " + what + " " +
                           text(it->second.value, unit) + " but '" + circuit.port_name(p) + "', joined to it, at " +
                           text(v, unit) + ": a joint cannot be in two places. Give them the same start " + what +
                           " (the components' start position parameters, e.g. x0 or s0)");
    }
  }
}

}  // namespace pneumo
