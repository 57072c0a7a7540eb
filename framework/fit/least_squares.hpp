// The common part of pneumo's fitting tools: named, bounded coefficients
// (initial value, bounds, optionally held fixed) and the report of a
// nonlinear least-squares fit (RSS, R2, standard errors), solved by Ceres
// (Debian libceres-dev) with residuals differentiated by its automatic
// differentiation. The models themselves live in friction_fit / throttle_fit.
#pragma once

#include <limits>
#include <string>
#include <vector>

namespace pneumo::fit {

struct FitParameter {
  std::string name;
  std::string unit;  // the unit the value is given in (paper units: N, N/bar, m/s, ...)
  double initial = 0.0;
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  bool fixed = false;  // held at `initial` (e.g. not identifiable from the data)
  double value = std::numeric_limits<double>::quiet_NaN();
  // One standard deviation from the covariance of the linearised problem,
  // scaled by RSS/(n - k); NaN when fixed or not estimable (singular).
  double std_error = std::numeric_limits<double>::quiet_NaN();
  std::string note;  // why a default is what it is (shown in the report)

  bool at_lower() const;
  bool at_upper() const;
};

struct FitReport {
  std::vector<FitParameter> parameters;
  int points = 0;
  int free_parameters = 0;
  double rss = 0.0;  // residual sum of squares, in the observed quantity's unit squared
  double tss = 0.0;  // total sum of squares about the mean
  double r2 = 0.0;   // 1 - RSS/TSS
  bool converged = false;
  int iterations = 0;
  std::string solver_message;

  const FitParameter& parameter(const std::string& name) const;  // throws std::out_of_range
  double value(const std::string& name) const { return parameter(name).value; }
  std::vector<double> values() const;
};

FitParameter bounded_parameter(const std::string& name, const std::string& unit, double initial, double lower,
                               double upper, const std::string& note = "");

// Sets one field of a named parameter from "NAME=VALUE" (the CLI's --init,
// --lower, --upper, --fix). Throws std::invalid_argument naming the known
// parameters.
enum class ParameterField { initial, lower, upper, fixed };
void set_parameter(std::vector<FitParameter>& params, const std::string& assignment, ParameterField field);

// Checks initial values against bounds; throws std::invalid_argument.
void check_parameters(const std::vector<FitParameter>& params);

// Human-readable table of a report (coefficients, standard errors, initial
// values, bounds, flags), RSS in `rss_unit`, R2.
std::string format_report(const FitReport& report, const std::string& rss_unit);

}  // namespace pneumo::fit
