// modelDescription.xml (FMI 2.0, section 2.2): the elements in the order
// the schema fixes - CoSimulation, UnitDefinitions, LogCategories,
// DefaultExperiment, ModelVariables, ModelStructure.
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "framework/core/text.hpp"
#include "framework/core/version.hpp"
#include "framework/fmi/description.hpp"

namespace pneumo::fmi {

namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.15g", v);
  return buf;
}

std::string base_unit(const std::string& unit) {
  const units::Dimension d = units::dimension_of(unit);
  std::string out = "<BaseUnit";
  auto add = [&](const char* name, int e) {
    if (e != 0) out += std::string(" ") + name + "=\"" + std::to_string(e) + "\"";
  };
  add("kg", d.kg), add("m", d.m), add("s", d.s), add("K", d.K);
  return out + "/>";
}

// Each SI unit once, with the display units the outputs show it in
// (display = factor * SI + offset).
std::string unit_definitions(const Description& d) {
  std::map<std::string, std::map<std::string, units::DisplayUnit>> units;
  for (const auto& v : d.variables) {
    if (v.unit.empty()) continue;
    auto& shown = units[v.unit];
    if (!v.display.unit.empty() && v.display.unit != v.unit) shown[v.display.unit] = v.display;
  }
  if (units.empty()) return "";
  std::string out = "  <UnitDefinitions>\n";
  for (const auto& [unit, shown] : units) {
    out += "    <Unit name=\"" + markup_escaped(unit) + "\">" + base_unit(unit);
    for (const auto& [name, du] : shown)
      out += "<DisplayUnit name=\"" + markup_escaped(name) + "\" factor=\"" + num(1.0 / du.scale) + "\" offset=\"" +
             num(-du.offset / du.scale) + "\"/>";
    out += "</Unit>\n";
  }
  return out + "  </UnitDefinitions>\n";
}

std::string real_element(const Variable& v) {
  std::string out = "<Real";
  if (!v.unit.empty()) out += " unit=\"" + markup_escaped(v.unit) + "\"";
  if (!v.display.unit.empty() && v.display.unit != v.unit) out += " displayUnit=\"" + markup_escaped(v.display.unit) + "\"";
  if (v.causality != Variable::Causality::output) out += " start=\"" + num(v.start) + "\"";
  return out + "/>";
}

std::string scalar_variable(const Variable& v, std::size_t vr) {
  static const char* kinds[] = {
      R"(causality="output" variability="continuous" initial="calculated")",
      R"(causality="input" variability="continuous")",
      // Set before initialisation only: a parameter shapes the elaborated
      // circuit (volumes, start pressures), which is built then.
      R"(causality="parameter" variability="fixed" initial="exact")",
  };
  return "    <ScalarVariable name=\"" + markup_escaped(v.name) + "\" valueReference=\"" + std::to_string(vr) + "\" " +
         kinds[static_cast<int>(v.causality)] + " description=\"" + markup_escaped(v.description) + "\">" + real_element(v) +
         "</ScalarVariable>\n";
}

// Outputs, and the same as initial unknowns (calculated at initialisation);
// no dependencies given: each may depend on every input.
std::string model_structure(const Description& d) {
  std::string unknowns;
  for (std::size_t i = 0; i < d.variables.size(); ++i)
    if (d.variables[i].causality == Variable::Causality::output)
      unknowns += "      <Unknown index=\"" + std::to_string(i + 1) + "\"/>\n";
  if (unknowns.empty()) return "  <ModelStructure/>\n";
  return "  <ModelStructure>\n    <Outputs>\n" + unknowns + "    </Outputs>\n    <InitialUnknowns>\n" + unknowns +
         "    </InitialUnknowns>\n  </ModelStructure>\n";
}

}  // namespace

std::string model_description_xml(const Description& d, const std::string& identifier) {
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"" + markup_escaped(d.model_name) + "\" guid=\"" + d.guid +
         "\" description=\"pneumo circuit " + markup_escaped(d.model_name) + "\" generationTool=\"pneumo " +
         markup_escaped(PNEUMO_VERSION_STRING) + "\" variableNamingConvention=\"flat\" numberOfEventIndicators=\"0\">\n";
  out += "  <CoSimulation modelIdentifier=\"" + markup_escaped(identifier) +
         "\" needsExecutionTool=\"false\" canHandleVariableCommunicationStepSize=\"true\" "
         "canInterpolateInputs=\"false\" maxOutputDerivativeOrder=\"0\" canRunAsynchronuously=\"false\" "
         "canBeInstantiatedOnlyOncePerProcess=\"false\" canNotUseMemoryManagementFunctions=\"true\" "
         "canGetAndSetFMUstate=\"false\" canSerializeFMUstate=\"false\" providesDirectionalDerivative=\"false\"/>\n";
  out += unit_definitions(d);
  out += "  <LogCategories>\n"
         "    <Category name=\"logEvents\" description=\"the circuit's events (valves, stops, switches)\"/>\n"
         "    <Category name=\"logStatusError\" description=\"errors: why a call returned fmi2Error\"/>\n"
         "  </LogCategories>\n";
  out += "  <DefaultExperiment startTime=\"" + num(d.t_start) + "\" stopTime=\"" + num(d.t_end) + "\" tolerance=\"" +
         num(d.rtol) + "\" stepSize=\"" + num(d.step) + "\"/>\n";
  out += "  <ModelVariables>\n";
  for (std::size_t i = 0; i < d.variables.size(); ++i) out += scalar_variable(d.variables[i], i);
  out += "  </ModelVariables>\n";
  return out + model_structure(d) + "</fmiModelDescription>\n";
}

}  // namespace pneumo::fmi
