// Small text helpers shared by the readers of user files (measured data,
// fit data, sample lists) - whitespace trimming and field splitting - and by
// the reports that people read: numbers rounded to what they resolve.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
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
// `s` on one line: line breaks and other control characters made spaces, so
// that a name quoted in a file's comment or title cannot start a new line.
inline std::string one_line(std::string s) {
  for (auto& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  return s;
}

// `s` as XML, SVG or HTML text or attribute value: the markup characters
// as entities, control characters (which XML 1.0 does not allow) as spaces.
inline std::string markup_escaped(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += static_cast<unsigned char>(c) < 0x20 ? ' ' : c;
    }
  }
  return out;
}

inline std::vector<std::string> split_trimmed(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::stringstream ss(s);
  while (std::getline(ss, item, sep)) out.push_back(trim(item));
  if (!s.empty() && s.back() == sep) out.push_back("");
  return out;
}

// `v` rounded to `n` significant digits, in plain notation where that stays
// short (210, 0.0042), else in exponent form (1.5e-07); "-" when not finite.
inline std::string rounded(double v, int n) {
  if (!std::isfinite(v)) return "-";
  if (v == 0) return "0";
  const int e = static_cast<int>(std::floor(std::log10(std::fabs(v))));
  char buf[48];
  if (e < -4 || e >= 7) {
    std::snprintf(buf, sizeof buf, "%.*g", n, v);
  } else {
    const double q = std::pow(10.0, e - n + 1);
    std::snprintf(buf, sizeof buf, "%.*f", std::max(0, n - 1 - e), std::round(v / q) * q);
  }
  return buf;
}

}  // namespace pneumo
