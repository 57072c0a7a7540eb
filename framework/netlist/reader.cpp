#include "framework/netlist/reader.hpp"

#include <numeric>

namespace pneumo::netlist_detail {

namespace {

// Edit distance, for "did you mean" hints.
std::size_t distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  std::iota(prev.begin(), prev.end(), 0);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

}  // namespace


std::string join(const std::vector<std::string>& v, const std::string& sep) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
  return s;
}

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

std::string column_name_problem(const std::string& name) {
  if (name.empty()) return "is empty";
  for (const char c : name) {
    if (c == ',') return "contains a comma";
    if (c == '"') return "contains a double quote";
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return "contains a control character (a line break or tab)";
  }
  return "";
}

std::string choices_hint(const std::string& given, const std::vector<std::string>& valid) {
  std::string best;
  std::size_t best_d = 3;
  for (const auto& v : valid) {
    const auto d = distance(given, v);
    if (d < best_d) best_d = d, best = v;
  }
  std::string s;
  if (!best.empty()) s = "did you mean '" + best + "'? ";
  return s + "valid: " + (valid.empty() ? std::string("none") : join(valid));
}

}  // namespace pneumo::netlist_detail
