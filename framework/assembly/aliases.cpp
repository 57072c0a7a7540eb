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
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>

#include "framework/assembly/blocks.hpp"
#include "framework/assembly/system.hpp"

namespace pneumo {

namespace {

struct Candidate {
  const Block* block;
  int k;                     // local row
  std::vector<int> cols;     // 1 or 2 global columns
  std::vector<double> coef;  // dF/dy per column (first point)
  double offset = 0.0;       // F - sum coef y (first point)
  bool ok = true;
};

// Rows without y' over one or two unknowns, outside components with modes.
std::vector<Candidate> alias_candidates(const std::vector<std::unique_ptr<Block>>& blocks,
                                        const std::vector<std::vector<int>>& dep_y,
                                        const std::vector<std::vector<int>>& dep_yp, int n) {
  // The stream temperatures at a node of three or more pneumatic ports (the
  // mixed T_in and the T_out it mixes) stay unknowns of their own. Merged
  // into the classes of the components' gas temperatures they would start
  // the consistent-initialisation Newton at different temperatures; the
  // mixing weights are steep at zero flow, so the first Newton step then
  // sends the mixed temperatures to 1e5 K (three test circuits failed so).
  // Kept apart they all start at the ambient guess and that term vanishes.
  std::vector<char> is_mixed(n, 0);
  for (const auto& b : blocks)
    if (is_stream_mix(*b))
      for (std::size_t i = 0; i < b->vars.size(); i += 2) is_mixed[b->vars[i]] = 1;
  std::vector<Candidate> cand;
  for (const auto& b : blocks)
    for (int k = 0; k < b->n_rows; ++k) {
      const int r = b->row0 + k;
      const auto& cols = dep_y[r];
      if (!dep_yp[r].empty() || cols.empty() || cols.size() > 2) continue;
      if (std::any_of(cols.begin(), cols.end(), [&](int c) { return is_mixed[c]; })) continue;
      if (b->component && b->component->info().modes > 0) continue;
      cand.push_back({b.get(), k, cols, {}, 0.0, true});
    }
  return cand;
}

// A candidate at one point: its coefficients must be +-1 and the same at
// every point; with two unknowns there is no offset, with one the offset
// (the constant) is the same at every point and time.
void check_candidate(Candidate& c, const Dual& f, const std::vector<double>& y0, int pass) {
  const Block& b = *c.block;
  const int nl = static_cast<int>(b.vars.size());
  std::vector<double> coef(c.cols.size(), 0.0);
  for (int i = 0; i < nl; ++i)
    for (std::size_t j = 0; j < c.cols.size(); ++j)
      if (b.vars[i] == c.cols[j]) coef[j] += f.deriv(i);
  double offset = f.v, magnitude = std::abs(f.v);
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

}  // namespace

// Union-find with signs: y_v = sign[v] * y_parent[v]; a root may be a constant.
struct AliasClasses {
  std::vector<int> parent;
  std::vector<double> sign, value;
  std::vector<char> constant, differential;

  AliasClasses(int n, const std::vector<std::vector<int>>& dep_yp)
      : parent(n), sign(n, 1.0), value(n, 0.0), constant(n, 0), differential(n, 0) {
    std::iota(parent.begin(), parent.end(), 0);
    for (int r = 0; r < n; ++r)
      for (int c : dep_yp[r]) differential[c] = 1;
  }
  std::pair<int, double> find(int v) {
    if (parent[v] == v) return {v, 1.0};
    auto [root, s] = find(parent[v]);
    parent[v] = root;
    sign[v] *= s;
    return {root, sign[v]};
  }
  // Joins the classes a checked candidate relates; false if it cannot be
  // used (already implied, two constants, two states, a state and a constant).
  bool join(const Candidate& c) {
    if (c.cols.size() == 1) {
      const auto [ra, sa] = find(c.cols[0]);
      if (constant[ra] || differential[ra]) return false;
      constant[ra] = 1;
      value[ra] = sa * (-c.offset / c.coef[0]);
      return true;
    }
    const auto [ra, sa] = find(c.cols[0]);
    const auto [rb, sb] = find(c.cols[1]);
    if (ra == rb || (constant[ra] && constant[rb]) || (differential[ra] && differential[rb])) return false;
    if ((constant[ra] && differential[rb]) || (constant[rb] && differential[ra])) return false;
    // coef_a sa y_ra + coef_b sb y_rb = 0  =>  y_rb = q y_ra, q = +-1
    const double q = -(c.coef[0] * sa) / (c.coef[1] * sb);
    const bool keep_a = constant[ra] || (!constant[rb] && (differential[ra] || !differential[rb]));
    const int root = keep_a ? ra : rb, child = keep_a ? rb : ra;
    parent[child] = root;
    sign[child] = q;
    differential[root] |= differential[child];
    return true;
  }
};

void System::eliminate_aliases() {
  const int n = n_;
  aliases_.n_full = n;
  std::vector<Candidate> cand = alias_candidates(blocks_, dep_y_, dep_yp_, n);
  // Check linearity at the start point and two perturbed points, at three
  // far-apart times: a row that sets a variable to a function of time (a
  // source following a table) is no constant.
  constexpr double kCheckTimes[3] = {0.0, 0.3711, 97.13};
  std::mt19937 rng(54321);
  bool invalid = false;
  EvalContext ctx{&circuit_.gas, modes_.data(), &invalid, rest_heat_};
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
        b.residual(kCheckTimes[pass], ly.data(), lyp.data(), res.data(), ctx);
        evaluated = &b;
      }
      check_candidate(c, res[c.k], y0, pass);
    }
  }
  AliasClasses classes(n, dep_yp_);
  std::vector<char> eliminated(n, 0);
  for (const auto& c : cand)
    if (c.ok && classes.join(c)) eliminated[c.block->row0 + c.k] = 1;
  const std::vector<int> reduced = renumber_aliases(classes, eliminated);
  reduce_pattern(classes, reduced);
}

// The unknowns left: one per class that is no constant, with the strongest
// start value of the class and its smallest scale. Returns the new index of
// each class root (-1 for others).
std::vector<int> System::renumber_aliases(AliasClasses& classes, const std::vector<char>& eliminated) {
  const int n = n_;
  std::vector<int> reduced(n, -1);
  std::vector<std::string> names;
  std::vector<double> start, nominal;
  std::vector<unsigned char> kind;
  std::vector<char> junction;
  int m = 0;
  for (int v = 0; v < n; ++v) {
    const auto [root, s] = classes.find(v);
    if (root != v || classes.constant[v]) continue;
    reduced[v] = m++;
    names.push_back(var_names_[v]);
    start.push_back(start_value_[v]);
    kind.push_back(start_kind_[v]);
    junction.push_back(0);
    nominal.push_back(nominal_[v]);
  }
  for (int v = 0; v < n; ++v) {
    const auto [root, s] = classes.find(v);
    if (classes.constant[root]) continue;
    const int g = reduced[root];
    if (start_kind_[v] > kind[g]) {  // fixed beats guess beats none
      start[g] = s * start_value_[v];
      kind[g] = start_kind_[v];
    }
    nominal[g] = std::min(nominal[g], nominal_[v]);
    junction[g] = junction[g] || junction_[v];
  }
  aliases_.row_of.assign(n, -1);
  aliases_.eliminated.clear();
  int kept = 0;
  for (int r = 0; r < n; ++r) {
    if (eliminated[r]) aliases_.eliminated.push_back(r);
    else aliases_.row_of[r] = kept++;
  }
  if (kept != m)
    throw StructureError("internal error: alias elimination left " + std::to_string(kept) + " equations for " +
                         std::to_string(m) + " unknowns");
  aliases_.eliminated_nominal.clear();
  for (int r : aliases_.eliminated) aliases_.eliminated_nominal.push_back(nominal_[dep_y_[r][0]]);
  var_names_ = std::move(names);
  start_value_ = std::move(start);
  start_kind_ = std::move(kind);
  junction_ = std::move(junction);
  nominal_ = std::move(nominal);
  return reduced;
}

// Pattern and differential flags of the reduced system; each block's
// locals read their class root times its sign, or its constant.
void System::reduce_pattern(AliasClasses& classes, const std::vector<int>& reduced) {
  const int n = aliases_.n_full;
  const int m = static_cast<int>(var_names_.size());
  std::vector<std::set<int>> cols(m);
  std::vector<double> id(m, 0.0);
  for (int r = 0; r < n; ++r) {
    if (aliases_.row_of[r] < 0) continue;
    for (int c : dep_y_[r]) {
      const auto [root, s] = classes.find(c);
      if (!classes.constant[root]) cols[reduced[root]].insert(aliases_.row_of[r]);
    }
    for (int c : dep_yp_[r]) {
      const auto [root, s] = classes.find(c);
      if (classes.constant[root]) continue;
      cols[reduced[root]].insert(aliases_.row_of[r]);
      id[reduced[root]] = 1.0;
    }
  }
  const auto pos = compress_columns(cols, col_ptr_, row_idx_);
  for (auto& b : blocks_) {
    const int nl = static_cast<int>(b->vars.size());
    b->scale.assign(nl, 1.0);
    b->offset.assign(nl, 0.0);
    for (int i = 0; i < nl; ++i) {
      const auto [root, s] = classes.find(b->vars[i]);
      if (classes.constant[root]) {
        b->offset[i] = s * classes.value[root];
        b->vars[i] = -1;
      } else {
        b->scale[i] = s;
        b->vars[i] = reduced[root];
      }
    }
    b->jac_pos.assign(static_cast<std::size_t>(b->n_rows) * nl, -1);
    for (int k = 0; k < b->n_rows; ++k) {
      const int r = aliases_.row_of[b->row0 + k];
      if (r < 0) continue;
      for (int i = 0; i < nl; ++i) {
        if (b->vars[i] < 0) continue;
        auto it = pos.find({r, b->vars[i]});
        if (it != pos.end()) b->jac_pos[static_cast<std::size_t>(k) * nl + i] = it->second;
      }
    }
  }
  id_ = std::move(id);
  n_ = m;
}

}  // namespace pneumo
