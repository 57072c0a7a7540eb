#include "framework/assembly/system.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include "framework/core/smooth.hpp"

namespace pneumo {

namespace {

// ---------------------------------------------------------------------------
// Blocks.

class ComponentBlock final : public Block {
 public:
  template <class T>
  void eval(double t, const T* y, const T* yp, T* r, const EvalContext& c) const {
    Eval<T> e(*component, t, y, yp, c.modes + mode0, connected.get(), *c.gas, c.invalid);
    component->residual(e, r);
  }
  void residual(double t, const double* y, const double* yp, double* r, const EvalContext& c) const override {
    eval(t, y, yp, r, c);
  }
  void residual(double t, const Dual* y, const Dual* yp, Dual* r, const EvalContext& c) const override {
    eval(t, y, yp, r, c);
  }
  void residual(double t, const Pattern* y, const Pattern* yp, Pattern* r, const EvalContext& c) const override {
    eval(t, y, yp, r, c);
  }
};

// Through variables of a node sum to zero (Kirchhoff).
class FlowSumBlock final : public Block {
 public:
  template <class T>
  void eval(const T* y, T* r) const {
    T s = y[0];
    for (std::size_t i = 1; i < vars.size(); ++i) s = s + y[i];
    r[0] = s;
  }
  void residual(double, const double* y, const double*, double* r, const EvalContext&) const override { eval(y, r); }
  void residual(double, const Dual* y, const Dual*, Dual* r, const EvalContext&) const override { eval(y, r); }
  void residual(double, const Pattern* y, const Pattern*, Pattern* r, const EvalContext&) const override { eval(y, r); }
};

// inStream for a node of three or more pneumatic ports: the temperature of
// the gas arriving at port i is the mix of what the other ports deliver,
// weighted by their smoothed outflows into the node (Modelica's stream
// connector rule, regularised so that it stays defined at zero flow).
// vars: [T_in_i, (m_flow_j, T_out_j) for j != i]
class StreamMixBlock final : public Block {
 public:
  template <class T>
  void eval(const T* y, T* r, const EvalContext& c) const {
    const double eps = c.gas->m_flow_small;
    T w_sum = 0.0, wt_sum = 0.0;
    for (std::size_t j = 1; j + 1 < vars.size(); j += 2) {
      const T w = smooth_pos(T(-y[j]), eps);  // outflow of port j = flow into the node
      w_sum = w_sum + w;
      wt_sum = wt_sum + w * y[j + 1];
    }
    r[0] = y[0] - wt_sum / w_sum;
  }
  void residual(double, const double* y, const double*, double* r, const EvalContext& c) const override { eval(y, r, c); }
  void residual(double, const Dual* y, const Dual*, Dual* r, const EvalContext& c) const override { eval(y, r, c); }
  void residual(double, const Pattern* y, const Pattern*, Pattern* r, const EvalContext& c) const override { eval(y, r, c); }
};

// Kinematics of a translational node: ds/dt = v. vars: [s, v]
class KinematicBlock final : public Block {
 public:
  template <class T>
  void eval(const T* y, const T* yp, T* r) const { r[0] = yp[0] - y[1]; }
  void residual(double, const double* y, const double* yp, double* r, const EvalContext&) const override { eval(y, yp, r); }
  void residual(double, const Dual* y, const Dual* yp, Dual* r, const EvalContext&) const override { eval(y, yp, r); }
  void residual(double, const Pattern* y, const Pattern* yp, Pattern* r, const EvalContext&) const override { eval(y, yp, r); }
};

// An unconnected optional signal input holds its default value.
class SignalDefaultBlock final : public Block {
 public:
  double value = 0.0;
  template <class T>
  void eval(const T* y, T* r) const { r[0] = y[0] - value; }
  void residual(double, const double* y, const double*, double* r, const EvalContext&) const override { eval(y, r); }
  void residual(double, const Dual* y, const Dual*, Dual* r, const EvalContext&) const override { eval(y, r); }
  void residual(double, const Pattern* y, const Pattern*, Pattern* r, const EvalContext&) const override { eval(y, r); }
};


struct PortVars {
  int across = -1;
  int flow = -1;
  int t_out = -1;
};

// Copy a block's local variables (and their derivatives) out of the global
// vectors (the hot path: every block evaluation starts here).
void gather(const Block& b, const double* y, const double* yp, double* ly, double* lyp) {
  for (const auto& [i, c] : b.constants) {
    ly[i] = c;
    lyp[i] = 0.0;
  }
  for (const auto& m : b.mapped) {
    ly[m.local] = m.scale * y[m.var];
    lyp[m.local] = m.scale * yp[m.var];
  }
}

// A block's rows at one point, with the Pattern scalar (which locals each
// row reads, and which of them nonlinearly) and with Dual numbers, one
// direction per local (dF/d local, times the local's alias sign). y and yp
// are the unknowns the blocks read (after alias elimination).
void evaluate_structure(const Block& b, double t, const double* y, const double* yp, const EvalContext& ctx,
                        std::vector<Pattern>& pr, std::vector<Dual>& dr) {
  const int nl = static_cast<int>(b.vars.size());
  std::vector<Pattern> py(nl), pyp(nl);
  std::vector<Dual> dy(nl), dyp(nl);
  for (int i = 0; i < nl; ++i) {
    const int g = b.vars[i];
    const double v = g >= 0 ? b.scale[i] * y[g] : b.offset[i];
    const double vp = g >= 0 ? b.scale[i] * yp[g] : 0.0;
    py[i] = Pattern(v);
    pyp[i] = Pattern(vp);
    if (g >= 0) {
      py[i].deps.set(i);
      pyp[i].deps.set(kMaxLocal + i);
    }
    dy[i] = Dual::variable(v, i, g >= 0 ? b.scale[i] : 0.0, nl);
    dyp[i] = Dual(vp);
  }
  pr.assign(std::max(1, b.n_rows), Pattern(0.0));
  dr.assign(std::max(1, b.n_rows), Dual(0.0));
  b.residual(t, py.data(), pyp.data(), pr.data(), ctx);
  b.residual(t, dy.data(), dyp.data(), dr.data(), ctx);
}

std::string node_text(const Circuit& c, const std::vector<PortId>& ports) {
  std::string s = "{";
  for (std::size_t i = 0; i < ports.size(); ++i) s += (i ? ", " : "") + c.port_name(ports[i]);
  return s + "}";
}

// The compressed-column (CSC) form KLU takes of the pattern whose column c
// holds the rows cols[c]; returns the position in row_idx of each (row,
// column) entry.
std::map<std::pair<int, int>, int> compress_columns(const std::vector<std::set<int>>& cols,
                                                    std::vector<long>& col_ptr, std::vector<long>& row_idx) {
  const int n = static_cast<int>(cols.size());
  col_ptr.assign(n + 1, 0);
  row_idx.clear();
  std::map<std::pair<int, int>, int> pos;
  for (int c = 0; c < n; ++c) {
    col_ptr[c] = static_cast<long>(row_idx.size());
    for (int r : cols[c]) {
      pos[{r, c}] = static_cast<int>(row_idx.size());
      row_idx.push_back(r);
    }
  }
  col_ptr[n] = static_cast<long>(row_idx.size());
  return pos;
}

}  // namespace

// ---------------------------------------------------------------------------

System::System(Circuit circuit, const AssemblyOptions& options) : circuit_(std::move(circuit)) {
  build_nodes();
  build_pattern();
  check_structure();
  if (options.eliminate_aliases) {
    eliminate_aliases();
  } else {
    n_full_ = n_;
    row_of_.resize(n_);
    std::iota(row_of_.begin(), row_of_.end(), 0);
    F_full_.assign(n_, 0.0);
    for (auto& b : blocks_) {
      b->scale.assign(b->vars.size(), 1.0);
      b->offset.assign(b->vars.size(), 0.0);
    }
  }
  build_slots();
  m_ = n_;
  j1_col_ptr_ = col_ptr_;
  j1_row_idx_ = row_idx_;
  ida_row_of_full_ = row_of_;
  ida_to_m_.resize(n_);
  std::iota(ida_to_m_.begin(), ida_to_m_.end(), 0);
  m_to_ida_ = ida_to_m_;
  explicit_of_m_.assign(n_, -1);
  m_start_ = start_value_;
  if (options.eliminate_aliases && options.eliminate_explicit) eliminate_explicit();
  if (explicit_.empty())
    for (std::size_t bi = 0; bi < blocks_.size(); ++bi)
      if (!blocks_[bi]->all_eliminated) final_blocks_.push_back(static_cast<int>(bi));
  // Row maps of the residual's hot loop: IDA's rows, and the substituted
  // rows of blocks that are evaluated (the others are never written).
  for (int r = 0; r < n_full_; ++r)
    if (ida_row_of_full_[r] >= 0) kept_full_rows_.push_back({r, ida_row_of_full_[r]});
  std::vector<char> evaluated(blocks_.size(), 0);
  for (int bi : final_blocks_) evaluated[bi] = 1;
  for (const auto& stage : stages_)
    for (const auto& entry : stage) evaluated[entry.first] = 1;
  for (std::size_t e = 0; e < eliminated_.size(); ++e)
    for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
      const Block& b = *blocks_[bi];
      if (evaluated[bi] && eliminated_[e] >= b.row0 && eliminated_[e] < b.row0 + b.n_rows)
        checked_aliases_.push_back(static_cast<int>(e));
    }
  reset_modes();
}

void System::build_slots() {
  for (auto& b : blocks_) {
    b->mapped.clear();
    b->constants.clear();
    for (std::size_t i = 0; i < b->vars.size(); ++i) {
      if (b->vars[i] >= 0) b->mapped.push_back({static_cast<int>(i), b->vars[i], b->scale[i]});
      else b->constants.push_back({static_cast<int>(i), b->offset[i]});
    }
    b->all_eliminated = true;
    for (int k = 0; k < b->n_rows; ++k) b->all_eliminated &= row_of_[b->row0 + k] < 0;
    const int nl = static_cast<int>(b->vars.size());
    b->slot.assign(nl, -1);
    b->slot_local.clear();
    // Differential unknowns take the first directions: a Dual carries as
    // many derivatives as its highest direction, and a component's costly
    // part (a cylinder's flows and friction from its positions, masses and
    // energies) usually depends on its states alone.
    std::vector<int> order(nl);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int c) {
      auto rank = [&](int i) { return b->vars[i] >= 0 && id_[b->vars[i]] != 0.0 ? 0 : 1; };
      return rank(a) < rank(c);
    });
    std::map<int, int> seen;
    for (int i : order) {
      if (b->vars[i] < 0) continue;
      auto [it, fresh] = seen.emplace(b->vars[i], static_cast<int>(b->slot_local.size()));
      if (fresh) b->slot_local.push_back(i);
      b->slot[i] = it->second;
    }
  }
}

System::~System() = default;

void System::build_nodes() {
  const Circuit& c = circuit_;
  auto new_var = [&](std::string name, double start, unsigned char kind, double nominal) {
    var_names_.push_back(std::move(name));
    start_value_.push_back(start);
    start_kind_.push_back(kind);
    nominal_.push_back(nominal);
    return n_++;
  };

  // Union-find of ports into nodes.
  std::map<std::pair<int, int>, int> port_node;  // (component, port) -> node
  std::vector<std::vector<PortId>> nodes;
  std::vector<SourceLocation> node_where;
  for (const auto& conn : c.connections) {
    std::set<int> existing;
    for (const auto& p : conn.ports) {
      auto it = port_node.find({p.component, p.port});
      if (it != port_node.end()) existing.insert(it->second);
    }
    int target;
    if (existing.empty()) {
      target = static_cast<int>(nodes.size());
      nodes.emplace_back();
      node_where.push_back(conn.where);
    } else {
      target = *existing.begin();
      for (int other : existing) {
        if (other == target) continue;
        for (const auto& p : nodes[other]) {
          nodes[target].push_back(p);
          port_node[{p.component, p.port}] = target;
        }
        nodes[other].clear();
      }
    }
    for (const auto& p : conn.ports) {
      if (!port_node.count({p.component, p.port})) {
        nodes[target].push_back(p);
        port_node[{p.component, p.port}] = target;
      }
    }
  }
  // Unconnected ports: optional ones get a node of their own, others are errors.
  for (std::size_t ci = 0; ci < c.components.size(); ++ci) {
    const auto& info = c.components[ci]->info();
    for (std::size_t pi = 0; pi < info.ports.size(); ++pi) {
      if (port_node.count({static_cast<int>(ci), static_cast<int>(pi)})) continue;
      const auto& ps = info.ports[pi];
      if (!ps.optional) {
        throw InputError(c.component_where[ci], c.components[ci]->name(), "",
                         "port '" + ps.name + "' (" + domain_name(ps.domain) +
                             ") is not connected; connect it under 'connections:' (dangling port)");
      }
      port_node[{static_cast<int>(ci), static_cast<int>(pi)}] = static_cast<int>(nodes.size());
      nodes.push_back({PortId{static_cast<int>(ci), static_cast<int>(pi)}});
      node_where.push_back(c.component_where[ci]);
    }
  }
  // Domain and causality checks.
  for (std::size_t ni = 0; ni < nodes.size(); ++ni) {
    const auto& ports = nodes[ni];
    if (ports.empty()) continue;
    const auto& first = c.components[ports[0].component]->info().ports[ports[0].port];
    int outputs = 0;
    for (const auto& p : ports) {
      const auto& ps = c.components[p.component]->info().ports[p.port];
      if (ps.domain != first.domain)
        throw InputError(node_where[ni], c.components[p.component]->name(), "",
                         "cannot connect " + c.port_name(ports[0]) + " (" + domain_name(first.domain) + ") with " +
                             c.port_name(p) + " (" + domain_name(ps.domain) + ")");
      if (ps.causality == Causality::output) ++outputs;
    }
    if (first.domain == Domain::signal) {
      if (outputs > 1)
        throw InputError(node_where[ni], "", "", "signal node " + node_text(c, ports) + " has " +
                                                     std::to_string(outputs) + " outputs driving it; only one may");
      if (outputs == 0 && ports.size() > 1)
        throw InputError(node_where[ni], "", "", "signal node " + node_text(c, ports) +
                                                     " connects only inputs; nothing drives it");
    }
  }

  // Variables: node across variables first.
  std::vector<int> node_across(nodes.size(), -1);
  std::vector<int> node_velocity(nodes.size(), -1);
  for (std::size_t ni = 0; ni < nodes.size(); ++ni) {
    if (nodes[ni].empty()) continue;
    const auto& ps = c.components[nodes[ni][0].component]->info().ports[nodes[ni][0].port];
    const std::string where = nodes[ni].size() == 1 ? c.port_name(nodes[ni][0]) : node_text(c, nodes[ni]);
    switch (ps.domain) {
      case Domain::pneumatic: node_across[ni] = new_var("p at " + where, c.gas.p_ambient, 0, 1e5); break;
      case Domain::thermal: node_across[ni] = new_var("T at " + where, c.gas.T_ambient, 0, 300.0); break;
      case Domain::translational:
        // Typical magnitudes of a pneumatic drive: 1 cm, 0.1 m/s (the hand-
        // written reference in tests/reference scales its absolute
        // tolerances so). 1 mm and 1 cm/s held a piston at rest to 1e-9 m
        // and 1e-8 m/s, which cost 20 % more steps for no gain in accuracy.
        node_across[ni] = new_var("s at " + where, 0.0, 0, 1e-2);
        node_velocity[ni] = new_var("v at " + where, 0.0, 0, 1e-1);
        break;
      case Domain::signal: node_across[ni] = new_var("value at " + where, ps.default_value, 0, 1.0); break;
    }
  }

  // Component blocks with their own variables.
  std::map<std::pair<int, int>, PortVars> port_vars;
  int row = 0, mode = 0, root = 0;
  for (std::size_t ci = 0; ci < c.components.size(); ++ci) {
    const Component& comp = *c.components[ci];
    const auto& info = comp.info();
    if (comp.n_local() > kMaxLocal)
      throw StructureError("component '" + comp.name() + "' (" + info.type + ") has " +
                           std::to_string(comp.n_local()) + " local variables; the limit is " +
                           std::to_string(kMaxLocal));
    auto b = std::make_unique<ComponentBlock>();
    b->component = &comp;
    b->component_index = static_cast<int>(ci);
    b->label = comp.name() + " (" + info.type + ")";
    b->where = c.component_where[ci];
    b->vars.assign(comp.n_local(), -1);
    b->connected.reset(new bool[info.ports.size() + 1]);
    for (std::size_t pi = 0; pi < info.ports.size(); ++pi) {
      const auto& ps = info.ports[pi];
      const int node = port_node[{static_cast<int>(ci), static_cast<int>(pi)}];
      b->connected[pi] = nodes[node].size() > 1;
      const int o = comp.port_offset(static_cast<int>(pi));
      const std::string pn = comp.name() + "." + ps.name;
      PortVars pv;
      pv.across = node_across[node];
      b->vars[o] = pv.across;
      switch (ps.domain) {
        case Domain::pneumatic:
          pv.flow = b->vars[o + 1] = new_var(pn + ".m_flow", 0.0, 0, 1e-4);
          pv.t_out = b->vars[o + 2] = new_var(pn + ".T_out", c.gas.T_ambient, 0, 300.0);
          break;
        case Domain::thermal: pv.flow = b->vars[o + 1] = new_var(pn + ".Q", 0.0, 0, 1e-3); break;
        case Domain::translational:
          pv.flow = b->vars[o + 1] = new_var(pn + ".f", 0.0, 0, 1.0);
          b->vars[o + 2] = node_velocity[node];
          break;
        case Domain::signal: break;
      }
      port_vars[{static_cast<int>(ci), static_cast<int>(pi)}] = pv;
    }
    // Start values from the component (local), merged into the global start.
    std::vector<double> local_start(comp.n_local(), 0.0);
    std::vector<StartValues::Kind> local_kind(comp.n_local(), StartValues::Kind::none);
    StartValues sv(comp, local_start.data(), local_kind.data());
    comp.start(sv, c.gas);
    for (std::size_t k = 0; k < info.variables.size(); ++k) {
      const int local = comp.internal_offset() + static_cast<int>(k);
      const auto& vs = info.variables[k];
      const double start = local_start[local];
      const double nominal = vs.nominal > 0 ? vs.nominal : std::max(std::abs(start), nominal_floor(vs.unit));
      b->vars[local] = new_var(comp.name() + "." + vs.name, start, static_cast<unsigned char>(local_kind[local]), nominal);
    }
    for (int local = 0; local < comp.internal_offset(); ++local) {
      const int g = b->vars[local];
      if (g < 0 || local_kind[local] == StartValues::Kind::none) continue;
      const auto kind = static_cast<unsigned char>(local_kind[local]);
      if (kind > start_kind_[g]) {  // fixed beats guess beats none
        start_value_[g] = local_start[local];
        start_kind_[g] = kind;
        nominal_[g] = std::max(nominal_[g], std::abs(local_start[local]));
      }
    }
    b->row0 = row;
    b->n_rows = comp.n_equations();
    for (int k = 0; k < b->n_rows; ++k)
      b->row_names.push_back(comp.name() + ": " +
                             (k < static_cast<int>(info.equations.size()) ? info.equations[k]
                                                                          : "equation " + std::to_string(k + 1)));
    row += b->n_rows;
    b->mode0 = mode;
    mode += info.modes;
    b->root0 = root;
    root += info.roots;
    if (info.roots > 0) root_blocks_.push_back(static_cast<int>(blocks_.size()));
    blocks_.push_back(std::move(b));
  }
  modes_.assign(mode, 0.0);
  n_roots_ = root;
  reset_modes();

  // Stream routing: T_in of each pneumatic port.
  for (std::size_t ni = 0; ni < nodes.size(); ++ni) {
    const auto& ports = nodes[ni];
    if (ports.empty()) continue;
    if (c.components[ports[0].component]->info().ports[ports[0].port].domain != Domain::pneumatic) continue;
    auto t_in_slot = [&](const PortId& p) -> int& {
      auto& blk = *blocks_[p.component];
      return blk.vars[c.components[p.component]->port_offset(p.port) + 3];
    };
    if (ports.size() == 1) {
      t_in_slot(ports[0]) = port_vars[{ports[0].component, ports[0].port}].t_out;  // closed port
    } else if (ports.size() == 2) {
      t_in_slot(ports[0]) = port_vars[{ports[1].component, ports[1].port}].t_out;
      t_in_slot(ports[1]) = port_vars[{ports[0].component, ports[0].port}].t_out;
    } else {
      for (std::size_t i = 0; i < ports.size(); ++i) {
        auto mix = std::make_unique<StreamMixBlock>();
        const int t_in = new_var(c.port_name(ports[i]) + ".T_in", c.gas.T_ambient, 0, 300.0);
        t_in_slot(ports[i]) = t_in;
        mix->vars.push_back(t_in);
        for (std::size_t j = 0; j < ports.size(); ++j) {
          if (j == i) continue;
          const auto& pv = port_vars[{ports[j].component, ports[j].port}];
          mix->vars.push_back(pv.flow);
          mix->vars.push_back(pv.t_out);
        }
        mix->label = "stream mixing at " + node_text(c, ports);
        mix->where = node_where[ni];
        mix->row0 = row++;
        mix->n_rows = 1;
        mix->row_names.push_back("inStream(T) of " + c.port_name(ports[i]) + " at " + node_text(c, ports));
        blocks_.push_back(std::move(mix));
      }
    }
  }
  // Node balances and signal defaults.
  for (std::size_t ni = 0; ni < nodes.size(); ++ni) {
    const auto& ports = nodes[ni];
    if (ports.empty()) continue;
    const auto& ps = c.components[ports[0].component]->info().ports[ports[0].port];
    if (ps.domain == Domain::signal) {
      bool driven = false;
      for (const auto& p : ports)
        driven |= c.components[p.component]->info().ports[p.port].causality == Causality::output;
      if (driven) continue;
      auto def = std::make_unique<SignalDefaultBlock>();
      def->value = ps.default_value;
      def->vars = {node_across[ni]};
      def->label = "default of unconnected input " + c.port_name(ports[0]);
      def->where = node_where[ni];
      def->row0 = row++;
      def->n_rows = 1;
      def->row_names.push_back(def->label);
      blocks_.push_back(std::move(def));
      continue;
    }
    if (ps.domain == Domain::translational) {
      auto kin = std::make_unique<KinematicBlock>();
      kin->vars = {node_across[ni], node_velocity[ni]};
      kin->label = "kinematics ds/dt = v at " + node_text(c, ports);
      kin->where = node_where[ni];
      kin->row0 = row++;
      kin->n_rows = 1;
      kin->row_names.push_back(kin->label);
      blocks_.push_back(std::move(kin));
    }
    auto sum = std::make_unique<FlowSumBlock>();
    for (const auto& p : ports) sum->vars.push_back(port_vars[{p.component, p.port}].flow);
    sum->label = std::string(ps.domain == Domain::pneumatic ? "mass" : ps.domain == Domain::thermal ? "heat" : "force") +
                 " balance at " + node_text(c, ports);
    sum->where = node_where[ni];
    sum->row0 = row++;
    sum->n_rows = 1;
    sum->row_names.push_back(sum->label);
    blocks_.push_back(std::move(sum));
  }

  if (row != n_)
    throw StructureError("internal error: " + std::to_string(row) + " equations for " + std::to_string(n_) +
                         " variables");
  for (const auto& b : blocks_)
    for (int v : b->vars)
      if (v < 0) throw StructureError("internal error: unmapped local variable in " + b->label);
}

void System::reset_modes() {
  for (const auto& b : blocks_)
    if (b->component) b->component->initial_modes(modes_.data() + b->mode0);
  yw_ = m_start_;
  ypw_.assign(m_start_.size(), 0.0);
  cache_valid_ = false;
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
    EvalContext ctx{&circuit_.gas, modes_.data(), &invalid};
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
  std::vector<int> stack(free_rows);
  while (!stack.empty()) {
    const int r = stack.back();
    stack.pop_back();
    if (!over_rows.insert(r).second) continue;
    for (int c : adj[r]) {
      over_cols.insert(c);
      if (match_col[c] >= 0) stack.push_back(match_col[c]);
    }
  }
  stack = free_cols;
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    if (!under_cols.insert(c).second) continue;
    for (int r : col_rows[c]) {
      under_rows.insert(r);
      if (match_row[r] >= 0) stack.push_back(match_row[r]);
    }
  }
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
void System::eliminate_aliases() {
  const int n = n_;
  n_full_ = n;
  struct Candidate {
    const Block* block;
    int k;                          // local row
    std::vector<int> cols;          // 1 or 2 global columns
    std::vector<double> coef;       // dF/dy per column (first point)
    double offset = 0.0;            // F - sum coef y (first point)
    bool ok = true;
  };
  // The stream temperatures at a node of three or more pneumatic ports (the
  // mixed T_in and the T_out it mixes) stay unknowns of their own. Merged
  // into the classes of the components' gas temperatures they would start
  // the consistent-initialisation Newton at different temperatures; the
  // mixing weights are steep at zero flow, so the first Newton step then
  // sends the mixed temperatures to 1e5 K (three test circuits failed so).
  // Kept apart they all start at the ambient guess and that term vanishes.
  std::vector<char> is_mixed(n, 0);
  for (const auto& b : blocks_)
    if (dynamic_cast<const StreamMixBlock*>(b.get()))
      for (std::size_t i = 0; i < b->vars.size(); i += 2) is_mixed[b->vars[i]] = 1;
  std::vector<Candidate> cand;
  for (const auto& b : blocks_)
    for (int k = 0; k < b->n_rows; ++k) {
      const int r = b->row0 + k;
      const auto& cols = dep_y_[r];
      if (!dep_yp_[r].empty() || cols.empty() || cols.size() > 2) continue;
      if (std::any_of(cols.begin(), cols.end(), [&](int c) { return is_mixed[c]; })) continue;
      if (b->component && b->component->info().modes > 0) continue;
      cand.push_back({b.get(), k, cols, {}, 0.0, true});
    }

  // Check linearity at the start point and two perturbed points.
  constexpr double kCheckTimes[3] = {0.0, 0.3711, 97.13};
  std::mt19937 rng(54321);
  bool invalid = false;
  EvalContext ctx{&circuit_.gas, modes_.data(), &invalid};
  std::vector<Dual> ly(kMaxLocal), lyp(kMaxLocal), res(kMaxLocal * 2);
  for (int pass = 0; pass < 3 && !cand.empty(); ++pass) {
    std::vector<double> y0, yp0;
    check_point(pass, rng, y0, yp0);
    const Block* evaluated = nullptr;
    for (auto& c : cand) {
      const Block& b = *c.block;
      const int nl = static_cast<int>(b.vars.size());
      if (evaluated != &b) {
        for (int i = 0; i < nl; ++i) {
          ly[i] = Dual::variable(y0[b.vars[i]], i, 1.0, nl);
          lyp[i] = Dual(yp0[b.vars[i]]);
        }
        if (static_cast<int>(res.size()) < b.n_rows) res.resize(b.n_rows);
        // Three far-apart times: a row that sets a variable to a function of
        // time (a source following a table) is no constant.
        b.residual(kCheckTimes[pass], ly.data(), lyp.data(), res.data(), ctx);
        evaluated = &b;
      }
      std::vector<double> coef(c.cols.size(), 0.0);
      for (int i = 0; i < nl; ++i)
        for (std::size_t j = 0; j < c.cols.size(); ++j)
          if (b.vars[i] == c.cols[j]) coef[j] += res[c.k].deriv(i);
      double offset = res[c.k].v, magnitude = std::abs(res[c.k].v);
      for (std::size_t j = 0; j < c.cols.size(); ++j) {
        offset -= coef[j] * y0[c.cols[j]];
        magnitude += std::abs(coef[j] * y0[c.cols[j]]);
      }
      if (pass == 0) {
        c.coef = coef;
        c.offset = offset;
      }
      for (std::size_t j = 0; j < coef.size(); ++j) c.ok &= coef[j] == c.coef[j] && std::abs(coef[j]) == 1.0;
      if (c.cols.size() == 2) c.ok &= std::abs(offset) <= 1e-12 * magnitude;
      else c.ok &= std::abs(offset - c.offset) <= 1e-12 * std::max(std::abs(c.offset), magnitude);
      if (!std::isfinite(offset)) c.ok = false;
    }
  }

  // Union-find with signs: y_v = sign[v] * y_parent[v]; a root may be a constant.
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<double> sign(n, 1.0), value(n, 0.0);
  std::vector<char> constant(n, 0), differential(n, 0);
  for (int r = 0; r < n; ++r)
    for (int c : dep_yp_[r]) differential[c] = 1;
  std::function<std::pair<int, double>(int)> find = [&](int v) -> std::pair<int, double> {
    if (parent[v] == v) return {v, 1.0};
    auto [root, s] = find(parent[v]);
    parent[v] = root;
    sign[v] *= s;
    return {root, sign[v]};
  };
  std::vector<char> eliminated(n, 0);
  for (const auto& c : cand) {
    if (!c.ok) continue;
    const int row = c.block->row0 + c.k;
    if (c.cols.size() == 1) {
      const auto [ra, sa] = find(c.cols[0]);
      if (constant[ra] || differential[ra]) continue;
      constant[ra] = 1;
      value[ra] = sa * (-c.offset / c.coef[0]);
      eliminated[row] = 1;
      continue;
    }
    const auto [ra, sa] = find(c.cols[0]);
    const auto [rb, sb] = find(c.cols[1]);
    if (ra == rb || (constant[ra] && constant[rb]) || (differential[ra] && differential[rb])) continue;
    if ((constant[ra] && differential[rb]) || (constant[rb] && differential[ra])) continue;
    // coef_a sa y_ra + coef_b sb y_rb = 0  =>  y_rb = q y_ra, q = +-1
    const double q = -(c.coef[0] * sa) / (c.coef[1] * sb);
    const bool keep_a = constant[ra] || (!constant[rb] && (differential[ra] || !differential[rb]));
    const int root = keep_a ? ra : rb, child = keep_a ? rb : ra;
    parent[child] = root;
    sign[child] = q;
    differential[root] |= differential[child];
    eliminated[row] = 1;
  }

  // Reduced numbering.
  std::vector<int> reduced(n, -1);
  std::vector<std::string> names;
  std::vector<double> start, nominal;
  std::vector<unsigned char> kind;
  int m = 0;
  for (int v = 0; v < n; ++v) {
    const auto [root, s] = find(v);
    if (root != v || constant[v]) continue;
    reduced[v] = m++;
    names.push_back(var_names_[v]);
    start.push_back(start_value_[v]);
    kind.push_back(start_kind_[v]);
    nominal.push_back(nominal_[v]);
  }
  for (int v = 0; v < n; ++v) {
    const auto [root, s] = find(v);
    if (constant[root]) continue;
    const int g = reduced[root];
    if (start_kind_[v] > kind[g]) {  // fixed beats guess beats none
      start[g] = s * start_value_[v];
      kind[g] = start_kind_[v];
    }
    nominal[g] = std::min(nominal[g], nominal_[v]);
  }
  row_of_.assign(n, -1);
  eliminated_.clear();
  int kept = 0;
  for (int r = 0; r < n; ++r) {
    if (eliminated[r]) eliminated_.push_back(r);
    else row_of_[r] = kept++;
  }
  if (kept != m)
    throw StructureError("internal error: alias elimination left " + std::to_string(kept) + " equations for " +
                         std::to_string(m) + " unknowns");

  // Pattern and differential flags of the reduced system.
  std::vector<std::set<int>> cols(m);
  std::vector<double> id(m, 0.0);
  for (int r = 0; r < n; ++r) {
    if (row_of_[r] < 0) continue;
    for (int c : dep_y_[r]) {
      const auto [root, s] = find(c);
      if (!constant[root]) cols[reduced[root]].insert(row_of_[r]);
    }
    for (int c : dep_yp_[r]) {
      const auto [root, s] = find(c);
      if (constant[root]) continue;
      cols[reduced[root]].insert(row_of_[r]);
      id[reduced[root]] = 1.0;
    }
  }
  const auto pos = compress_columns(cols, col_ptr_, row_idx_);
  for (auto& b : blocks_) {
    const int nl = static_cast<int>(b->vars.size());
    b->scale.assign(nl, 1.0);
    b->offset.assign(nl, 0.0);
    for (int i = 0; i < nl; ++i) {
      const auto [root, s] = find(b->vars[i]);
      if (constant[root]) {
        b->offset[i] = s * value[root];
        b->vars[i] = -1;
      } else {
        b->scale[i] = s;
        b->vars[i] = reduced[root];
      }
    }
    b->jac_pos.assign(static_cast<std::size_t>(b->n_rows) * nl, -1);
    for (int k = 0; k < b->n_rows; ++k) {
      const int r = row_of_[b->row0 + k];
      if (r < 0) continue;
      for (int i = 0; i < nl; ++i) {
        if (b->vars[i] < 0) continue;
        auto it = pos.find({r, b->vars[i]});
        if (it != pos.end()) b->jac_pos[static_cast<std::size_t>(k) * nl + i] = it->second;
      }
    }
  }
  eliminated_nominal_.clear();
  for (int r : eliminated_) eliminated_nominal_.push_back(nominal_[dep_y_[r][0]]);
  var_names_ = std::move(names);
  start_value_ = std::move(start);
  start_kind_ = std::move(kind);
  nominal_ = std::move(nominal);
  id_ = std::move(id);
  n_ = m;
  F_full_.assign(n_full_, 0.0);
}

// Explicit elimination. After alias elimination most algebraic unknowns of a
// pneumatic circuit are given by one equation each, explicitly, from states
// and from unknowns given before them: a chamber's port pressure
// p = (kappa-1) U/V, a throttle's flow from the pressures around it, a port's
// outflow temperature, the force a cylinder puts on its flange. Handed to
// IDA, each is another Newton unknown with its own convergence test (the
// tight flow tolerances caused most of the rig's convergence failures) and
// another entry in every vector operation. Here they are solved inside the
// residual instead: in dependency order ("levels"), each block that gives
// unknowns of a level is evaluated once, and each such unknown is corrected
// by -F_row / coef - exact, since the row is linear in it with the constant
// coefficient coef. IDA then sees the states and the few unknowns that no
// equation gives explicitly (torn: a pressure between two throttles without
// a volume, a signal from a component with modes). Its Jacobian is the
// Schur complement of the AD Jacobian over the alias-reduced unknowns.
//
// An equation qualifies for unknown v if it has no y', depends on v only
// linearly through sums and constant factors (the Pattern scalar's `nonlin`
// set, at three points) with the same nonzero dF/dv at those points and
// three times. Rows of components with discrete modes (a signal source's
// output, a directional valve's flows) qualify too: when an event changes
// their modes they are checked again (verify_explicit), and every Jacobian
// evaluation re-checks the coefficient.
void System::eliminate_explicit() {
  const int m = n_;
  // Structure at the alias-reduced level: y and y' dependencies of each
  // kept row, the unknowns it depends on nonlinearly, and dF/dy per unknown.
  std::vector<std::set<int>> dy(m), dyp(m), nonlin(m);
  std::vector<std::map<int, double>> coef(m);
  std::vector<std::map<int, char>> coef_const(m);
  std::vector<int> full_row(m, -1), row_block(m, -1);
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
    const Block& b = *blocks_[bi];
    for (int k = 0; k < b.n_rows; ++k) {
      const int q = row_of_[b.row0 + k];
      if (q < 0) continue;
      full_row[q] = b.row0 + k;
      row_block[q] = static_cast<int>(bi);
    }
  }
  constexpr double kCheckTimes[3] = {0.0, 0.3711, 97.13};
  std::mt19937 rng(24680);
  bool invalid = false;
  EvalContext ctx{&circuit_.gas, modes_.data(), &invalid};
  std::vector<Pattern> pr;
  std::vector<Dual> dr;
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<double> y0, yp0;
    check_point(pass, rng, y0, yp0);
    for (const auto& bp : blocks_) {
      const Block& b = *bp;
      if (b.all_eliminated) continue;
      const int nl = static_cast<int>(b.vars.size());
      evaluate_structure(b, kCheckTimes[pass], y0.data(), yp0.data(), ctx, pr, dr);
      for (int k = 0; k < b.n_rows; ++k) {
        const int q = row_of_[b.row0 + k];
        if (q < 0) continue;
        std::map<int, double> c;
        for (int i = 0; i < nl; ++i) {
          const int g = b.vars[i];
          if (g < 0) continue;
          if (pr[k].deps.test(i)) dy[q].insert(g);
          if (pr[k].nonlin.test(i)) nonlin[q].insert(g);
          if (pr[k].deps.test(kMaxLocal + i)) dyp[q].insert(g);
          c[g] += dr[k].deriv(i);
        }
        for (const auto& [g, d] : c) {
          if (pass == 0) {
            coef[q][g] = d;
            coef_const[q][g] = std::isfinite(d) && d != 0.0;
          } else if (d != coef[q][g]) {
            coef_const[q][g] = 0;
          }
        }
      }
    }
  }

  // Candidate (row, unknown) pairs.
  std::vector<char> candidate_row(m, 0);
  auto usable = [&](int q, int v) {
    if (!candidate_row[q] || id_[v] != 0.0 || nonlin[q].count(v)) return false;
    auto it = coef_const[q].find(v);
    return it != coef_const[q].end() && it->second;
  };
  for (int q = 0; q < m; ++q) {
    if (row_block[q] < 0 || !dyp[q].empty() || dy[q].empty()) continue;
    const Block& b = *blocks_[row_block[q]];
    // The mixed temperature at a node of three or more ports stays an
    // unknown of IDA: computed from the flows, its steep weights near zero
    // flow stalled the consistent-initialisation Newton on the flows.
    if (dynamic_cast<const StreamMixBlock*>(&b)) continue;
    candidate_row[q] = 1;
  }
  // Forward propagation from the states: a row whose unknowns but one are
  // known gives that one. When stuck, one unknown stays with IDA (torn):
  // the one whose tearing lets the most rows be solved, preferring one that
  // no row gives explicitly.
  std::vector<char> known(m, 0), used(m, 0);
  std::vector<int> level(m, 0);
  std::vector<int> order_var, order_row;
  for (int v = 0; v < m; ++v) known[v] = id_[v] != 0.0;
  auto propagate = [&](std::vector<char>& kn, std::vector<char>& us, bool record) {
    int solved = 0;
    for (bool progress = true; progress;) {
      progress = false;
      for (int q = 0; q < m; ++q) {
        if (!candidate_row[q] || us[q]) continue;
        int unknown = -1, count = 0, lvl = 0;
        for (int v : dy[q]) {
          if (!kn[v]) unknown = v, ++count;
          else lvl = std::max(lvl, level[v]);
        }
        if (count != 1 || !usable(q, unknown)) continue;
        kn[unknown] = 1;
        us[q] = 1;
        ++solved;
        progress = true;
        if (!record) continue;
        level[unknown] = lvl + 1;
        order_var.push_back(unknown);
        order_row.push_back(q);
      }
    }
    return solved;
  };
  for (;;) {
    propagate(known, used, true);
    int best = -1;
    long best_score = -1;
    for (int v = 0; v < m; ++v) {
      if (known[v]) continue;
      bool explicit_somewhere = false;
      int rows = 0;
      for (int q = 0; q < m; ++q) {
        if (used[q] || !dy[q].count(v)) continue;
        ++rows;
        explicit_somewhere |= usable(q, v);
      }
      auto kn = known;
      auto us = used;
      kn[v] = 1;
      const long unlocked = propagate(kn, us, false);
      const long score = unlocked * 1000000L + (explicit_somewhere ? 0 : 1000) + rows;
      if (score > best_score) best = v, best_score = score;
    }
    if (best < 0) break;
    known[best] = 1;  // torn: level 0, an unknown of IDA
  }
  // Nothing to do - or everything: a circuit without states (sources and
  // flow elements only) keeps its unknowns, IDA needs at least one.
  if (order_var.empty() || static_cast<int>(order_var.size()) == m) return;

  // Explicit unknowns in level order (stable).
  std::vector<int> idx(order_var.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::stable_sort(idx.begin(), idx.end(), [&](int a, int b) { return level[order_var[a]] < level[order_var[b]]; });
  explicit_of_m_.assign(m, -1);
  for (int a : idx) {
    ExplicitUnknown x;
    x.var = order_var[a];
    x.row = full_row[order_row[a]];
    x.coef = coef[order_row[a]][x.var];
    x.level = level[x.var];
    x.deps.assign(dy[order_row[a]].begin(), dy[order_row[a]].end());
    explicit_of_m_[x.var] = static_cast<int>(explicit_.size());
    explicit_.push_back(std::move(x));
  }
  // IDA's unknowns and rows.
  m_to_ida_.assign(m, -1);
  ida_to_m_.clear();
  for (int v = 0; v < m; ++v)
    if (explicit_of_m_[v] < 0) {
      m_to_ida_[v] = static_cast<int>(ida_to_m_.size());
      ida_to_m_.push_back(v);
    }
  const int n = static_cast<int>(ida_to_m_.size());
  std::vector<int> ida_row_of_m(m, -1);
  int rows = 0;
  for (int q = 0; q < m; ++q)
    if (!used[q]) ida_row_of_m[q] = rows++;
  if (rows != n)
    throw StructureError("internal error: explicit elimination left " + std::to_string(rows) + " equations for " +
                         std::to_string(n) + " unknowns");
  ida_row_of_full_.assign(n_full_, -1);
  for (int r = 0; r < n_full_; ++r)
    if (row_of_[r] >= 0) ida_row_of_full_[r] = ida_row_of_m[row_of_[r]];

  // Rows of the alias-level Jacobian, by row.
  std::vector<std::vector<std::pair<long, int>>> j1_rows(m);
  for (int c = 0; c < m; ++c)
    for (long p = j1_col_ptr_[c]; p < j1_col_ptr_[c + 1]; ++p) j1_rows[j1_row_idx_[p]].push_back({p, c});
  // Symbolic Schur complement: d var / d y_IDA of each explicit unknown.
  std::vector<std::vector<int>> d_pattern(explicit_.size());
  // IDA's columns a row reaches through its entries (as accumulate() in
  // jacobian()), leaving out column `skip`.
  auto ida_columns = [&](const std::vector<std::pair<long, int>>& entries, int skip) {
    std::set<int> cols;
    for (const auto& [p, c] : entries) {
      if (c == skip) continue;
      const int j = explicit_of_m_[c];
      if (j >= 0) cols.insert(d_pattern[j].begin(), d_pattern[j].end());
      else cols.insert(m_to_ida_[c]);
    }
    return cols;
  };
  d_cols_.clear();
  for (std::size_t e = 0; e < explicit_.size(); ++e) {
    auto& x = explicit_[e];
    x.entries = j1_rows[row_of_[x.row]];
    const std::set<int> cols = ida_columns(x.entries, x.var);
    d_pattern[e].assign(cols.begin(), cols.end());
    x.d0 = static_cast<int>(d_cols_.size());
    x.dn = static_cast<int>(cols.size());
    d_cols_.insert(d_cols_.end(), cols.begin(), cols.end());
  }
  std::vector<std::set<int>> cols(n);  // IDA pattern: column -> rows
  std::vector<std::vector<int>> kept_cols(m);
  std::vector<double> id(n, 0.0);
  for (int q = 0; q < m; ++q) {
    if (used[q]) continue;
    const std::set<int> cs = ida_columns(j1_rows[q], -1);
    for (int c : cs) cols[c].insert(ida_row_of_m[q]);
    kept_cols[q].assign(cs.begin(), cs.end());
    for (int v : dyp[q]) id[m_to_ida_[v]] = 1.0;
  }
  const auto pos = compress_columns(cols, col_ptr_, row_idx_);
  kept_rows_.clear();
  for (int q = 0; q < m; ++q) {
    if (used[q]) continue;
    KeptRow k;
    k.row = full_row[q];
    k.entries = j1_rows[q];
    for (int c : kept_cols[q]) k.out.push_back({c, pos.at({ida_row_of_m[q], c})});
    kept_rows_.push_back(std::move(k));
  }

  // Evaluation plan: per level the blocks giving its unknowns; at the end
  // the blocks with rows for IDA.
  int max_level = 0;
  for (const auto& x : explicit_) max_level = std::max(max_level, x.level);
  stages_.assign(max_level, {});
  std::vector<char> keeps(blocks_.size(), 0);
  for (std::size_t e = 0; e < explicit_.size(); ++e) {
    const int bi = row_block[row_of_[explicit_[e].row]];
    auto& stage = stages_[explicit_[e].level - 1];
    auto it = std::find_if(stage.begin(), stage.end(), [&](const auto& s) { return s.first == bi; });
    if (it == stage.end()) stage.push_back({bi, {static_cast<int>(e)}});
    else it->second.push_back(static_cast<int>(e));
  }
  for (int q = 0; q < m; ++q)
    if (!used[q] && row_block[q] >= 0) keeps[row_block[q]] = 1;
  final_blocks_.clear();
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi)
    if (keeps[bi]) final_blocks_.push_back(static_cast<int>(bi));

  // IDA-level names, start values, scales.
  std::vector<std::string> names;
  std::vector<double> start, nominal;
  std::vector<unsigned char> kind;
  for (int v : ida_to_m_) {
    names.push_back(var_names_[v]);
    start.push_back(start_value_[v]);
    kind.push_back(start_kind_[v]);
    nominal.push_back(nominal_[v]);
  }
  m_start_ = start_value_;
  m_names_ = var_names_;
  var_names_ = std::move(names);
  start_value_ = std::move(start);
  start_kind_ = std::move(kind);
  nominal_ = std::move(nominal);
  id_ = std::move(id);
  n_ = n;
  // Root functions usually read a position or a time only. Evaluated with
  // every explicit unknown set to NaN at three points, a block whose roots
  // stay finite does not read them: IDA's root checks (one per step and per
  // output) then skip expand().
  roots_read_explicit_.assign(blocks_.size(), 0);
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
    const Block& b = *blocks_[bi];
    if (!b.component || b.component->info().roots == 0) continue;
    std::mt19937 rng2(13579);
    std::vector<double> g(b.component->info().roots);
    double ly[kMaxLocal], lyp[kMaxLocal];
    for (int pass = 0; pass < 3 && !roots_read_explicit_[bi]; ++pass) {
      poisoned_locals(b, pass, rng2, true, false, ly, lyp);
      Eval<double> e(*b.component, 0.1 * pass, ly, lyp, modes_.data() + b.mode0, b.connected.get(), circuit_.gas,
                     &invalid);
      b.component->roots(e, g.data());
      for (double x : g) roots_read_explicit_[bi] |= !std::isfinite(x);
    }
    any_roots_read_explicit_ |= roots_read_explicit_[bi] != 0;
  }
  j1_values_.assign(j1_row_idx_.size(), 0.0);
  d_values_.assign(d_cols_.size(), 0.0);
  scatter_.assign(n, 0.0);
  cache_y_.assign(n, 0.0);
}

void System::verify_explicit(int block, double t) const {
  const Block& b = *blocks_[block];
  const int nl = static_cast<int>(b.vars.size());
  bool invalid = false;
  EvalContext ctx{&circuit_.gas, modes_.data(), &invalid};
  std::vector<Pattern> pr;
  std::vector<Dual> dr;
  evaluate_structure(b, t, yw_.data(), ypw_.data(), ctx, pr, dr);
  for (const auto& x : explicit_) {
    if (x.row < b.row0 || x.row >= b.row0 + b.n_rows) continue;
    const int k = x.row - b.row0;
    bool ok = true;
    double c = 0.0;
    for (int i = 0; i < nl; ++i) {
      const int g = b.vars[i];
      if (g < 0) continue;
      if (pr[k].deps.test(kMaxLocal + i)) ok = false;
      if (pr[k].deps.test(i) && !std::binary_search(x.deps.begin(), x.deps.end(), g)) ok = false;
      if (g == x.var) {
        if (pr[k].nonlin.test(i)) ok = false;
        c += dr[k].deriv(i);
      }
    }
    if (ok && c == x.coef) continue;
    throw std::runtime_error("equation '" + equation_name(x.row) + "' of " + b.label + ", solved explicitly for '" + m_names_[x.var] +
                             "' at assembly, no longer gives it linearly with the same coefficient after an event "
                             "changed the component's modes; assemble with eliminate_explicit = false");
  }
}

void System::block_inputs(double t, const double*& y, const double*& yp, bool read_explicit) const {
  if (explicit_.empty()) return;
  if (read_explicit) {
    expand(t, y, yp);
  } else {
    for (int i = 0; i < n_; ++i) {
      yw_[ida_to_m_[i]] = y[i];
      ypw_[ida_to_m_[i]] = yp[i];
    }
    cache_valid_ = false;  // yw_'s states no longer match the cached expansion
  }
  y = yw_.data();
  yp = ypw_.data();
}

bool System::expand(double t, const double* y, const double* yp) const {
  for (int i = 0; i < n_; ++i) ypw_[ida_to_m_[i]] = yp[i];
  if (cache_valid_ && t == cache_t_ && std::equal(y, y + n_, cache_y_.begin())) return cache_invalid_;
  for (int i = 0; i < n_; ++i) yw_[ida_to_m_[i]] = y[i];
  // Each explicit unknown is solved from its start value, not from the last
  // call's: the result is then a function of (t, y) alone, without rounding
  // noise from the call history (which stalled IDA's initialisation Newton
  // at rtol 1e-9); a start value also keeps blocks that read an unknown
  // before its level from seeing zero pressures.
  for (const auto& x : explicit_) yw_[x.var] = m_start_[x.var];
  bool invalid = false;
  EvalContext ctx{&circuit_.gas, modes_.data(), &invalid};
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (const auto& stage : stages_)
    for (const auto& [bi, list] : stage) {
      const Block& b = *blocks_[bi];
      gather(b, yw_.data(), ypw_.data(), ly, lyp);
      b.residual(t, ly, lyp, F_full_.data() + b.row0, ctx);
      for (int e : list) {
        const auto& x = explicit_[e];
        yw_[x.var] -= F_full_[x.row] / x.coef;
      }
    }
  std::copy_n(y, n_, cache_y_.begin());
  cache_t_ = t;
  cache_valid_ = true;
  cache_invalid_ = invalid;
  return invalid;
}

void System::check_point(int pass, std::mt19937& rng, std::vector<double>& y0, std::vector<double>& yp0) const {
  start_values(y0, yp0);
  if (pass == 0) return;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < n_; ++i) {
    y0[i] += 0.05 * nominal_[i] * u(rng) + 0.01 * y0[i] * u(rng);
    yp0[i] = 0.1 * nominal_[i] * u(rng);
  }
}

void System::poisoned_locals(const Block& b, int pass, std::mt19937& rng, bool nan_explicit, bool nan_yp, double* ly,
                             double* lyp) const {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < b.vars.size(); ++i) {
    const int v = b.vars[i];
    const double y0 = v >= 0 ? b.scale[i] * m_start_[v] * (1.0 + 0.01 * pass * u(rng)) : b.offset[i];
    ly[i] = nan_explicit && v >= 0 && explicit_of_m_[v] >= 0 ? nan : y0;
    lyp[i] = nan_yp ? nan : 0.0;
  }
}

void System::start_values(std::vector<double>& y0, std::vector<double>& yp0) const {
  y0 = start_value_;
  yp0.assign(n_, 0.0);
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
  for (const auto& [r, q] : kept_full_rows_)
    if (q == ida_row) row = r;
  for (const auto& b : blocks_)
    if (row >= b->row0 && row < b->row0 + b->n_rows)
      return row - b->row0 < static_cast<int>(b->row_names.size()) ? b->row_names[row - b->row0] : b->label;
  return "row " + std::to_string(row);
}

int System::residual(double t, const double* y, const double* yp, double* F) const {
  bool invalid = false;
  EvalContext ctx{&circuit_.gas, modes_.data(), &invalid};
  double ly[kMaxLocal], lyp[kMaxLocal];
  const bool reduced = n_full_ != n_;
  if (!explicit_.empty()) {
    invalid = expand(t, y, yp);
    y = yw_.data();
    yp = ypw_.data();
  }
  // Blocks whose rows were all substituted as aliases are not evaluated:
  // their rows are identities after substitution, checked at assembly at
  // three points and times, and such a block has no discrete modes that
  // could change them. The other blocks' eliminated rows are checked here.
  double* Ff = reduced ? F_full_.data() : F;
  for (int bi : final_blocks_) {
    const Block& b = *blocks_[bi];
    gather(b, y, yp, ly, lyp);
    b.residual(t, ly, lyp, Ff + b.row0, ctx);
  }
  if (reduced)
    for (const auto& [r, q] : kept_full_rows_) F[q] = Ff[r];
  for (int e : checked_aliases_) {
    const int r = eliminated_[e];
    if (std::abs(Ff[r]) > 1e-10 * eliminated_nominal_[e] && std::isfinite(Ff[r])) {
      throw std::runtime_error("equation '" + equation_name(r) + "', substituted as an alias at assembly, no longer holds at t = " +
                               std::to_string(t) + " (residual " + std::to_string(Ff[r]) +
                               "); a component must not change such an equation at an event");
    }
  }
  if (invalid) return 1;
  for (int i = 0; i < n_; ++i)
    if (!std::isfinite(F[i])) return 1;
  return 0;
}

int System::jacobian(double t, const double* y, const double* yp, double cj, double* values) const {
  if (explicit_.empty()) return jacobian_blocks(t, y, yp, cj, values);
  const bool invalid = expand(t, y, yp);
  const int flag = jacobian_blocks(t, yw_.data(), ypw_.data(), cj, j1_values_.data());
  // Adds a dF/d(column c) entry to the row being reduced (scatter_, over
  // IDA's columns): directly for an unknown of IDA, through dc/dy for an
  // explicit one.
  auto accumulate = [&](double a, int c) {
    if (a == 0.0) return;
    const int j = explicit_of_m_[c];
    if (j < 0) {
      scatter_[m_to_ida_[c]] += a;
      return;
    }
    const auto& xj = explicit_[j];
    for (int k = 0; k < xj.dn; ++k) scatter_[d_cols_[xj.d0 + k]] += a * d_values_[xj.d0 + k];
  };
  // d var / d y_IDA of each explicit unknown, in level order:
  //   coef dvar + sum_c F_row,c dc = 0, dc of an explicit c known already.
  for (const auto& x : explicit_) {
    for (int k = 0; k < x.dn; ++k) scatter_[d_cols_[x.d0 + k]] = 0.0;
    for (const auto& [p, c] : x.entries) {
      const double a = j1_values_[p];
      if (c == x.var) {
        if (std::abs(a - x.coef) > 1e-9 * std::abs(x.coef)) {
          throw std::runtime_error("equation '" + equation_name(x.row) + "', solved explicitly at assembly (linear, dF/dy " +
                                   std::to_string(x.coef) + "), now has dF/dy " + std::to_string(a) + " at t = " +
                                   std::to_string(t) + "; assemble with eliminate_explicit = false");
        }
        continue;
      }
      accumulate(a, c);
    }
    for (int k = 0; k < x.dn; ++k) d_values_[x.d0 + k] = -scatter_[d_cols_[x.d0 + k]] / x.coef;
  }
  // IDA's rows: F_row,y + sum over explicit c of F_row,c dc/dy.
  std::fill(values, values + nnz(), 0.0);
  for (const auto& kr : kept_rows_) {
    for (const auto& [c, p] : kr.out) scatter_[c] = 0.0;
    for (const auto& [p, c] : kr.entries) accumulate(j1_values_[p], c);
    for (const auto& [c, p] : kr.out) values[p] = scatter_[c];
  }
  return invalid || flag ? 1 : 0;
}

int System::jacobian_blocks(double t, const double* y, const double* yp, double cj, double* values) const {
  std::fill(values, values + j1_row_idx_.size(), 0.0);
  bool invalid = false;
  EvalContext ctx{&circuit_.gas, modes_.data(), &invalid};
  static thread_local std::vector<Dual> ly(kMaxLocal), lyp(kMaxLocal), r(kMaxLocal * 2);
  for (const auto& b : blocks_) {
    if (b->all_eliminated) continue;
    const int nl = static_cast<int>(b->vars.size());
    for (int i = 0; i < nl; ++i) {
      // One pass gives dF/dy + cj dF/dy': y_i seeded with 1, y'_i with cj
      // (times the alias sign: local i is scale_i * y_g), in the direction
      // of its unknown. Seeded in place: a Dual is 0.5 kB.
      const int g = b->vars[i];
      Dual& a = ly[i];
      Dual& ap = lyp[i];
      if (g < 0) {
        a.v = b->offset[i];
        ap.v = 0.0;
        a.n = ap.n = 0;
        continue;
      }
      const double s = b->scale[i];
      a.v = s * y[g];
      ap.v = s * yp[g];
      // Only the directions up to its own are active (see build_slots), in
      // whole groups (Dual::padded).
      const int active = Dual::padded(b->slot[i] + 1);
      a.n = ap.n = active;
      std::fill_n(a.d.begin(), active, 0.0);
      std::fill_n(ap.d.begin(), active, 0.0);
      a.d[b->slot[i]] = s;
      ap.d[b->slot[i]] = cj * s;
    }
    if (static_cast<int>(r.size()) < b->n_rows) r.resize(b->n_rows);
    b->residual(t, ly.data(), lyp.data(), r.data(), ctx);
    for (int k = 0; k < b->n_rows; ++k) {
      if (row_of_[b->row0 + k] < 0) continue;
      const Dual& f = r[k];
      const int directions = std::min(f.n, static_cast<int>(b->slot_local.size()));  // without the padding
      for (int i = 0; i < directions; ++i) {
        const double d = f.d[i];
        if (d == 0.0) continue;
        const int p = b->jac_pos[static_cast<std::size_t>(k) * nl + b->slot_local[i]];
        if (p >= 0) values[p] += d;
        else ++pattern_misses_;
      }
    }
  }
  return invalid ? 1 : 0;
}

int System::newton_matrix_parts(double t, const double* y, const double* yp, double* dFdy, double* dFdyp) const {
  // The explicit unknowns have no y': dF/dy' = J(cj = 1) - J(cj = 0).
  int flag = jacobian(t, y, yp, 0.0, dFdy);
  flag |= jacobian(t, y, yp, 1.0, dFdyp);
  for (long p = 0; p < nnz(); ++p) dFdyp[p] -= dFdy[p];
  return flag;
}

void System::jacobian_parts(double t, const double* y, const double* yp, std::vector<double>& dFdy,
                            std::vector<double>& dFdyp) const {
  dFdy.assign(static_cast<std::size_t>(n_) * n_, 0.0);
  dFdyp.assign(static_cast<std::size_t>(n_) * n_, 0.0);
  if (!explicit_.empty()) {
    std::vector<double> j0(nnz()), j1(nnz());
    newton_matrix_parts(t, y, yp, j0.data(), j1.data());
    for (int c = 0; c < n_; ++c)
      for (long p = col_ptr_[c]; p < col_ptr_[c + 1]; ++p) {
        const std::size_t k = static_cast<std::size_t>(row_idx_[p]) * n_ + c;
        dFdy[k] = j0[p];
        dFdyp[k] = j1[p];
      }
    return;
  }
  bool invalid = false;
  EvalContext ctx{&circuit_.gas, modes_.data(), &invalid};
  std::vector<Dual> ly(kMaxLocal), lyp(kMaxLocal), r(kMaxLocal * 2);
  for (int part = 0; part < 2; ++part)
    for (const auto& b : blocks_) {
      const int nl = static_cast<int>(b->vars.size());
      for (int i = 0; i < nl; ++i) {
        const int g = b->vars[i];
        const double s = g >= 0 ? b->scale[i] : 0.0;
        ly[i] = Dual::variable(g >= 0 ? s * y[g] : b->offset[i], i, part == 0 ? s : 0.0, nl);
        lyp[i] = Dual::variable(g >= 0 ? s * yp[g] : 0.0, i, part == 1 ? s : 0.0, nl);
      }
      if (static_cast<int>(r.size()) < b->n_rows) r.resize(b->n_rows);
      b->residual(t, ly.data(), lyp.data(), r.data(), ctx);
      auto& out = part == 0 ? dFdy : dFdyp;
      for (int k = 0; k < b->n_rows; ++k) {
        const int row = row_of_[b->row0 + k];
        if (row < 0) continue;
        for (int i = 0; i < nl; ++i)
          if (b->vars[i] >= 0) out[static_cast<std::size_t>(row) * n_ + b->vars[i]] += r[k].deriv(i);
      }
    }
}

void System::roots(double t, const double* y, const double* yp, double* g) const {
  block_inputs(t, y, yp, any_roots_read_explicit_);
  bool invalid = false;
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (int bi : root_blocks_) {
    const Block& b = *blocks_[bi];
    gather(b, y, yp, ly, lyp);
    Eval<double> e(*b.component, t, ly, lyp, modes_.data() + b.mode0, b.connected.get(), circuit_.gas, &invalid);
    b.component->roots(e, g + b.root0);
  }
}

std::vector<double> System::time_events() const {
  std::vector<double> out;
  for (const auto& b : blocks_)
    if (b->component)
      for (double t : b->component->time_events()) out.push_back(t);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// Modes changed by an event: the explicit unknowns may take other values at
// the same (t, y) - a signal source's step - and the rows that give them are
// checked again.
void System::after_event(const Block& b, const std::vector<double>& modes_before, double t) const {
  if (std::equal(modes_before.begin(), modes_before.end(), modes_.begin() + b.mode0)) return;
  if (explicit_.empty()) return;
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi)
    if (blocks_[bi].get() == &b) verify_explicit(static_cast<int>(bi), t);
  cache_valid_ = false;
}

bool System::handle_time_event(double t, const double* y, const double* yp, std::vector<EventLogEntry>& log) {
  block_inputs(t, y, yp);
  bool changed = false;
  bool invalid = false;
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (const auto& b : blocks_) {
    if (!b->component) continue;
    const auto evs = b->component->time_events();
    bool due = false;
    for (double te : evs) due |= std::abs(te - t) <= 1e-12 * std::max(1.0, std::abs(t));
    if (!due) continue;
    gather(*b, y, yp, ly, lyp);
    Eval<double> e(*b->component, t, ly, lyp, modes_.data() + b->mode0, b->connected.get(), circuit_.gas, &invalid);
    const std::vector<double> before(modes_.begin() + b->mode0, modes_.begin() + b->mode0 + b->component->info().modes);
    const EventResult res = b->component->on_event(e, modes_.data() + b->mode0, EventKind::time, -1, 0);
    after_event(*b, before, t);
    changed |= res.changed;
    if (!res.message.empty() || !res.tag.empty()) log.push_back({t, b->component->name(), res.message, res.tag});
  }
  return changed;
}

bool System::handle_roots(double t, const double* y, const double* yp, const int* root_info,
                          std::vector<EventLogEntry>& log) {
  block_inputs(t, y, yp);
  bool changed = false;
  bool invalid = false;
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (const auto& b : blocks_) {
    if (!b->component) continue;
    const int nr = b->component->info().roots;
    for (int k = 0; k < nr; ++k) {
      const int dir = root_info[b->root0 + k];
      if (dir == 0) continue;
      gather(*b, y, yp, ly, lyp);
      Eval<double> e(*b->component, t, ly, lyp, modes_.data() + b->mode0, b->connected.get(), circuit_.gas,
                     &invalid);
      const std::vector<double> before(modes_.begin() + b->mode0,
                                       modes_.begin() + b->mode0 + b->component->info().modes);
      const EventResult res = b->component->on_event(e, modes_.data() + b->mode0, EventKind::root, k, dir);
      after_event(*b, before, t);
      changed |= res.changed;
      if (!res.message.empty() || !res.tag.empty()) log.push_back({t, b->component->name(), res.message, res.tag});
    }
  }
  return changed;
}

bool System::handle_input_changes(double t, const double* y, const double* yp, std::vector<EventLogEntry>& log,
                                  std::vector<std::string>* changed) {
  block_inputs(t, y, yp);
  bool any = false;
  bool invalid = false;
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (const auto& b : blocks_) {
    if (!b->component || !b->component->info().follows_inputs) continue;
    gather(*b, y, yp, ly, lyp);
    Eval<double> e(*b->component, t, ly, lyp, modes_.data() + b->mode0, b->connected.get(), circuit_.gas, &invalid);
    const std::vector<double> before(modes_.begin() + b->mode0, modes_.begin() + b->mode0 + b->component->info().modes);
    const EventResult res = b->component->on_inputs_changed(e, modes_.data() + b->mode0);
    after_event(*b, before, t);
    if (res.changed && changed) changed->push_back(b->component->name());
    any |= res.changed;
    if (!res.message.empty() || !res.tag.empty()) log.push_back({t, b->component->name(), res.message, res.tag});
  }
  return any;
}

double System::probe(const Probe& p, double t, const double* y, const double* yp) const {
  block_inputs(t, y, yp);
  const Block& b = *blocks_[p.component];  // component blocks come first, in order
  if (p.kind == Probe::Kind::local) {
    const int g = b.vars[p.index];
    return g >= 0 ? b.scale[p.index] * y[g] : b.offset[p.index];
  }
  double ly[kMaxLocal], lyp[kMaxLocal];
  gather(b, y, yp, ly, lyp);
  bool invalid = false;
  Eval<double> e(*b.component, t, ly, lyp, modes_.data() + b.mode0, b.connected.get(), circuit_.gas, &invalid);
  return b.component->observe(p.index, e);
}

ProbeSet System::probe_set(const std::vector<Probe>& probes) const {
  ProbeSet set;
  set.size = probes.size();
  std::size_t widest = 0;
  for (std::size_t i = 0; i < probes.size(); ++i) {
    const Probe& p = probes[i];
    const int slot = static_cast<int>(i);
    if (p.kind == Probe::Kind::local) {
      set.locals.push_back(p);
      set.local_slots.push_back(slot);
      continue;
    }
    auto g = std::find_if(set.groups.begin(), set.groups.end(),
                          [&](const ProbeSet::Group& x) { return x.component == p.component; });
    if (g == set.groups.end()) {
      set.groups.push_back({p.component, {}, {}});
      g = set.groups.end() - 1;
    }
    g->observables.push_back(p.index);
    g->slots.push_back(slot);
    widest = std::max(widest, g->observables.size());
  }
  set.scratch.resize(widest);
  // Which inputs the probes read: evaluated at the start values and two
  // perturbations of them, once with every explicit unknown NaN, once with
  // every y' NaN; a probe that stays finite does not read them.
  bool explicit_read = false, yp_read = false;
  for (const auto& lp : set.locals) {
    const int v = blocks_[lp.component]->vars[lp.index];
    explicit_read |= v >= 0 && explicit_of_m_[v] >= 0;
  }
  std::mt19937 rng(97531);
  bool invalid = false;
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (int pass = 0; pass < 3; ++pass)
    for (int poison = 0; poison < 2; ++poison)
      for (const auto& g : set.groups) {
        const Block& b = *blocks_[g.component];
        poisoned_locals(b, pass, rng, poison == 0, poison == 1, ly, lyp);
        Eval<double> e(*b.component, 0.1 * pass, ly, lyp, modes_.data() + b.mode0, b.connected.get(), circuit_.gas,
                       &invalid);
        b.component->observe_all(g.observables.data(), static_cast<int>(g.observables.size()), e,
                                 set.scratch.data());
        for (std::size_t k = 0; k < g.observables.size(); ++k)
          if (!std::isfinite(set.scratch[k])) (poison == 0 ? explicit_read : yp_read) = true;
      }
  set.reads_explicit = explicit_read && !explicit_.empty();
  set.reads_yp = yp_read;
  return set;
}

void System::probe_all(const ProbeSet& set, double t, const double* y, const double* yp, double* out) const {
  for (std::size_t i = 0; i < set.locals.size(); ++i) out[set.local_slots[i]] = probe(set.locals[i], t, y, yp);
  block_inputs(t, y, yp, set.reads_explicit);
  double ly[kMaxLocal], lyp[kMaxLocal];
  bool invalid = false;
  for (const auto& g : set.groups) {
    const Block& b = *blocks_[g.component];  // component blocks come first, in order
    gather(b, y, yp, ly, lyp);
    Eval<double> e(*b.component, t, ly, lyp, modes_.data() + b.mode0, b.connected.get(), circuit_.gas, &invalid);
    const int n = static_cast<int>(g.observables.size());
    b.component->observe_all(g.observables.data(), n, e, set.scratch.data());
    for (int k = 0; k < n; ++k) out[g.slots[k]] = set.scratch[k];
  }
}

}  // namespace pneumo
