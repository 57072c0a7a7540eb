#include "framework/io/data_file.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "framework/core/text.hpp"
#include "framework/core/units.hpp"
#include "framework/io/files.hpp"

namespace pneumo {

int DataColumns::column(const std::string& name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

DataSeparator parse_data_separator(const std::string& t) {
  if (t == "comma" || t == ",") return DataSeparator::comma;
  if (t == "semicolon" || t == ";") return DataSeparator::semicolon;
  if (t == "tab") return DataSeparator::tab;
  if (t == "whitespace") return DataSeparator::whitespace;
  throw std::invalid_argument("separator '" + t + "' is not one of: comma, semicolon, tab, whitespace");
}

char parse_number_mark(const std::string& t, bool allow_none) {
  if (allow_none && (t == "none" || t.empty())) return 0;
  if (t == "." || t == "," || t == "'" || t == " ") return t[0];
  throw std::invalid_argument("'" + t + "' is not a number mark: write \".\", \",\", \"'\"" +
                              std::string(allow_none ? ", \" \" or none" : " or \" \""));
}

namespace {

bool all_digits(const std::string& s) {
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

// Drops the thousands marks of the integer part `s`, checking that every
// group after the first has three digits.
bool ungroup(const std::string& s, char thousands, std::string& out) {
  std::size_t begin = 0;
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) out += s[0], begin = 1;
  bool first = true;
  while (true) {
    const std::size_t mark = thousands ? s.find(thousands, begin) : std::string::npos;
    const std::string group = s.substr(begin, mark == std::string::npos ? std::string::npos : mark - begin);
    if (group.empty() || !all_digits(group) || (!first && group.size() != 3) || (first && group.size() > 3 && mark != std::string::npos))
      return false;
    out += group;
    if (mark == std::string::npos) return true;
    begin = mark + 1;
    first = false;
  }
}

std::vector<std::string> split_cells(const std::string& line, DataSeparator sep) {
  if (sep == DataSeparator::whitespace) {
    std::vector<std::string> out;
    std::istringstream in(line);
    for (std::string cell; in >> cell;) out.push_back(cell);
    return out;
  }
  return split_trimmed(line, sep == DataSeparator::comma ? ',' : sep == DataSeparator::semicolon ? ';' : '\t');
}

// A cell as shown in a message: one line, at most 40 characters.
std::string shown(const std::string& cell) {
  const std::string s = one_line(cell);
  return s.size() > 40 ? s.substr(0, 40) + "..." : s;
}

std::string listed(const std::vector<std::string>& cells) {
  std::string out;
  for (const auto& c : cells) out += (out.empty() ? "" : ", ") + shown(c);
  return out;
}

// Each sample replaced by the median of the `window` samples centred on it
// (the window shrinks symmetrically at the ends).
std::vector<double> running_median(const std::vector<double>& x, int window) {
  if (window <= 1) return x;
  const std::size_t half = static_cast<std::size_t>(window / 2), n = x.size();
  std::vector<double> out(n), w;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t h = std::min({half, i, n - 1 - i});
    w.assign(x.begin() + static_cast<std::ptrdiff_t>(i - h), x.begin() + static_cast<std::ptrdiff_t>(i + h + 1));
    std::nth_element(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(h), w.end());
    out[i] = w[h];
  }
  return out;
}

// Each sample replaced by the line fitted through the `window` samples
// centred on it (shrinking symmetrically at the ends), taken at its time:
// with even sampling the window's mean; with a gap in the logging or uneven
// time stamps a ramp still stays exact.
std::vector<double> running_line(const std::vector<double>& t, const std::vector<double>& x, int window) {
  if (window <= 1) return x;
  const std::size_t half = static_cast<std::size_t>(window / 2), n = x.size();
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t h = std::min({half, i, n - 1 - i}), m = 2 * h + 1;
    double tm = 0, xm = 0;
    for (std::size_t j = i - h; j <= i + h; ++j) {
      tm += t[j] / static_cast<double>(m);
      xm += x[j] / static_cast<double>(m);
    }
    double stx = 0, stt = 0;
    for (std::size_t j = i - h; j <= i + h; ++j) {
      stx += (t[j] - tm) * (x[j] - xm);
      stt += (t[j] - tm) * (t[j] - tm);
    }
    out[i] = xm + (stt > 0 ? stx / stt * (t[i] - tm) : 0.0);
  }
  return out;
}

// Each column through its running median and line; the line follows the
// time column ("t") when the description has one, else the row.
void clean_columns(const DataFileSpec& spec, DataColumns& out) {
  std::vector<double> time;
  for (std::size_t k = 0; k < spec.columns.size(); ++k) {
    const DataColumnSpec& c = spec.columns[k];
    if (c.median > 1) out.values[k] = running_median(out.values[k], c.median);
    if (c.average <= 1) continue;
    if (time.empty()) {
      const int t = out.column("t");
      if (t >= 0) time = out.values[static_cast<std::size_t>(t)];
      for (std::size_t i = 0; t < 0 && i < out.rows(); ++i) time.push_back(static_cast<double>(i));
    }
    out.values[k] = running_line(time, out.values[k], c.average);
  }
}

}  // namespace

std::string window_problem(double n) {
  if (n >= 1 && n <= 99 && n == std::floor(n) && static_cast<int>(n) % 2 == 1) return "";
  char shown_n[32];
  std::snprintf(shown_n, sizeof shown_n, "%g", n);
  return "an odd number of samples from 1 to 99 (1 = as measured), not " + std::string(shown_n);
}

bool parse_lab_number(const std::string& cell, char decimal, char thousands, double& out) {
  if (cell.empty()) return false;
  // The decimal mark: the last one (a thousands mark equal to it groups the
  // digits before it).
  const std::size_t dot = thousands == decimal ? cell.rfind(decimal) : cell.find(decimal);
  std::string mantissa = cell, exponent;
  if (const auto e = cell.find_first_of("eE"); e != std::string::npos) {
    mantissa = cell.substr(0, e);
    exponent = cell.substr(e);
  }
  std::string integer = mantissa.substr(0, std::min(dot, mantissa.size()));
  const std::string fraction = dot < mantissa.size() ? mantissa.substr(dot + 1) : "";
  if (!all_digits(fraction) || (thousands != decimal && fraction.find(thousands) != std::string::npos)) return false;
  std::string plain;
  if (!ungroup(integer, thousands, plain)) return false;
  plain += "." + fraction + exponent;
  const char* begin = plain.c_str();
  char* end = nullptr;
  out = std::strtod(begin, &end);
  return end != begin && *end == '\0' && std::isfinite(out);
}

DataColumns parse_data_file(const DataFileSpec& spec, const std::string& text, double ambient_pressure_pa) {
  const std::string& file = spec.file;
  if (spec.columns.empty())
    throw InputError(spec.described_at, "", "columns", "the data description names no column: list the columns used");
  std::vector<units::Unit> col_units;
  for (const auto& c : spec.columns) {
    try {
      col_units.push_back(units::parse_unit(c.unit));
    } catch (const std::exception& e) {
      throw InputError(spec.described_at, "", c.name, "column '" + c.name + "': unit '" + c.unit + "': " + e.what());
    }
    for (const auto& [what, n] : {std::pair<std::string, int>{"median", c.median}, {"average", c.average}})
      if (const std::string why = window_problem(n); !why.empty())
        throw InputError(spec.described_at, "", c.name, "column '" + c.name + "': " + what + ": " + why);
    if (c.number <= 0 && (c.header_name.empty() || !spec.header))
      throw InputError(spec.described_at, "", c.name,
                       "column '" + c.name + "': give its number (1 = first)" +
                           std::string(spec.header ? " or its header name" : "; the file has no header"));
  }
  DataColumns out;
  out.file = file;
  out.values.assign(spec.columns.size(), {});
  for (const auto& c : spec.columns) out.names.push_back(c.name);
  std::vector<int> index(spec.columns.size());
  for (std::size_t k = 0; k < spec.columns.size(); ++k) index[k] = spec.columns[k].number - 1;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  bool need_header = spec.header;
  while (std::getline(in, line)) {
    ++line_no;
    if (line_no <= spec.skip_rows) continue;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string s = trim(line);
    if (s.empty() || s[0] == '#') continue;
    const auto cells = split_cells(s, spec.separator);
    const SourceLocation at{file, line_no, 1};
    if (need_header) {
      need_header = false;
      for (std::size_t k = 0; k < spec.columns.size(); ++k) {
        if (spec.columns[k].number > 0) continue;
        for (std::size_t j = 0; j < cells.size() && index[k] < 0; ++j)
          if (cells[j] == spec.columns[k].header_name) index[k] = static_cast<int>(j);
        if (index[k] < 0)
          throw InputError(at, "", spec.columns[k].name,
                           "column '" + spec.columns[k].name + "': the header has no cell '" +
                               spec.columns[k].header_name + "' (it has: " + listed(cells) + ")");
      }
      continue;
    }
    for (std::size_t k = 0; k < spec.columns.size(); ++k) {
      const auto& c = spec.columns[k];
      if (static_cast<std::size_t>(index[k]) >= cells.size())
        throw InputError(at, "", c.name,
                         "column '" + c.name + "' is column " + std::to_string(index[k] + 1) + " but the row has " +
                             std::to_string(cells.size()) + " values; check the separator and the column number");
      double v = 0;
      const std::string& cell = cells[static_cast<std::size_t>(index[k])];
      if (!parse_lab_number(cell, spec.decimal, spec.thousands, v))
        throw InputError(at, "", c.name,
                         "column '" + c.name + "': '" + shown(cell) +
                             "' is not a number with the described decimal mark '" + std::string(1, spec.decimal) +
                             "' and thousands separator " +
                             (spec.thousands ? "'" + std::string(1, spec.thousands) + "'" : std::string("none")));
      out.values[k].push_back(units::to_si(col_units[k], v * c.scale + c.offset, ambient_pressure_pa));
    }
    out.lines.push_back(line_no);
  }
  if (out.lines.empty())
    throw InputError(SourceLocation{file, line_no, 1}, "", "", "no data rows (after " +
                                                                   std::to_string(spec.skip_rows) + " skipped lines" +
                                                                   (spec.header ? " and the header)" : ")"));
  clean_columns(spec, out);
  return out;
}

DataColumns read_data_file(const DataFileSpec& spec, double ambient_pressure_pa) {
  std::string text;
  try {
    text = read_input_file(spec.file, "data file");
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{spec.file, 0, 0}, "", "", e.what());
  }
  return parse_data_file(spec, text, ambient_pressure_pa);
}

}  // namespace pneumo
