// Coefficient sets of seed paper 000, Annex A (eq. 4), Annex B (eq. 7, one
// row per supply pressure p0 in bar_rel) and Annex C (eq. 8), as printed.
#include "components/friction.hpp"

#include <stdexcept>

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

namespace {

constexpr double kPerBar = 1e5;  // Pa per bar: the coefficients are per bar inside

// The custom eq. 8 coefficients of one set (prefix "friction" or
// "friction_cushion"); FC and vS of the main set are the shared
// friction_FC / friction_vS (declared with the other models' parameters).
std::vector<ParameterSpec> custom_parameters(const std::string& pre, bool with_FC_vS) {
  using P = ParameterSpec;
  const std::string set = pre == "friction" ? "main-stroke" : "cushioning-zone";
  const std::string when = " (" + pre + ": custom)";
  std::vector<ParameterSpec> out = {
      P::text(pre + "_pressure", {"none", "pAB-", "pAB+", "pEC"},
              "pressure p of the " + set + " eq. 8 set" + when +
                  ": pAB- = |p_A - p_B|, pAB+ = p_A + p_B - 2 p_amb, pEC = p_EC - p_amb",
              "none"),
      P::scalar(pre + "_b0", "N", "eq. 8 bias b0" + when + "; default 0").optional(),
      P::scalar(pre + "_b1", "N/Pa", "eq. 8 pressure slope b1, e.g. -0.1 N/bar" + when + "; default 0").optional(),
      P::scalar(pre + "_FS0", "N", "eq. 8 static force FS0" + when + "; default 0").optional(),
      P::scalar(pre + "_FS1", "N/Pa", "eq. 8 static force slope FS1, e.g. 0.714 N/bar" + when + "; default 0")
          .optional(),
      P::scalar(pre + "_kv0", "N", "eq. 8 viscous force kv0 at |v| = 1 m/s" + when + "; default 0").optional(),
      P::scalar(pre + "_kv1", "N/Pa", "eq. 8 viscous slope kv1 at 1 m/s, e.g. 6.1 N/bar" + when + "; default 0")
          .optional(),
      P::scalar(pre + "_a", "1", "eq. 8 speed exponent a" + when + "; default 1").positive().optional(),
  };
  if (with_FC_vS) {
    out.push_back(
        P::scalar(pre + "_FC", "N", "eq. 8 Coulomb force FC (enters as FS0 - FC)" + when + "; default 0")
            .non_negative()
            .optional());
    out.push_back(P::scalar(pre + "_vS", "m/s", "eq. 8 Stribeck velocity vS" + when + "; default 1 mm/s")
                      .positive()
                      .optional());
  }
  return out;
}

// The coefficient set named by the text parameter `pre` (a preset, or the
// custom coefficients pre_b0 ...). Custom coefficients beside a preset are
// an error: a pasted fit must not be silently ignored.
FrictionCoefficients read_set(const ParameterValues& p, const std::string& pre, const std::string& name) {
  const std::vector<std::string> own = {"_b0", "_b1", "_FS0", "_FS1", "_kv0", "_kv1", "_a"};
  if (name != "custom") {
    for (const auto& suffix : own)
      if (p.has(pre + suffix))
        throw ParameterError(pre + suffix, pre + suffix + " is a coefficient of " + pre + ": custom, but " + pre +
                                               " is '" + name + "'; set " + pre + ": custom or remove it");
    if (p.text(pre + "_pressure") != "none")
      throw ParameterError(pre + "_pressure", pre + "_pressure selects the pressure of " + pre +
                                                  ": custom; the preset '" + name + "' has its own");
    return friction_presets().at(name);
  }
  auto get = [&](const std::string& suffix, double fallback) { return p.has(pre + suffix) ? p[pre + suffix] : fallback; };
  // friction_FC / friction_vS always have a value (the defaults of the other
  // models); friction_cushion_FC / _vS are optional.
  return FrictionCoefficients{get("_b0", 0.0),
                              get("_b1", 0.0) * kPerBar,
                              get("_FS0", 0.0),
                              get("_FS1", 0.0) * kPerBar,
                              get("_FC", 0.0),
                              get("_vS", 1e-3),
                              get("_kv0", 0.0),
                              get("_kv1", 0.0) * kPerBar,
                              get("_a", 1.0),
                              friction_pressure_from_name(p.text(pre + "_pressure"))};
}

}  // namespace

std::vector<ParameterSpec> FrictionLaw::parameters(bool with_cushion) {
  using P = ParameterSpec;
  std::vector<ParameterSpec> out = {
      P::text("friction_model", {"preset", "coulomb_viscous", "lugre"},
              "friction law: preset (paper [1] eq. 4/7/8 set named by 'friction'), coulomb_viscous "
              "(F_C tanh(v/v_reg) + d v), lugre (paper [3] eq. 8, bristle state z)",
              "preset"),
      P::text("friction", friction_set_names(),
              "coefficient set of paper [1] (friction_model preset), or custom: eq. 8 with friction_b0 ... friction_a",
              "none"),
  };
  if (with_cushion)
    out.push_back(P::text("friction_cushion", friction_set_names(),
                          "preset set in the cushioning zone, or custom (friction_cushion_b0 ...); default: same "
                          "as main stroke",
                          std::nullopt)
                      .optional());
  const std::vector<ParameterSpec> rest = {
      P::scalar("friction_scale", "1", "factor on the friction force", 1.0).non_negative(),
      P::scalar("friction_coulomb_scale", "1",
                "factor on the dry part alone: F_C (coulomb_viscous), F_C and F_S (lugre), b0 + b1 p and the "
                "Stribeck term (presets, custom)",
                1.0)
          .non_negative(),
      P::scalar("friction_viscous_scale", "1",
                "factor on the viscous part alone: d v (coulomb_viscous), sigma2 v (lugre), (kv0 + kv1 p) |v|^a "
                "(presets, custom)",
                1.0)
          .non_negative(),
      P::scalar("friction_v_reg", "m/s", "velocity scale of the tanh sign regularisation", 1e-4).positive(),
      P::scalar("friction_v_eps", "m/s", "velocity below which |v| is rounded (|v|^a stays smooth)", 1e-6)
          .positive(),
      P::scalar("friction_FC", "N", "Coulomb force F_C (coulomb_viscous, lugre; custom: eq. 8 FC, enters as FS0 - FC)",
                0.0)
          .non_negative(),
      P::scalar("friction_FS", "N", "static (break-away) force F_S (lugre); default F_C").non_negative().optional(),
      P::scalar("friction_vS", "m/s", "Stribeck velocity v_S (lugre; custom: eq. 8 vS)", 1e-3).positive(),
      P::scalar("friction_sigma0", "N/m", "bristle stiffness sigma0 (lugre)", 1e5).positive(),
      P::scalar("friction_sigma1", "N*s/m", "bristle damping sigma1 (lugre)", 300.0).non_negative(),
      P::scalar("friction_viscous", "N*s/m", "viscous coefficient: d (coulomb_viscous), sigma2 (lugre)", 0.0)
          .non_negative(),
  };
  out.insert(out.end(), rest.begin(), rest.end());
  for (auto& c : custom_parameters("friction", false)) out.push_back(std::move(c));
  if (with_cushion)
    for (auto& c : custom_parameters("friction_cushion", true)) out.push_back(std::move(c));
  return out;
}

namespace {

// The factors on the dry and the viscous part are folded into the
// coefficients once, so that the laws' equations stay as the papers write
// them. LuGre's bristle force follows g(v), so scaling F_C and F_S scales it.
void fold_part_scales(FrictionLaw& f, double dry, double viscous) {
  for (FrictionCoefficients* c : {&f.main, &f.cushion}) {
    for (double* x : {&c->b0, &c->b1, &c->FS0, &c->FS1, &c->FC}) *x *= dry;
    c->kv0 *= viscous;
    c->kv1 *= viscous;
  }
  f.FC *= dry;
  f.FS *= dry;
  f.viscous *= viscous;
}

}  // namespace

FrictionLaw FrictionLaw::from(const ParameterValues& p) {
  FrictionLaw f;
  const std::string& m = p.text("friction_model");
  f.model = m == "lugre" ? FrictionModel::lugre
            : m == "coulomb_viscous" ? FrictionModel::coulomb_viscous
                                     : FrictionModel::preset;
  const std::string& main = p.text("friction");
  if (f.model != FrictionModel::preset && main == "custom")
    throw ParameterError("friction", "friction: custom is a coefficient set of eq. 8; it needs friction_model: preset");
  f.main = read_set(p, "friction", main);
  const bool has_cushion_choice = p.has("friction_cushion");
  if (has_cushion_choice) {
    f.cushion = read_set(p, "friction_cushion", p.text("friction_cushion"));
    if (p.text("friction_cushion") != "custom")
      for (const char* name : {"friction_cushion_FC", "friction_cushion_vS"})
        if (p.has(name))
          throw ParameterError(name, std::string(name) + " is a coefficient of friction_cushion: custom, but "
                                                         "friction_cushion is '" + p.text("friction_cushion") + "'");
  } else {
    f.cushion = f.main;
    // Cushion coefficients without `friction_cushion: custom` would be ignored.
    for (const char* name : {"friction_cushion_b0", "friction_cushion_b1", "friction_cushion_FS0",
                             "friction_cushion_FS1", "friction_cushion_kv0", "friction_cushion_kv1",
                             "friction_cushion_a", "friction_cushion_FC", "friction_cushion_vS"})
      if (p.has(name))
        throw ParameterError(name, std::string(name) + " needs friction_cushion: custom");
    if (p.has("friction_cushion_pressure") && p.text("friction_cushion_pressure") != "none")
      throw ParameterError("friction_cushion_pressure", "friction_cushion_pressure needs friction_cushion: custom");
  }
  if (f.model != FrictionModel::preset && has_cushion_choice)
    throw ParameterError("friction_cushion", "friction_cushion selects a preset; it needs friction_model: preset");
  f.scale = p["friction_scale"];
  f.v_reg = p["friction_v_reg"];
  f.v_eps = p["friction_v_eps"];
  f.FC = p["friction_FC"];
  f.FS = p.has("friction_FS") ? p["friction_FS"] : f.FC;
  f.vS = p["friction_vS"];
  f.sigma0 = p["friction_sigma0"];
  f.sigma1 = p["friction_sigma1"];
  f.viscous = p["friction_viscous"];
  fold_part_scales(f, p["friction_coulomb_scale"], p["friction_viscous_scale"]);
  if (f.model == FrictionModel::lugre && !(f.FC > 0))
    throw ParameterError("friction_FC", "LuGre friction needs a Coulomb force friction_FC > 0 (g(v) > 0)");
  return f;
}

std::vector<std::string> friction_preset_names() {
  std::vector<std::string> names;
  for (const auto& [k, v] : friction_presets()) names.push_back(k);
  return names;
}

std::vector<std::string> friction_set_names() {
  std::vector<std::string> names = friction_preset_names();
  names.push_back("custom");
  return names;
}

FrictionPressure friction_pressure_from_name(const std::string& name) {
  if (name == "none") return FrictionPressure::none;
  if (name == "pAB-") return FrictionPressure::ab_minus;
  if (name == "pAB+") return FrictionPressure::ab_plus;
  if (name == "pEC") return FrictionPressure::ec;
  throw std::invalid_argument("unknown friction pressure '" + name + "' (none, pAB-, pAB+ or pEC)");
}

}  // namespace pneumo::components
