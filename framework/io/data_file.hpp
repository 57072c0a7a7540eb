// A lab data file as it comes off the rig, described instead of converted by
// hand: which separator (comma, semicolon, tab or any whitespace), whether
// the first row after `skip_rows` is a header, the decimal mark and the
// thousands separator of its numbers, and for each column the program uses
// its number (1-based) or header name and its unit. A column written in
// volts by a linear sensor gives `scale` (and `offset`): the value is
// (number * scale + offset) in `unit`. Values come out in SI.
//
// A column may be read through a running median of `median` samples (odd):
// it removes outliers of up to (median - 1) / 2 consecutive samples - a
// laser's dropouts, a sensor's spikes - and leaves every monotone stretch
// exactly as measured (the middle of a sorted window is its middle sample),
// so a replayed position keeps its ramps and loses only its spikes; turning
// points are flattened by at most the travel within half the window.
// Then `average` (odd) samples may smooth what jitters about a smooth course
// - a position read with timing jitter, whose difference quotient would
// stall and leap: each sample becomes the straight line through the samples
// centred on it, at its time (against the column named "t" when there is
// one, else the row): the moving average of evenly logged samples, and a
// ramp stays exact across a gap in the logging.
//
// When the thousands separator is the decimal mark too (files written with
// "151.203.000" for 151203.000 ms), the last mark of a number is the decimal
// one and the others group thousands; every group must have three digits,
// so a number read with the wrong description is refused, not misread.
//
// Every refusal is an InputError naming the file and line and saying what to
// change in the description.
#pragma once

#include <string>
#include <vector>

#include "framework/core/error.hpp"

namespace pneumo {

enum class DataSeparator { comma, semicolon, tab, whitespace };

struct DataColumnSpec {
  std::string name;         // the quantity's name in pneumo ("t", "s", "F", ...)
  int number = 0;           // 1-based column number; 0: chosen by header_name
  std::string header_name;  // the column's header cell (files with a header)
  std::string unit;         // unit of number*scale+offset: "ms", "mm", "bar g", "N", "" = SI
  double scale = 1.0;       // e.g. N per V for a raw load-cell voltage
  double offset = 0.0;      // in `unit`
  int median = 1;           // running median window in samples (odd; 1 = as measured)
  int average = 1;          // then a centred running line over this many samples (odd; 1 = none)
};

struct DataFileSpec {
  std::string file;
  DataSeparator separator = DataSeparator::comma;
  bool header = true;   // the first row read is a header of column names
  int skip_rows = 0;    // lines dropped at the top of the file (before the header)
  char decimal = '.';
  char thousands = 0;   // 0: none
  std::vector<DataColumnSpec> columns;
  SourceLocation described_at;  // where the description was written (for its errors)
};

struct DataColumns {
  std::string file;
  std::vector<std::string> names;           // as the spec's columns
  std::vector<std::vector<double>> values;  // per column, SI
  std::vector<int> lines;                   // file line of each row (1-based)

  int column(const std::string& name) const;  // index or -1
  std::size_t rows() const { return lines.size(); }
};

// "comma" | "semicolon" | "tab" | "whitespace"; throws std::invalid_argument.
DataSeparator parse_data_separator(const std::string& text);
// "." | "," | "'" | " " | "none" (thousands only) -> the mark (0 for none);
// throws std::invalid_argument.
char parse_number_mark(const std::string& text, bool allow_none);

// "" when n can be a column's median or average window (a whole odd number
// of samples from 1 to 99), else what is wrong with it.
std::string window_problem(double n);

// A number written with `decimal` and `thousands`; false if it is not one.
bool parse_lab_number(const std::string& cell, char decimal, char thousands, double& out);

// Throws InputError: no column, a column number beyond a row, a header name
// not in the header, an unknown unit, a cell that is not a finite number.
DataColumns parse_data_file(const DataFileSpec& spec, const std::string& text, double ambient_pressure_pa = 101325.0);
// Reads spec.file (a regular file only, framework/io/files.hpp).
DataColumns read_data_file(const DataFileSpec& spec, double ambient_pressure_pa = 101325.0);

}  // namespace pneumo
