// Study parameters: which netlist values a sweep or a sensitivity analysis
// varies, and how a run's values are put into the netlist.
//
// A parameter is named either as a top-level netlist parameter (`p_supply`,
// as with `pneumo simulate --set`) or as `component.parameter`
// (`cylinder.friction_scale`), which replaces that component's value in the
// netlist - so that any scalar parameter can be studied without editing the
// netlist. Values are SI numbers inside; on the command line they may carry
// units (`5 bar`, `2 cm3`).
#pragma once

#include <string>
#include <vector>

#include "framework/model/registry.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo::study {

struct StudyParameter {
  std::string name;       // as written: "p_supply" or "cylinder.friction_scale"
  std::string component;  // empty for a top-level parameter
  std::string parameter;  // the top-level or component parameter name
  std::string unit;       // SI unit of the value
  // How results show it: the unit the user wrote (in --grid or a samples
  // header), else dm3/(s*bar) for a conductance, else the SI unit.
  std::string display_unit;
  double display_scale = 1.0, display_offset = 0.0;  // si = scale * shown + offset
  double shown(double si) const { return (si - display_offset) / display_scale; }
};

// Resolve NAME against the netlist (and the registry for component
// parameters); throws InputError naming the netlist and what exists.
StudyParameter resolve_parameter(const Netlist& netlist, const Registry& registry, const std::string& name);

// Parse a value for `p`: an SI number or a quantity with a unit of the right
// dimension. `option` names the command-line text for error messages.
double parse_value(const Netlist& netlist, const Registry& registry, const StudyParameter& p,
                   const std::string& text, const std::string& option);

// One run's parameter values, in the order of the study's parameters.
using Sample = std::vector<double>;

struct Design {
  std::vector<StudyParameter> parameters;
  std::vector<Sample> samples;
};

// --grid NAME=a:b:n ...: the full factorial grid, n values from a to b
// (inclusive, evenly spaced; n = 1 takes a). The last parameter varies fastest.
Design grid_design(const Netlist& netlist, const Registry& registry, const std::vector<std::string>& specs);

// --samples FILE: a CSV whose header names the parameters (optionally
// "name [unit]", values then in that unit) and whose rows are the runs.
// '#' lines are comments. Errors name FILE:line.
Design samples_design(const Netlist& netlist, const Registry& registry, const std::string& path);

// Throws InputError naming the parameter when `parameters` holds one twice
// (a study that set it twice would silently use one of the values); `what`
// says where they were given, e.g. "--grid".
void refuse_repeated(const Netlist& netlist, const std::vector<StudyParameter>& parameters, const std::string& what);

// NAME=lo:hi ranges (for sensitivity analysis).
struct Range {
  StudyParameter parameter;
  double lo = 0.0, hi = 0.0;
};
std::vector<Range> parse_ranges(const Netlist& netlist, const Registry& registry,
                                const std::vector<std::string>& specs, const std::string& flag = "--param");

}  // namespace pneumo::study
