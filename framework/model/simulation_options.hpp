// The solver settings of a netlist's `simulation:` section, declared once:
// the values in SimulationSettings (their initialisers are the defaults) and
// one row per setting in simulation_options() - the netlist key, unit,
// default, valid range and what it does. The netlist reader takes its keys,
// units and ranges from the table, `pneumo simulate --help` prints it, and
// tests/simulation_options_test.cpp holds the reader, the help and
// docs/reference/netlist.md's table against it. Adding a setting: a member here, a row in
// simulation_options.cpp, and its use in the solver (SolverOptions extends
// SimulationSettings).
#pragma once

#include <string>
#include <vector>

#include "framework/core/error.hpp"
#include "framework/model/component.hpp"

namespace pneumo {

struct SimulationSettings {
  double t_start = 0.0;
  double t_end = 1.0;
  double rtol = 1e-6;
  double atol = 1e-6;
  double output_interval = 1e-3;
  double max_step = 0.0;
  bool jacobian_reuse = true;
  bool steady_start = false;
};

// One setting: its spec (name, unit, default, range, description; a
// true/false setting is a text spec with those two choices) and where its
// value lives in SimulationSettings.
struct SimulationOption {
  ParameterSpec spec;
  double SimulationSettings::*number = nullptr;  // a quantity in spec.unit
  bool SimulationSettings::*flag = nullptr;      // true or false
};

const std::vector<SimulationOption>& simulation_options();

// What is wrong with settings whose values are each in range, as a whole
// ("t_end (...) must be > t_start (...)"), or "" if nothing.
std::string simulation_settings_problem(const SimulationSettings& s);

// `--set simulation.KEY=VALUE`: KEY a row of the table, VALUE a number, a
// quantity in the row's unit ("20 ms") or true/false. Returns false, and
// changes nothing, if `assignment` does not start with "simulation.". Bad
// keys and values are InputErrors at `where` naming simulation.KEY.
bool apply_simulation_override(SimulationSettings& s, const std::string& assignment, const SourceLocation& where);

// One line per setting: "  rtol [1]  default 1e-06, (0, 1): relative ...".
std::string simulation_options_help();

}  // namespace pneumo
