// Piston friction laws of seed paper 000 (eq. 4, 7, 8) in one general form,
// with the paper's fitted coefficient sets (Annex A-C) as named presets.
//
//   |F| = b0 + b1 p + (FS0 + FS1 p - FC) exp(-|v|/vS) + (kv0 + kv1 p) |v|^a
//
// eq. 4 (Stribeck + k_p p):   b0 = FC, b1 = k_p, FS1 = kv1 = 0
// eq. 7 (modified Stribeck):  b0 = b,  b1 = FS1 = kv1 = 0, no pressure
// eq. 8 (pressure-linearised eq. 7): all coefficients
// The pressure p is, in bar (the unit of the paper's coefficients):
//   pAB-: |p_A - p_B|; pAB+: (p_A - p_amb) + (p_B - p_amb); pEC: p_EC - p_amb.
// (The paper's coefficient units are N/bar_rel, so the summed and cushion
// pressures are taken as gauge pressures - our reading, stated here.)
// The force opposes the motion: F = -sign(v) |F|, with sign regularised as
// tanh(v / v_reg) and |v| as sqrt(v^2 + v_eps^2) so that |v|^a (a < 1) has a
// finite slope at rest. Both scales are parameters of the cylinder.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "framework/core/smooth.hpp"

namespace pneumo::components {

enum class FrictionPressure { none, ab_minus, ab_plus, ec };

struct FrictionCoefficients {
  double b0 = 0, b1 = 0;    // N, N/bar
  double FS0 = 0, FS1 = 0;  // N, N/bar
  double FC = 0;            // N
  double vS = 1e-3;         // m/s
  double kv0 = 0, kv1 = 0;  // kg/s (N s/m^a strictly), per bar
  double a = 1;             // -
  FrictionPressure pressure = FrictionPressure::none;
};

// Named presets: "annexA_pAB-", "annexA_pAB+", "annexB_2.07" ... "annexB_8.075"
// (p0 in bar_rel), "annexC_pAB-", "annexC_pAB+", "annexC_pEC", and "none".
const std::map<std::string, FrictionCoefficients>& friction_presets();
std::vector<std::string> friction_preset_names();

// Magnitude |F| (N) at speed |v| and pressure p (bar).
template <class T>
T friction_magnitude(const FrictionCoefficients& c, const T& abs_v, const T& p_bar) {
  return c.b0 + c.b1 * p_bar + (c.FS0 + c.FS1 * p_bar - c.FC) * exp(-abs_v / c.vS) +
         (c.kv0 + c.kv1 * p_bar) * pow(abs_v, c.a);
}

// Friction force on the piston (opposing v), N.
template <class T>
T friction_force(const FrictionCoefficients& c, const T& v, const T& p_A, const T& p_B, const T& p_EC,
                 double p_ambient, double v_reg, double v_eps) {
  T p_bar = 0.0 * v;
  switch (c.pressure) {
    case FrictionPressure::none: break;
    case FrictionPressure::ab_minus: p_bar = smooth_abs(T(p_A - p_B), 1.0) / 1e5; break;
    case FrictionPressure::ab_plus: p_bar = (p_A + p_B - 2.0 * p_ambient) / 1e5; break;
    case FrictionPressure::ec: p_bar = (p_EC - p_ambient) / 1e5; break;
  }
  const T abs_v = smooth_abs(v, v_eps);
  return -smooth_sign(v, v_reg) * friction_magnitude(c, abs_v, p_bar);
}

}  // namespace pneumo::components
