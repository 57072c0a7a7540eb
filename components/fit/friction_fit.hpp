// Friction identification from rig data, seed paper 000 section 3.1:
//   eq. 4: F = FC + kp p + (FS - FC) exp(-|v|/vS) + kv |v|^a
//   eq. 7: F = b + (FS - FC) exp(-|v|/vS) + kv |v|^a          (one supply pressure)
//   eq. 8: F = b0 + b1 p + (FS0 + FS1 p - FC) exp(-|v|/vS) + (kv0 + kv1 p) |v|^a
// in the paper's units: F in N, v in m/s, p in bar (pAB- = |p_A - p_B|,
// pAB+ = p_A + p_B - 2 p_amb, pEC = p_EC - p_amb; components/friction.hpp),
// kv the force at |v| = 1 m/s in N (the paper's "kg/s" holds for a = 1 only).
// In eq. 7 and 8, FC enters only through FS - FC (FS0 - FC): the data
// determine the difference, not FC itself, so FC is held fixed (default
// 5 N, the order of the paper's values; --fix FC=VALUE to choose) and FS
// (FS0) is reported relative to it.
#pragma once

#include <string>
#include <vector>

#include "components/friction.hpp"
#include "framework/fit/data_table.hpp"
#include "framework/fit/least_squares.hpp"

namespace pneumo::fit {

enum class FrictionModel { eq4, eq7, eq8 };

// "eq4" | "eq7" | "eq8"; throws std::invalid_argument.
FrictionModel parse_friction_model(const std::string& text);
std::string friction_model_name(FrictionModel m);
// "pAB-" | "pAB+" | "pEC" | "none"; throws std::invalid_argument.
components::FrictionPressure parse_friction_pressure(const std::string& text);
std::string friction_pressure_name(components::FrictionPressure p);

// Without a force offset only the magnitudes of v and F are used; with one,
// F is the measured force signed along the motion (positive when it resists
// a positive v): F = sign(v) law(|v|, p) + F0.
struct FrictionPoint {
  double v = 0;      // m/s
  double p_bar = 0;  // the model's pressure, bar
  double F = 0;      // friction force, N
  int line = 0;      // data file line, 0 if none
};

// Coefficients with the paper's initial values and bounds (eq. 4: FC >= 2 N
// and vS >= 1 mm/s as the constraints of Annex A).
std::vector<FitParameter> default_friction_parameters(FrictionModel m);
// With `offset`, a last coefficient F0 (N): a constant force added to the
// signed law (a load cell's zero error), fitted alongside it.
std::vector<FitParameter> default_friction_parameters(FrictionModel m, bool offset);

// The model's force (N) for coefficient values in the order of
// default_friction_parameters(m).
double friction_model_force(FrictionModel m, const std::vector<double>& c, double v, double p_bar);

// The least RSS from four starts: the given values and the three best points
// of a (vS, a) grid with the other coefficients solved linearly (the Stribeck
// term has local minima, and the paper's initial values can lie far from
// the data's optimum). Throws
// std::invalid_argument (too few points, bad bounds, offset data signed the
// wrong way).
FitReport fit_friction(FrictionModel m, const std::vector<FrictionPoint>& points,
                       std::vector<FitParameter> params);

// The RMS force error (N) of a fitted law on points it may not have seen
// (another pressure, a held-out run), in the fit's own sense: |F| against
// the law, or the signed force with the fitted offset.
double friction_rms(FrictionModel m, const FitReport& r, const std::vector<FrictionPoint>& points);

// Points from a data table with columns v, F and, by pressure, p_A and p_B
// (pAB-, pAB+) or p_EC (pEC). Throws InputError naming file and line.
std::vector<FrictionPoint> friction_points(const DataTable& data, components::FrictionPressure pressure,
                                           double p_ambient = 101325.0);

// The fitted coefficients in the general eq. 8 form of components/friction.hpp.
components::FrictionCoefficients friction_coefficients(FrictionModel m, const FitReport& r,
                                                       components::FrictionPressure pressure);

// A netlist-ready YAML snippet for a cylinder's friction: `friction: custom`
// and the coefficients as friction_b0 ... friction_a with units (prefix
// friction_cushion_ for the cushioning zone). `header` lines become comments.
std::string friction_preset_yaml(const components::FrictionCoefficients& c, const FitReport& r,
                                 FrictionModel m, bool cushion_zone, const std::string& header);

}  // namespace pneumo::fit
