// Results files. A results file is either complete or absent: it is written
// to a temporary file beside the target and renamed into place only when the
// run has succeeded. A failed run removes any stale file of that name and
// leaves its data in NAME.partial.csv, whose first line says it is incomplete.
#pragma once

#include <string>
#include <vector>

#include "framework/core/units.hpp"

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
  // Removes every column whose name starts with `prefix` (hidden outputs).
  void drop_columns(const std::string& prefix);
};

// Writes `text` to PATH.writing (creating PATH's directory) and renames it
// to PATH, so that PATH is never half-written. Throws std::runtime_error
// naming the path and the reason.
void write_text_atomic(const std::string& path, const std::string& text);

// Before any work: throws std::invalid_argument if `path` cannot name an
// output file (empty, or a directory); `option` names the argument ("-o").
void check_output_file(const std::string& path, const std::string& option);

// Header "t [s],p [Pa],...". Throws std::runtime_error naming the path.
// On success also removes a stale PATH.partial.csv left by an earlier failed
// run, so that the directory never holds results from two different runs.
void write_csv_atomic(const std::string& path, const ResultsTable& table);

// The name of the partial file for results path `path`: "out.csv" ->
// "out.partial.csv", "out" -> "out.partial.csv".
std::string partial_csv_path(const std::string& path);

// For a failed run: removes `path` if present, writes PATH.partial.csv with a
// leading "# INCOMPLETE ..." comment line. Returns the partial file's path.
std::string write_partial_csv(const std::string& path, const ResultsTable& table, const std::string& reason);

// Read a CSV written by write_csv_atomic (or any numeric CSV with a header).
ResultsTable read_csv(const std::string& path);

}  // namespace pneumo
