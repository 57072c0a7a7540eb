#include "framework/model/signal_loops.hpp"

#include <algorithm>
#include <string>
#include <vector>

namespace pneumo {

bool is_memoryless_signal_block(const ComponentInfo& info) {
  if (info.ports.empty() || !info.variables.empty() || info.modes > 0 || info.roots > 0 || info.follows_inputs)
    return false;
  return std::all_of(info.ports.begin(), info.ports.end(), [](const PortSpec& p) { return p.domain == Domain::signal; });
}

namespace {

struct Edge {
  int to;
  int connection;
};

// Depth-first search for a cycle; when found, `path` holds its components
// in order and `closing_connection` the connection back to the first.
class LoopFinder {
 public:
  explicit LoopFinder(std::vector<std::vector<Edge>> edges)
      : edges_(std::move(edges)), state_(edges_.size(), 0) {}

  bool find() {
    for (int c = 0; c < static_cast<int>(edges_.size()); ++c)
      if (state_[c] == 0 && visit(c)) return true;
    return false;
  }
  std::vector<int> path;
  int closing_connection = -1;

 private:
  bool visit(int c) {
    state_[c] = 1;
    path.push_back(c);
    for (const Edge& e : edges_[c]) {
      if (state_[e.to] == 1) {
        closing_connection = e.connection;
        path.erase(path.begin(), std::find(path.begin(), path.end(), e.to));
        return true;
      }
      if (state_[e.to] == 0 && visit(e.to)) return true;
    }
    state_[c] = 2;
    path.pop_back();
    return false;
  }
  std::vector<std::vector<Edge>> edges_;
  std::vector<char> state_;  // 0 unvisited, 1 on the path, 2 done
};

}  // namespace

void check_signal_loops(const Circuit& circuit) {
  const int n = static_cast<int>(circuit.components.size());
  std::vector<bool> block(n);
  for (int c = 0; c < n; ++c) block[c] = is_memoryless_signal_block(circuit.components[c]->info());
  std::vector<std::vector<Edge>> edges(n);
  for (int k = 0; k < static_cast<int>(circuit.connections.size()); ++k) {
    const auto& ports = circuit.connections[k].ports;
    auto causality = [&](PortId id) { return circuit.components[id.component]->info().ports[id.port].causality; };
    for (const PortId& out : ports)
      if (block[out.component] && causality(out) == Causality::output)
        for (const PortId& in : ports)
          if (block[in.component] && causality(in) == Causality::input) edges[out.component].push_back({in.component, k});
  }
  LoopFinder f(std::move(edges));
  if (!f.find()) return;
  std::string names;
  for (int c : f.path) names += (names.empty() ? "'" : " -> '") + circuit.components[c]->name() + "'";
  names += " -> '" + circuit.components[f.path.front()]->name() + "'";
  const int first = f.path.front();
  throw InputError(circuit.connections[f.closing_connection].where, circuit.components[first]->name(), "",
                   "the memoryless signal blocks (logic gates) " + names +
                       " feed their own inputs at the same instant (an algebraic loop): it has no 0/1 solution (a "
                       "NOT fed by its own output would sit at 0.5). Break the loop with a component that has "
                       "memory (a flip-flop) or a delay (a timer, also for an oscillator)");
}

}  // namespace pneumo
