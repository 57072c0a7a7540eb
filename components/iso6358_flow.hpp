// The ISO 6358 flow law, shared by every component that contains a C-b
// resistance (throttle, valve paths, cylinder cushion throttle).
#pragma once

#include "framework/core/smooth.hpp"
#include "framework/model/gas.hpp"

namespace pneumo::components {

// Flow function phi(r) of the pressure ratio r = p_down/p_up <= 1:
//   1                                  r <= b          (choked, eq. 16)
//   sqrt(1 - ((r - b)/(1 - b))^2)      b < r <= r_lam  (subsonic, eq. 15)
//   laminar continuation               r > r_lam, u = 1 - r, u0 = 1 - r_lam:
//     phi = a u + (a - s) u^2 (u0 - u) / u0^2
// with a = phi(r_lam) / u0, the conductance at zero flow of the linear
// continuation, and s = -dphi/dr of eq. 15 at r_lam: phi and its slope are
// continuous at r_lam (s < a, so phi rises monotonically from 0). A kink
// there (the slope halves for b = 0.3) stalls Newton on a node without
// volume whose pressure settles at the kink - a valve's exhaust into a
// silencer as the flow dies away (issue 36).
template <class T>
T iso6358_phi(const T& r, double b, double r_lam) {
  const double x_lam = (r_lam - b) / (1.0 - b);
  const double phi_lam = std::sqrt(1.0 - x_lam * x_lam);
  auto subsonic = [&] {
    const T x = (min(r, T(r_lam)) - b) / (1.0 - b);
    return sqrt(1.0 - max(x, T(0.0)) * max(x, T(0.0)));
  };
  auto laminar = [&] {
    const double u0 = 1.0 - r_lam, a = phi_lam / u0;
    const double s = x_lam / ((1.0 - b) * phi_lam);
    const T u = 1.0 - r;
    return a * u + (a - s) / (u0 * u0) * u * u * (u0 - u);
  };
  return select_lazy<T>(value(r) <= r_lam, subsonic, laminar);
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
