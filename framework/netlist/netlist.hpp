// YAML netlists: reading, top-level parameter overrides and elaboration into
// a Circuit of component instances. Every error names file:line:column, the
// component and the parameter.
//
// Format (see docs/reference/netlist.md):
//   gas:        {R: 287.05 J/(kg*K), kappa: 1.4}          # optional, dry air
//   ambient:    {p: 1 atm, T: 20 degC}                     # optional
//   parameters: {p_supply: 5 bar, V: 1 L}                  # referenced by name
//   components:
//     tank: {type: volume, V: V, p0: 1 bar, T0: 293.15 K}
//   connections:
//     - [source.port, valve.a]
//   outputs:    {p: tank.p, T: {var: tank.T, unit: degC}}
//   metrics:    {p_max: {max: p}, t_full: {of: p, crosses: 4 bar, direction: rising}}
//   simulation: {t_end: 2 s, rtol: 1e-6, atol: 1e-6, output_interval: 1 ms}
//   plugins:    [build/my_components.so]  # relative to the netlist's directory
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "framework/core/error.hpp"
#include "framework/core/units.hpp"
#include "framework/model/circuit.hpp"
#include "framework/model/registry.hpp"
#include "framework/model/simulation_options.hpp"

namespace pneumo {

struct TopParameter {
  std::string name;
  double si_value = 0.0;
  units::Dimension dim;
  bool had_unit = false;  // false: a plain number, taken as SI
  bool gauge = false;     // written in a gauge unit (barg, psig)
  SourceLocation where;
};

// A component parameter's value as written, read once from the file: a
// scalar (a number, a quantity with unit, the name of a top-level parameter,
// or a choice), or a list of values (a table's rows, each a list of cells);
// or an SI number set by a study, which is never printed and read again.
struct ValueDecl {
  enum class Shape { scalar, list, other };  // other: a mapping or no value
  Shape shape = Shape::scalar;
  std::string text;               // scalar
  bool quoted = false;            // written in quotes: error columns point at the quote
  std::vector<ValueDecl> items;   // list
  SourceLocation where;
  std::optional<double> si;       // a study's value (SI): no text to read
  std::string given_by;           // "--set C.P=V" when the command line gave it: errors say so

  static ValueDecl number(double si_value, SourceLocation where) {
    ValueDecl v;
    v.si = si_value;
    v.where = std::move(where);
    return v;
  }
};

struct ComponentDecl {
  std::string name;
  std::string type;
  SourceLocation where;       // of the component's name
  SourceLocation type_where;  // of the value of 'type:'
  std::vector<std::pair<std::string, ValueDecl>> parameters;  // in file order
  std::vector<SourceLocation> parameter_where;  // of each parameter's key, same order (may be empty)

  // Where parameter `name` is written (its key), or the component if absent.
  SourceLocation where_of(const std::string& parameter) const;
  // The value written for `parameter`; nullptr when it is left at its default.
  const ValueDecl* written(const std::string& parameter) const;
  // Replaces the written value, or adds it (keyed at `key`).
  void write(const std::string& parameter, ValueDecl value, const SourceLocation& key);
};

struct PortRefDecl {
  std::string component;
  std::string port;
  SourceLocation where;
};

struct ConnectionDecl {
  std::vector<PortRefDecl> ports;
  SourceLocation where;
};

struct OutputDecl {
  std::string name;       // column name in the results
  std::string component;  // instance
  std::string quantity;   // variable, observable or port variable ("port.p")
  SourceLocation where;
  bool integral = false;  // {integral: comp.var}: its time integral from t_start
  std::string unit;       // display unit in result files ("" = SI), e.g. barg, mm
  SourceLocation unit_where;
};

// A moment a metric refers to: a fixed time, or the n-th event COMPONENT.TAG
// (EventResult::tag) of a run.
struct TimeRef {
  double t = 0.0;  // s, when no event is named
  std::string component, tag;
  int occurrence = 1;
  bool is_event() const { return !tag.empty(); }
};

// A named scalar result of a run (`metrics:`), defined from the outputs and
// the events (framework/analysis/run_metrics.hpp evaluates them):
//   {max: OUT}, {min: OUT}          extreme, optionally within from / to
//   {value: OUT, at: TIME|EVENT}    value at a time or an event
//   {final: OUT}                    value at the end of the run
//   {of: OUT, crosses: LEVEL, direction: rising|falling|any, n: N}
//                                   time of the n-th crossing (within from / to)
//   {event: COMP.TAG, n: N}         time of the n-th such event
//   {integral: COMP.QUANTITY}       time integral (IDAS quadrature) over from / to
//   {expr: "a - b", unit: s}        arithmetic of metrics, numbers and event times COMP.TAG
//   {audit: COMP.TERM}              a term of COMP's energy audit (J); COMP.residual
//                                   is the audit's relative closure (in - out) / in
struct MetricDecl {
  enum class Kind { max, min, value, final_value, crossing, event_time, integral, expression, audit };
  std::string name;
  Kind kind = Kind::max;
  std::string output;  // column; for integral and audit: COMPONENT.QUANTITY / COMPONENT.TERM
  std::optional<TimeRef> from, to, at;
  units::Quantity level{};  // SI
  int direction = 0;  // +1 rising, -1 falling, 0 either
  int occurrence = 1;
  TimeRef event;
  std::string expression;
  std::string unit;  // declared display unit ("" = its output's, else SI)
  SourceLocation where;
};

// A component plugin the netlist loads (framework/plugin/plugin.hpp).
struct PluginDecl {
  std::string path;      // as written
  std::string resolved;  // relative paths taken from the netlist's directory
  SourceLocation where;
};

// `display:` - the unit result files, plots and printed figures show a
// quantity in when its output or metric names none; inside, values stay SI.
// A pressure output is an absolute pressure, so a gauge default shows it
// gauge; a metric computed from pressures (an expression, an integral) is
// shown in the default's plain twin (barg -> bar), which is true of a
// difference and of an absolute value alike.
struct DisplayDefault {
  std::string quantity;  // "pressure", "length", ... (units::named_quantities)
  units::Dimension dim;
  std::string unit;  // "barg", "mm", "degC"
  SourceLocation where;
};

struct Netlist {
  std::string file;
  GasModel gas;
  std::vector<TopParameter> parameters;
  std::vector<ComponentDecl> components;
  std::vector<ConnectionDecl> connections;
  std::vector<OutputDecl> outputs;
  std::vector<MetricDecl> metrics;
  SimulationSettings simulation;
  SourceLocation parameters_where;  // of the 'parameters:' key; file:1:1 if there is none
  std::vector<PluginDecl> plugins;
  std::vector<DisplayDefault> display;

  const TopParameter* parameter(const std::string& name) const;
  const ComponentDecl* component(const std::string& name) const;
  ComponentDecl* component(const std::string& name);
  // The unit `display:` gives values of dimension `dim`, or "" (SI).
  std::string display_unit_for(units::Dimension dim) const;
};

// Read and check the structure of a netlist file (not yet the components'
// parameters, which need the registry). Throws InputError.
Netlist load_netlist(const std::string& path);
Netlist parse_netlist(const std::string& text, const std::string& file_name);

// The name of a value of a netlist: a top-level parameter (component empty),
// a component's parameter, or a `simulation:` key (component "simulation").
struct ParameterPath {
  std::string component, parameter;
  static ParameterPath parse(const std::string& name);  // NAME, COMPONENT.PARAMETER or simulation.KEY
  std::string text() const { return component.empty() ? parameter : component + "." + parameter; }
};

// The one way to change a value of a netlist, for every face (--set, a run
// file's operating point, studies, the diagnosis, Python): `text` an SI
// number or a quantity for a top-level parameter or a simulation key, or a
// component's value as it would be written in the netlist (read and checked
// at elaboration). Errors start with `origin` ("--set p=7 bar", "run cal1:
// operating point") and point at the netlist's declaration.
void set_value(Netlist& netlist, const ParameterPath& path, const std::string& text, const std::string& origin);
// A component's value as it is written somewhere else - a catalogue's
// patch - keeping that place (v.where) for its errors: it replaces the
// netlist's value or is added. Throws InputError for a component the
// netlist lacks.
void set_value(Netlist& netlist, const ParameterPath& path, ValueDecl v);
// A component parameter's value as the netlist writes it; nullptr when it
// is left at its default or the netlist has no such component.
const ValueDecl* value_of(const Netlist& netlist, const ParameterPath& path);
// An SI number from a study or a fit, never printed and read again: a
// top-level parameter's value, or a component's (added if the netlist left
// it at its default). Throws InputError for a name the netlist lacks.
void set_si_value(Netlist& netlist, const ParameterPath& path, double si_value);

// Apply `--set NAME=VALUE`, the same for every command and Python: NAME a
// top-level parameter (VALUE an SI number or a quantity with unit, "7 bar",
// of the declared dimension), COMPONENT.PARAMETER (VALUE as it would be
// written in the netlist, read and checked at elaboration) or simulation.KEY.
// Errors point at the declaration (or at 'parameters:' for an unknown NAME)
// and their message starts with "--set NAME=VALUE".
void apply_override(Netlist& netlist, const std::string& assignment);

// Instantiate the components (parameters converted, defaulted and range
// checked) and resolve the connections.
Circuit elaborate(const Netlist& netlist, const Registry& registry);
// The parameter values component `c` of `netlist` is built with (converted,
// defaulted, range checked), as elaborate() gives them to its constructor.
ParameterValues resolved_parameters(const Netlist& netlist, const ComponentDecl& c, const Registry& registry);
// Add one more output to a circuit elaborated from `netlist`, as if it had
// been declared last under its `outputs:` (an analysis that learns from the
// circuit which columns it needs adds them so, without elaborating again).
void add_output(const Netlist& netlist, Circuit& circuit, const OutputDecl& output);

// Parse one scalar parameter value against its spec (exposed for tests and
// for the fitting tools): number, quantity with unit, or top-level name.
double parameter_value(const Netlist& netlist, const ComponentDecl& component,
                       const ParameterSpec& spec, const ValueDecl& value);

}  // namespace pneumo
