// Builders for the fault modes components declare (FaultSpec in
// framework/model/component.hpp), so that a describe() lists them like a
// maintenance table.
#pragma once

#include <string>
#include <vector>

#include "framework/model/component.hpp"

namespace pneumo::components {

// A factor on the instance's own value of `parameter` (null 1): a throttle
// misadjusted or clogged, a mass or volume off its data sheet.
inline FaultParameterSpec fault_factor(const std::string& parameter, double lower, double upper, double initial) {
  return {"k", parameter, "1", true, 1.0, lower, upper, initial, true};
}

// An amount of a fault-only parameter whose null is 0 (a leak's conductance,
// a delay, an offset): the range [lower, upper] in the parameter's unit.
inline FaultParameterSpec fault_amount(const std::string& name, const std::string& parameter, const std::string& unit,
                                       double lower, double upper, double initial) {
  return {name, parameter, unit, false, 0.0, lower, upper, initial, false};
}

inline FaultSpec fault(std::string name, std::string description, std::vector<FaultParameterSpec> parameters) {
  return {std::move(name), std::move(description), std::move(parameters)};
}

// A hand-set value off its setting (FaultSpec::setting): a needle turned, a
// knob, a dial, a set screw.
inline FaultSpec setting_fault(std::string name, std::string description, std::vector<FaultParameterSpec> parameters) {
  FaultSpec f = fault(std::move(name), std::move(description), std::move(parameters));
  f.setting = true;
  return f;
}

// A fault-only parameter the equations read; its default is the null (0).
inline ParameterSpec fault_parameter(const std::string& name, const std::string& unit, const std::string& what) {
  return ParameterSpec::scalar(name, unit, "fault (diagnosis): " + what + "; 0 = none", 0.0);
}

// A throttling line (ISO 6358: 1/C and its critical ratio) that exists only
// as a fault, as a supply's sag and a restricted line write it: the two
// parameters (`what`: where the line sits; `that`: how b names it) and the
// fault's amount, 0-2e9 Pa*s/m3.
inline std::vector<ParameterSpec> line_restriction_parameters(const std::string& what, const std::string& that) {
  return {fault_parameter("fault_line_restriction", "Pa*s/m3",
                          "1/C of " + what + " (ISO 6358, critical ratio fault_line_b): write e.g. 2 s*bar/dm3 for a "
                          "line of C = 0.5 dm3/(s*bar)")
              .non_negative(),
          ParameterSpec::scalar("fault_line_b", "1", "critical pressure ratio of " + that, 0.3).range(0.0, 0.99)};
}
inline FaultParameterSpec line_restriction_amount() {
  return fault_amount("r", "fault_line_restriction", "Pa*s/m3", 0.0, 2e9, 2e8);
}

}  // namespace pneumo::components
