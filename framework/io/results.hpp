// Results files. A results file is either complete or untouched: it is
// written through framework/io/files (a temporary beside the target, renamed
// into place only when the run has succeeded). A failed run leaves the target
// as it was and its rows in NAME.partial.csv, whose first line says it is
// incomplete.
#pragma once

#include <string>
#include <vector>

#include "framework/core/units.hpp"
#include "framework/io/files.hpp"

namespace pneumo {

struct ResultsTable {
  std::vector<std::string> names;  // first column is always "t"
  std::vector<std::string> units;
  // Per column (or empty): the unit files show instead of units[i]; the
  // rows stay SI.
  std::vector<units::DisplayUnit> display;
  std::vector<std::vector<double>> rows;

  void add_row(std::vector<double> row) { rows.push_back(std::move(row)); }
  int column(const std::string& name) const;
  // How column i is shown: its display unit, else its SI unit as is.
  units::DisplayUnit shown_as(std::size_t i) const;
  // Removes every column whose name starts with `prefix` (hidden outputs).
  void drop_columns(const std::string& prefix);
};

// Header "t [s],p [Pa],...". Throws std::runtime_error naming the path.
// On success also removes a stale PATH.partial.csv that an earlier failed run
// of pneumo left, so that the directory never holds results of two runs.
void write_csv_atomic(const std::string& path, const ResultsTable& table);

// The name of the partial file for results path `path`: "out.csv" ->
// "out.partial.csv", "out" -> "out.partial.csv".
std::string partial_csv_path(const std::string& path);

// Whether a first line is that of a partial file pneumo wrote.
bool is_partial_csv_header(const std::string& first_line);

// For a failed run: writes PATH.partial.csv with a leading "# INCOMPLETE ..."
// comment line, leaving PATH as it was. A PATH.partial.csv that pneumo did not
// write is not replaced: then nothing is written and "" returned. Returns the
// partial file's path.
std::string write_partial_csv(const std::string& path, const ResultsTable& table, const std::string& reason);

// Read a CSV written by write_csv_atomic (or any numeric CSV with a header).
ResultsTable read_csv(const std::string& path);

}  // namespace pneumo
