// The diagnosis's and the calibration's JSON reports write numbers and
// strings the same way: non-finite numbers as null (JSON has no NaN), six
// significant digits, strings escaped on one line.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

namespace pneumo::diagnose::json {

inline std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

inline std::string str(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\', o += c;
    else if (c == '\n') o += "\\n";
    else if (static_cast<unsigned char>(c) < 0x20) o += ' ';
    else o += c;
  }
  return o + "\"";
}

}  // namespace pneumo::diagnose::json
