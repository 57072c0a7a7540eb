// First-order sensor lag (PT1) shared by the sensors: tau y' + y = x, or
// y = x for an ideal sensor (tau = 0). A lagged output is a differential
// state and needs an initial value: the sensors take it as a parameter
// (default: the ambient value, a sensor that has been reading the
// atmosphere), because the measured quantity at t_start is only known after
// the consistent initialisation.
#pragma once

#include <string>
#include <vector>

#include "framework/model/component.hpp"

namespace pneumo::components {

template <class T>
T pt1_residual(const Eval<T>& e, int output_port, const T& measured, double tau) {
  const int o = e.port_offset(output_port);
  if (tau > 0.0) return tau * e.yp(o) + e.y(o) - measured;
  return e.y(o) - measured;
}

// Start value of a PT1 output at local offset `offset`: fixed when lagged
// (a differential state), else only a guess for the consistent initialisation
// (the output is then algebraic, y = x).
inline void pt1_start(StartValues& s, int offset, double tau, double initial) {
  if (tau > 0.0)
    s.fix_local(offset, initial);
  else
    s.guess_local(offset, initial);
}

inline ParameterSpec pt1_tau_parameter(const std::string& what) {
  return ParameterSpec::scalar("tau", "s", "time constant of the first-order lag of " + what + " (0 = ideal)", 0.0)
      .non_negative();
}

// A sensor's calibration fault (diagnosis): it reads gain x + offset. At the
// nulls (1, 0) the reading is x itself, bit for bit.
struct SensorCalibration {
  double gain = 1.0, offset = 0.0;
  explicit SensorCalibration(const ParameterValues& p) : gain(p["fault_gain"]), offset(p["fault_offset"]) {}
  template <class T>
  T reading(const T& x) const {
    return gain * x + offset;
  }
  // Its parameters, `unit` the reading's.
  static std::vector<ParameterSpec> parameters(const std::string& unit) {
    return {ParameterSpec::scalar("fault_gain", "1", "fault (diagnosis): gain error of the reading; 1 = none", 1.0),
            ParameterSpec::scalar("fault_offset", unit, "fault (diagnosis): zero offset of the reading; 0 = none", 0.0)};
  }
  // Offset, gain and lag faults; `span` a plausible offset bound in `unit`.
  static std::vector<FaultSpec> faults(const std::string& unit, double span) {
    return {{"offset", "zero offset of the reading (transducer drift, wrong zero)",
             {{"offset", "fault_offset", unit, false, 0.0, -span, span, 0.1 * span, false}}},
            {"gain", "gain error of the reading (transducer calibration)",
             {{"gain", "fault_gain", "1", false, 1.0, 0.8, 1.25, 1.02, false}}},
            {"lag", "slow reading (first-order lag, e.g. a long tube or a damped transducer)",
             {{"tau", "tau", "s", false, 0.0, 0.0, 0.1, 0.01, false}}}};
  }
};

}  // namespace pneumo::components
