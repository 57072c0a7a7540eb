// The ISO 6358 flow law, shared by every component that contains a C-b
// resistance (throttle, valve paths, cylinder cushion throttle).
#pragma once

#include "framework/core/smooth.hpp"
#include "framework/model/gas.hpp"

namespace pneumo::components {

// Flow function phi(r) of the pressure ratio r = p_down/p_up <= 1:
//   1                                  r <= b          (choked, eq. 16)
//   sqrt(1 - ((r - b)/(1 - b))^2)      b < r <= r_lam  (subsonic, eq. 15)
//   phi(r_lam) (1 - r)/(1 - r_lam)     r > r_lam       (laminar continuation)
template <class T>
T iso6358_phi(const T& r, double b, double r_lam) {
  auto subsonic = [&] {
    const T x = (min(r, T(r_lam)) - b) / (1.0 - b);
    return sqrt(1.0 - max(x, T(0.0)) * max(x, T(0.0)));
  };
  auto laminar = [&] {
    const double x_lam = (r_lam - b) / (1.0 - b);
    const double phi_lam = std::sqrt(1.0 - x_lam * x_lam);
    return phi_lam * (1.0 - r) / (1.0 - r_lam);
  };
  return select_lazy<T>(value(r) <= r_lam, subsonic, laminar);
}

// The pressure ratio r = p_down/p_up at which the flow function is x, the
// inverse of iso6358_phi: for a flow imposed on a resistance (a supply line
// fed by a source). x >= 1 (more than the choked flow) has no ratio; past
// x_c the ratio falls on exponentially with the slope it has there, so that
// the downstream pressure, and with it the demand, falls instead of the
// equations having no solution. x < 0 (reverse flow) continues the laminar
// line above 1.
template <class T>
T iso6358_ratio_for_flow(const T& x, double b, double r_lam) {
  constexpr double x_c = 0.995;
  const double x_lam = (r_lam - b) / (1.0 - b);
  const double phi_lam = std::sqrt(1.0 - x_lam * x_lam);
  const double root_c = std::sqrt(1.0 - x_c * x_c);
  const double r_c = b + (1.0 - b) * root_c;
  const double slope_c = (1.0 - b) * x_c / root_c;  // -dr/dx at x_c
  auto laminar = [&] { return T(1.0 - x * (1.0 - r_lam) / phi_lam); };
  auto subsonic = [&] { return T(b + (1.0 - b) * sqrt(1.0 - x * x)); };
  auto beyond = [&] { return T(r_c * exp(-slope_c / r_c * (x - x_c))); };
  auto above_laminar = [&] { return select_lazy<T>(value(x) <= x_c, subsonic, beyond); };
  return select_lazy<T>(value(x) <= phi_lam, laminar, above_laminar);
}

// The open fraction of a path whose seat or spool no longer seals: the
// fraction `leakage` of its conductance open whatever `open` says.
template <class T>
T with_leakage(const T& open, double leakage) {
  return leakage + (1.0 - leakage) * open;
}

// Mass flow from port a to port b (negative for reverse flow). T_a and T_b are
// the temperatures of the gas arriving from each side (the upstream one is
// used). C in m3/(s Pa).
template <class T>
T iso6358_mass_flow(const T& p_a, const T& p_b, const T& T_a, const T& T_b, const T& C, double b, double r_lam,
                    const GasModel& gas) {
  const bool forward = value(p_a) >= value(p_b);
  const T p_up = select(forward, p_a, p_b);
  const T p_dn = select(forward, p_b, p_a);
  const T T_up = select(forward, T_a, T_b);
  const T phi = iso6358_phi(T(p_dn / p_up), b, r_lam);
  const T m = C * gas.rho_ref * p_up * sqrt(gas.T_ref / T_up) * phi;
  return select(forward, m, T(-m));
}

}  // namespace pneumo::components
