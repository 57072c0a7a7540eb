// A check for whole-number options (threads, evaluations, points) with a
// message a user can act on: CLI::PositiveNumber printed DBL_MAX in full.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

namespace pneumo::cli {

// More threads than this is a typing error, not a machine.
inline constexpr long kMaxThreads = 4096;

// Accepts a whole number in [lo, hi], also written like 2e3; the upper bound
// keeps what the option allocates within reason.
inline CLI::Validator whole_number(long lo, long hi) {
  const std::string range = "a whole number from " + std::to_string(lo) + " to " + std::to_string(hi);
  return CLI::Validator(
      [lo, hi, range](std::string& s) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        if (s.empty() || *end != '\0' || !std::isfinite(v) || v != std::floor(v))
          return "'" + s + "' is not a whole number; give " + range;
        if (v < static_cast<double>(lo) || v > static_cast<double>(hi)) return "'" + s + "' is out of range; give " + range;
        s = std::to_string(static_cast<long>(v));
        return "";
      },
      "INT in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

}  // namespace pneumo::cli
