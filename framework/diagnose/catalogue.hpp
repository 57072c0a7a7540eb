// Candidate effects for sim-to-real diagnosis: patches to a netlist with free
// parameters (see docs/how-to/diagnose.md). The catalogue
// file is read once into typed declarations (components, values,
// connections); applying an effect edits a Netlist, no YAML.
//
// A catalogue file:
//   effects:
//     leakage_piston_seal:
//       description: leak across the piston seal, rod side <-> cap side
//       parameters:                 # free parameters, SI values
//         C_leak: {initial: 1e-10, lower: 0, upper: 2e-9, null: 0, unit: m3/(s*Pa), scale: linear}
//       requires: {types: [t], parameters: [type.param], ports: [type.port]}   # optional
//       add_components:     {NAME: {type: ..., param: ${C_leak}}}   # new components
//       replace_components: {NAME: {type: ..., ...}}                # whole declaration replaced
//       set: {COMPONENT.PARAM: VALUE, parameters.NAME: VALUE}       # one parameter changed
//       disconnect: [[a.port, b.port]]   # removes the connection list with exactly these ports
//       connect:    [[a.port, b.port]]   # adds a connection list
//       measure:    {OUTPUT: {lag: ${tau}, offset: ${o}, gain: ${g}}}  # measurement model: the reading is
//                   # gain * (the output through a first-order lag tau, s) + offset (SI unit of the output)
// `${name}` in any value is replaced by the parameter's SI value; `${...}`
// may also hold arithmetic of the parameters and numbers (+ - * /,
// parentheses), e.g. "${(1 - w) * 2.776 + w * 9.66}". `null` is
// the value at which the effect vanishes (optional for structural switches,
// whose reference is then the unpatched model). scale: log fits log(value)
// (lower must then be > 0). An effect whose component type, parameter or
// port is not in the registry is unavailable, not an error.
//
// Model parameters as candidates: the netlist's own values re-calibrated,
// so that a wrong data-sheet value is found as such rather than mimicked by
// an effect:
//   recalibrate:
//     cylinder.dead_volume_rod_side: {lower: 0.5x, upper: 2x}   # COMPONENT.PARAMETER
//     m_load: {}                                                # top-level parameter
// Each entry is a candidate named by its key, with one free parameter whose
// null and initial value are the netlist's value (the component's default if
// the netlist leaves it out); lower and upper are SI numbers or factors of
// that value ("0.5x"; default 0.25x and 4x, kept within the component's
// range), scale log by default (`scale: linear` for a range through zero),
// `description` optional. Only scalar parameters; a component parameter the
// netlist gives as a top-level name is re-calibrated by that name, and a
// top-level parameter a run's operating point sets cannot be (diagnose()
// says so at the catalogue's line).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "framework/core/error.hpp"
#include "framework/model/registry.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo::diagnose {

struct EffectParameter {
  std::string name;
  double initial = 0, lower = 0, upper = 0;
  std::optional<double> null_value;
  std::string unit;
  bool log_scale = false;
  SourceLocation where;
  // A pressure that is a difference (a cracking pressure, ParameterSpec
  // without is_absolute): shown in bar, not bar abs.
  bool difference = false;
};

// `set: {TARGET: VALUE}`: TARGET is COMPONENT.PARAMETER or parameters.NAME
// (checked when applied); VALUE may hold ${...} templates.
struct SetPatch {
  std::string target;
  SourceLocation where;  // of the key
  ValueDecl value;
  // Non-empty: `value` is a factor on this top-level parameter, which the
  // runs' operating points set and `target` is written as (a load's mass
  // `m: m_load`): the target is the factor times each run's own value.
  std::string per_run_of = {};
};

// `measure: {OUTPUT: {lag: SECONDS, offset: SI, gain: FACTOR}}`; each may
// be a ${...} template, each may be left out.
struct MeasurePatch {
  std::string output;
  std::optional<ValueDecl> lag, offset, gain;
};

struct Effect {
  std::string name;
  std::string description;
  SourceLocation where;
  std::vector<EffectParameter> parameters;
  // The patch, with the catalogue's file:line on every declaration; values
  // may hold ${...} templates until apply_effects() substitutes them.
  std::vector<ComponentDecl> add_components, replace_components;
  std::vector<SetPatch> set;
  std::vector<ConnectionDecl> disconnect, connect;
  std::vector<MeasurePatch> measure;
  std::string unavailable;  // non-empty: why the effect cannot be used with this registry
  std::string recalibrates;  // a `recalibrate:` entry: the netlist parameter (NAME or COMPONENT.PARAMETER)
  // A fault a component declares (ComponentInfo::faults) or a measured
  // signal's measurement fault: the component (or output) and the fault.
  std::string component, fault;
  bool setting = false;  // a hand-set value off its setting (FaultSpec::setting)

  int parameter_index(const std::string& n) const;
  // The parameters' initial values, in the catalogue's order.
  std::vector<double> initial_values() const;
  // The parameters' null values (where the effect vanishes); empty for a
  // structural switch (a parameter without a null).
  std::vector<double> null_values() const;
  // Whether the effect changes the netlist (not only the measurement).
  bool patches_netlist() const {
    return !add_components.empty() || !replace_components.empty() || !set.empty() || !connect.empty() ||
           !disconnect.empty();
  }
};

// A phase of the runs in the gap report: it starts at `from` - "start", an
// event of the unpatched model COMPONENT.TAG, or a time-valued metric of the
// model's `metrics:` - and lasts until the next phase starts.
struct PhaseDecl {
  std::string name;
  std::string from;
  SourceLocation where;
};

struct Catalogue {
  std::string file;
  std::vector<Effect> effects;
  std::vector<PhaseDecl> phases;  // empty: phases from the model's own events
  const Effect* find(const std::string& name) const;
};

// An effect with values for its parameters, in the catalogue's order.
struct EffectInstance {
  const Effect* effect = nullptr;
  std::vector<double> values;
};

// Measurement model per output: the reading is gain * (the output through a
// first-order lag, time constant s) + offset (the output's SI unit).
struct MeasurementModel {
  std::map<std::string, double> lag, offset, gain;
};

// A value set per run (SetPatch::per_run_of): `target` is `factor` times the
// run's value of top-level parameter `of`, once the run's operating point is
// applied (apply_run_factors).
struct RunFactor {
  ParameterPath target;
  std::string of;
  double factor = 1.0;
};

// Reads and checks a catalogue; each effect is applied at its initial values
// to `model` (its `file` names it in errors) and elaborated, so that a broken
// patch is reported at load time with the catalogue's file:line, the effect
// and the parameter.
Catalogue load_catalogue(const std::string& path, const Netlist& model, const Registry& registry);

// A measured signal: its name (a model output) and the span of its
// measured values (max - min over the runs), which bounds a plausible offset.
struct MeasuredSignal {
  std::string name;
  double span = 0;
  std::string unit;  // SI unit of the model output
};

// The measurement faults of one measured signal, named OUTPUT.offset
// (signal unit), OUTPUT.gain and OUTPUT.lag (s), each vanishing at its null
// (0, 1, 0) and bounded by the signal's span and the runs' duration `t_span`.
std::vector<Effect> measurement_faults(const MeasuredSignal& s, const SourceLocation& where, double t_span);

// The faults the circuit's components declare (ComponentInfo::faults) as
// effects named COMPONENT.FAULT, each setting the component's own
// parameters (a factor fault: a factor on the netlist's value, within the
// component's range), plus for each measured signal whose component
// declares no offset of its own the measurement faults OUTPUT.offset,
// OUTPUT.gain and OUTPUT.lag. A factor on a parameter the netlist gives as a
// top-level parameter that a run's operating point sets (`per_run`) acts on
// each run's value (SetPatch::per_run_of). A fault that cannot be used here
// - a factor on a parameter the netlist leaves without value or that a
// run's operating point sets as COMPONENT.PARAMETER, a patch the model does
// not accept - is unavailable, with the reason, not an error.
Catalogue declared_faults(const Netlist& model, const Registry& registry, const std::vector<MeasuredSignal>& signals,
                          const std::vector<std::string>& per_run);

// One netlist parameter as a fitted parameter, as a `recalibrate:` entry
// would make it (`pneumo calibrate --free`): KEY is NAME or
// COMPONENT.PARAMETER; `lower` and `upper` are SI numbers or factors of the
// netlist's value ("0.5x"), empty for 0.25x and 4x; the scale is log unless
// the range reaches zero or below. Errors name `origin` (the option).
Effect recalibration(const std::string& key, const std::string& lower, const std::string& upper, const Netlist& model,
                     const Registry& registry, const std::string& origin);

// A recalibration of a top-level parameter the runs' operating points set
// (a load written m: m_load): no single value can be fitted, so the effect
// becomes a factor k on each run's own value (a RunFactor), its range the
// recalibration's over the netlist's value; null and initial 1.
void recalibrate_each_runs_value(Effect& e);

// `extra`'s effects added to `base`'s, one of the same name replacing it;
// `extra`'s phases when it has any.
Catalogue merge_catalogues(Catalogue base, const Catalogue& extra);

// Only the effects named in `keep` as NAME, COMPONENT or FAULT (a
// component's or output's faults, one fault of every component); an entry
// matching none is an error naming it (the `--faults` option).
Catalogue narrow_catalogue(Catalogue cat, const std::vector<std::string>& keep);

// The model with the effects applied in order (later `set`s win). A value
// that is exactly ${expr} becomes its SI number (ValueDecl::number); patched
// declarations keep the catalogue's file:line.
// A set per run goes to `run_factors` when given; else it is applied at the
// model's own value of its top-level parameter (a model not run per run).
Netlist apply_effects(const Netlist& model, const std::vector<EffectInstance>& effects,
                      MeasurementModel* measurement, std::vector<RunFactor>* run_factors = nullptr);
// The sets per run on a run's netlist, after its operating point.
void apply_run_factors(Netlist& run, const std::vector<RunFactor>& run_factors);

// The parameter names two effects both `set`, replace or disconnect (a conflict for combining them).
bool effects_conflict(const Effect& a, const Effect& b);

// Whether effect `e` at its null leaves `model` exactly as it is: it adds,
// replaces and reconnects nothing, every component it sets is built with the
// same parameter values as before (a declared fault's null is its
// parameter's default), every top-level value it sets is unchanged, and its
// measurement is the identity. Such an instance can be left out of a model
// without changing a single bit of its runs.
bool vanishes_at_null(const Effect& e, const Netlist& model, const Registry& registry);

}  // namespace pneumo::diagnose
