// Calibration of netlist parameters to measured runs (pneumo calibrate,
// docs/how-to/calibrate.md): the parameters named free are fitted on the
// calibration runs by weighted least squares - each signal weighted by the
// noise it shows itself, as the diagnosis weighs it - with the diagnosis's
// engine (framework/diagnose/engine.hpp: the runs at their operating
// points, the bounded Levenberg-Marquardt of framework/fit/bounded_lm.hpp).
// Standard errors come from the Jacobian at the fit after whitening each
// residual series with its own AR(p) model, so that smooth, autocorrelated
// model error does not pass for thousands of independent samples.
#pragma once

#include <string>
#include <vector>

#include "framework/core/units.hpp"
#include "framework/diagnose/diagnose.hpp"

namespace pneumo::diagnose {

struct CalibrateOptions {
  // NAME or COMPONENT.PARAMETER, optionally =LOW:HIGH (SI numbers,
  // quantities of the parameter's unit, or factors of the netlist's value,
  // "0.5x"; default 0.25x:4x); or a measured output's reading error,
  // OUTPUT.offset, OUTPUT.gain, OUTPUT.lag (starting at none).
  std::vector<std::string> free;
  std::vector<std::string> sets;  // --set on the model, before any run's operating point
  int threads = 2;
  int max_iterations = 30;
  bool progress = true;
};

struct CalibratedParameter {
  std::string name;              // as given: NAME, COMPONENT.PARAMETER or OUTPUT.offset|gain|lag
  bool reading = false;          // a measured output's reading error, not a netlist value
  std::string unit;              // SI unit of the values
  double start = 0, value = 0;   // the netlist's value and the fitted one
  double lower = 0, upper = 0;   // the range searched
  double standard_error = 0;     // NaN when the data do not determine it
  bool at_bound = false;         // the fit stopped on a bound: the range, not the data, holds it
  // The unit people read it in: the netlist's `display:` unit of its
  // quantity, else the habitual one when SI is unreadable (dm3/(s*bar)),
  // else SI; si = shown_scale * shown + shown_offset.
  std::string shown_unit;
  double shown_scale = 1, shown_offset = 0;
  double shown(double si) const { return (si - shown_offset) / shown_scale; }
};

// One run and signal: normalised RMS (noise = 1) and RMS in the signal's
// SI unit, before and after.
struct RunSignalGap {
  std::string run, signal, unit;
  Role role = Role::calibration;
  double sigma = 0;
  double rms_before = 0, rms_after = 0;          // noise units
  double rms_before_si = 0, rms_after_si = 0;    // SI unit of the signal
  std::string shown_unit;                        // the unit its output is shown in, as a difference (bar, not bar g)
  double shown_scale = 1;                        // si = shown_scale * shown
};

struct CalibrationTrace {  // one run's signal, for the plots
  std::string run, signal, unit;
  units::DisplayUnit display;  // how its output is shown
  std::vector<double> t, measured, before, after;  // SI
};

struct CalibrationReport {
  std::string model_file, runs_dir;
  std::vector<CalibratedParameter> parameters;
  std::vector<std::vector<double>> correlation;  // of the estimates, row per parameter
  std::vector<RunSignalGap> gaps;
  Gap calibration_before, calibration_after, validation_before, validation_after;
  double residual_scale = 0;  // sqrt of the whitened residual variance (1: the fit leaves only noise)
  int evaluations = 0;
  long simulations = 0, failed_runs = 0;
  std::vector<std::string> run_failures;  // why (the first few)
  std::vector<CalibrationTrace> traces;
  double seconds = 0;
};

// Fits `options.free` to the runs in `runs_dir` (run files as diagnose
// reads them: data, role, operating_point). InputError for a free
// parameter the model lacks, gives twice, or a run's operating point sets.
CalibrationReport calibrate(const std::string& model_file, const std::string& runs_dir, const Registry& base,
                            const CalibrateOptions& options);

// The fitted values as a netlist snippet: top-level parameters under
// `parameters:`, component parameters under `components:` (to merge into
// their lines), each in its shown unit with its standard error as a comment.
std::string calibration_snippet(const CalibrationReport& report);

// Printed lines: each parameter's value, standard error and range, the
// correlations, and the gap per run and signal (noise units and the
// signal's unit).
std::string calibration_summary(const CalibrationReport& report);

void write_calibration_json(const CalibrationReport& report, const std::string& path);

}  // namespace pneumo::diagnose
