// The evaluator: IDA's residual and Newton matrix. The explicitly solved
// unknowns are expanded from IDA's y first (in level order, cached for the
// last t and y); every block that has rows for IDA is evaluated with double
// numbers for the residual and with Dual numbers (one direction per unknown
// the block reads) for the Jacobian, whose explicit columns are folded in
// by the Schur complement.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "framework/assembly/evaluator.hpp"

#include "framework/assembly/blocks.hpp"

namespace pneumo {

Evaluator::Evaluator(const System& system) : s_(system), modes_(system.modes_.size(), 0.0) {
  work_.F_full.assign(s_.aliases_.n_full, 0.0);
  work_.j1_values.assign(s_.plan_.j1_row_idx.size(), 0.0);
  work_.d_values.assign(s_.plan_.d_cols.size(), 0.0);
  work_.scatter.assign(s_.n_, 0.0);
  work_.cache_y.assign(s_.n_, 0.0);
  reset_modes();
}

EvalContext Evaluator::context(bool* invalid) const {
  return {&s_.circuit_.gas, modes_.data(), invalid, rest_heat_};
}

bool Evaluator::set_resting(bool resting) {
  if (!s_.rest_heat_ports_) return false;
  rest_heat_ = resting ? System::kRestHeatConductance : 0.0;
  work_.cache_valid = false;  // the explicit unknowns (the ports' heat flows) change
  return true;
}

void Evaluator::block_inputs(double t, const double*& y, const double*& yp, bool read_explicit) const {
  if (s_.plan_.unknowns.empty()) return;
  if (read_explicit) {
    expand(t, y, yp);
  } else {
    for (int i = 0; i < s_.n_; ++i) {
      work_.y[s_.plan_.ida_to_m[i]] = y[i];
      work_.yp[s_.plan_.ida_to_m[i]] = yp[i];
    }
    work_.cache_valid = false;  // work_.y's states no longer match the cached expansion
  }
  y = work_.y.data();
  yp = work_.yp.data();
}

void Evaluator::load_states(const double* y, const double* yp) const {
  for (int i = 0; i < s_.n_; ++i) {
    work_.y[s_.plan_.ida_to_m[i]] = y[i];
    work_.yp[s_.plan_.ida_to_m[i]] = yp[i];
  }
  // Each explicit unknown is solved from its start value, not from the last
  // call's: the result is then a function of (t, y) alone, without rounding
  // noise from the call history (which stalled IDA's initialisation Newton
  // at rtol 1e-9); a start value also keeps blocks that read an unknown
  // before its level from seeing zero pressures.
  for (const auto& x : s_.plan_.unknowns) work_.y[x.var] = s_.plan_.m_start[x.var];
}

void Evaluator::solve_stage(double t, const Stage& stage, const EvalContext& ctx) const {
  double ly[kMaxLocal], lyp[kMaxLocal];
  for (const auto& [bi, list] : stage) {
    const Block& b = *s_.blocks_[bi];
    gather(b, work_.y.data(), work_.yp.data(), ly, lyp);
    b.residual(t, ly, lyp, work_.F_full.data() + b.row0, ctx);
    for (int e : list) {
      const auto& x = s_.plan_.unknowns[e];
      work_.y[x.var] -= work_.F_full[x.row] / x.coef;
    }
  }
}

bool Evaluator::expand(double t, const double* y, const double* yp) const {
  if (work_.cache_valid && t == work_.cache_t && std::equal(y, y + s_.n_, work_.cache_y.begin())) {
    for (int i = 0; i < s_.n_; ++i) work_.yp[s_.plan_.ida_to_m[i]] = yp[i];
    return work_.cache_invalid;
  }
  load_states(y, yp);
  bool invalid = false;
  const EvalContext ctx = context(&invalid);
  for (const auto& stage : s_.plan_.stages) solve_stage(t, stage, ctx);
  std::copy_n(y, s_.n_, work_.cache_y.begin());
  work_.cache_t = t;
  work_.cache_valid = true;
  work_.cache_invalid = invalid;
  return invalid;
}

bool Evaluator::expand_part(double t, const double* y, const double* yp, const Stage& part) const {
  // The whole expansion at this point is at hand: it holds the part's values.
  if (work_.cache_valid && t == work_.cache_t && std::equal(y, y + s_.n_, work_.cache_y.begin())) return expand(t, y, yp);
  load_states(y, yp);
  bool invalid = false;
  const EvalContext ctx = context(&invalid);
  solve_stage(t, part, ctx);
  work_.cache_valid = false;  // the unknowns outside the part keep their start values
  return invalid;
}

int Evaluator::residual(double t, const double* y, const double* yp, double* F) const {
  bool invalid = false;
  EvalContext ctx = context(&invalid);
  double ly[kMaxLocal], lyp[kMaxLocal];
  const bool reduced = s_.aliases_.n_full != s_.n_;
  if (!s_.plan_.unknowns.empty()) {
    invalid = expand(t, y, yp);
    y = work_.y.data();
    yp = work_.yp.data();
  }
  // Blocks whose rows were all substituted as aliases are not evaluated:
  // their rows are identities after substitution, checked at assembly at
  // three points and times, and such a block has no discrete modes that
  // could change them. The other blocks' eliminated rows are checked here.
  double* Ff = reduced ? work_.F_full.data() : F;
  for (int bi : s_.plan_.final_blocks) {
    const Block& b = *s_.blocks_[bi];
    gather(b, y, yp, ly, lyp);
    b.residual(t, ly, lyp, Ff + b.row0, ctx);
  }
  if (reduced)
    for (const auto& [r, q] : s_.plan_.kept_full_rows) F[q] = Ff[r];
  for (int e : s_.aliases_.checked) {
    const int r = s_.aliases_.eliminated[e];
    if (std::abs(Ff[r]) > 1e-10 * s_.aliases_.eliminated_nominal[e] && std::isfinite(Ff[r])) {
      throw std::runtime_error("equation '" + s_.equation_name(r) + "', substituted as an alias at assembly, no longer holds at t = " +
                               std::to_string(t) + " (residual " + std::to_string(Ff[r]) +
                               "); a component must not change such an equation at an event");
    }
  }
  if (invalid) return 1;
  for (int i = 0; i < s_.n_; ++i)
    if (!std::isfinite(F[i])) return 1;
  return 0;
}

int Evaluator::jacobian(double t, const double* y, const double* yp, double cj, double* values) const {
  if (s_.plan_.unknowns.empty()) return jacobian_blocks(t, y, yp, cj, values);
  const bool invalid = expand(t, y, yp);
  const int flag = jacobian_blocks(t, work_.y.data(), work_.yp.data(), cj, work_.j1_values.data());
  // Adds a dF/d(column c) entry to the row being reduced (work_.scatter, over
  // IDA's columns): directly for an unknown of IDA, through dc/dy for an
  // explicit one.
  auto accumulate = [&](double a, int c) {
    if (a == 0.0) return;
    const int j = s_.plan_.of_m[c];
    if (j < 0) {
      work_.scatter[s_.plan_.m_to_ida[c]] += a;
      return;
    }
    const auto& xj = s_.plan_.unknowns[j];
    for (int k = 0; k < xj.dn; ++k) work_.scatter[s_.plan_.d_cols[xj.d0 + k]] += a * work_.d_values[xj.d0 + k];
  };
  // d var / d y_IDA of each explicit unknown, in level order:
  //   coef dvar + sum_c F_row,c dc = 0, dc of an explicit c known already.
  for (const auto& x : s_.plan_.unknowns) {
    for (int k = 0; k < x.dn; ++k) work_.scatter[s_.plan_.d_cols[x.d0 + k]] = 0.0;
    for (const auto& [p, c] : x.entries) {
      const double a = work_.j1_values[p];
      if (c == x.var) {
        if (std::abs(a - x.coef) > 1e-9 * std::abs(x.coef)) {
          throw std::runtime_error("equation '" + s_.equation_name(x.row) + "', solved explicitly at assembly (linear, dF/dy " +
                                   std::to_string(x.coef) + "), now has dF/dy " + std::to_string(a) + " at t = " +
                                   std::to_string(t) + "; assemble with eliminate_explicit = false");
        }
        continue;
      }
      accumulate(a, c);
    }
    for (int k = 0; k < x.dn; ++k) work_.d_values[x.d0 + k] = -work_.scatter[s_.plan_.d_cols[x.d0 + k]] / x.coef;
  }
  // IDA's rows: F_row,y + sum over explicit c of F_row,c dc/dy.
  std::fill(values, values + s_.nnz(), 0.0);
  for (const auto& kr : s_.plan_.kept_rows) {
    for (const auto& [c, p] : kr.out) work_.scatter[c] = 0.0;
    for (const auto& [p, c] : kr.entries) accumulate(work_.j1_values[p], c);
    for (const auto& [c, p] : kr.out) values[p] = work_.scatter[c];
  }
  return invalid || flag ? 1 : 0;
}

int Evaluator::jacobian_blocks(double t, const double* y, const double* yp, double cj, double* values) const {
  std::fill(values, values + s_.plan_.j1_row_idx.size(), 0.0);
  bool invalid = false;
  EvalContext ctx = context(&invalid);
  static thread_local std::vector<Dual> ly(kMaxLocal), lyp(kMaxLocal), r(kMaxLocal * 2);
  for (const auto& b : s_.blocks_) {
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
      if (s_.aliases_.row_of[b->row0 + k] < 0) continue;
      const Dual& f = r[k];
      const int directions = std::min(f.n, static_cast<int>(b->slot_local.size()));  // without the padding
      for (int i = 0; i < directions; ++i) {
        const double d = f.d[i];
        if (d == 0.0) continue;
        const int p = b->jac_pos[static_cast<std::size_t>(k) * nl + b->slot_local[i]];
        if (p >= 0) values[p] += d;
        else ++work_.pattern_misses;
      }
    }
  }
  return invalid ? 1 : 0;
}

int Evaluator::newton_matrix_parts(double t, const double* y, const double* yp, double* dFdy, double* dFdyp) const {
  // The explicit unknowns have no y': dF/dy' = J(cj = 1) - J(cj = 0).
  int flag = jacobian(t, y, yp, 0.0, dFdy);
  flag |= jacobian(t, y, yp, 1.0, dFdyp);
  for (long p = 0; p < s_.nnz(); ++p) dFdyp[p] -= dFdy[p];
  return flag;
}

void Evaluator::jacobian_parts(double t, const double* y, const double* yp, std::vector<double>& dFdy,
                               std::vector<double>& dFdyp) const {
  dFdy.assign(static_cast<std::size_t>(s_.n_) * s_.n_, 0.0);
  dFdyp.assign(static_cast<std::size_t>(s_.n_) * s_.n_, 0.0);
  if (!s_.plan_.unknowns.empty()) {
    std::vector<double> j0(s_.nnz()), j1(s_.nnz());
    newton_matrix_parts(t, y, yp, j0.data(), j1.data());
    for (int c = 0; c < s_.n_; ++c)
      for (long p = s_.col_ptr_[c]; p < s_.col_ptr_[c + 1]; ++p) {
        const std::size_t k = static_cast<std::size_t>(s_.row_idx_[p]) * s_.n_ + c;
        dFdy[k] = j0[p];
        dFdyp[k] = j1[p];
      }
    return;
  }
  bool invalid = false;
  EvalContext ctx = context(&invalid);
  std::vector<Dual> ly(kMaxLocal), lyp(kMaxLocal), r(kMaxLocal * 2);
  for (int part = 0; part < 2; ++part)
    for (const auto& b : s_.blocks_) {
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
        const int row = s_.aliases_.row_of[b->row0 + k];
        if (row < 0) continue;
        for (int i = 0; i < nl; ++i)
          if (b->vars[i] >= 0) out[static_cast<std::size_t>(row) * s_.n_ + b->vars[i]] += r[k].deriv(i);
      }
    }
}

}  // namespace pneumo
