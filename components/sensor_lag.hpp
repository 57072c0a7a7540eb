// First-order sensor lag (PT1) shared by the sensors: tau y' + y = x, or
// y = x for an ideal sensor (tau = 0). A lagged output is a differential
// state and needs an initial value: the sensors take it as a parameter
// (default: the ambient value, a sensor that has been reading the
// atmosphere), because the measured quantity at t_start is only known after
// the consistent initialisation.
#pragma once

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

}  // namespace pneumo::components
