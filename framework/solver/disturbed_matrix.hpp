// The disturbances' share of IDA's Newton matrix. A disturbed run's
// equations are G(y, y') = F(y, y' - s(t, y, y')) (UserData::disturbed_yp): a
// shift s_u comes off the rate of unknown u - a disturbed balance, or the
// internal energy its gas's enthalpy moves - and s_u reads the state (a
// form's terms read a temperature, a speed, a pressure difference, an
// acceleration; a leak's enthalpy reads the chamber's mass and energy). So
// the matrix is
//   dG/dy + cj dG/dy' = dF/dy - dF/dy'_u ds_u/dy + cj dF/dy' (1 - ds_u/dy').
// Without the middle part a term that weighs on its balance leaves IDA's
// Newton iteration converging on a wrong matrix, at a fine step all the way
// (measured on the six-cylinder line's form search: 8-20 times the steps of
// the run without it).
#pragma once

#include <sundials/sundials_types.h>

#include <cstddef>
#include <vector>

namespace pneumo {

class DisturbedMatrix {
 public:
  // One shifted unknown and the unknowns whose values and rates its shift
  // reads (IDA's numbering).
  struct Shift {
    int unknown = -1;  // -1: a slot with no shift (a disturbance without gas energy)
    std::vector<int> reads, rate_reads;
  };

  DisturbedMatrix() = default;
  // `col_ptr`/`row_idx`: the System's pattern (CSC). The matrix's pattern
  // is that one and, for every row that reads unknown u, the columns its
  // shift reads (values or rates).
  DisturbedMatrix(const std::vector<sunindextype>& col_ptr, const std::vector<sunindextype>& row_idx,
                  const std::vector<Shift>& shifts);

  bool active() const { return !entries_[0].empty() || !entries_[1].empty(); }
  const std::vector<sunindextype>& col_ptr() const { return col_ptr_; }
  const std::vector<sunindextype>& row_idx() const { return row_idx_; }
  std::size_t nnz() const { return row_idx_.size(); }
  // The unknowns whose values' and rates' slopes assemble() needs, ascending.
  const std::vector<int>& columns() const { return columns_[0]; }
  const std::vector<int>& rate_columns() const { return columns_[1]; }

  // The System's parts (IDA's scaled columns, its pattern) into this
  // pattern, with -dF/dy'_u ds_u/dy added to dF/dy and -dF/dy'_u ds_u/dy'
  // to dF/dy'. slopes[q * n + k]: the shift in slot k (of n, the
  // constructor's order) per unit of unknown columns()[q], in SI;
  // rate_slopes the same per unit of rate_columns()[q]'s rate.
  void assemble(const double* system_dFdy, const double* system_dFdyp, const std::vector<double>& slopes,
                const std::vector<double>& rate_slopes, const std::vector<double>& nominal, double* dFdy,
                double* dFdyp) const;

 private:
  struct Entry {
    int system_at;      // (row, u) in the System's pattern: dF/dy'_u there
    int at;             // (row, column) in this pattern
    int slope;          // into slopes, or rate_slopes
    int unknown, column;
  };
  std::vector<sunindextype> col_ptr_, row_idx_;
  std::vector<int> from_system_;  // where the System's entry k is in this pattern
  std::vector<int> columns_[2];  // of values, of rates
  std::vector<Entry> entries_[2];
  int slots_ = 0;
};

}  // namespace pneumo
