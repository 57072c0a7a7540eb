#include "framework/diagnose/data_spec.hpp"

#include <algorithm>
#include <stdexcept>

#include "framework/netlist/yaml_location.hpp"

namespace pneumo::diagnose {

namespace {

bool is_number(const std::string& s) {
  return !s.empty() && s.size() < 6 && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

double number_of(const std::string& file, const YAML::Node& n, const std::string& what) {
  const std::string s = plain_text(file, n, "", what, "'" + what + "'");
  try {
    std::size_t used = 0;
    const double v = std::stod(s, &used);
    if (used == s.size()) return v;
  } catch (const std::exception&) {
  }
  throw InputError(location_of(file, n), "", what, what + ": '" + s + "' is not a number");
}

DataColumnSpec column_from_yaml(const std::string& file, const std::string& name, const YAML::Node& n) {
  const SourceLocation at = location_of(file, n);
  if (!n.IsMap())
    throw InputError(at, "", name, "column '" + name + "': write {column: NUMBER or HEADER NAME, unit: UNIT}");
  DataColumnSpec c;
  c.name = name;
  for (auto it = n.begin(); it != n.end(); ++it) {
    const std::string k = plain_text(file, it->first, "", "", "a key");
    if (k == "column") {
      const std::string v = plain_text(file, it->second, "", "column", "'column'");
      if (is_number(v)) c.number = std::stoi(v);
      else c.header_name = v;
      if (is_number(v) && c.number < 1)
        throw InputError(location_of(file, it->second), "", name, "column numbers start at 1");
    } else if (k == "unit") {
      c.unit = plain_text(file, it->second, "", "unit", "'unit'");
    } else if (k == "scale") {
      c.scale = number_of(file, it->second, "scale");
    } else if (k == "offset") {
      c.offset = number_of(file, it->second, "offset");
    } else if (k == "median" || k == "average") {
      const double v = number_of(file, it->second, k);
      if (const std::string why = window_problem(v); !why.empty())
        throw InputError(location_of(file, it->second), "", name, "column '" + name + "': " + k + ": " + why);
      (k == "median" ? c.median : c.average) = static_cast<int>(v);
    } else {
      throw InputError(location_of(file, it->first), "", k,
                       "column '" + name + "': unknown key '" + k + "' (column, unit, scale, offset, median, average)");
    }
  }
  if (c.number == 0 && c.header_name.empty())
    throw InputError(at, "", name, "column '" + name + "': missing 'column: NUMBER or HEADER NAME'");
  return c;
}

}  // namespace

DataFileSpec data_spec_from_yaml(const std::string& file, const YAML::Node& node) {
  DataFileSpec s;
  s.described_at = location_of(file, node);
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string k = plain_text(file, it->first, "", "", "a key");
    const SourceLocation at = location_of(file, it->second);
    const auto text = [&] { return plain_text(file, it->second, "", k, "'" + k + "'"); };
    try {
      if (k == "file") {
        s.file = text();
      } else if (k == "separator") {
        s.separator = parse_data_separator(text());
      } else if (k == "header") {
        const std::string v = text();
        if (v != "yes" && v != "no" && v != "true" && v != "false")
          throw std::invalid_argument("header: write yes or no, not '" + v + "'");
        s.header = v == "yes" || v == "true";
      } else if (k == "skip_rows") {
        const double v = number_of(file, it->second, "skip_rows");
        if (v < 0 || v != static_cast<int>(v)) throw std::invalid_argument("skip_rows: a whole number >= 0");
        s.skip_rows = static_cast<int>(v);
      } else if (k == "decimal") {
        s.decimal = parse_number_mark(text(), false);
      } else if (k == "thousands") {
        s.thousands = parse_number_mark(text(), true);
      } else if (k == "columns") {
        if (!it->second.IsMap())
          throw std::invalid_argument("columns maps pneumo's names to {column: ..., unit: ...}");
        for (auto c = it->second.begin(); c != it->second.end(); ++c)
          s.columns.push_back(column_from_yaml(file, plain_text(file, c->first, "", "", "a column's name"), c->second));
      } else {
        throw InputError(location_of(file, it->first), "", k,
                         "unknown key '" + k +
                             "' of a data description (file, separator, header, skip_rows, decimal, thousands, "
                             "columns)");
      }
    } catch (const std::invalid_argument& e) {
      throw InputError(at, "", k, e.what());
    }
  }
  if (s.file.empty()) throw InputError(s.described_at, "", "file", "the data description needs 'file: NAME'");
  if (s.decimal == s.thousands && s.thousands == ',')
    throw InputError(s.described_at, "", "thousands", "',' as both decimal mark and thousands separator is ambiguous");
  return s;
}

}  // namespace pneumo::diagnose
