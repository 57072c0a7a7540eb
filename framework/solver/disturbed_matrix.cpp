#include "framework/solver/disturbed_matrix.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <utility>

namespace pneumo {

namespace {

const std::vector<int>& read_by(const DisturbedMatrix::Shift& s, int kind) {
  return kind == 0 ? s.reads : s.rate_reads;
}

}  // namespace

DisturbedMatrix::DisturbedMatrix(const std::vector<sunindextype>& col_ptr, const std::vector<sunindextype>& row_idx,
                                 const std::vector<Shift>& shifts)
    : slots_(static_cast<int>(shifts.size())) {
  const int n = static_cast<int>(col_ptr.size()) - 1;
  std::vector<std::set<int>> rows_of(n);
  for (int c = 0; c < n; ++c)
    for (auto k = col_ptr[c]; k < col_ptr[c + 1]; ++k) rows_of[c].insert(static_cast<int>(row_idx[k]));
  const auto system_rows = rows_of;
  std::set<int> columns[2];
  for (const auto& s : shifts)
    for (int kind = 0; kind < 2 && s.unknown >= 0; ++kind)
      for (int c : read_by(s, kind)) {
        columns[kind].insert(c);
        rows_of[c].insert(system_rows[s.unknown].begin(), system_rows[s.unknown].end());
      }
  for (int kind = 0; kind < 2; ++kind) columns_[kind].assign(columns[kind].begin(), columns[kind].end());
  std::map<std::pair<int, int>, int> at;  // (row, column) -> position in this pattern
  col_ptr_.assign(1, 0);
  for (int c = 0; c < n; ++c) {
    for (int r : rows_of[c]) {
      at[{r, c}] = static_cast<int>(row_idx_.size());
      row_idx_.push_back(r);
    }
    col_ptr_.push_back(static_cast<sunindextype>(row_idx_.size()));
  }
  from_system_.resize(row_idx.size());
  for (int c = 0; c < n; ++c)
    for (auto k = col_ptr[c]; k < col_ptr[c + 1]; ++k) from_system_[k] = at.at({static_cast<int>(row_idx[k]), c});
  for (int slot = 0; slot < slots_; ++slot)
    for (int kind = 0; kind < 2 && shifts[slot].unknown >= 0; ++kind) {
      const int u = shifts[slot].unknown;
      const auto& cols = columns_[kind];
      for (int c : read_by(shifts[slot], kind)) {
        const int q = static_cast<int>(std::lower_bound(cols.begin(), cols.end(), c) - cols.begin());
        for (auto k = col_ptr[u]; k < col_ptr[u + 1]; ++k)
          entries_[kind].push_back(
              {static_cast<int>(k), at.at({static_cast<int>(row_idx[k]), c}), q * slots_ + slot, u, c});
      }
    }
}

void DisturbedMatrix::assemble(const double* system_dFdy, const double* system_dFdyp,
                               const std::vector<double>& slopes, const std::vector<double>& rate_slopes,
                               const std::vector<double>& nominal, double* dFdy, double* dFdyp) const {
  std::fill(dFdy, dFdy + nnz(), 0.0);
  std::fill(dFdyp, dFdyp + nnz(), 0.0);
  for (std::size_t k = 0; k < from_system_.size(); ++k) {
    dFdy[from_system_[k]] = system_dFdy[k];
    dFdyp[from_system_[k]] = system_dFdyp[k];
  }
  // The parts are in IDA's scaled unknowns (column c times nominal[c]):
  // dF/dy'_u is the scaled entry over nominal[u], and the shift's slope
  // per unit of column c comes in times nominal[c].
  double* part[2] = {dFdy, dFdyp};
  const std::vector<double>* slope[2] = {&slopes, &rate_slopes};
  for (int kind = 0; kind < 2; ++kind)
    for (const auto& e : entries_[kind])
      part[kind][e.at] -= system_dFdyp[e.system_at] / nominal[e.unknown] * (*slope[kind])[e.slope] * nominal[e.column];
}

}  // namespace pneumo
