#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include "framework/assembly/blocks.hpp"
#include "framework/assembly/system.hpp"

namespace pneumo {

// Structure at the alias-reduced level, per kept row q: its y and y'
// dependencies, the unknowns it depends on nonlinearly, dF/dy per unknown
// and whether that stayed the same nonzero number at every check point.
struct ExplicitRows {
  std::vector<std::set<int>> dy, dyp, nonlin;
  std::vector<std::map<int, double>> coef;
  std::vector<std::map<int, char>> coef_const;
  std::vector<int> full_row, row_block;
  std::vector<char> candidate;
  const std::vector<double>* id = nullptr;  // differential flags (alias level)

  bool usable(int q, int v) const {
    if (!candidate[q] || (*id)[v] != 0.0 || nonlin[q].count(v)) return false;
    auto it = coef_const[q].find(v);
    return it != coef_const[q].end() && it->second;
  }
};

// Which row gives which unknown, at which level; `used` rows give one.
struct ExplicitOrder {
  std::vector<char> known, used;
  std::vector<int> level;
  std::vector<int> order_var, order_row;
};

namespace {

// Forward propagation from the known unknowns: a row whose unknowns but one
// are known gives that one. Returns how many it solved; `record` keeps
// the order and levels.
int propagate(const ExplicitRows& rows, ExplicitOrder& o, std::vector<char>& known, std::vector<char>& used,
              bool record) {
  const int m = static_cast<int>(rows.dy.size());
  int solved = 0;
  for (bool progress = true; progress;) {
    progress = false;
    for (int q = 0; q < m; ++q) {
      if (!rows.candidate[q] || used[q]) continue;
      int unknown = -1, count = 0, lvl = 0;
      for (int v : rows.dy[q]) {
        if (!known[v]) unknown = v, ++count;
        else lvl = std::max(lvl, o.level[v]);
      }
      if (count != 1 || !rows.usable(q, unknown)) continue;
      known[unknown] = 1;
      used[q] = 1;
      ++solved;
      progress = true;
      if (!record) continue;
      o.level[unknown] = lvl + 1;
      o.order_var.push_back(unknown);
      o.order_row.push_back(q);
    }
  }
  return solved;
}

// The unknown to tear when propagation is stuck (it stays with IDA): the
// one whose tearing lets the most rows be solved, preferring one that no
// row gives explicitly; -1 when all are known.
int tear(const ExplicitRows& rows, ExplicitOrder& o) {
  const int m = static_cast<int>(rows.dy.size());
  int best = -1;
  long best_score = -1;
  for (int v = 0; v < m; ++v) {
    if (o.known[v]) continue;
    bool explicit_somewhere = false;
    int count = 0;
    for (int q = 0; q < m; ++q) {
      if (o.used[q] || !rows.dy[q].count(v)) continue;
      ++count;
      explicit_somewhere |= rows.usable(q, v);
    }
    auto kn = o.known;
    auto us = o.used;
    kn[v] = 1;
    const long unlocked = propagate(rows, o, kn, us, false);
    const long score = unlocked * 1000000L + (explicit_somewhere ? 0 : 1000) + count;
    if (score > best_score) best = v, best_score = score;
  }
  return best;
}

ExplicitOrder choose_explicit(const ExplicitRows& rows) {
  const int m = static_cast<int>(rows.dy.size());
  ExplicitOrder o;
  o.known.assign(m, 0);
  o.used.assign(m, 0);
  o.level.assign(m, 0);
  for (int v = 0; v < m; ++v) o.known[v] = (*rows.id)[v] != 0.0;
  // An unknown no row gives explicitly (a mixing temperature, a pressure
  // between two throttles) stays with IDA whatever is torn: torn first, it
  // unlocks its rows before the greedy tear below spends a tear on an
  // unknown that a row could have given (a hose's flow at a junction).
  std::vector<char> explicit_somewhere(m, 0);
  for (int q = 0; q < m; ++q)
    for (int v : rows.dy[q]) explicit_somewhere[v] |= rows.usable(q, v);
  for (int v = 0; v < m; ++v) o.known[v] |= !explicit_somewhere[v];
  for (;;) {
    propagate(rows, o, o.known, o.used, true);
    const int best = tear(rows, o);
    if (best < 0) break;
    o.known[best] = 1;  // torn: level 0, an unknown of IDA
  }
  return o;
}

}  // namespace

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
  ExplicitRows rows = explicit_rows();
  const ExplicitOrder order = choose_explicit(rows);
  // Nothing to do - or everything: a circuit without states (sources and
  // flow elements only) keeps its unknowns, IDA needs at least one.
  if (order.order_var.empty() || static_cast<int>(order.order_var.size()) == m) return;
  const std::vector<int> ida_row_of_m = number_explicit(rows, order);
  const std::vector<double> id = schur_pattern(rows, order, ida_row_of_m);
  plan_stages(rows, order);
  // IDA-level names, start values, scales.
  std::vector<std::string> names;
  std::vector<double> start, nominal;
  std::vector<unsigned char> kind;
  std::vector<char> junction;
  for (int v : plan_.ida_to_m) {
    names.push_back(var_names_[v]);
    start.push_back(start_value_[v]);
    kind.push_back(start_kind_[v]);
    junction.push_back(junction_[v]);
    nominal.push_back(nominal_[v]);
  }
  plan_.m_start = start_value_;
  plan_.m_names = var_names_;
  var_names_ = std::move(names);
  start_value_ = std::move(start);
  start_kind_ = std::move(kind);
  junction_ = std::move(junction);
  nominal_ = std::move(nominal);
  id_ = id;
  n_ = static_cast<int>(plan_.ida_to_m.size());
  find_root_inputs();
}

ExplicitRows System::explicit_rows() const {
  const int m = n_;
  ExplicitRows rows;
  rows.dy.assign(m, {});
  rows.dyp.assign(m, {});
  rows.nonlin.assign(m, {});
  rows.coef.assign(m, {});
  rows.coef_const.assign(m, {});
  rows.full_row.assign(m, -1);
  rows.row_block.assign(m, -1);
  rows.id = &id_;
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi) {
    const Block& b = *blocks_[bi];
    for (int k = 0; k < b.n_rows; ++k) {
      const int q = aliases_.row_of[b.row0 + k];
      if (q < 0) continue;
      rows.full_row[q] = b.row0 + k;
      rows.row_block[q] = static_cast<int>(bi);
    }
  }
  constexpr double kCheckTimes[3] = {0.0, 0.3711, 97.13};
  std::mt19937 rng(24680);
  bool invalid = false;
  EvalContext ctx{&circuit_.gas, modes_.data(), &invalid, rest_heat_};
  std::vector<Pattern> pr;
  std::vector<Dual> dr;
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<double> y0, yp0;
    check_point(pass, rng, y0, yp0);
    for (const auto& bp : blocks_) {
      if (bp->all_eliminated) continue;
      evaluate_structure(*bp, kCheckTimes[pass], y0.data(), yp0.data(), ctx, pr, dr);
      for (int k = 0; k < bp->n_rows; ++k) {
        const int q = aliases_.row_of[bp->row0 + k];
        if (q >= 0) record_row(*bp, pr[k], dr[k], pass, rows, q);
      }
    }
  }
  rows.candidate.assign(m, 0);
  for (int q = 0; q < m; ++q) {
    if (rows.row_block[q] < 0 || !rows.dyp[q].empty() || rows.dy[q].empty()) continue;
    // The mixed temperature at a node of three or more ports stays an
    // unknown of IDA: computed from the flows, its steep weights near zero
    // flow stalled the consistent-initialisation Newton on the flows.
    if (is_stream_mix(*blocks_[rows.row_block[q]])) continue;
    rows.candidate[q] = 1;
  }
  return rows;
}

// One row of block b (its Pattern and Dual values) at one check point, into
// the row structure of alias-level row q.
void System::record_row(const Block& b, const Pattern& p, const Dual& d, int pass, ExplicitRows& rows,
                        int q) const {
  const int nl = static_cast<int>(b.vars.size());
  std::map<int, double> c;
  for (int i = 0; i < nl; ++i) {
    const int g = b.vars[i];
    if (g < 0) continue;
    if (p.deps.test(i)) rows.dy[q].insert(g);
    if (p.nonlin.test(i)) rows.nonlin[q].insert(g);
    if (p.deps.test(kMaxLocal + i)) rows.dyp[q].insert(g);
    c[g] += d.deriv(i);
  }
  for (const auto& [g, v] : c) {
    if (pass == 0) {
      rows.coef[q][g] = v;
      rows.coef_const[q][g] = std::isfinite(v) && v != 0.0;
    } else if (v != rows.coef[q][g]) {
      rows.coef_const[q][g] = 0;
    }
  }
}

// The explicit unknowns in level order (stable), IDA's unknowns (the
// others) and rows (those that give none). Returns IDA's row of each
// alias-level row, -1 if it gives an explicit unknown.
std::vector<int> System::number_explicit(const ExplicitRows& rows, const ExplicitOrder& o) {
  const int m = n_;
  std::vector<int> idx(o.order_var.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::stable_sort(idx.begin(), idx.end(),
                   [&](int a, int b) { return o.level[o.order_var[a]] < o.level[o.order_var[b]]; });
  plan_.of_m.assign(m, -1);
  for (int a : idx) {
    ExplicitUnknown x;
    x.var = o.order_var[a];
    x.row = rows.full_row[o.order_row[a]];
    x.coef = rows.coef[o.order_row[a]].at(x.var);
    x.level = o.level[x.var];
    x.deps.assign(rows.dy[o.order_row[a]].begin(), rows.dy[o.order_row[a]].end());
    plan_.of_m[x.var] = static_cast<int>(plan_.unknowns.size());
    plan_.unknowns.push_back(std::move(x));
  }
  plan_.m_to_ida.assign(m, -1);
  plan_.ida_to_m.clear();
  for (int v = 0; v < m; ++v)
    if (plan_.of_m[v] < 0) {
      plan_.m_to_ida[v] = static_cast<int>(plan_.ida_to_m.size());
      plan_.ida_to_m.push_back(v);
    }
  const int n = static_cast<int>(plan_.ida_to_m.size());
  std::vector<int> ida_row_of_m(m, -1);
  int count = 0;
  for (int q = 0; q < m; ++q)
    if (!o.used[q]) ida_row_of_m[q] = count++;
  if (count != n)
    throw StructureError("internal error: explicit elimination left " + std::to_string(count) + " equations for " +
                         std::to_string(n) + " unknowns");
  plan_.ida_row_of_full.assign(aliases_.n_full, -1);
  for (int r = 0; r < aliases_.n_full; ++r)
    if (aliases_.row_of[r] >= 0) plan_.ida_row_of_full[r] = ida_row_of_m[aliases_.row_of[r]];
  return ida_row_of_m;
}

// Symbolic Schur complement: the columns d var / d y_IDA of each explicit
// unknown may have, and IDA's pattern. Returns IDA's differential flags.
std::vector<double> System::schur_pattern(const ExplicitRows& rows, const ExplicitOrder& o,
                                          const std::vector<int>& ida_row_of_m) {
  const int m = n_;
  const int n = static_cast<int>(plan_.ida_to_m.size());
  // Rows of the alias-level Jacobian, by row.
  std::vector<std::vector<std::pair<long, int>>> j1_rows(m);
  for (int c = 0; c < m; ++c)
    for (long p = plan_.j1_col_ptr[c]; p < plan_.j1_col_ptr[c + 1]; ++p) j1_rows[plan_.j1_row_idx[p]].push_back({p, c});
  std::vector<std::vector<int>> d_pattern(plan_.unknowns.size());
  // IDA's columns a row reaches through its entries (as accumulate() in
  // jacobian()), leaving out column `skip`.
  auto ida_columns = [&](const std::vector<std::pair<long, int>>& entries, int skip) {
    std::set<int> cols;
    for (const auto& [p, c] : entries) {
      if (c == skip) continue;
      const int j = plan_.of_m[c];
      if (j >= 0) cols.insert(d_pattern[j].begin(), d_pattern[j].end());
      else cols.insert(plan_.m_to_ida[c]);
    }
    return cols;
  };
  plan_.d_cols.clear();
  for (std::size_t e = 0; e < plan_.unknowns.size(); ++e) {
    auto& x = plan_.unknowns[e];
    x.entries = j1_rows[aliases_.row_of[x.row]];
    const std::set<int> cols = ida_columns(x.entries, x.var);
    d_pattern[e].assign(cols.begin(), cols.end());
    x.d0 = static_cast<int>(plan_.d_cols.size());
    x.dn = static_cast<int>(cols.size());
    plan_.d_cols.insert(plan_.d_cols.end(), cols.begin(), cols.end());
  }
  std::vector<std::set<int>> cols(n);  // IDA pattern: column -> rows
  std::vector<std::vector<int>> kept_cols(m);
  std::vector<double> id(n, 0.0);
  for (int q = 0; q < m; ++q) {
    if (o.used[q]) continue;
    const std::set<int> cs = ida_columns(j1_rows[q], -1);
    for (int c : cs) cols[c].insert(ida_row_of_m[q]);
    kept_cols[q].assign(cs.begin(), cs.end());
    for (int v : rows.dyp[q]) id[plan_.m_to_ida[v]] = 1.0;
  }
  const auto pos = compress_columns(cols, col_ptr_, row_idx_);
  plan_.kept_rows.clear();
  for (int q = 0; q < m; ++q) {
    if (o.used[q]) continue;
    KeptRow k;
    k.row = rows.full_row[q];
    k.entries = j1_rows[q];
    for (int c : kept_cols[q]) k.out.push_back({c, pos.at({ida_row_of_m[q], c})});
    plan_.kept_rows.push_back(std::move(k));
  }
  return id;
}

// Evaluation plan: per level the blocks giving its unknowns; at the end
// the blocks with rows for IDA.
void System::plan_stages(const ExplicitRows& rows, const ExplicitOrder& o) {
  const int m = n_;
  int max_level = 0;
  for (const auto& x : plan_.unknowns) max_level = std::max(max_level, x.level);
  plan_.stages.assign(max_level, {});
  std::vector<char> keeps(blocks_.size(), 0);
  for (std::size_t e = 0; e < plan_.unknowns.size(); ++e) {
    const int bi = rows.row_block[aliases_.row_of[plan_.unknowns[e].row]];
    auto& stage = plan_.stages[plan_.unknowns[e].level - 1];
    auto it = std::find_if(stage.begin(), stage.end(), [&](const auto& s) { return s.first == bi; });
    if (it == stage.end()) stage.push_back({bi, {static_cast<int>(e)}});
    else it->second.push_back(static_cast<int>(e));
  }
  for (int q = 0; q < m; ++q)
    if (!o.used[q] && rows.row_block[q] >= 0) keeps[rows.row_block[q]] = 1;
  plan_.final_blocks.clear();
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi)
    if (keeps[bi]) plan_.final_blocks.push_back(static_cast<int>(bi));
}

// Root functions usually read a position, a time or a command. IDA's root
// checks (one per step and per output) solve only the explicit unknowns
// they read, with those these depend on (plan_.root_stages): a valve's
// command, not the circuit's flows; none, and no expand(), when roots read
// states alone.
void System::find_root_inputs() {
  std::vector<char> needed(plan_.unknowns.size(), 0);
  std::vector<int> work;
  auto need = [&](int e) {
    if (e < 0 || needed[e]) return;
    needed[e] = 1;
    work.push_back(e);
  };
  for (std::size_t bi = 0; bi < blocks_.size(); ++bi)
    for (int e : explicit_root_inputs(*blocks_[bi])) need(e);
  plan_.any_roots_read_explicit = !work.empty();
  while (!work.empty()) {
    const int e = work.back();
    work.pop_back();
    for (int v : plan_.unknowns[e].deps) need(plan_.of_m[v]);
  }
  plan_.root_stages.clear();
  for (const auto& stage : plan_.stages)
    for (const auto& [bi, list] : stage) {
      std::vector<int> part;
      std::copy_if(list.begin(), list.end(), std::back_inserter(part), [&](int e) { return needed[e] != 0; });
      if (!part.empty()) plan_.root_stages.push_back({bi, std::move(part)});
    }
}

std::vector<int> System::explicit_root_inputs(const Block& b) const {
  std::vector<int> out;
  if (!b.component || b.component->info().roots == 0) return out;
  bool invalid = false;
  std::vector<double> g(b.component->info().roots);
  // The three points' locals, drawn once: every unknown is poisoned at the
  // same points.
  double points[3][kMaxLocal], lyp[kMaxLocal];
  std::mt19937 rng(13579);
  for (int pass = 0; pass < 3; ++pass) poisoned_locals(b, pass, rng, false, false, points[pass], lyp);
  double ly[kMaxLocal];
  for (std::size_t i = 0; i < b.vars.size(); ++i) {
    const int v = b.vars[i];
    if (v < 0 || plan_.of_m[v] < 0) continue;
    bool reads = false;
    for (int pass = 0; pass < 3 && !reads; ++pass) {
      std::copy(points[pass], points[pass] + b.vars.size(), ly);
      ly[i] = std::numeric_limits<double>::quiet_NaN();
      Eval<double> e(*b.component, 0.1 * pass, ly, lyp, modes_.data() + b.mode0, b.connected.get(), circuit_.gas,
                     &invalid);
      b.component->roots(e, g.data());
      for (double x : g) reads |= !std::isfinite(x);
    }
    if (reads) out.push_back(plan_.of_m[v]);
  }
  return out;
}

}  // namespace pneumo
