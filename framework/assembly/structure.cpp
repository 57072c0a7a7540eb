// The structure: the circuit's ports joined into nodes, one unknown per
// across and through variable, the component blocks and the node blocks
// (balances, stream routing, kinematics, input defaults), and the sparsity
// pattern found by evaluating every block with the Pattern scalar. A
// structural check (maximum matching of equations to variables, with
// differential variables matched through y' and algebraic ones through y)
// rejects structurally singular and higher-index systems before solving,
// naming the components and ports involved.
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <set>

#include "framework/assembly/blocks.hpp"
#include "framework/assembly/system.hpp"

namespace pneumo {

namespace {

const PortSpec& spec(const Circuit& c, const PortId& p) { return c.components[p.component]->info().ports[p.port]; }

}  // namespace

struct PortVars {
  int across = -1;
  int flow = -1;
  int t_out = -1;
};

namespace {

// How route_streams groups the n ports of a node for stream mixing: one
// group of all up to 32 ports (their mix reads 2 n - 1 locals, within
// kMaxLocal); beyond, ceil(sqrt(n)) groups of consecutive ports whose sizes
// differ by at most one (a mix reads 2 g + 2 c - 3 locals: its own group's
// other ports and the other groups' sums).
constexpr int kMixOneByOne = (kMaxLocal + 1) / 2;
constexpr int stream_groups(int n) {
  int c = 1;
  while (n > kMixOneByOne && c * c < n) ++c;
  return c;
}
constexpr int mix_locals(int n) {
  const int c = stream_groups(n), g = (n + c - 1) / c;
  return c == 1 ? 2 * n - 1 : 2 * g + 2 * c - 3;
}
// The largest node whose mixes fit (272 ports for kMaxLocal = 64).
constexpr int max_mixed_ports() {
  int n = 3;
  while (mix_locals(n + 1) <= kMaxLocal) ++n;
  return n;
}

struct StreamGroups {
  static constexpr int kMaxPorts = max_mixed_ports();

  explicit StreamGroups(int ports) : n(ports), count(stream_groups(ports)) {}
  int first(int g) const { return static_cast<int>(static_cast<long>(g) * n / count); }
  int of(int port) const {
    int g = 0;
    while (first(g + 1) <= port) ++g;
    return g;
  }
  const int n, count;
};

}  // namespace

// Ports joined into nodes by the netlist's connections, and the unknowns
// made for them; `row` counts the rows made so far.
struct NodeLayout {
  std::vector<std::vector<PortId>> nodes;
  std::vector<SourceLocation> where;
  std::map<std::pair<int, int>, int> node_of;  // (component, port) -> node
  std::vector<int> across, velocity;           // per node
  std::map<std::pair<int, int>, PortVars> port_vars;
  int row = 0;
  int node(const PortId& p) const { return node_of.at({p.component, p.port}); }
  const PortVars& vars(const PortId& p) const { return port_vars.at({p.component, p.port}); }
};

namespace {

// Union-find of the connections' ports into nodes.
void join_connections(const Circuit& c, NodeLayout& l) {
  for (const auto& conn : c.connections) {
    std::set<int> existing;
    for (const auto& p : conn.ports) {
      auto it = l.node_of.find({p.component, p.port});
      if (it != l.node_of.end()) existing.insert(it->second);
    }
    int target;
    if (existing.empty()) {
      target = static_cast<int>(l.nodes.size());
      l.nodes.emplace_back();
      l.where.push_back(conn.where);
    } else {
      target = *existing.begin();
      for (int other : existing) {
        if (other == target) continue;
        for (const auto& p : l.nodes[other]) {
          l.nodes[target].push_back(p);
          l.node_of[{p.component, p.port}] = target;
        }
        l.nodes[other].clear();
      }
    }
    for (const auto& p : conn.ports) {
      if (!l.node_of.count({p.component, p.port})) {
        l.nodes[target].push_back(p);
        l.node_of[{p.component, p.port}] = target;
      }
    }
  }
}

// Unconnected ports: optional ones get a node of their own, others are errors.
void add_lone_ports(const Circuit& c, NodeLayout& l) {
  for (std::size_t ci = 0; ci < c.components.size(); ++ci) {
    const auto& info = c.components[ci]->info();
    for (std::size_t pi = 0; pi < info.ports.size(); ++pi) {
      if (l.node_of.count({static_cast<int>(ci), static_cast<int>(pi)})) continue;
      const auto& ps = info.ports[pi];
      if (!ps.optional) {
        throw InputError(c.component_where[ci], c.components[ci]->name(), "",
                         "port '" + ps.name + "' (" + domain_name(ps.domain) +
                             ") is not connected; connect it under 'connections:' (dangling port)");
      }
      l.node_of[{static_cast<int>(ci), static_cast<int>(pi)}] = static_cast<int>(l.nodes.size());
      l.nodes.push_back({PortId{static_cast<int>(ci), static_cast<int>(pi)}});
      l.where.push_back(c.component_where[ci]);
    }
  }
}

// Domain and causality checks.
void check_nodes(const Circuit& c, const NodeLayout& l) {
  for (std::size_t ni = 0; ni < l.nodes.size(); ++ni) {
    const auto& ports = l.nodes[ni];
    if (ports.empty()) continue;
    const auto& first = spec(c, ports[0]);
    int outputs = 0;
    for (const auto& p : ports) {
      const auto& ps = spec(c, p);
      if (ps.domain != first.domain)
        throw InputError(l.where[ni], c.components[p.component]->name(), "",
                         "cannot connect " + c.port_name(ports[0]) + " (" + domain_name(first.domain) + ") with " +
                             c.port_name(p) + " (" + domain_name(ps.domain) + ")");
      if (ps.causality == Causality::output) ++outputs;
    }
    if (first.domain == Domain::signal) {
      if (outputs > 1)
        throw InputError(l.where[ni], "", "", "signal node " + node_text(c, ports) + " has " +
                                                  std::to_string(outputs) + " outputs driving it; only one may");
      if (outputs == 0 && ports.size() > 1)
        throw InputError(l.where[ni], "", "", "signal node " + node_text(c, ports) +
                                                  " connects only inputs; nothing drives it");
    }
  }
}

}  // namespace

void System::build_nodes() {
  const Circuit& c = circuit_;
  NodeLayout l;
  join_connections(c, l);
  add_lone_ports(c, l);
  check_nodes(c, l);
  for (const auto& ports : l.nodes)
    if (!ports.empty()) nodes_.push_back(ports);
  add_node_variables(l);
  int mode = 0, root = 0;
  for (std::size_t ci = 0; ci < c.components.size(); ++ci) add_component_block(static_cast<int>(ci), l, mode, root);
  guess_junction_pressures(l);
  modes_.assign(mode, 0.0);
  for (const auto& b : blocks_)
    if (b->component) b->component->initial_modes(modes_.data() + b->mode0);
  n_roots_ = root;
  route_streams(l);
  add_node_balances(l);
  if (l.row != n_)
    throw StructureError("internal error: " + std::to_string(l.row) + " equations for " + std::to_string(n_) +
                         " variables");
  for (const auto& b : blocks_)
    for (int v : b->vars)
      if (v < 0) throw StructureError("internal error: unmapped local variable in " + b->label);
}

int System::new_var(std::string name, double start, unsigned char kind, double nominal) {
  var_names_.push_back(std::move(name));
  start_value_.push_back(start);
  start_kind_.push_back(kind);
  junction_.push_back(0);
  nominal_.push_back(nominal);
  return n_++;
}

// Node across variables come first.
void System::add_node_variables(NodeLayout& l) {
  const Circuit& c = circuit_;
  l.across.assign(l.nodes.size(), -1);
  l.velocity.assign(l.nodes.size(), -1);
  for (std::size_t ni = 0; ni < l.nodes.size(); ++ni) {
    if (l.nodes[ni].empty()) continue;
    const auto& ps = spec(c, l.nodes[ni][0]);
    const std::string where = l.nodes[ni].size() == 1 ? c.port_name(l.nodes[ni][0]) : node_text(c, l.nodes[ni]);
    switch (ps.domain) {
      case Domain::pneumatic: l.across[ni] = new_var("p at " + where, c.gas.p_ambient, 0, 1e5); break;
      case Domain::thermal: l.across[ni] = new_var("T at " + where, c.gas.T_ambient, 0, 300.0); break;
      case Domain::translational:
        // Typical magnitudes of a pneumatic drive: 1 cm, 0.1 m/s (the hand-
        // written reference in tests/reference scales its absolute
        // tolerances so). 1 mm and 1 cm/s held a piston at rest to 1e-9 m
        // and 1e-8 m/s, which cost 20 % more steps for no gain in accuracy.
        l.across[ni] = new_var("s at " + where, 0.0, 0, 1e-2);
        l.velocity[ni] = new_var("v at " + where, 0.0, 0, 1e-1);
        break;
      case Domain::signal: l.across[ni] = new_var("value at " + where, ps.default_value, 0, 1.0); break;
    }
  }
}

// A component's block: its ports' variables (the node's across variable,
// a through variable and outflow temperature of its own), its internal
// variables, its rows, modes and roots.
void System::add_component_block(int ci, NodeLayout& l, int& mode, int& root) {
  const Circuit& c = circuit_;
  const Component& comp = *c.components[ci];
  const auto& info = comp.info();
  if (comp.n_local() > kMaxLocal)
    throw StructureError("component '" + comp.name() + "' (" + info.type + ") has " + std::to_string(comp.n_local()) +
                         " local variables; the limit is " + std::to_string(kMaxLocal));
  auto b = make_component_block();
  b->component = &comp;
  b->component_index = ci;
  b->label = comp.name() + " (" + info.type + ")";
  b->where = c.component_where[ci];
  b->vars.assign(comp.n_local(), -1);
  b->connected.reset(new bool[info.ports.size() + 1]);
  for (std::size_t pi = 0; pi < info.ports.size(); ++pi) {
    const auto& ps = info.ports[pi];
    const int node = l.node({ci, static_cast<int>(pi)});
    b->connected[pi] = l.nodes[node].size() > 1;
    const int o = comp.port_offset(static_cast<int>(pi));
    const std::string pn = comp.name() + "." + ps.name;
    PortVars pv;
    pv.across = l.across[node];
    b->vars[o] = pv.across;
    switch (ps.domain) {
      case Domain::pneumatic:
        pv.flow = b->vars[o + 1] = new_var(pn + ".m_flow", 0.0, 0, 1e-4);
        pv.t_out = b->vars[o + 2] = new_var(pn + ".T_out", c.gas.T_ambient, 0, 300.0);
        break;
      case Domain::thermal: pv.flow = b->vars[o + 1] = new_var(pn + ".Q", 0.0, 0, 1e-3); break;
      case Domain::translational:
        pv.flow = b->vars[o + 1] = new_var(pn + ".f", 0.0, 0, 1.0);
        b->vars[o + 2] = l.velocity[node];
        break;
      case Domain::signal: break;
    }
    l.port_vars[{ci, static_cast<int>(pi)}] = pv;
  }
  add_internal_variables(comp, *b);
  b->row0 = l.row;
  b->n_rows = comp.n_equations();
  for (int k = 0; k < b->n_rows; ++k)
    b->row_names.push_back(comp.name() + ": " +
                           (k < static_cast<int>(info.equations.size()) ? info.equations[k]
                                                                        : "equation " + std::to_string(k + 1)));
  l.row += b->n_rows;
  b->mode0 = mode;
  mode += info.modes;
  b->root0 = root;
  root += info.roots;
  if (info.roots > 0) root_blocks_.push_back(static_cast<int>(blocks_.size()));
  blocks_.push_back(std::move(b));
}

// The component's internal variables with its start values; its start
// values of port variables are merged into the node's.
void System::add_internal_variables(const Component& comp, Block& b) {
  const auto& info = comp.info();
  std::vector<double> local_start(comp.n_local(), 0.0);
  std::vector<StartValues::Kind> local_kind(comp.n_local(), StartValues::Kind::none);
  StartValues sv(comp, local_start.data(), local_kind.data());
  comp.start(sv, circuit_.gas);
  for (std::size_t k = 0; k < info.variables.size(); ++k) {
    const int local = comp.internal_offset() + static_cast<int>(k);
    const auto& vs = info.variables[k];
    const double start = local_start[local];
    const double nominal = vs.nominal > 0 ? vs.nominal : std::max(std::abs(start), nominal_floor(vs.unit));
    b.vars[local] = new_var(comp.name() + "." + vs.name, start, static_cast<unsigned char>(local_kind[local]), nominal);
  }
  for (int local = 0; local < comp.internal_offset(); ++local) {
    const int g = b.vars[local];
    if (g < 0 || local_kind[local] == StartValues::Kind::none) continue;
    const auto kind = static_cast<unsigned char>(local_kind[local]);
    if (kind > start_kind_[g]) {  // fixed beats guess beats none
      start_value_[g] = local_start[local];
      start_kind_[g] = kind;
      nominal_[g] = std::max(nominal_[g], std::abs(local_start[local]));
    }
  }
}

// A junction without a volume (no component gives its pressure a start
// value) starts at the mean of the start pressures at the far ends of the
// two-port elements it joins (throttles, flow controls, check valves),
// passed on along chains of such junctions; ambient where it joins none.
// Started at ambient, a junction between a supply and a charged chamber
// chokes every path into it, so no equation depends on its pressure and the
// Newton matrix of the consistent-start search is singular; between its
// neighbours the paths are subsonic and the flow balance decides. (Across a
// valve of more ports the far end is not known before its position is.)
void System::guess_junction_pressures(const NodeLayout& l) {
  const Circuit& c = circuit_;
  std::vector<char> known(n_, 0);
  for (int v = 0; v < n_; ++v) known[v] = start_kind_[v] != 0;
  for (std::size_t ni = 0; ni < l.nodes.size(); ++ni) {
    const int p = l.across[ni];
    if (p < 0 || l.nodes[ni].empty() || spec(c, l.nodes[ni][0]).domain != Domain::pneumatic) continue;
    if (known[p]) pressure_levels_.push_back(start_value_[p]);
    else junction_[p] = 1;  // 2 once guessed from its neighbours
  }
  std::sort(pressure_levels_.begin(), pressure_levels_.end());
  pressure_levels_.erase(std::unique(pressure_levels_.begin(), pressure_levels_.end(),
                                     [](double a, double b) { return std::abs(a - b) <= 1e-6 * std::abs(b); }),
                         pressure_levels_.end());
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t ni = 0; ni < l.nodes.size(); ++ni) {
      const int p = l.across[ni];
      if (p < 0 || known[p] || l.nodes[ni].empty() || spec(c, l.nodes[ni][0]).domain != Domain::pneumatic) continue;
      double sum = 0.0;
      int count = 0;
      for (const auto& port : l.nodes[ni]) {
        const auto& ports = c.components[port.component]->info().ports;
        const auto pneumatic = std::count_if(ports.begin(), ports.end(),
                                             [](const PortSpec& q) { return q.domain == Domain::pneumatic; });
        if (pneumatic != 2) continue;
        for (std::size_t q = 0; q < ports.size(); ++q) {
          if (ports[q].domain != Domain::pneumatic || static_cast<int>(q) == port.port) continue;
          const int other = l.across[l.node({port.component, static_cast<int>(q)})];
          if (other != p && known[other]) sum += start_value_[other], ++count;
        }
      }
      if (count == 0) continue;
      start_value_[p] = sum / count;
      known[p] = 1;
      junction_[p] = 2;
      changed = true;
    }
  }
}

// A framework block at a node: a row for each of `row_names` (one named
// after the label when none is given).
void System::add_node_block(std::unique_ptr<Block> b, std::string label, std::vector<std::string> row_names,
                            NodeLayout& l, int node) {
  // The evaluator's scratch and the Pattern scalar hold kMaxLocal locals a
  // block: a stream mix reads 2 g + 2 c - 3 at a node of c groups of at
  // most g ports (StreamGroups).
  if (b->vars.size() > static_cast<std::size_t>(kMaxLocal))
    throw InputError(l.where[node], "", "",
                     "this connection joins " + std::to_string(l.nodes[node].size()) + " ports; its " + label +
                         " reads " + std::to_string(b->vars.size()) + " variables, more than the limit of " +
                         std::to_string(kMaxLocal) + " (at most " + std::to_string(StreamGroups::kMaxPorts) +
                         " pneumatic ports a node): split it into several nodes joined by volumes");
  b->label = std::move(label);
  b->where = l.where[node];
  if (row_names.empty()) row_names.push_back(b->label);
  b->row0 = l.row;
  b->n_rows = static_cast<int>(row_names.size());
  l.row += b->n_rows;
  b->row_names = std::move(row_names);
  blocks_.push_back(std::move(b));
}

// Stream routing: T_in of each pneumatic port. A port alone sees its own
// T_out, two ports each the other's; at three or more ports T_in is the mix
// (StreamMixBlock): of the other ports one by one up to 32 ports (2 n - 1
// locals, within kMaxLocal); at more, of the other ports of its own group
// one by one and of the other groups' sums (StreamSumBlock), which keeps a
// mix's locals and work near 4 sqrt(n) instead of 2 n.
void System::route_streams(NodeLayout& l) {
  const Circuit& c = circuit_;
  auto t_in_slot = [&](const PortId& p) -> int& {
    return blocks_[p.component]->vars[c.components[p.component]->port_offset(p.port) + 3];
  };
  for (std::size_t ni = 0; ni < l.nodes.size(); ++ni) {
    const auto& ports = l.nodes[ni];
    if (ports.empty() || spec(c, ports[0]).domain != Domain::pneumatic) continue;
    if (ports.size() == 1) {
      t_in_slot(ports[0]) = l.vars(ports[0]).t_out;  // closed port
    } else if (ports.size() == 2) {
      t_in_slot(ports[0]) = l.vars(ports[1]).t_out;
      t_in_slot(ports[1]) = l.vars(ports[0]).t_out;
    } else {
      const StreamGroups groups(static_cast<int>(ports.size()));
      const std::string at = node_text(c, ports);
      // Each group's sums W, H (when there are several groups).
      std::vector<std::pair<int, int>> sums;
      for (int g = 0; g < groups.count && groups.count > 1; ++g) {
        auto sum = make_stream_sum_block();
        const std::string name = "stream group " + std::to_string(g + 1) + " at " + at;
        // Start values as at zero flow: each weight eps / 2, at the ambient temperature.
        const double w0 = 0.5 * c.gas.m_flow_small * (groups.first(g + 1) - groups.first(g));
        sums.emplace_back(new_var(name + ".W", w0, 0, 1e-4), new_var(name + ".H", w0 * c.gas.T_ambient, 0, 3e-2));
        sum->vars = {sums.back().first};
        for (int j = groups.first(g); j < groups.first(g + 1); ++j) {
          sum->vars.push_back(l.vars(ports[j]).flow);
          sum->vars.push_back(l.vars(ports[j]).t_out);
        }
        sum->vars.push_back(sums.back().second);
        add_node_block(std::move(sum), "stream group sums at " + at,
                       {"sum of weights of " + name, "sum of weighted T_out of " + name}, l, static_cast<int>(ni));
      }
      for (std::size_t i = 0; i < ports.size(); ++i) {
        const int own = groups.of(static_cast<int>(i));
        const int t_in = new_var(c.port_name(ports[i]) + ".T_in", c.gas.T_ambient, 0, 300.0);
        t_in_slot(ports[i]) = t_in;
        std::vector<int> vars{t_in};
        for (int j = groups.first(own); j < groups.first(own + 1); ++j) {
          if (j == static_cast<int>(i)) continue;
          vars.push_back(l.vars(ports[j]).flow);
          vars.push_back(l.vars(ports[j]).t_out);
        }
        auto mix = make_stream_mix_block(static_cast<int>(vars.size() / 2));
        for (int g = 0; g < static_cast<int>(sums.size()); ++g)
          if (g != own) vars.insert(vars.end(), {sums[g].first, sums[g].second});
        mix->vars = std::move(vars);
        add_node_block(std::move(mix), "stream mixing at " + at, {"inStream(T) of " + c.port_name(ports[i]) + " at " + at},
                       l, static_cast<int>(ni));
      }
    }
  }
}

// Node balances (with ds/dt = v at translational nodes), and the defaults
// of signal inputs that nothing drives.
void System::add_node_balances(NodeLayout& l) {
  const Circuit& c = circuit_;
  for (std::size_t ni = 0; ni < l.nodes.size(); ++ni) {
    const auto& ports = l.nodes[ni];
    if (ports.empty()) continue;
    const int node = static_cast<int>(ni);
    const auto& ps = spec(c, ports[0]);
    if (ps.domain == Domain::signal) {
      const bool driven = std::any_of(ports.begin(), ports.end(),
                                      [&](const PortId& p) { return spec(c, p).causality == Causality::output; });
      if (driven) continue;
      auto def = make_fixed_value_block(ps.default_value);
      def->vars = {l.across[ni]};
      add_node_block(std::move(def), "default of unconnected input " + c.port_name(ports[0]), {}, l, node);
      continue;
    }
    if (ps.domain == Domain::translational) {
      auto kin = make_kinematic_block();
      kin->vars = {l.across[ni], l.velocity[ni]};
      add_node_block(std::move(kin), "kinematics ds/dt = v at " + node_text(c, ports), {}, l, node);
    }
    const char* what = ps.domain == Domain::pneumatic ? "mass" : ps.domain == Domain::thermal ? "heat" : "force";
    const std::string at = node_text(c, ports);
    if (ps.domain == Domain::thermal && ports.size() == 1 &&
        c.components[ports[0].component]->unconnected_heat_port_at_ambient(ports[0].port)) {
      auto wall = make_fixed_value_block(c.gas.T_ambient);
      wall->vars = {l.across[ni]};
      add_node_block(std::move(wall), "ambient temperature at the unconnected " + at, {}, l, node);
      continue;
    }
    if (rest_heat_ports_ && ps.domain == Domain::thermal && ports.size() == 1) {
      auto rest = make_rest_heat_block(c.gas.T_ambient);
      rest->vars = {l.vars(ports[0]).flow, l.across[ni]};
      add_node_block(std::move(rest), "heat from the ambient at rest into " + at, {}, l, node);
      continue;
    }
    std::vector<int> flows;
    for (const auto& p : ports) flows.push_back(l.vars(p).flow);
    // More flows than a block's locals: the balance adds the sums of groups
    // of them (unknowns of their own, each a group's sum).
    if (flows.size() > static_cast<std::size_t>(kMaxLocal)) {
      const StreamGroups groups(static_cast<int>(flows.size()));
      std::vector<int> totals;
      for (int g = 0; g < groups.count; ++g) {
        auto part = make_flow_sum_block(true);
        const std::string name = std::string(what) + " flow of group " + std::to_string(g + 1) + " at " + at;
        part->vars = {new_var(name, 0.0, 0, nominal_[flows[0]])};
        part->vars.insert(part->vars.end(), flows.begin() + groups.first(g), flows.begin() + groups.first(g + 1));
        totals.push_back(part->vars[0]);
        add_node_block(std::move(part), name, {}, l, node);
      }
      flows = totals;
    }
    auto sum = make_flow_sum_block();
    sum->vars = flows;
    add_node_block(std::move(sum), std::string(what) + " balance at " + at, {}, l, node);
  }
}

void System::build_pattern() {
  dep_y_.assign(n_, {});
  dep_yp_.assign(n_, {});
  std::vector<std::set<int>> sy(n_), syp(n_);
  std::mt19937 rng(12345);
  // Evaluate at the start point and at two perturbed points; the union of
  // the dependencies is the structural pattern.
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<double> y0, yp0;
    check_point(pass, rng, y0, yp0);
    bool invalid = false;
    EvalContext ctx{&circuit_.gas, modes_.data(), &invalid, rest_heat_};
    std::vector<Pattern> ly(kMaxLocal), lyp(kMaxLocal), r(kMaxLocal * 2);
    for (const auto& b : blocks_) {
      const int nl = static_cast<int>(b->vars.size());
      for (int i = 0; i < nl; ++i) {
        ly[i] = Pattern(y0[b->vars[i]]);
        ly[i].deps.set(i);
        lyp[i] = Pattern(yp0[b->vars[i]]);
        lyp[i].deps.set(kMaxLocal + i);
      }
      r.assign(std::max(1, b->n_rows), Pattern(0.0));
      b->residual(0.0, ly.data(), lyp.data(), r.data(), ctx);
      for (int k = 0; k < b->n_rows; ++k)
        for (int i = 0; i < nl; ++i) {
          if (r[k].deps.test(i)) sy[b->row0 + k].insert(b->vars[i]);
          if (r[k].deps.test(kMaxLocal + i)) syp[b->row0 + k].insert(b->vars[i]);
        }
    }
  }
  id_.assign(n_, 0.0);
  std::vector<std::set<int>> cols(n_);
  for (int row = 0; row < n_; ++row) {
    dep_y_[row].assign(sy[row].begin(), sy[row].end());
    dep_yp_[row].assign(syp[row].begin(), syp[row].end());
    for (int c : sy[row]) cols[c].insert(row);
    for (int c : syp[row]) {
      cols[c].insert(row);
      id_[c] = 1.0;
    }
  }
  const auto pos = compress_columns(cols, col_ptr_, row_idx_);
  for (auto& b : blocks_) {
    const int nl = static_cast<int>(b->vars.size());
    b->jac_pos.assign(static_cast<std::size_t>(b->n_rows) * nl, -1);
    for (int k = 0; k < b->n_rows; ++k)
      for (int i = 0; i < nl; ++i) {
        auto it = pos.find({b->row0 + k, b->vars[i]});
        if (it != pos.end()) b->jac_pos[static_cast<std::size_t>(k) * nl + i] = it->second;
      }
  }
}

namespace {

// The nodes reachable from `start` by alternating paths of a bipartite
// matching: from a node to its neighbours (`touched`), and on from each
// neighbour to the node it is matched with (`partner`, -1 if none).
void alternating_closure(const std::vector<int>& start, const std::vector<std::vector<int>>& next,
                         const std::vector<int>& partner, std::set<int>& reached, std::set<int>& touched) {
  std::vector<int> stack(start);
  while (!stack.empty()) {
    const int a = stack.back();
    stack.pop_back();
    if (!reached.insert(a).second) continue;
    for (int b : next[a]) {
      touched.insert(b);
      if (partner[b] >= 0) stack.push_back(partner[b]);
    }
  }
}

}  // namespace

void System::check_structure() const {
  // Candidate (equation, variable) pairs for an index-1 matching.
  std::vector<std::vector<int>> adj(n_);
  for (int r = 0; r < n_; ++r) {
    for (int c : dep_y_[r])
      if (id_[c] == 0.0) adj[r].push_back(c);
    for (int c : dep_yp_[r]) adj[r].push_back(c);
  }
  std::vector<int> match_col(n_, -1), match_row(n_, -1);
  std::vector<int> seen(n_, -1);
  std::function<bool(int, int)> augment = [&](int r, int stamp) -> bool {
    for (int c : adj[r]) {
      if (seen[c] == stamp) continue;
      seen[c] = stamp;
      if (match_col[c] < 0 || augment(match_col[c], stamp)) {
        match_col[c] = r;
        match_row[r] = c;
        return true;
      }
    }
    return false;
  };
  for (int r = 0; r < n_; ++r) augment(r, r);
  std::vector<int> free_rows, free_cols;
  for (int r = 0; r < n_; ++r)
    if (match_row[r] < 0) free_rows.push_back(r);
  for (int c = 0; c < n_; ++c)
    if (match_col[c] < 0) free_cols.push_back(c);
  if (free_rows.empty()) return;

  // Dulmage-Mendelsohn style diagnosis: equations reachable from unmatched
  // equations by alternating paths form the over-determined part; variables
  // reachable from unmatched variables the under-determined part.
  std::vector<std::vector<int>> col_rows(n_);
  for (int r = 0; r < n_; ++r)
    for (int c : adj[r]) col_rows[c].push_back(r);
  std::set<int> over_rows, over_cols, under_rows, under_cols;
  alternating_closure(free_rows, adj, match_col, over_rows, over_cols);
  alternating_closure(free_cols, col_rows, match_row, under_cols, under_rows);
  std::string msg = "the circuit's equations are structurally singular (or of index > 1): " +
                    std::to_string(free_rows.size()) + " equation(s) cannot be paired with an unknown.\n";
  msg += "  over-determined - these " + std::to_string(over_rows.size()) + " equations constrain only " +
         std::to_string(over_cols.size()) + " unknown(s):\n";
  for (int r : over_rows) msg += "    equation  " + equation_name(r) + "\n";
  for (int c : over_cols) msg += "    unknown   " + var_names_[c] + "\n";
  msg += "  under-determined - these unknowns are not fixed by any remaining equation:\n";
  for (int c : under_cols) msg += "    unknown   " + var_names_[c] + "\n";
  msg +=
      "  hint: two components that both set the pressure (or temperature, or position) of one node - e.g. two "
      "volumes or a source and a volume connected with nothing between them - need a flow component (throttle, "
      "hose, valve) between them.";
  throw StructureError(msg);
}

// Alias elimination. Connection equations (two-port flow balances, stream
// temperature routing) and component rows like T_out = T make about half the
// unknowns of a typical circuit copies of others: y_b = +-y_a. IDA's cost per
// step grows with the number of unknowns (vector operations, interpolation,
// root finding), so these are substituted once here instead of being solved
// at every Newton iteration. A row qualifies if it has no y' and depends on
// two unknowns with coefficients exactly +-1 and no offset (checked with AD at
// three points and times), or sets one unknown to a constant (a port alone at
// its node: flow = 0; an unconnected input: its default; a source's pressure
// and temperature - the same value at three times). Rows of components with
// discrete modes never qualify (an event could change them). Every
// eliminated row is still evaluated and must stay satisfied (residual()).
// The default (AssemblyOptions).
void System::check_point(int pass, std::mt19937& rng, std::vector<double>& y0, std::vector<double>& yp0) const {
  start_values(y0, yp0);
  if (pass == 0) return;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < n_; ++i) {
    y0[i] += 0.05 * nominal_[i] * u(rng) + 0.01 * y0[i] * u(rng);
    yp0[i] = 0.1 * nominal_[i] * u(rng);
  }
}

void System::start_values(std::vector<double>& y0, std::vector<double>& yp0) const {
  y0 = start_value_;
  yp0.assign(n_, 0.0);
}

System::Junctions System::junction_pressures() const {
  Junctions out;
  for (int i = 0; i < n_; ++i)
    if (junction_[i] && start_kind_[i] == 0) (junction_[i] == 2 ? out.guessed : out.unguessed).push_back(i);
  return out;
}

// Lower bound of a variable's typical magnitude, by unit.
double nominal_floor(const std::string& unit) {
  static const std::map<std::string, double> floors{
      {"Pa", 1e4}, {"K", 10.0},  {"kg", 1e-9}, {"J", 1e-4},  {"kg/s", 1e-6}, {"W", 1e-3},
      {"m", 1e-3}, {"m/s", 1e-3}, {"N", 1e-1}, {"m3", 1e-9}, {"1", 1e-3}};
  auto it = floors.find(unit);
  return it == floors.end() ? 1.0 : it->second;
}

std::string System::equation_name(int row) const {
  for (const auto& b : blocks_)
    if (row >= b->row0 && row < b->row0 + b->n_rows)
      return b->row_names[row - b->row0] + " [" + b->where.to_string() + "]";
  return "?";
}

std::string System::row_name(int ida_row) const {
  int row = ida_row;  // the full row behind IDA's row
  for (const auto& [r, q] : plan_.kept_full_rows)
    if (q == ida_row) row = r;
  for (const auto& b : blocks_)
    if (row >= b->row0 && row < b->row0 + b->n_rows)
      return row - b->row0 < static_cast<int>(b->row_names.size()) ? b->row_names[row - b->row0] : b->label;
  return "row " + std::to_string(row);
}

}  // namespace pneumo
