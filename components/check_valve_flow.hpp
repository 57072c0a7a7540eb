// A spring-loaded check valve as an ISO 6358 resistance whose conductance
// opens with the pressure difference: closed below the cracking pressure
// difference, fully open (C) at cracking + ramp, in between the C1 smoothstep
// 3 x^2 - 2 x^3 of x = (dp - cracking)/ramp. The flow is therefore
// continuous with a continuous slope in both pressures (no jump at cracking,
// no kink at full opening), and exactly zero for dp <= cracking, including
// all reverse pressure differences. Shared by check_valve and
// one_way_flow_control.
#pragma once

#include "components/iso6358_flow.hpp"

namespace pneumo::components {

// Fraction of the conductance that is open, for dp = p_in - p_out.
template <class T>
T check_valve_opening(const T& dp, double cracking, double ramp) {
  const T x = min(max(T((dp - cracking) / ramp), T(0.0)), T(1.0));
  return x * x * (3.0 - 2.0 * x);
}

// Mass flow from `in` to `out` (never negative but for the leakage fraction,
// which conducts in both directions).
template <class T>
T check_valve_mass_flow(const T& p_in, const T& p_out, const T& T_in, const T& T_out, double C, double b,
                        double cracking, double ramp, double leakage, const GasModel& gas) {
  const T open = with_leakage(check_valve_opening(T(p_in - p_out), cracking, ramp), leakage);
  return iso6358_mass_flow(p_in, p_out, T_in, T_out, T(C * open), b, 0.999, gas);
}

}  // namespace pneumo::components
