// What an exported FMU shows an importer: its variables (the netlist's
// outputs, the circuit's external inputs, the top-level parameters) with
// value references, units and display units, and modelDescription.xml.
// The export (pneumo export-fmu) and the FMU's runtime build the same
// description from the same netlist and selection, so value references
// agree by construction.
#pragma once

#include <string>
#include <vector>

#include "framework/core/units.hpp"
#include "framework/run/model.hpp"

namespace pneumo::fmi {

struct Variable {
  enum class Causality { output, input, parameter };
  std::string name;
  Causality causality = Causality::output;
  std::string unit;               // SI ("" dimensionless)
  units::DisplayUnit display;     // display.unit "" = SI
  double start = 0.0;             // inputs and parameters
  std::string description;
  int index = -1;                 // output: the circuit probe; input: the System's external input
};

// Which of the netlist's outputs and external inputs the FMU offers (empty:
// all). Names not found throw InputError naming the choices.
struct Selection {
  std::vector<std::string> inputs, outputs;
};

struct Description {
  std::string model_name;  // the netlist's title or file name
  std::string guid;        // from the netlist's text and the selection
  std::vector<Variable> variables;  // value reference = position
  // The netlist's simulation settings, the importer's default experiment.
  double t_start = 0, t_end = 1, rtol = 1e-6, step = 1e-3;
};

// Elaborates and assembles the model once to find its inputs.
Description describe(const Model& model, const Selection& selection);

// modelDescription.xml of a co-simulation FMU whose shared library is
// binaries/linux64/IDENTIFIER.so.
std::string model_description_xml(const Description& d, const std::string& identifier);

// The selection as stored in the FMU's resources (one "input NAME" or
// "output NAME" a line), and read back.
std::string selection_text(const Selection& s);
Selection parse_selection(const std::string& text);

}  // namespace pneumo::fmi
