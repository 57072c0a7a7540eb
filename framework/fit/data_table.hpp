// Measured data for the fitting tools: a CSV file with a header of column
// names, each optionally with its unit in brackets ("p_A [bar_rel]",
// "v [m/s]", "m_flow [g/s]"). Values are converted to SI on reading (gauge
// pressures become absolute against the ambient pressure); a column without
// a unit is taken as SI, as everywhere in pneumo. Lines starting with '#' and
// blank lines are skipped. Every error names the file and line.
#pragma once

#include <string>
#include <vector>

#include "framework/core/error.hpp"

namespace pneumo::fit {

struct DataTable {
  std::string file;
  std::vector<std::string> names;   // without the unit
  std::vector<std::string> units;   // as written ("" if none)
  std::vector<std::vector<double>> rows;  // SI values
  std::vector<int> lines;                 // file line of each row (1-based)
  int header_line = 1;

  // Index of column `name`, or -1.
  int column(const std::string& name) const;
  // Index of a column the caller needs for `purpose`; throws an InputError
  // at the header line listing the columns present.
  int require(const std::string& name, const std::string& purpose) const;
  SourceLocation where(std::size_t row) const { return {file, lines.at(row), 1}; }
};

// Throws InputError: unreadable file, no header, unknown unit, a value that
// is not a finite number (NaN included), a row with the wrong column count.
DataTable read_data_table(const std::string& path, double ambient_pressure_pa = 101325.0);
DataTable parse_data_table(const std::string& text, const std::string& file_name,
                           double ambient_pressure_pa = 101325.0);

}  // namespace pneumo::fit
