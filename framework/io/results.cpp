#include "framework/io/results.hpp"

#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace pneumo {

void ResultsTable::drop_columns(const std::string& prefix) {
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i].rfind(prefix, 0) != 0) keep.push_back(i);
  if (keep.size() == names.size()) return;
  auto filter = [&](auto& v) {
    std::remove_reference_t<decltype(v)> out;
    for (std::size_t i : keep) out.push_back(v[i]);
    v = std::move(out);
  };
  const bool with_display = display.size() == names.size();
  filter(names);
  filter(units);
  if (with_display) filter(display);
  for (auto& row : rows) filter(row);
}

int ResultsTable::column(const std::string& name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

units::DisplayUnit ResultsTable::shown_as(std::size_t i) const {
  if (i < display.size() && !display[i].unit.empty()) return display[i];
  return {i < units.size() ? units[i] : "", 1.0, 0.0};
}

namespace {

void write_table(std::ostream& out, const ResultsTable& table) {
  auto shown = [&](std::size_t i) -> const units::DisplayUnit* {
    return i < table.display.size() && !table.display[i].unit.empty() ? &table.display[i] : nullptr;
  };
  for (std::size_t i = 0; i < table.names.size(); ++i) {
    out << (i ? "," : "") << table.names[i];
    const std::string unit = shown(i) ? shown(i)->unit : i < table.units.size() ? table.units[i] : "";
    if (!unit.empty()) out << " [" << unit << "]";
  }
  out << "\n";
  // Ten significant digits, the text of printf's %.10g; to_chars writes it
  // without a stream's locale machinery, several times faster (a small
  // circuit's CSV otherwise costs two thirds of its integration).
  std::string line;
  char number[32];
  for (const auto& row : table.rows) {
    line.clear();
    for (std::size_t i = 0; i < row.size(); ++i) {
      const units::DisplayUnit* d = shown(i);
      if (i) line += ',';
      const auto end = std::to_chars(number, number + sizeof number, d ? d->shown(row[i]) : row[i],
                                     std::chars_format::general, 10).ptr;
      line.append(number, end);
    }
    line += '\n';
    out << line;
  }
}

}  // namespace

void write_csv_atomic(const std::string& path, const ResultsTable& table) {
  std::ostringstream out;
  write_table(out, table);
  write_text_atomic(path, out.str());
  remove_if_ours(partial_csv_path(path), is_partial_csv_header);
}

std::string partial_csv_path(const std::string& path) {
  std::filesystem::path partial(path);
  partial.replace_extension(".partial.csv");
  return partial.string();
}

namespace {
constexpr const char* kIncomplete = "# INCOMPLETE: the run failed; ";
}

bool is_partial_csv_header(const std::string& first_line) { return first_line.rfind("# INCOMPLETE:", 0) == 0; }

std::string write_partial_csv(const std::string& path, const ResultsTable& table, const std::string& reason) {
  const std::string partial = partial_csv_path(path);
  try {
    check_chosen_output_file(partial, "", {}, is_partial_csv_header);
  } catch (const std::invalid_argument&) {
    return "";
  }
  std::string one_line = reason;
  for (auto& ch : one_line)
    if (ch == '\n' || ch == '\r') ch = ' ';
  std::ostringstream out;
  out << kIncomplete << one_line << "\n";
  write_table(out, table);
  try {
    write_text_atomic(partial, out.str());
  } catch (const std::exception&) {
    return "";
  }
  return partial;
}

ResultsTable read_csv(const std::string& path) {
  check_input_file(path, "results file");
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open '" + path + "'");
  ResultsTable t;
  std::string line;
  int line_no = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    if (!header) {
      while (std::getline(ss, cell, ',')) {
        std::string unit;
        const auto open = cell.find(" [");
        if (open != std::string::npos && cell.back() == ']') {
          unit = cell.substr(open + 2, cell.size() - open - 3);
          cell = cell.substr(0, open);
        }
        t.names.push_back(cell);
        t.units.push_back(unit);
      }
      header = true;
      continue;
    }
    std::vector<double> row;
    while (std::getline(ss, cell, ',')) {
      try {
        std::size_t used = 0;
        row.push_back(std::stod(cell, &used));
      } catch (const std::exception&) {
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": not a number: '" + cell + "'");
      }
    }
    if (row.size() != t.names.size())
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected " +
                               std::to_string(t.names.size()) + " values, found " + std::to_string(row.size()));
    t.rows.push_back(std::move(row));
  }
  if (!header) throw std::runtime_error(path + ": no header line");
  return t;
}

}  // namespace pneumo
