// Isentropic flow through a convergent nozzle (orifice), paper [1] eq. 14 and
// paper [2] eq. 8-11, shared by every component that contains one.
//
//   m = Cd A p_up sqrt(2 kappa / ((kappa - 1) R T_up)) psi(r),  r = p_dn/p_up
//   psi(r) = sqrt(r^(2/kappa) - r^((kappa+1)/kappa))     r_crit < r <= r_lam
//   psi(r) = psi(r_crit)                                  r <= r_crit (choked)
//   r_crit = (2/(kappa+1))^(kappa/(kappa-1))              (0.528 for kappa 1.4)
//   psi(r_crit) = (2/(kappa+1))^(1/(kappa-1)) sqrt((kappa-1)/(kappa+1))
// (Seed 001 prints the choked value with the exponent kappa/(kappa-1); the
// value of its own subsonic formula at r_crit, which the one above is, has
// 1/(kappa-1): 0.2588 for kappa 1.4, not 0.2155.)
//
// psi has an infinite slope at r -> 1 (psi ~ sqrt((kappa-1)/kappa (1-r))), so
// the Jacobian would be singular at zero pressure drop. Above r_lam the law
// is continued by the quadratic in u = 1 - r that matches psi's value and
// slope at r_lam and is 0 at u = 0: psi = a u + c u^2 with
//   a = 2 psi_l/u_l - s,  c = (s - psi_l/u_l)/u_l,  s = dpsi/du at u_l.
// The flow is then C1 in p_dn everywhere (the subsonic law is flat at r_crit
// as well), linear through dp = 0 with slope a, and monotone (a + 2 c u > 0
// on [0, u_l] because psi is concave there).
#pragma once

#include <cmath>

#include "framework/core/smooth.hpp"
#include "framework/model/gas.hpp"

namespace pneumo::components {

struct NozzleLaw {
  double kappa, r_crit, psi_crit, r_lam, a, c;

  static double psi(double r, double kappa) {
    return std::sqrt(std::max(std::pow(r, 2.0 / kappa) - std::pow(r, (kappa + 1.0) / kappa), 0.0));
  }
  // Critical pressure ratio (2/(kappa+1))^(kappa/(kappa-1)).
  static double critical_ratio(double kappa) { return std::pow(2.0 / (kappa + 1.0), kappa / (kappa - 1.0)); }

  NozzleLaw(double kappa_, double r_lam_) : kappa(kappa_), r_lam(r_lam_) {
    r_crit = critical_ratio(kappa);
    psi_crit = psi(r_crit, kappa);
    const double psi_l = psi(r_lam, kappa);
    const double u_l = 1.0 - r_lam;
    // d psi/dr = ((2/k) r^(2/k-1) - ((k+1)/k) r^(1/k)) / (2 psi); s = -dpsi/dr
    const double dpsi_dr =
        ((2.0 / kappa) * std::pow(r_lam, 2.0 / kappa - 1.0) - ((kappa + 1.0) / kappa) * std::pow(r_lam, 1.0 / kappa)) /
        (2.0 * psi_l);
    const double s = -dpsi_dr;
    a = 2.0 * psi_l / u_l - s;
    c = (s - psi_l / u_l) / u_l;
  }

  // psi(r) for 0 < r <= 1 with the choked plateau and the C1 continuation.
  template <class T>
  T operator()(const T& r) const {
    const T rs = min(max(r, T(r_crit)), T(r_lam));
    const T subsonic = sqrt(pow(rs, 2.0 / kappa) - pow(rs, (kappa + 1.0) / kappa));
    const T u = 1.0 - r;
    const T continuation = a * u + c * u * u;
    return select(value(r) <= r_lam, subsonic, continuation);
  }
};

// Mass flow from port a to port b (negative for reverse flow) through an
// effective area Cd A (m2); T_a, T_b are the temperatures of the gas arriving
// from each side (the upstream one is used).
template <class T>
T nozzle_mass_flow(const T& p_a, const T& p_b, const T& T_a, const T& T_b, const T& CdA, const NozzleLaw& law,
                   const GasModel& gas) {
  const bool forward = value(p_a) >= value(p_b);
  const T p_up = select(forward, p_a, p_b);
  const T p_dn = select(forward, p_b, p_a);
  const T T_up = select(forward, T_a, T_b);
  const double k = gas.kappa;
  const T m = CdA * p_up * sqrt(2.0 * k / ((k - 1.0) * gas.R * T_up)) * law(T(p_dn / p_up));
  return select(forward, m, T(-m));
}

}  // namespace pneumo::components
