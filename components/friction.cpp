// Coefficient sets of seed paper 000, Annex A (eq. 4), Annex B (eq. 7, one
// row per supply pressure p0 in bar_rel) and Annex C (eq. 8), as printed.
#include "components/friction.hpp"

namespace pneumo::components {

namespace {

FrictionCoefficients eq8(double b0, double b1, double FS0, double FS1, double FC, double vS, double kv0, double kv1,
                         double a, FrictionPressure p) {
  FrictionCoefficients c{b0, b1, FS0, FS1, FC, vS, kv0, kv1, a, p};
  return c;
}
// eq. 4: F = FC + k_p p + (FS - FC) exp(-|v|/vS) + kv |v|^a
FrictionCoefficients eq4(double FC, double FS, double vS, double kv, double a, double kp, FrictionPressure p) {
  return eq8(FC, kp, FS, 0, FC, vS, kv, 0, a, p);
}
// eq. 7: F = b + (FS - FC) exp(-|v|/vS) + kv |v|^a
FrictionCoefficients eq7(double b, double FS, double FC, double vS, double kv, double a) {
  return eq8(b, 0, FS, 0, FC, vS, kv, 0, a, FrictionPressure::none);
}

}  // namespace

const std::map<std::string, FrictionCoefficients>& friction_presets() {
  using P = FrictionPressure;
  static const std::map<std::string, FrictionCoefficients> presets{
      {"none", FrictionCoefficients{0, 0, 0, 0, 0, 1e-3, 0, 0, 1, P::none}},
      // Annex A: eq. 4, FC and vS at their constraints in the paper's fit.
      {"annexA_pAB-", eq4(2.0, 12.32, 0.001, 111.5, 0.8914, 12.56, P::ab_minus)},
      {"annexA_pAB+", eq4(2.0, 14.45, 0.00151, 133.5, 0.8497, 0.994, P::ab_plus)},
      // Annex B: eq. 7 per supply pressure p0 (bar_rel).
      {"annexB_2.07", eq7(5.447, 20.46, 5.94, 0.00367, 102.5, 0.6796)},
      {"annexB_3.127", eq7(2.824, 22.59, 5.273, 0.004483, 106.1, 0.7018)},
      {"annexB_4.115", eq7(1.468, 25.78, 6.407, 0.004925, 123.7, 0.6513)},
      {"annexB_5.14", eq7(2.776, 25.05, 4.31, 0.004033, 128.7, 0.6843)},
      {"annexB_6.13", eq7(2.509, 25.51, 3.855, 0.003434, 140.8, 0.662)},
      {"annexB_7.085", eq7(1.274, 32.95, 7.864, 0.005579, 147.6, 0.6468)},
      {"annexB_8.075", eq7(-1.17, 31.08, 5.856, 0.005311, 158.8, 0.6317)},
      // Annex C: eq. 8, main stroke (pAB-, pAB+) and cushioning zone (pEC).
      {"annexC_pAB-", eq8(-0.67, -4.4, 21.64, 11.78, 5.08, 4.16e-3, 49.9, 43.41, 0.429, P::ab_minus)},
      {"annexC_pAB+", eq8(5.63, -0.1, 17.06, 0.714, 5.4, 3.98e-3, 87.46, 6.1, 0.746, P::ab_plus)},
      {"annexC_pEC", eq8(9.66, 0.26, 8.8, 2.197, 8.8, 2.96e-3, 121, 19.61, 1.0, P::ec)},
  };
  return presets;
}

std::vector<std::string> friction_preset_names() {
  std::vector<std::string> names;
  for (const auto& [k, v] : friction_presets()) names.push_back(k);
  return names;
}

}  // namespace pneumo::components
