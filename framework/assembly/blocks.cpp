#include "framework/assembly/blocks.hpp"

#include <algorithm>

#include "framework/core/smooth.hpp"

namespace pneumo {

namespace {

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

// Through variables of a node sum to zero (Kirchhoff); or, of a group of
// a node's ports, sum to the group's total, vars[0].
class FlowSumBlock final : public Block {
 public:
  explicit FlowSumBlock(bool total_first) : total_first(total_first) {}
  template <class T>
  void eval(const T* y, T* r) const {
    const std::size_t first = total_first ? 1 : 0;
    T s = y[first];
    for (std::size_t i = first + 1; i < vars.size(); ++i) s = s + y[i];
    r[0] = total_first ? s - y[0] : s;
  }
  const bool total_first;
  void residual(double, const double* y, const double*, double* r, const EvalContext&) const override { eval(y, r); }
  void residual(double, const Dual* y, const Dual*, Dual* r, const EvalContext&) const override { eval(y, r); }
  void residual(double, const Pattern* y, const Pattern*, Pattern* r, const EvalContext&) const override { eval(y, r); }
};

// The smoothed outflows w_j of the ports (m_flow_j, T_out_j) = (y[j],
// y[j + 1]), j = 1, 3, ... < end, into the node, added to w_sum, and w_j
// T_out_j to wt_sum.
template <class T>
void add_weights(const T* y, std::size_t end, double eps, T& w_sum, T& wt_sum) {
  for (std::size_t j = 1; j < end; j += 2) {
    const T w = smooth_pos(T(-y[j]), eps);  // outflow of port j = flow into the node
    w_sum = w_sum + w;
    wt_sum = wt_sum + w * y[j + 1];
  }
}

// inStream for a node of three or more pneumatic ports: the temperature of
// the gas arriving at port i is the mix of what the other ports deliver,
// weighted by their smoothed outflows into the node (Modelica's stream
// connector rule, regularised so that it stays defined at zero flow).
// vars: [T_in_i, (m_flow_j, T_out_j) for `ports` ports j != i, then
// (W, H) of groups of the other ports (StreamSumBlock)]
class StreamMixBlock final : public Block {
 public:
  explicit StreamMixBlock(int ports) : ports(ports) {}
  template <class T>
  void eval(const T* y, T* r, const EvalContext& c) const {
    const double eps = c.gas->m_flow_small;
    T w_sum = 0.0, wt_sum = 0.0;
    const std::size_t groups = 1 + 2 * static_cast<std::size_t>(ports);
    add_weights(y, groups, eps, w_sum, wt_sum);
    for (std::size_t j = groups; j + 1 < vars.size(); j += 2) {
      w_sum = w_sum + y[j];
      wt_sum = wt_sum + y[j + 1];
    }
    r[0] = y[0] - wt_sum / w_sum;
  }
  const int ports;
  void residual(double, const double* y, const double*, double* r, const EvalContext& c) const override { eval(y, r, c); }
  void residual(double, const Dual* y, const Dual*, Dual* r, const EvalContext& c) const override { eval(y, r, c); }
  void residual(double, const Pattern* y, const Pattern*, Pattern* r, const EvalContext& c) const override { eval(y, r, c); }
};

// The weights of a group of a node's ports, summed once for every port
// outside the group that mixes them: W = sum w_j, H = sum w_j T_out_j,
// w_j as in StreamMixBlock; W and H are solved explicitly from the flows
// and temperatures (kept as unknowns of IDA, the line benchmark's 33-port
// node failed to converge after an event). vars: [W, (m_flow_j, T_out_j)
// of the group, H]
class StreamSumBlock final : public Block {
 public:
  template <class T>
  void eval(const T* y, T* r, const EvalContext& c) const {
    const double eps = c.gas->m_flow_small;
    T w_sum = 0.0, wt_sum = 0.0;
    const std::size_t h = vars.size() - 1;
    add_weights(y, h, eps, w_sum, wt_sum);
    r[0] = y[0] - w_sum;
    r[1] = y[h] - wt_sum;
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

// An unknown held at a constant (an unconnected input's default, an
// unconnected heat port's ambient temperature).
class FixedValueBlock final : public Block {
 public:
  double value = 0.0;
  template <class T>
  void eval(const T* y, T* r) const { r[0] = y[0] - value; }
  void residual(double, const double* y, const double*, double* r, const EvalContext&) const override { eval(y, r); }
  void residual(double, const Dual* y, const Dual*, Dual* r, const EvalContext&) const override { eval(y, r); }
  void residual(double, const Pattern* y, const Pattern*, Pattern* r, const EvalContext&) const override { eval(y, r); }
};

class RestHeatBlock final : public Block {
 public:
  double T_ambient = 0.0;
  template <class T>
  void eval(const T* y, T* r, double conductance) const { r[0] = y[0] - conductance * (T_ambient - y[1]); }
  void residual(double, const double* y, const double*, double* r, const EvalContext& c) const override {
    eval(y, r, c.rest_heat);
  }
  void residual(double, const Dual* y, const Dual*, Dual* r, const EvalContext& c) const override {
    eval(y, r, c.rest_heat);
  }
  void residual(double, const Pattern* y, const Pattern*, Pattern* r, const EvalContext& c) const override {
    eval(y, r, c.rest_heat);
  }
};

}  // namespace

std::unique_ptr<Block> make_rest_heat_block(double T_ambient) {
  auto b = std::make_unique<RestHeatBlock>();
  b->T_ambient = T_ambient;
  return b;
}
std::unique_ptr<Block> make_component_block() { return std::make_unique<ComponentBlock>(); }
std::unique_ptr<Block> make_flow_sum_block(bool total_first) { return std::make_unique<FlowSumBlock>(total_first); }
std::unique_ptr<Block> make_stream_mix_block(int ports) { return std::make_unique<StreamMixBlock>(ports); }
std::unique_ptr<Block> make_stream_sum_block() { return std::make_unique<StreamSumBlock>(); }
std::unique_ptr<Block> make_kinematic_block() { return std::make_unique<KinematicBlock>(); }
std::unique_ptr<Block> make_fixed_value_block(double value) {
  auto b = std::make_unique<FixedValueBlock>();
  b->value = value;
  return b;
}
bool is_stream_mix(const Block& b) { return dynamic_cast<const StreamMixBlock*>(&b) != nullptr; }
bool is_stream_sum(const Block& b) { return dynamic_cast<const StreamSumBlock*>(&b) != nullptr; }

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
}  // namespace pneumo
