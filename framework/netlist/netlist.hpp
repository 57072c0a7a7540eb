// YAML netlists: reading, top-level parameter overrides and elaboration into
// a Circuit of component instances. Every error names file:line:column, the
// component and the parameter.
//
// Format (see README "Writing a netlist"):
//   gas:        {R: 287.05 J/(kg*K), kappa: 1.4}          # optional, dry air
//   ambient:    {p: 1 atm, T: 20 degC}                     # optional
//   parameters: {p_supply: 5 bar, V: 1 L}                  # referenced by name
//   components:
//     tank: {type: volume, V: V, p0: 1 bar, T0: 293.15 K}
//   connections:
//     - [source.port, valve.a]
//   outputs:    {p: tank.p, T: tank.T}
//   simulation: {t_end: 2 s, rtol: 1e-6, atol: 1e-6, output_interval: 1 ms}
//   plugins:    [build/my_components.so]  # relative to the netlist's directory
#pragma once

#include <yaml-cpp/yaml.h>

#include <map>
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
  SourceLocation where;
};

struct ComponentDecl {
  std::string name;
  std::string type;
  SourceLocation where;       // of the component's name
  SourceLocation type_where;  // of the value of 'type:'
  std::vector<std::pair<std::string, YAML::Node>> parameters;  // in file order
  std::vector<SourceLocation> parameter_where;  // of each parameter's key, same order (may be empty)

  // Where parameter `name` is written (its key), or the component if absent.
  SourceLocation where_of(const std::string& parameter) const;
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
};

// A component plugin the netlist loads (framework/plugin/plugin.hpp).
struct PluginDecl {
  std::string path;      // as written
  std::string resolved;  // relative paths taken from the netlist's directory
  SourceLocation where;
};

struct Netlist {
  std::string file;
  GasModel gas;
  std::vector<TopParameter> parameters;
  std::vector<ComponentDecl> components;
  std::vector<ConnectionDecl> connections;
  std::vector<OutputDecl> outputs;
  SimulationSettings simulation;
  SourceLocation parameters_where;  // of the 'parameters:' key; file:1:1 if there is none
  std::vector<PluginDecl> plugins;

  const TopParameter* parameter(const std::string& name) const;
};

// Read and check the structure of a netlist file (not yet the components'
// parameters, which need the registry). Throws InputError.
Netlist load_netlist(const std::string& path);
Netlist parse_netlist(const std::string& text, const std::string& file_name);

// Apply `NAME=VALUE` to a top-level parameter. VALUE is an SI number or a
// quantity with unit ("7 bar"); its dimension must match the declaration.
// Errors point at the declaration (or at 'parameters:' for an unknown NAME)
// and their message starts with "--set NAME=VALUE".
void apply_override(Netlist& netlist, const std::string& assignment);

// Instantiate the components (parameters converted, defaulted and range
// checked) and resolve the connections.
Circuit elaborate(const Netlist& netlist, const Registry& registry);

// Parse one scalar parameter value against its spec (exposed for tests and
// for the fitting tools): number, quantity with unit, or top-level name.
double parameter_value(const Netlist& netlist, const ComponentDecl& component,
                       const ParameterSpec& spec, const YAML::Node& node);

SourceLocation location_of(const std::string& file, const YAML::Node& node);

}  // namespace pneumo
