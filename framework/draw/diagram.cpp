// Layout and routing of circuit diagrams (diagram.hpp says why our own).
#include "framework/draw/diagram.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <queue>
#include <set>
#include <sstream>

#include "framework/core/text.hpp"

namespace pneumo::draw {

namespace {

constexpr double kGrid = 10.0;
constexpr double kRowGap = 80.0;     // between rows: room for lines and labels
constexpr double kColumnGap = 90.0;  // between actuator columns
constexpr double kMargin = 70.0;

double snap_up(double v) { return std::ceil(v / kGrid - 1e-9) * kGrid; }

SymbolShape text_shape(double x, double y, std::string t) {
  SymbolShape s;
  s.kind = SymbolShape::Kind::text;
  s.v = {x, y};
  s.text = std::move(t);
  return s;
}

// Ports of a box: signal inputs left, signal outputs and flanges right,
// gas ports below, heat ports above.
char box_side(const PortSpec& p) {
  switch (p.domain) {
    case Domain::signal: return p.causality == Causality::input ? 'l' : 'r';
    case Domain::translational: return 'r';
    case Domain::thermal: return 't';
    case Domain::pneumatic: return 'b';
  }
  return 'b';
}

Symbol box_symbol(const ComponentInfo& info, const std::string& title, Symbol::Tier tier) {
  std::map<char, std::vector<const PortSpec*>> side;
  for (const auto& p : info.ports) side[box_side(p)].push_back(&p);
  const auto n = [&](char c) { return static_cast<double>(side[c].size()); };
  auto longest = [&](char c) {
    std::size_t m = 0;
    for (const auto* p : side[c]) m = std::max(m, p->name.size());
    return static_cast<double>(m);
  };
  Symbol s;
  s.tier = tier;
  s.title = title;
  s.height = snap_up(std::max({2.0, n('l'), n('r')}) * 20 + 20);
  s.width = snap_up(std::max({60.0, (std::max(n('b'), n('t')) + 1) * 40,
                              static_cast<double>(title.size()) * 8 + (longest('l') + longest('r')) * 6 + 24}));
  s.shapes.push_back({SymbolShape::Kind::rect, {0, 0, s.width, s.height}, "", false, false, ""});
  s.shapes.push_back(text_shape(s.width / 2, s.height / 2 + 5, title));
  for (char c : {'l', 'r', 'b', 't'}) {
    const auto& ports = side[c];
    for (std::size_t k = 0; k < ports.size(); ++k) {
      const double along = 20.0 * static_cast<double>(k + 1);
      SymbolAnchor a{ports[k]->name, 0, 0, c};
      if (c == 'l' || c == 'r') {
        a.x = c == 'l' ? 0 : s.width;
        a.y = along;
      } else {
        a.x = 40.0 * static_cast<double>(k + 1) - 20 + (s.width - 40.0 * n(c)) / 2;
        a.x = std::round(a.x / kGrid) * kGrid;
        a.y = c == 't' ? 0 : s.height;
      }
      s.anchors.push_back(a);
      SymbolShape t = text_shape(a.x + (c == 'l' ? 3 : c == 'r' ? -3 : 0),
                                 a.y + (c == 't' ? 10 : c == 'b' ? -3 : 4), ports[k]->name);
      t.dashed = true;  // marks a port name: small text
      t.filled = c == 'r';  // right aligned
      s.shapes.push_back(std::move(t));
    }
  }
  return s;
}

}  // namespace

Symbol complete_symbol(const ComponentInfo& info) {
  if (info.symbol.empty())
    return box_symbol(info, info.symbol.title.empty() ? info.type : info.symbol.title, info.symbol.tier);
  Symbol s = info.symbol;
  // Ports the symbol does not place (instance ports, heat ports) go along
  // the top edge at free grid points.
  std::set<double> used;
  for (const auto& a : s.anchors)
    if (a.side == 't') used.insert(a.x);
  double x = kGrid;
  for (const auto& p : info.ports) {
    if (s.anchor(p.name)) continue;
    while (used.count(x) && x < s.width) x += 2 * kGrid;
    if (x >= s.width) return box_symbol(info, s.title.empty() ? info.type : s.title, s.tier);
    s.anchors.push_back({p.name, x, 0, 't'});
    used.insert(x);
    x += 2 * kGrid;
  }
  // Anchors of ports this instance does not have would be dead ends.
  std::erase_if(s.anchors, [&](const SymbolAnchor& a) { return info.port_index(a.port) < 0; });
  return s;
}

namespace {

// ---------------------------------------------------------------- labels
std::string parameter_text(const Netlist& nl, const ComponentDecl& c, const std::string& name) {
  for (const auto& [key, v] : c.parameters) {
    if (key != name || v.shape != ValueDecl::Shape::scalar) continue;
    if (v.si) return key + " " + units::format_si(*v.si, {});
    if (const TopParameter* t = nl.parameter(v.text)) {
      // a netlist parameter: its value, pressures in bar (absolute) as people write them
      if (t->dim == units::dimension_of("Pa")) {
        std::ostringstream o;
        o << t->si_value / 1e5 << " bar";
        return key + " " + o.str() + " (" + v.text + ")";
      }
      return key + " " + units::format_si(t->si_value, t->dim) + " (" + v.text + ")";
    }
    return key + " " + v.text;
  }
  return "";
}

std::vector<std::string> label_of(const Netlist& nl, const ComponentDecl* decl, const std::string& name,
                                  const Symbol& s) {
  std::vector<std::string> lines{name};
  if (!decl) return lines;
  std::string params;
  for (const auto& p : s.label_parameters) {
    const std::string t = parameter_text(nl, *decl, p);
    if (t.empty()) continue;
    params += (params.empty() ? "" : ", ") + t;
  }
  if (!params.empty()) lines.push_back(params);
  return lines;
}

double label_width(const std::vector<std::string>& lines) {
  std::size_t m = 0;
  for (const auto& l : lines) m = std::max(m, l.size());
  return static_cast<double>(m) * 6.2 + 6;
}

// Whether a connected port leaves the symbol on `side`.
bool has_side(const PlacedSymbol& p, char side) {
  return std::any_of(p.symbol.anchors.begin(), p.symbol.anchors.end(),
                     [&](const SymbolAnchor& a) { return a.side == side && p.connected.count(a.port); });
}

// Labels go right of a symbol without ports on the right, else above one
// without ports on top, else below. Returns the room they take on the right.
double place_label(PlacedSymbol& p) {
  const double w = label_width(p.label);
  if (!has_side(p, 'r')) {
    p.label_x = p.x + p.symbol.width + 6;
    p.label_y = p.y + 10;
    return w + 6;
  }
  p.label_x = p.x;
  p.label_y = has_side(p, 't') ? p.y + p.symbol.height + 14
                                      : p.y - 6 - 13.0 * static_cast<double>(p.label.size() - 1);
  return std::max(0.0, w - p.symbol.width);
}

// ---------------------------------------------------------------- placement
struct Node {
  Symbol::Tier tier;
  int column = -1;
  int level = 0;
  int parent = -1;  // the node the spread along air lines reached it from
  bool placed = false;
};

class Placer {
 public:
  Placer(const Circuit& c, Diagram& d) : c_(c), d_(d), nodes_(d.symbols.size()) {
    for (std::size_t i = 0; i < nodes_.size(); ++i) nodes_[i].tier = d.symbols[i].symbol.tier;
  }

  void run() {
    assign_columns();
    place();
  }

 private:
  using Tier = Symbol::Tier;

  Domain domain_of(const Connection& k) const {
    const PortId p = k.ports.front();
    return c_.components[p.component]->info().ports[p.port].domain;
  }
  // Neighbours of component i through connections of `domain`.
  std::vector<int> neighbours(int i, Domain domain) const {
    std::vector<int> out;
    for (const auto& k : c_.connections) {
      if (domain_of(k) != domain) continue;
      bool here = false;
      for (auto p : k.ports) here |= p.component == i;
      if (!here) continue;
      for (auto p : k.ports)
        if (p.component != i) out.push_back(p.component);
    }
    return out;
  }
  bool any_neighbour(int i, int j) const {
    for (const auto& k : c_.connections) {
      bool a = false, b = false;
      for (auto p : k.ports) a |= p.component == i, b |= p.component == j;
      if (a && b) return true;
    }
    return false;
  }

  bool is_air_line(int i) const {
    const Tier t = nodes_[i].tier;
    return t == Tier::valve || t == Tier::line || t == Tier::other || t == Tier::actuator;
  }

  // BFS along air lines from the column heads; supply and exhaust stop it.
  void spread(std::vector<int> heads) {
    std::queue<int> q;
    for (int h : heads) q.push(h);
    while (!q.empty()) {
      const int i = q.front();
      q.pop();
      for (int j : neighbours(i, Domain::pneumatic)) {
        // Reached as near through a valve and through something else: it
        // lies between the actuator and the valve, not beyond the valve.
        Node& nj = nodes_[j];
        if (nj.column == nodes_[i].column && nj.level == nodes_[i].level + 1 && nj.parent >= 0 &&
            nodes_[nj.parent].tier == Tier::valve && nodes_[i].tier != Tier::valve)
          nj.parent = i;
        if (nodes_[j].column >= 0 || !is_air_line(j)) continue;
        nodes_[j].column = nodes_[i].column;
        nodes_[j].level = nodes_[i].level + 1;
        nodes_[j].parent = i;
        q.push(j);
      }
    }
  }

  int distance_from_supply(int target) const {
    std::vector<int> dist(nodes_.size(), -1);
    std::queue<int> q;
    for (std::size_t i = 0; i < nodes_.size(); ++i)
      if (nodes_[i].tier == Tier::supply) dist[i] = 0, q.push(static_cast<int>(i));
    while (!q.empty()) {
      const int i = q.front();
      q.pop();
      for (int j : neighbours(i, Domain::pneumatic))
        if (dist[j] < 0) dist[j] = dist[i] + 1, q.push(j);
    }
    return dist[target];
  }

  // ISO 1219-2: energy flows bottom to top, so an actuator's directional
  // valve sits at the foot of its column, beneath the flow controls, lines
  // and hoses between them - however many of those one path holds.
  // What lies beyond the valve (a silencer on its exhaust) stays beneath it.
  void valves_at_the_bottom() {
    auto valve_above = [&](int i) {
      for (int a = nodes_[i].parent; a >= 0; a = nodes_[a].parent)
        if (nodes_[a].tier == Tier::valve) return a;
      return -1;
    };
    std::map<int, int> deepest;
    for (std::size_t i = 0; i < nodes_.size(); ++i)
      if (nodes_[i].column >= 0 && valve_above(static_cast<int>(i)) < 0)
        deepest[nodes_[i].column] = std::max(deepest[nodes_[i].column], nodes_[i].level);
    std::vector<int> level(nodes_.size());
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      const Node& n = nodes_[i];
      const int v = valve_above(static_cast<int>(i));
      const bool valve = n.tier == Tier::valve && v < 0 && n.level > 0;
      level[i] = valve ? deepest[n.column] + 1
                 : v >= 0 && nodes_[v].level > 0 ? deepest[n.column] + 1 + (n.level - nodes_[v].level)
                                                 : n.level;
    }
    for (std::size_t i = 0; i < nodes_.size(); ++i) nodes_[i].level = level[i];
  }

  void assign_columns() {
    std::vector<int> heads;
    for (std::size_t i = 0; i < nodes_.size(); ++i)
      if (nodes_[i].tier == Tier::actuator) {
        nodes_[i].column = columns_++;
        heads.push_back(static_cast<int>(i));
      }
    spread(heads);
    valves_at_the_bottom();
    // Circuits (or parts) without an actuator: the component farthest from
    // the supply heads a column (a tank being filled).
    for (;;) {
      int best = -1, best_d = -2;
      for (std::size_t i = 0; i < nodes_.size(); ++i) {
        if (nodes_[i].column >= 0 || !is_air_line(static_cast<int>(i))) continue;
        if (neighbours(static_cast<int>(i), Domain::pneumatic).empty()) continue;
        const int d = distance_from_supply(static_cast<int>(i));
        if (d > best_d) best_d = d, best = static_cast<int>(i);
      }
      if (best < 0) break;
      nodes_[best].column = columns_++;
      nodes_[best].level = 0;
      spread({best});
    }
    // Sensors and the mechanical side at their actuator; the rest beside
    // what it is connected to.
    for (int pass = 0; pass < 3; ++pass)
      for (std::size_t i = 0; i < nodes_.size(); ++i) {
        Node& n = nodes_[i];
        if (n.column >= 0 || n.tier == Tier::supply || n.tier == Tier::signal) continue;
        for (std::size_t j = 0; j < nodes_.size(); ++j) {
          if (i == j || nodes_[j].column < 0 || !any_neighbour(static_cast<int>(i), static_cast<int>(j))) continue;
          if (nodes_[j].tier == Tier::sensor && n.tier != Tier::sensor) continue;
          n.column = nodes_[j].column;
          n.level = n.tier == Tier::sensor ? nodes_[j].level - 1 : nodes_[j].level;
          break;
        }
      }
    for (auto& n : nodes_)
      if (n.column < 0 && n.tier != Tier::supply && n.tier != Tier::signal) {
        n.column = columns_++;  // on its own
        n.level = 0;
      }
  }

  // Where component i's anchors would like it: the mean, over its
  // connections to placed components, of (their anchor - its own anchor).
  std::optional<double> desired_x(int i) const {
    double sum = 0;
    int n = 0;
    for (const auto& k : c_.connections) {
      const PortId* mine = nullptr;
      for (const auto& p : k.ports)
        if (p.component == i) mine = &p;
      if (!mine) continue;
      const auto& me = d_.symbols[i];
      const double own = me.symbol.anchor(c_.components[i]->info().ports[mine->port].name)->x;
      for (const auto& p : k.ports) {
        if (p.component == i || !nodes_[p.component].placed) continue;
        const auto& other = d_.symbols[p.component];
        const double ax = other.x + other.symbol.anchor(c_.components[p.component]->info().ports[p.port].name)->x;
        sum += ax - own;
        ++n;
      }
    }
    if (n == 0) return std::nullopt;
    return sum / n;
  }

  // Places `row` (indices) left to right from `left`, each as near its
  // desired x as the ones before allow; returns the right edge used.
  double place_row(std::vector<int> row, double left, double y) {
    std::vector<std::pair<double, int>> order;
    for (std::size_t k = 0; k < row.size(); ++k) {
      const auto want = desired_x(row[k]);
      // the actuator heads its row, what it moves follows
      const double first = nodes_[row[k]].tier == Tier::actuator ? -1e-2 : 0.0;
      order.push_back({want ? *want : left + first + 1e-3 * static_cast<double>(k), row[k]});
    }
    std::stable_sort(order.begin(), order.end());
    double x = left, right = left;
    for (auto [want, i] : order) {
      auto& s = d_.symbols[i];
      s.x = std::max(x, std::round(want / kGrid) * kGrid);
      s.x = std::round(s.x / kGrid) * kGrid;
      s.y = y;
      nodes_[i].placed = true;
      const double room = place_label(s);
      x = snap_up(s.x + s.symbol.width + room + 30);
      right = std::max(right, s.x + s.symbol.width + room);
    }
    return right;
  }

  void place() {
    int lo = 0, hi = 0;
    for (const auto& n : nodes_)
      if (n.column >= 0) lo = std::min(lo, n.level), hi = std::max(hi, n.level);
    // Row tops: sensors (-1) first, then level 0 (actuators) downward.
    std::map<int, double> row_y, row_h;
    for (std::size_t i = 0; i < nodes_.size(); ++i)
      if (nodes_[i].column >= 0)
        row_h[nodes_[i].level] = std::max(row_h[nodes_[i].level], d_.symbols[i].symbol.height);
    double y = kMargin + 20;
    for (int l = lo; l <= hi; ++l) {
      row_y[l] = y;
      y = snap_up(y + row_h[l] + kRowGap);
    }
    const double bottom_y = y;

    // Signal logic: a column on the left.
    double x_signal = kMargin, sy = kMargin + 20, signal_right = 0;
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      if (nodes_[i].tier != Tier::signal) continue;
      auto& s = d_.symbols[i];
      s.x = x_signal;
      s.y = sy;
      nodes_[i].placed = true;
      s.label_x = s.x;
      s.label_y = s.y - 6;
      signal_right = std::max(signal_right, s.x + std::max(s.symbol.width, label_width(s.label)));
      sy = snap_up(sy + s.symbol.height + 50);
    }
    double left = signal_right > 0 ? snap_up(signal_right + 110) : kMargin;

    for (int c = 0; c < columns_; ++c) {
      double right = left;
      // Level 0 first (the head), then down the column, then the sensors.
      std::vector<int> levels;
      for (int l = 0; l <= hi; ++l) levels.push_back(l);
      for (int l = -1; l >= lo; --l) levels.push_back(l);
      for (int l : levels) {
        std::vector<int> row;
        for (std::size_t i = 0; i < nodes_.size(); ++i)
          if (nodes_[i].column == c && nodes_[i].level == l) row.push_back(static_cast<int>(i));
        if (row.empty()) continue;
        double start = left;
        if (l < 0) {  // sensors over the actuator's rod end
          for (int i : row)
            if (nodes_[i].tier == Tier::sensor)
              for (std::size_t j = 0; j < nodes_.size(); ++j)
                if (nodes_[j].tier == Tier::actuator && nodes_[j].column == c)
                  start = std::max(start, d_.symbols[j].x + 110);
        }
        right = std::max(right, place_row(row, start, row_y[l] + (row_h[l] - max_height(row))));
      }
      left = snap_up(right + kColumnGap);
    }
    // Supply and exhaust: the bottom row, under what they feed.
    std::vector<int> bottom;
    for (std::size_t i = 0; i < nodes_.size(); ++i)
      if (!nodes_[i].placed) bottom.push_back(static_cast<int>(i));
    place_row(bottom, kMargin + (signal_right > 0 ? signal_right + 110 - kMargin : 0), bottom_y);
  }

  double max_height(const std::vector<int>& row) const {
    double h = 0;
    for (int i : row) h = std::max(h, d_.symbols[i].symbol.height);
    return h;
  }

  const Circuit& c_;
  Diagram& d_;
  std::vector<Node> nodes_;
  int columns_ = 0;
};

// ---------------------------------------------------------------- routing
class Router {
 public:
  explicit Router(Diagram& d) : d_(d) {
    double x1 = 0, y1 = 0;
    for (const auto& s : d.symbols) {
      x1 = std::max({x1, s.x + s.symbol.width, s.label_x + label_width(s.label)});
      y1 = std::max(y1, s.y + s.symbol.height + 13.0 * static_cast<double>(s.label.size()) + 14);
    }
    nx_ = static_cast<int>(std::ceil((x1 + kMargin) / kGrid)) + 1;
    ny_ = static_cast<int>(std::ceil((y1 + kMargin) / kGrid)) + 1;
    d.width = (nx_ - 1) * kGrid;
    d.height = (ny_ - 1) * kGrid;
    const std::size_t n = static_cast<std::size_t>(nx_) * ny_;
    blocked_.assign(n, false);
    cost_.assign(n, 0);
    owner_.assign(n, -1);
    use_[0].assign(n, -1);
    use_[1].assign(n, -1);
    for (const auto& s : d.symbols) {
      const int gx0 = gi(s.x), gy0 = gi(s.y), gx1 = gi(s.x + s.symbol.width), gy1 = gi(s.y + s.symbol.height);
      for (int gy = gy0 - 1; gy <= gy1 + 1; ++gy)
        for (int gx = gx0 - 1; gx <= gx1 + 1; ++gx) {
          if (!inside(gx, gy)) continue;
          if (gx >= gx0 && gx <= gx1 && gy >= gy0 && gy <= gy1)
            blocked_[at(gx, gy)] = true;
          else
            cost_[at(gx, gy)] += 3;  // keep lines off the symbols' edges
        }
      // labels: lines may cross them, at a price
      const double lw = label_width(s.label), lh = 13.0 * static_cast<double>(s.label.size());
      for (int gy = gi(s.label_y - 10); gy <= gi(s.label_y + lh - 8); ++gy)
        for (int gx = gi(s.label_x); gx <= gi(s.label_x + lw); ++gx)
          if (inside(gx, gy)) cost_[at(gx, gy)] += 6;
    }
  }

  void route_all(const Circuit& c) {
    // Short nets first: they get the straight lines.
    std::vector<std::pair<double, int>> order;
    for (std::size_t k = 0; k < d_.wires.size(); ++k) {
      double x0 = 1e18, x1 = -1e18, y0 = 1e18, y1 = -1e18;
      for (const auto& e : d_.wires[k].ends) {
        auto [x, y, side] = anchor(e);
        (void)side;
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
      const double pneumatic_first = d_.wires[k].domain == "pneumatic" ? 0 : 1e6;
      order.push_back({pneumatic_first + (x1 - x0) + (y1 - y0), static_cast<int>(k)});
      for (const auto& e : d_.wires[k].ends) {
        auto [x, y, side] = anchor(e);
        (void)side;
        owner_[at(gi(x), gi(y))] = static_cast<int>(k);
        blocked_[at(gi(x), gi(y))] = false;
      }
    }
    (void)c;
    for (std::size_t k = 0; k < d_.wires.size(); ++k)
      if (!d_.wires[k].reference.empty()) stubs(static_cast<int>(k));
    std::sort(order.begin(), order.end());
    for (auto [len, k] : order)
      if (d_.wires[k].reference.empty()) route(k);
  }

 private:
  struct Anchor {
    double x, y;
    char side;
  };
  Anchor anchor(const WireEnd& e) const {
    const auto& s = d_.symbols[e.symbol];
    const SymbolAnchor* a = s.symbol.anchor(e.port);
    return {s.x + a->x, s.y + a->y, a->side};
  }
  int gi(double v) const { return static_cast<int>(std::lround(v / kGrid)); }
  bool inside(int gx, int gy) const { return gx >= 0 && gy >= 0 && gx < nx_ && gy < ny_; }
  std::size_t at(int gx, int gy) const { return static_cast<std::size_t>(gy) * nx_ + gx; }

  static constexpr int kDx[4] = {1, 0, -1, 0};
  static constexpr int kDy[4] = {0, 1, 0, -1};
  static int orient(int dir) { return dir % 2; }  // 0 horizontal, 1 vertical
  static int dir_of(char side) { return side == 'r' ? 0 : side == 'b' ? 1 : side == 'l' ? 2 : 3; }

  bool free_for(std::size_t p, int o, int net) const { return use_[o][p] < 0 || use_[o][p] == net; }
  bool foreign(std::size_t p, int net) const { return !free_for(p, 0, net) || !free_for(p, 1, net); }

  // Dijkstra from `from` (leaving in direction `dir0`) to any point of
  // `targets`; returns the path (grid points) or empty.
  std::vector<std::size_t> search(int net, std::size_t from, int dir0, const std::set<std::size_t>& targets) {
    const std::size_t n = blocked_.size() * 4;
    std::vector<double> dist(n, 1e18);
    std::vector<std::size_t> prev(n, SIZE_MAX);
    using Item = std::pair<double, std::size_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> q;
    const std::size_t s0 = from * 4 + dir0;
    dist[s0] = 0;
    q.push({0, s0});
    while (!q.empty()) {
      auto [dcur, s] = q.top();
      q.pop();
      if (dcur > dist[s]) continue;
      const std::size_t p = s / 4;
      const int din = static_cast<int>(s % 4);
      if (p != from && targets.count(p)) {
        std::vector<std::size_t> path;
        for (std::size_t t = s; t != SIZE_MAX; t = prev[t]) path.push_back(t / 4);
        std::reverse(path.begin(), path.end());
        return path;
      }
      const int px = static_cast<int>(p % nx_), py = static_cast<int>(p / nx_);
      for (int d = 0; d < 4; ++d) {
        if (d == (din + 2) % 4) continue;
        if (p == from && d != dir0) continue;  // leave the symbol outward
        const bool bend = d != din;
        if (bend && foreign(p, net)) continue;
        const int qx = px + kDx[d], qy = py + kDy[d];
        if (!inside(qx, qy)) continue;
        const std::size_t qp = at(qx, qy);
        if (blocked_[qp] && !(targets.count(qp) && owner_[qp] == net)) continue;
        if (owner_[qp] >= 0 && owner_[qp] != net) continue;
        const int o = orient(d);
        if (!free_for(p, o, net) || !free_for(qp, o, net)) continue;
        if (targets.count(qp) && foreign(qp, net)) continue;
        double step = 1 + cost_[qp] + (bend ? 4 : 0);
        if (!free_for(qp, 1 - o, net)) step += 10;  // a crossing
        const std::size_t t = qp * 4 + d;
        if (dist[s] + step < dist[t]) {
          dist[t] = dist[s] + step;
          prev[t] = s;
          q.push({dist[t], t});
        }
      }
    }
    return {};
  }

  void commit(int net, const std::vector<std::size_t>& path, std::set<std::size_t>& tree,
              std::set<std::pair<std::size_t, std::size_t>>& edges) {
    for (std::size_t k = 0; k < path.size(); ++k) {
      tree.insert(path[k]);
      if (k + 1 < path.size()) edges.insert(std::minmax(path[k], path[k + 1]));
      const bool straight_h = k > 0 && k + 1 < path.size() && path[k - 1] / nx_ == path[k + 1] / nx_;
      const bool straight_v = k > 0 && k + 1 < path.size() && path[k - 1] % nx_ == path[k + 1] % nx_;
      if (!straight_v) use_[0][path[k]] = net;
      if (!straight_h) use_[1][path[k]] = net;
    }
  }

  // A reference: from each port a stub kStub cells outward, its text beyond;
  // the cells are the net's, so no other line runs along them.
  static constexpr int kStub = 2;
  void stubs(int k) {
    Wire& w = d_.wires[k];
    for (const auto& e : w.ends) {
      const Anchor a = anchor(e);
      const int dir = dir_of(a.side), gx = gi(a.x), gy = gi(a.y);
      for (int s = 0; s <= kStub; ++s)
        if (inside(gx + s * kDx[dir], gy + s * kDy[dir]))
          use_[0][at(gx + s * kDx[dir], gy + s * kDy[dir])] = use_[1][at(gx + s * kDx[dir], gy + s * kDy[dir])] = k;
      const double x1 = a.x + kStub * kGrid * kDx[dir], y1 = a.y + kStub * kGrid * kDy[dir];
      w.segments.push_back({a.x, a.y, x1, y1});
      w.reference_labels.push_back({x1, y1, static_cast<double>(a.side)});
    }
  }

  void route(int k) {
    Wire& w = d_.wires[k];
    std::set<std::size_t> tree;
    std::set<std::pair<std::size_t, std::size_t>> edges;
    std::vector<bool> done(w.ends.size(), false);
    const Anchor a0 = anchor(w.ends[0]);
    tree.insert(at(gi(a0.x), gi(a0.y)));
    use_[0][at(gi(a0.x), gi(a0.y))] = use_[1][at(gi(a0.x), gi(a0.y))] = k;
    done[0] = true;
    for (std::size_t round = 1; round < w.ends.size(); ++round) {
      // the nearest terminal to the tree next
      std::size_t best = 0;
      double best_d = 1e18;
      for (std::size_t e = 0; e < w.ends.size(); ++e) {
        if (done[e]) continue;
        const Anchor a = anchor(w.ends[e]);
        for (std::size_t t : tree) {
          const double dd = std::abs(a.x / kGrid - static_cast<double>(t % nx_)) +
                            std::abs(a.y / kGrid - static_cast<double>(t / nx_));
          if (dd < best_d) best_d = dd, best = e;
        }
      }
      done[best] = true;
      const Anchor a = anchor(w.ends[best]);
      const std::size_t from = at(gi(a.x), gi(a.y));
      if (tree.count(from)) continue;  // two ports on one point
      const auto path = search(k, from, dir_of(a.side), tree);
      if (path.empty()) {
        w.routed = false;
        w.segments.push_back({a.x, a.y, a0.x, a0.y});
        continue;
      }
      commit(k, path, tree, edges);
    }
    emit(w, edges);
  }

  // Unit edges to maximal straight segments; junction dots where three or
  // more edges meet.
  void emit(Wire& w, const std::set<std::pair<std::size_t, std::size_t>>& edges) {
    std::map<std::size_t, int> degree;
    for (auto [a, b] : edges) ++degree[a], ++degree[b];
    for (auto [p, deg] : degree)
      if (deg >= 3) w.junctions.push_back({static_cast<double>(p % nx_) * kGrid, static_cast<double>(p / nx_) * kGrid});
    std::set<std::pair<std::size_t, std::size_t>> left = edges;
    while (!left.empty()) {
      auto [a, b] = *left.begin();
      left.erase(left.begin());
      const bool horizontal = b == a + 1;
      const std::size_t step = horizontal ? 1 : static_cast<std::size_t>(nx_);
      while (left.count({a - step, a}) && (horizontal ? a % nx_ > 0 : a >= step)) {
        left.erase({a - step, a});
        a -= step;
      }
      while (left.count({b, b + step})) {
        left.erase({b, b + step});
        b += step;
      }
      w.segments.push_back({static_cast<double>(a % nx_) * kGrid, static_cast<double>(a / nx_) * kGrid,
                            static_cast<double>(b % nx_) * kGrid, static_cast<double>(b / nx_) * kGrid});
    }
  }

  Diagram& d_;
  int nx_ = 0, ny_ = 0;
  std::vector<bool> blocked_;
  std::vector<double> cost_;
  std::vector<int> owner_;  // the net whose anchor a point is
  std::vector<int> use_[2];  // the net running through a point horizontally / vertically
};

// Half the perimeter of the bounding box of a wire's ports (px).
double span(const Diagram& d, const Wire& w) {
  double x0 = 1e18, x1 = -1e18, y0 = 1e18, y1 = -1e18;
  for (const auto& e : w.ends) {
    const auto& s = d.symbols[e.symbol];
    const SymbolAnchor* a = s.symbol.anchor(e.port);
    x0 = std::min(x0, s.x + a->x), x1 = std::max(x1, s.x + a->x);
    y0 = std::min(y0, s.y + a->y), y1 = std::max(y1, s.y + a->y);
  }
  return (x1 - x0) + (y1 - y0);
}

// A signal's tag: the port that drives it (an output), else its first port.
std::string signal_name(const Circuit& c, const Connection& k) {
  PortId source = k.ports.front();
  for (const auto& p : k.ports)
    if (c.components[p.component]->info().ports[p.port].causality == Causality::output) source = p;
  return c.components[source.component]->name() + "." + c.components[source.component]->info().ports[source.port].name;
}

}  // namespace

Diagram layout(const Netlist& netlist, const Circuit& circuit) {
  Diagram d;
  d.title = netlist.file;
  for (const auto& comp : circuit.components) {
    PlacedSymbol p;
    p.name = comp->name();
    p.type = comp->info().type;
    p.symbol = complete_symbol(comp->info());
    const ComponentDecl* decl = netlist.component(p.name);
    p.label = label_of(netlist, decl, p.name, p.symbol);
    d.symbols.push_back(std::move(p));
  }
  for (const auto& k : circuit.connections) {
    Wire w;
    const PortId first = k.ports.front();
    w.domain = domain_name(circuit.components[first.component]->info().ports[first.port].domain);
    for (auto p : k.ports) w.ends.push_back({p.component, circuit.components[p.component]->info().ports[p.port].name});
    d.wires.push_back(std::move(w));
  }
  for (const auto& w : d.wires)
    for (const auto& e : w.ends) d.symbols[e.symbol].connected.insert(e.port);
  Placer(circuit, d).run();
  for (std::size_t k = 0; k < d.wires.size(); ++k)
    if (d.wires[k].domain == "signal" && span(d, d.wires[k]) > kReferenceLength)
      d.wires[k].reference = signal_name(circuit, circuit.connections[k]);
  Router router(d);
  router.route_all(circuit);
  return d;
}

// ---------------------------------------------------------------- SVG
namespace {

std::string num(double v) {
  std::ostringstream o;
  o << std::round(v * 100) / 100;
  return o.str();
}

void shape_svg(std::ostringstream& o, const SymbolShape& s) {
  using K = SymbolShape::Kind;
  const auto& v = s.v;
  const std::string style = std::string(s.filled ? " class=\"fill\"" : "") + (s.dashed ? " stroke-dasharray=\"4 3\"" : "");
  switch (s.kind) {
    case K::line:
      o << "<line x1=\"" << num(v[0]) << "\" y1=\"" << num(v[1]) << "\" x2=\"" << num(v[2]) << "\" y2=\"" << num(v[3])
        << "\"" << style << "/>";
      break;
    case K::arrow: {
      const double dx = v[2] - v[0], dy = v[3] - v[1], len = std::max(1e-9, std::hypot(dx, dy));
      const double ux = dx / len, uy = dy / len, h = 7, w = 3.5;
      o << "<line x1=\"" << num(v[0]) << "\" y1=\"" << num(v[1]) << "\" x2=\"" << num(v[2] - ux * h) << "\" y2=\""
        << num(v[3] - uy * h) << "\"/>";
      o << "<polygon class=\"fill\" points=\"" << num(v[2]) << "," << num(v[3]) << " " << num(v[2] - ux * h - uy * w)
        << "," << num(v[3] - uy * h + ux * w) << " " << num(v[2] - ux * h + uy * w) << "," << num(v[3] - uy * h - ux * w)
        << "\"/>";
      break;
    }
    case K::polyline:
    case K::polygon: {
      o << (s.kind == K::polygon ? "<polygon" : "<polyline") << " points=\"";
      for (std::size_t k = 0; k + 1 < v.size(); k += 2) o << (k ? " " : "") << num(v[k]) << "," << num(v[k + 1]);
      o << "\"" << style << "/>";
      break;
    }
    case K::circle:
      o << "<circle cx=\"" << num(v[0]) << "\" cy=\"" << num(v[1]) << "\" r=\"" << num(v[2]) << "\"" << style << "/>";
      break;
    case K::arc: {
      const double a0 = v[3] * M_PI / 180, a1 = v[4] * M_PI / 180;
      o << "<path d=\"M" << num(v[0] + v[2] * std::cos(a0)) << " " << num(v[1] - v[2] * std::sin(a0)) << " A"
        << num(v[2]) << " " << num(v[2]) << " 0 " << (std::fmod(v[4] - v[3] + 720, 360) > 180 ? 1 : 0) << " 0 "
        << num(v[0] + v[2] * std::cos(a1)) << " " << num(v[1] - v[2] * std::sin(a1)) << "\"" << style << "/>";
      break;
    }
    case K::rect:
      o << "<rect x=\"" << num(v[0]) << "\" y=\"" << num(v[1]) << "\" width=\"" << num(v[2]) << "\" height=\""
        << num(v[3]) << "\"" << (v.size() > 4 ? " rx=\"" + num(v[4]) + "\"" : "") << style << "/>";
      break;
    case K::text:
      // dashed marks a port name (small), filled a right-aligned one
      o << "<text x=\"" << num(v[0]) << "\" y=\"" << num(v[1]) << "\" class=\""
        << (s.dashed ? (s.filled ? "port end" : "port") : "sym") << "\">" << markup_escaped(s.text) << "</text>";
      break;
    case K::spring: {
      const double dx = v[2] - v[0], dy = v[3] - v[1], len = std::max(1e-9, std::hypot(dx, dy));
      const double nx = -dy / len * v[4], ny = dx / len * v[4];
      o << "<polyline points=\"" << num(v[0]) << "," << num(v[1]);
      const int zig = 6;
      for (int k = 1; k < zig; ++k) {
        const double f = static_cast<double>(k) / zig, sg = k % 2 ? 1 : -1;
        o << " " << num(v[0] + dx * f + sg * nx) << "," << num(v[1] + dy * f + sg * ny);
      }
      o << " " << num(v[2]) << "," << num(v[3]) << "\"/>";
      break;
    }
  }
}

}  // namespace

std::string to_svg(const Diagram& d) {
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(d.width) << "\" height=\"" << num(d.height)
    << "\" viewBox=\"0 0 " << num(d.width) << " " << num(d.height) << "\" font-family=\"DejaVu Sans, sans-serif\">\n"
    << "<style>.symbol line,.symbol polyline,.symbol polygon,.symbol circle,.symbol path,.symbol rect"
       "{fill:none;stroke:#000;stroke-width:1.3}"
       ".symbol .fill{fill:#000}.symbol circle.anchor{fill:#000;stroke:none}"
       ".lamp.lit rect{fill:#ffd200}.lamp rect.fill{fill:#fff}"
       "text{font-size:11px}text.sym{font-size:13px;text-anchor:middle}text.port{font-size:9px;fill:#333}"
       "text.port.end{text-anchor:end}text.label{paint-order:stroke;stroke:#fff;stroke-width:3px}"
       ".net line{stroke:#000;stroke-width:1.6}.net circle.junction{fill:#000}"
       ".net[data-domain=signal] line{stroke:#1a5fb4;stroke-width:1;stroke-dasharray:6 3}"
       ".net[data-domain=signal] circle.junction{fill:#1a5fb4}"
       "text.ref{font-size:9px;fill:#1a5fb4}"
       ".net[data-domain=translational] line{stroke:#666;stroke-width:1;stroke-dasharray:10 3 2 3}"
       ".net[data-domain=thermal] line{stroke:#c01c28;stroke-width:1;stroke-dasharray:2 3}"
       ".net.unrouted line{stroke:#e01b24;stroke-dasharray:3 3}</style>\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n";
  o << "<g class=\"wires\">\n";
  for (std::size_t k = 0; k < d.wires.size(); ++k) {
    const Wire& w = d.wires[k];
    std::string ports;
    for (const auto& e : w.ends) ports += (ports.empty() ? "" : " ") + d.symbols[e.symbol].name + "." + e.port;
    o << "<g class=\"net" << (w.routed ? "" : " unrouted") << (w.reference.empty() ? "" : " ref") << "\" id=\"net"
      << k << "\" data-net=\"" << k << "\" data-domain=\"" << w.domain << "\" data-ports=\"" << markup_escaped(ports) << "\""
      << (w.reference.empty() ? "" : " data-ref=\"" + markup_escaped(w.reference) + "\"") << ">";
    for (const auto& [x, y, side] : w.reference_labels) {
      const char s = static_cast<char>(side);
      const double tx = x + (s == 'r' ? 3 : s == 'l' ? -3 : 0), ty = y + (s == 'b' ? 11 : s == 't' ? -4 : 4);
      o << "<text class=\"ref\" x=\"" << num(tx) << "\" y=\"" << num(ty) << "\" text-anchor=\""
        << (s == 'r' ? "start" : s == 'l' ? "end" : "middle") << "\">" << markup_escaped(w.reference) << "</text>";
    }
    for (const auto& s : w.segments)
      o << "<line class=\"wire\" x1=\"" << num(s[0]) << "\" y1=\"" << num(s[1]) << "\" x2=\"" << num(s[2])
        << "\" y2=\"" << num(s[3]) << "\"/>";
    for (const auto& j : w.junctions)
      o << "<circle class=\"junction\" cx=\"" << num(j[0]) << "\" cy=\"" << num(j[1]) << "\" r=\"3\"/>";
    o << "</g>\n";
  }
  o << "</g>\n<g class=\"symbols\">\n";
  for (std::size_t i = 0; i < d.symbols.size(); ++i) {
    const auto& p = d.symbols[i];
    const auto& s = p.symbol;
    o << "<g class=\"symbol\" id=\"sym" << i << "\" data-name=\"" << markup_escaped(p.name) << "\" data-type=\"" << markup_escaped(p.type)
      << "\" data-x=\"" << num(p.x) << "\" data-y=\"" << num(p.y) << "\" data-w=\"" << num(s.width) << "\" data-h=\""
      << num(s.height) << "\" transform=\"translate(" << num(p.x) << "," << num(p.y) << ")\">";
    std::map<std::string, std::vector<const SymbolShape*>> parts;
    for (const auto& sh : s.shapes) {
      if (sh.part.empty())
        shape_svg(o, sh);
      else
        parts[sh.part].push_back(&sh);
    }
    for (const auto& [part, shapes] : parts) {
      o << "<g class=\"part " << markup_escaped(part) << "\" data-part=\"" << markup_escaped(part) << "\">";
      for (const auto* sh : shapes) shape_svg(o, *sh);
      o << "</g>";
    }
    for (const auto& a : s.anchors)  // a free port shows no dot
      o << "<circle class=\"anchor\" data-port=\"" << markup_escaped(a.port) << "\" cx=\"" << num(a.x) << "\" cy=\"" << num(a.y)
        << "\" r=\"" << (p.connected.empty() || p.connected.count(a.port) ? "1.5" : "0") << "\"/>";
    o << "</g>\n";
    for (std::size_t l = 0; l < p.label.size(); ++l)
      o << "<text class=\"label\" x=\"" << num(p.label_x) << "\" y=\"" << num(p.label_y + 13.0 * static_cast<double>(l))
        << "\"" << (l == 0 ? " font-weight=\"bold\"" : "") << ">" << markup_escaped(p.label[l]) << "</text>\n";
  }
  o << "</g>\n</svg>\n";
  return o.str();
}

std::string symbol_svg(const ComponentInfo& info) {
  Diagram d;
  PlacedSymbol p;
  p.name = info.type;
  p.type = info.type;
  p.symbol = complete_symbol(info);
  // room for the port names beside the anchors
  std::size_t longest = 0;
  for (const auto& a : p.symbol.anchors) longest = std::max(longest, a.port.size());
  const double margin = snap_up(static_cast<double>(longest) * 6.5 + 20);
  p.x = margin;
  p.y = 30;
  d.width = p.symbol.width + 2 * margin;
  d.height = p.symbol.height + 60;
  d.symbols.push_back(std::move(p));
  std::string svg = to_svg(d);
  // the port names outside the anchors
  std::ostringstream names;
  for (const auto& a : d.symbols[0].symbol.anchors) {
    const double x = margin + a.x + (a.side == 'l' ? -4 : a.side == 'r' ? 4 : 3);
    const double y = 30 + a.y + (a.side == 't' ? -5 : a.side == 'b' ? 12 : -3);
    names << "<text class=\"port" << (a.side == 'l' ? " end" : "") << "\" x=\"" << num(x) << "\" y=\"" << num(y)
          << "\">" << markup_escaped(a.port) << "</text>\n";
  }
  svg.insert(svg.rfind("</svg>"), names.str());
  return svg;
}

}  // namespace pneumo::draw
