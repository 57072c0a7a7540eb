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
//
// Besides the presets, `friction: custom` (and `friction_cushion: custom`)
// takes the eq. 8 coefficients from the parameters, in the form `pneumo fit
// friction -o` writes them (components/fit/friction_fit.cpp):
//   friction_pressure  none | pAB- | pAB+ | pEC (default none)
//   friction_b0, friction_FS0, friction_FC, friction_kv0   N (kv0: force at 1 m/s)
//   friction_b1, friction_FS1, friction_kv1   N/Pa (netlists write N/bar)
//   friction_vS  m/s;  friction_a  1
// and the same with the prefix friction_cushion_ for the cushioning zone.
// Absent coefficients are 0 (a: 1, vS: 1 mm/s). friction_FC and friction_vS
// mean the same everywhere - the Coulomb force and the Stribeck velocity -
// for custom (eq. 8) and for coulomb_viscous / lugre; the static force of
// lugre is friction_FS, of eq. 8 friction_FS0 + friction_FS1 p. The custom
// coefficients (and a friction_pressure other than none) are an error with a
// named preset, so that a pasted fit cannot be silently ignored.
//
// FrictionLaw (below) selects one of three models per component
// (`friction_model`), with the same parameters wherever it is used (the
// cylinder, friction_element):
//   preset:          the eq. 4/7/8 coefficient set named by `friction`;
//   coulomb_viscous: F = -(F_C tanh(v / v_reg) + d v), no sticking (a creep
//                    of speed ~ F v_reg / F_C under a force F < F_C);
//   lugre:           paper [3] eq. 8 (Canudas de Wit et al. 1995), with the
//                    bristle deflection z as an internal state:
//                      dz/dt = v - sigma0 |v| z / g(v),
//                      g(v) = F_C + (F_S - F_C) exp(-(v / v_S)^2),
//                      F = -(sigma0 z + sigma1 dz/dt + sigma2 v).
//                    Below the break-away force the body sticks: z deflects
//                    elastically (stiffness sigma0) and v decays to ~0.
//                    (The paper prints "F_s - F" in g; F_s - F_c is meant.)
#pragma once

#include <map>
#include <string>
#include <vector>

#include "framework/core/smooth.hpp"
#include "framework/model/component.hpp"

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
// The choices of `friction` / `friction_cushion`: the presets and "custom".
std::vector<std::string> friction_set_names();
// "none" | "pAB-" | "pAB+" | "pEC"; throws std::invalid_argument otherwise.
FrictionPressure friction_pressure_from_name(const std::string& name);

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

enum class FrictionModel { preset, coulomb_viscous, lugre };

// One friction law with its parameters, read from the `friction_*`
// parameters of a component (FrictionLaw::parameters() lists them).
struct FrictionLaw {
  FrictionModel model = FrictionModel::preset;
  FrictionCoefficients main, cushion;  // preset: main stroke and cushioning zone
  double scale = 1.0;                  // factor on the force
  double v_reg = 1e-4, v_eps = 1e-6;   // m/s: tanh sign scale, |v| rounding
  double FC = 0, FS = 0, vS = 1e-3;    // N, N, m/s (coulomb_viscous, lugre)
  double sigma0 = 1e5, sigma1 = 300;   // N/m, N*s/m (lugre)
  double viscous = 0;                  // N*s/m: d (coulomb_viscous), sigma2 (lugre)

  // The friction_* parameter specs. `with_cushion` adds friction_cushion
  // and its custom coefficients friction_cushion_* (cylinders).
  static std::vector<ParameterSpec> parameters(bool with_cushion);
  // Throws ParameterError for inconsistent values.
  static FrictionLaw from(const ParameterValues& p);
  // The law's running friction off its data (FaultSpec). Seal wear, a dry
  // or swollen seal and a side load change the dry (Coulomb) part; the
  // lubricant's film, its viscosity and temperature the viscous part: each
  // has a factor, so that either can move alone. On a linear scale, since
  // the force is linear in both: a fit then crosses the valley where the
  // two trade off (at a steady speed they nearly do) in a Gauss-Newton
  // step, not in dozens.
  static FaultSpec running_fault() {
    return {"friction_running",
            "running friction off (seal wear, lubrication, side load): its dry (Coulomb) and its viscous part "
            "each by a factor",
            {{"k_coulomb", "friction_coulomb_scale", "1", true, 1.0, 0.25, 4.0, 1.3, false},
             {"k_viscous", "friction_viscous_scale", "1", true, 1.0, 0.25, 4.0, 1.3, false}}};
  }

  bool has_state() const { return model == FrictionModel::lugre; }

  // LuGre bristle dynamics dz/dt at speed v and deflection z.
  template <class T>
  T lugre_zdot(const T& v, const T& z) const {
    const T r = v / vS;
    const T g = FC + (FS - FC) * exp(-(r * r));
    return v - sigma0 * smooth_abs(v, v_eps) * z / g;
  }

  // Friction force (on the moving body, opposing v) of the models without
  // pressure dependence; for `preset` p_bar is the pressure of the set's
  // FrictionPressure kind (bar, gauge or difference) and `c` the set.
  template <class T>
  T force(const FrictionCoefficients& c, const T& v, const T& z, const T& p_bar) const {
    switch (model) {
      case FrictionModel::preset:
        return -scale * smooth_sign(v, v_reg) * friction_magnitude(c, smooth_abs(v, v_eps), p_bar);
      case FrictionModel::coulomb_viscous:
        return -scale * (FC * smooth_sign(v, v_reg) + viscous * v);
      case FrictionModel::lugre:
        return -scale * (sigma0 * z + sigma1 * lugre_zdot(v, z) + viscous * v);
    }
    return 0.0 * v;
  }
};

}  // namespace pneumo::components
