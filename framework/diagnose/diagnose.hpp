// Sim-to-real gap diagnosis (docs/how-to/diagnose.md).
//
// Where: residuals of the unpatched model on every measured run, weighted by
// the noise each signal shows itself (robust high-pass estimate), split by
// signal and by phase (the catalogue's `phases:`, else the model's own tagged
// events), plus the time windows whose residuals
// are significant against that noise.
// Which: every available candidate effect is calibrated on the calibration
// runs (bounded Levenberg-Marquardt, finite-difference sensitivities, runs in
// parallel) after a linearised screening from the same sensitivities, gated
// on the validation runs by a likelihood ratio of AR(p)-whitened residuals
// with a BIC penalty per parameter and by practical significance in noise
// units, and ranked by the share of the validation gap it removes
// (framework/diagnose/ranking.hpp). Effects whose improvements the signals
// cannot tell apart form a group; forward selection re-screens the remaining
// candidates against the gap left every round and fits each with the chosen
// effects' parameters free.
// How far: the validation gap before and after, per signal and phase.
#pragma once

#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "framework/diagnose/catalogue.hpp"
#include "framework/diagnose/sensors.hpp"
#include "framework/model/circuit.hpp"
#include "framework/model/registry.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo::diagnose {

enum class Role { calibration, validation };

// A value a run file's operating point sets, read once when the run is
// loaded: a top-level parameter's SI value, or a component's value as
// written (a replayed file resolved inside the runs folder), checked then.
struct OperatingValue {
  ParameterPath path;
  std::string text;          // as written
  std::optional<double> si;  // a top-level parameter's value
  SourceLocation where;      // in the run file
  std::string name() const { return path.text(); }
  void apply(Netlist& netlist) const;  // set_si_value, else set_value naming `where`
};

struct MeasuredRun {
  std::string name;
  std::string csv_file;
  Role role = Role::calibration;
  std::vector<OperatingValue> operating_point;
  std::vector<double> t;
  std::vector<std::string> signals;        // model output names, file order
  std::vector<std::vector<double>> y;      // per signal, at t
  std::vector<double> sigma;               // noise per signal, estimated from the data
};

// Reads DIR/*.yaml (each with data, role, operating_point) and their CSVs,
// checked against the model's outputs (`probes`: their SI units) and
// parameters: an operating point sets top-level NAMEs and
// COMPONENT.PARAMETERs (values as --set takes them; a file parameter, such
// as a data_signal's replayed file, names a file inside DIR). A CSV header cell may give its column's unit,
// "p [bar]", "p [barg]" (gauge: the model's ambient pressure added),
// "t [ms]"; without one the column is SI. Every value is converted to SI.
// `data:` must name a regular file inside DIR. A run's samples must lie in
// the model's [t_start, t_end] and span at least a tenth of it. Throws
// InputError naming the file, line and column or parameter.
// `roles`: whether a run file must name its role and the folder hold runs
// of both (the diagnosis), or a run without one is a calibration run and
// validation runs are optional (a calibration).
enum class RunRoles { both_required, validation_optional };
std::vector<MeasuredRun> load_runs(const std::string& dir, const Netlist& model, const std::vector<Probe>& probes,
                                   const Registry& registry, RunRoles roles = RunRoles::both_required);

// Robust white-noise level of a sampled signal: median absolute deviation of
// third differences / sqrt(20), floored by the quantisation step / sqrt(12).
double estimate_noise(const std::vector<double>& y);

struct DiagnoseOptions {
  int threads = 2;
  int max_effects = 2;        // forward selection depth
  int max_iterations = 12;    // Levenberg-Marquardt iterations per fit
  int screen_keep = 8;        // full fits for at most this many candidates (best screened first)
  // Significance, the gate: a likelihood ratio of the validation residuals
  // after AR(p) whitening (each signal of each run its own series, p <= 5
  // by BIC) minus a BIC penalty k ln(n) above this ("strong" evidence).
  double significance_bic = 6.0;
  double group_cosine = 0.9;  // grouped: improvements at least this collinear, neither fit practically better
  // Practical significance in noise units (framework/diagnose/ranking.hpp),
  // because a model-form mismatch of the right effect leaves residual
  // structure that abundant data make "statistically" significant: the model
  // explains the data when its validation gap is at most `adequate_gap`
  // (noise = 1) on the whole set and on every signal, and an effect must
  // remove at least one noise variance of mean square and at least what a
  // `noise_uncertainty` error of the noise level (relative, of sigma) would
  // move it by, on the total or on one signal whose own gap exceeds
  // `adequate_gap`.
  double adequate_gap = 1.3;
  double noise_uncertainty = 0.1;
  // Candidates: the faults the circuit's components declare and the
  // measurement faults of the measured signals (declared_faults(), as
  // COMPONENT.FAULT), the catalogue's effects added to them or replacing
  // one of the same name. Off: the catalogue's alone.
  bool declared_faults = false;
  std::vector<std::string> faults;  // non-empty: only these candidates (narrow_catalogue())
  std::vector<std::string> sets;    // --set on the model, before any run's operating point
  // --experiment NAME=LOW:HIGH: a top-level parameter the next run may set
  // and its range (values as --set takes them: SI numbers or quantities).
  // Without any, the next run varies what the runs vary, within their span.
  std::vector<std::string> experiments;
  bool progress = true;
  std::function<void(const std::string&)> log;  // progress lines (default: stderr)
};

struct Gap {  // normalised RMS residual (1 = noise level) and shares of the total
  double rms = 0;
  double ssr = 0;
  long n = 0;
};

struct GapTable {
  std::vector<std::string> signals;
  Gap total;
  std::vector<Gap> by_signal;                 // per signal
  std::vector<std::vector<Gap>> by_phase;   // per signal, per phase (DiagnosisReport::phase_names)
  std::vector<Gap> phase_total;
};

struct EffectResult {
  std::string name, description;
  std::string component, fault;  // a declared fault: its component (or measured output) and fault
  bool setting = false;          // a hand-set value off its setting (FaultSpec::setting)
  std::string unavailable;  // non-empty: not evaluated
  bool screened_out = false;
  double screening_improvement = 0;  // linearised share of the calibration SSR removed
  std::vector<std::string> parameter_names, parameter_units;
  std::vector<double> parameter_nulls;  // where each vanishes (NaN: a structural switch has none)
  std::vector<bool> parameter_differences;  // each a difference of its quantity (EffectParameter::difference)
  std::vector<double> values;
  std::optional<double> netlist_value;   // a re-calibration candidate: the netlist's value of its parameter
  double gap_before = 0, gap_after = 0;  // validation, normalised RMS
  GapTable validation_after;
  double lr_eff = 0, delta_bic = 0, p_value = 1, n_eff = 0;  // whitened LR, whitened samples
  bool significant = false;
  int rank = 0;              // 1 = best; 0 = not ranked (unavailable)
  std::vector<std::string> group;  // effects the data cannot tell apart from this one
  int fit_evaluations = 0;
  int failed_validation_runs = 0;  // the solver failed at the fitted values (residual set to 1e4 noise units)
  long failed_runs = 0;                   // runs that failed while it was screened and fitted
  std::vector<std::string> run_failures;  // why (the first few)
};

struct WindowFinding {
  std::string run, signal;
  double t0 = 0, t1 = 0, rms = 0, z = 0;
};

struct TracePlot {  // decimated traces of one validation run and signal
  std::string run, signal;
  std::vector<double> t, measured, before, after;
  std::vector<double> phase_times;  // each phase's start, then the end
};

// What the verdict leaves unexplained (docs/how-to/diagnose.md): set when
// the validation gap after the named effects stays above the noise
// (DiagnoseOptions::adequate_gap) on the whole set or on one signal.
// The model's balances (each differential equation, as the derivative of its
// state) and each sensor reading (offset and gain) are given a smooth
// additive disturbance in turn, fitted by regularised least squares over the
// runs; the one that explains most of the remaining gap is named, with its
// shape.
struct DisturbanceShape {  // one run's fitted disturbance, SI units of the balance's rate
  std::string run;
  std::vector<double> t, value;  // knots of the piecewise-linear d(t); a sensor's offset in the signal's unit
  double gain = 0;               // a sensor's relative gain error (reading = (1 + gain) simulated + offset)
};

struct BalanceFinding {  // one candidate balance or sensor
  std::string balance;      // e.g. "cylinder.m_EC" (a state) or "sensor x"
  std::string kind;         // "mass", "energy", "force", "sensor", ... (from the state's unit)
  std::string unit;         // unit of the disturbance (rate of the state)
  double gap_after = 0;     // all runs, normalised RMS, with this disturbance fitted
  double explained = 0;     // share of the remaining excess gap (gap - 1) it removes
  bool confirmed = false;   // gap_after simulated with the fitted disturbance, not linearly predicted
  std::string failure;      // why no step of its fit could be simulated (empty: one ran, or none was tried)
  double share = 1;         // of the linear fit the first simulated step that lowered the gap carried (0: none did)
  std::string longer_step_failed;  // why a longer step could not be simulated (the model left its domain)
  int hats = 0;             // a state's disturbance: hat functions per run (fewer than the knots: screened only)
};

// The best balance's correction as a function of the model's states
// (framework/diagnose/form.hpp): terms with coefficients in SI.
struct FormTermFinding {
  std::string text;         // e.g. "bump(s at load.flange; centre 45.0 mm, width 4.0 mm)"
  double coefficient = 0;   // SI
  std::string unit;         // of the coefficient ("" when dimensionless)
};

struct FormFinding {
  std::string balance, unit;            // the balance and its rate's unit (a reading: the signal and its unit)
  bool reading = false;                 // the terms add to a measured signal's reading, not to a balance
  std::vector<FormTermFinding> terms;
  std::string formula;                  // "d(balance) [unit] = ..."
  double gap_before = 0;                // all runs, the verdict's model
  double gap_after = 0;                 // simulated with the form in the model
  double gap_shape = 0;                 // the time-shaped correction's
  bool confirmed = false;               // gap_after is simulated, not predicted
  bool beats_shape = false;             // as good as the time-shaped correction, or down to 1.5 x noise
  std::string failure;                  // why the form's simulation failed
  int dictionary = 0;                   // candidate terms tried
  std::vector<std::string> read;        // the model's variables those terms are built from
  long simulations = 0;
  std::string sentence;
};

struct Unexplained {
  double gap = 0;                                  // validation gap left after the verdict (noise = 1)
  std::string signal, phase;                       // where most of it lies
  std::vector<WindowFinding> windows;              // significant windows of the remaining residuals
  std::vector<BalanceFinding> balances;            // best first
  std::vector<DisturbanceShape> shape;             // of the best balance, per run
  std::string sentence;                            // one plain sentence for the report
  std::optional<FormFinding> form;                 // the missing term's form, when the runs can judge one
  double gap_all_runs = 0;                         // the gap the balances work on: all runs, verdict model
  long simulations = 0;                            // the search's cost
  double seconds = 0;
};

// The next run that would decide (docs/how-to/diagnose.md,
// framework/diagnose/next_run.hpp): for candidates the data cannot tell
// apart, the operating point where their fitted models lie furthest apart
// in the measured signals.
struct NextRunSetting {
  std::string name;             // a top-level parameter of the model
  double value = 0;             // SI
  double lower = 0, upper = 0;  // the range searched, SI
  std::string unit;             // SI unit
  std::string shown_unit;       // the unit --experiment gave it in (empty: the report's engineering unit)
  double shown_scale = 1, shown_offset = 0;  // si = scale * shown + offset
};

struct NextRun {
  std::vector<std::string> effects;  // the candidates it would tell apart (a verdict slot's group, or the verdict and its runner-up)
  std::vector<NextRunSetting> operating_point;  // the parameters searched; the rest as in `template_run`
  std::string template_run;          // the run whose span, sampling, signals and other settings it keeps
  double separation = 0;             // the smallest pairwise separation there, noise sd (RMS over the run, best signal)
  double separation_measured = 0;    // the same measure, best of the measured runs' operating points
  std::string effect_a, effect_b;    // the pair closest there
  std::string signal, phase;         // where they differ most (phase: most of that signal's difference)
  std::string sensor;                // the sensor that would separate the same pair (sensor_clause), if any
  // The run decides: its separation is at least one noise sd (one noise
  // variance of mean square, as an effect must remove to be named) and
  // more than the measured runs' points give. Else no run in the ranges
  // searched tells them apart (twins, or effects the signals cannot see).
  bool decisive = false;
  long simulations = 0, failed_simulations = 0, points = 0;  // the search's cost; failed ones never scored
};

struct DiagnosisReport {
  std::string model_file, catalogue_file, runs_dir;
  std::vector<std::string> phase_names;  // the catalogue's phases, or the model's tagged events
  std::vector<std::string> verdict;
  std::vector<std::vector<std::string>> verdict_groups;
  std::vector<EffectResult> effects;
  GapTable calibration_before, validation_before, validation_after;
  std::vector<std::pair<std::string, double>> noise;  // signal, sigma (median over runs)
  std::vector<std::pair<std::string, std::string>> signal_units;  // signal, SI unit of the model output
  std::vector<WindowFinding> windows;
  std::vector<TracePlot> plots;
  std::vector<std::string> calibration_runs, validation_runs;
  std::vector<std::pair<std::string, std::vector<double>>> final_values;  // effect -> fitted values in the verdict model
  std::vector<SensorChoice> sensors;  // per verdict effect and one the data cannot tell from it: what would
  std::optional<Unexplained> unexplained;  // empty: the verdict brings the gap down to noise
  std::vector<NextRun> next_runs;          // per group the data cannot tell apart
  long base_failed_runs = 0;                 // runs of the unpatched model that failed
  std::vector<std::string> base_run_failures;  // why (the first few)
  double seconds = 0;
  long simulations = 0;
};

// `catalogue_file` may be empty when options.declared_faults is set. The
// model is loaded with load_model: its `plugins:` are added to `base`
// (usually builtin_registry()), once, for every run of the diagnosis.
DiagnosisReport diagnose(const std::string& model_file, const std::string& runs_dir,
                         const std::string& catalogue_file, const Registry& base, const DiagnoseOptions& options);

// The verdict in one plain sentence (the command's output, both reports):
// the effects named, or with none whether the model explains the data
// within noise or no candidate explains the gap left (its size in noise
// units) - an empty verdict is not "within noise" when a gap remains.
std::string verdict_sentence(const DiagnosisReport& report);

// The next run in one sentence, with the sensor advice for the same pair:
// "to tell a from b, run at z = 0.1 rev: 14 noise sd apart in p_ch, mostly
// during cushioning (0.8 at the measured runs); or a pressure sensor at ...".
std::string next_run_sentence(const NextRun& n);

void write_report_json(const DiagnosisReport& report, const std::string& path);
void write_report_html(const DiagnosisReport& report, const std::string& path);

}  // namespace pneumo::diagnose
