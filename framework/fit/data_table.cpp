#include "framework/fit/data_table.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "framework/core/text.hpp"
#include "framework/core/units.hpp"
#include "framework/io/files.hpp"

namespace pneumo::fit {

int DataTable::column(const std::string& name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

int DataTable::require(const std::string& name, const std::string& purpose) const {
  const int c = column(name);
  if (c >= 0) return c;
  std::string present;
  for (std::size_t i = 0; i < names.size(); ++i) present += (i ? ", " : "") + names[i];
  throw InputError(SourceLocation{file, header_line, 1}, "", "",
                   "column '" + name + "' is missing (" + purpose + "); the columns are: " + present);
}

DataTable parse_data_table(const std::string& text, const std::string& file_name, double ambient_pressure_pa) {
  DataTable t;
  t.file = file_name;
  std::vector<units::Unit> col_units;
  std::stringstream in(text);
  std::string line;
  int line_no = 0;
  bool have_header = false;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string s = trim(line);
    if (s.empty() || s[0] == '#') continue;
    const auto fields = split_trimmed(s, ',');
    if (!have_header) {
      have_header = true;
      t.header_line = line_no;
      for (const auto& f : fields) {
        std::string name = f, unit;
        if (const auto lb = f.find('['); lb != std::string::npos) {
          const auto rb = f.find(']', lb);
          if (rb == std::string::npos)
            throw InputError(SourceLocation{file_name, line_no, 1}, "", "",
                             "header field '" + f + "': unit bracket '[' is not closed");
          name = trim(f.substr(0, lb));
          unit = trim(f.substr(lb + 1, rb - lb - 1));
        }
        if (name.empty())
          throw InputError(SourceLocation{file_name, line_no, 1}, "", "", "header has an empty column name");
        if (t.column(name) >= 0)
          throw InputError(SourceLocation{file_name, line_no, 1}, "", "", "column '" + name + "' appears twice");
        try {
          col_units.push_back(units::parse_unit(unit));
        } catch (const std::exception& e) {
          throw InputError(SourceLocation{file_name, line_no, 1}, "", "",
                           "column '" + name + "': unit '" + unit + "': " + e.what());
        }
        t.names.push_back(name);
        t.units.push_back(unit);
      }
      continue;
    }
    if (fields.size() != t.names.size())
      throw InputError(SourceLocation{file_name, line_no, 1}, "", "",
                       "row has " + std::to_string(fields.size()) + " values but the header names " +
                           std::to_string(t.names.size()) + " columns");
    std::vector<double> row;
    for (std::size_t i = 0; i < fields.size(); ++i) {
      const char* begin = fields[i].c_str();
      char* end = nullptr;
      const double v = std::strtod(begin, &end);
      if (fields[i].empty() || end == begin || *end != '\0' || !std::isfinite(v))
        throw InputError(SourceLocation{file_name, line_no, 1}, "", "",
                         "column '" + t.names[i] + "': '" + fields[i] + "' is not a finite number");
      row.push_back(units::to_si(col_units[i], v, ambient_pressure_pa));
    }
    t.rows.push_back(std::move(row));
    t.lines.push_back(line_no);
  }
  if (!have_header)
    throw InputError(SourceLocation{file_name, 1, 1}, "", "", "no header line (column names) found");
  return t;
}

DataTable read_data_table(const std::string& path, double ambient_pressure_pa) {
  try {
    return parse_data_table(read_input_file(path, "data file"), path, ambient_pressure_pa);
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{path, 0, 0}, "", "", e.what());
  }
}

}  // namespace pneumo::fit
