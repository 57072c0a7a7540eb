// ISO 6358 identification from flow measurements (paper [1] eq. 15-16,
// section 3.2): points (p1, p2, T1, mass flow) -> sonic conductance C and
// critical pressure ratio b, with the same flow law as the components
// (components/iso6358_flow.hpp, linear continuation above p2/p1 = 0.999).
// For a needle throttle measured at several openings z: C and b per
// opening, then C(z) as the piecewise-linear table and b(C) = b0 + slope
// C/C_max as a straight line, in the cushioning cylinder's parameter names.
#pragma once

#include <string>
#include <vector>

#include "framework/fit/data_table.hpp"
#include "framework/fit/least_squares.hpp"
#include "framework/model/gas.hpp"

namespace pneumo::fit {

struct ThrottlePoint {
  double p1 = 0, p2 = 0;  // Pa absolute, upstream and downstream
  double T1 = 293.15;     // K, upstream
  double m_flow = 0;      // kg/s, p1 -> p2
  double z = 0;           // opening (rev), needle throttles only
  int line = 0;
};

// ISO 6358 mass flow (kg/s) for C in m3/(s Pa).
double iso6358_flow(const ThrottlePoint& p, double C, double b, const GasModel& gas, double r_lam = 0.999);

// Coefficients C [dm3/(s*bar)] and b [1], initial values from the data
// (C from the most choked point, b = 0.4). Throws std::invalid_argument.
FitReport fit_throttle(const std::vector<ThrottlePoint>& points, const GasModel& gas = {});

struct NeedleFit {
  std::vector<double> z;               // openings, increasing
  std::vector<FitReport> per_opening;  // C [dm3/(s*bar)], b per opening
  double C_max = 0;                    // dm3/(s*bar)
  double b0 = 0, b_slope = 0;          // b = b0 + slope C/C_max (least squares line)
  double b_line_r2 = 0;
};

// Groups the points by z (each opening needs at least 3 points, two of them
// subsonic, for b). Throws std::invalid_argument.
NeedleFit fit_needle_throttle(const std::vector<ThrottlePoint>& points, const GasModel& gas = {});

// Columns p1, p2, T1 (optional: 293.15 K), m_flow, and z (optional). Rows
// with p2 >= p1 or m_flow <= 0 are errors naming file and line.
std::vector<ThrottlePoint> throttle_points(const DataTable& data, bool* has_z = nullptr);

std::string throttle_yaml(const FitReport& r, const std::string& header);
std::string needle_throttle_yaml(const NeedleFit& f, const std::string& header);

}  // namespace pneumo::fit
