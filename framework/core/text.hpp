// Small text helpers shared by the readers of user files (measured data,
// fit data, sample lists): whitespace trimming and field splitting.
#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace pneumo {

// `s` without leading and trailing blanks, tabs and carriage returns.
inline std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}

// The fields of `s` separated by `sep`, each trimmed. A trailing separator
// gives a trailing empty field ("a,b," has three fields), so that a missing
// last value is reported as such rather than silently dropped.
inline std::vector<std::string> split_trimmed(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::stringstream ss(s);
  while (std::getline(ss, item, sep)) out.push_back(trim(item));
  if (!s.empty() && s.back() == sep) out.push_back("");
  return out;
}

}  // namespace pneumo
