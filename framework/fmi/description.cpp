#include "framework/fmi/description.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <map>
#include <sstream>

#include "framework/assembly/system.hpp"
#include "framework/core/error.hpp"

namespace pneumo::fmi {

namespace {

// 64-bit FNV-1a: the same GUID from the same text in the exporter and in the
// FMU (std::hash promises no such thing).
std::uint64_t fnv1a(const std::string& text, std::uint64_t h = 1469598103934665603ull) {
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

std::string guid_of(const std::string& text) {
  const std::uint64_t a = fnv1a(text), b = fnv1a(text, a ^ 0x9e3779b97f4a7c15ull);
  char buf[48];
  std::snprintf(buf, sizeof buf, "{%08x-%04x-%04x-%04x-%012llx}", static_cast<unsigned>(a >> 32),
                static_cast<unsigned>((a >> 16) & 0xffff), static_cast<unsigned>(a & 0xffff),
                static_cast<unsigned>(b >> 48), static_cast<unsigned long long>(b & 0xffffffffffffull));
  return buf;
}

std::string si_unit(const std::string& unit) { return unit == "1" ? "" : unit; }

// The names chosen, or all; an unknown name is an error listing the choices.
std::vector<int> choose(const std::vector<std::string>& names, const std::vector<std::string>& wanted,
                        const char* what, const std::string& file) {
  std::vector<int> out;
  if (wanted.empty()) {
    for (std::size_t i = 0; i < names.size(); ++i) out.push_back(static_cast<int>(i));
    return out;
  }
  for (const auto& w : wanted) {
    const auto it = std::find(names.begin(), names.end(), w);
    if (it == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      throw InputError({file, 0, 0}, "", "", std::string("no ") + what + " '" + w + "' in the netlist; " + what + "s: " +
                                       (list.empty() ? "none" : list));
    }
    out.push_back(static_cast<int>(it - names.begin()));
  }
  return out;
}

std::string stem(const std::string& path) {
  std::string s = path.substr(path.find_last_of('/') + 1);
  return s.substr(0, s.find('.'));
}

void add_outputs(const Circuit& circuit, const Selection& sel, const std::string& file, Description& d) {
  std::vector<std::string> names;
  std::vector<int> probe;
  // Integrals are IDAS quadratures of a whole run, not a state an FMU holds.
  for (std::size_t i = 0; i < circuit.probes.size(); ++i)
    if (!circuit.probes[i].integral) {
      names.push_back(circuit.probes[i].name);
      probe.push_back(static_cast<int>(i));
    }
  for (int k : choose(names, sel.outputs, "output", file)) {
    const Probe& p = circuit.probes[probe[k]];
    Variable v{p.name, Variable::Causality::output, si_unit(p.unit), p.display, 0.0, "netlist output " + p.name,
               probe[k]};
    d.variables.push_back(std::move(v));
  }
}

void add_inputs(const System& system, const Selection& sel, const std::string& file, Description& d) {
  const std::vector<ExternalInput> inputs = system.external_inputs();
  std::vector<std::string> names;
  for (const auto& in : inputs) names.push_back(in.name);
  for (int k : choose(names, sel.inputs, "input", file)) {
    const auto& in = inputs[k];
    d.variables.push_back(
        {in.name, Variable::Causality::input, si_unit(in.spec.unit), {}, in.spec.start, in.spec.description, k});
  }
}

void add_parameters(const Netlist& netlist, Description& d) {
  for (const auto& p : netlist.parameters) {
    const std::string unit = p.dim.dimensionless() ? "" : units::si_unit_name(p.dim);
    d.variables.push_back({p.name, Variable::Causality::parameter, unit, {}, p.si_value,
                           "top-level parameter (" + p.where.to_string() + ")", -1});
  }
}

}  // namespace

Description describe(const Model& model, const Selection& selection) {
  Description d;
  d.model_name = stem(model.path);
  d.guid = guid_of(model.text + "\n--\n" + selection_text(selection));
  const auto& sim = model.netlist.simulation;
  d.t_start = sim.t_start, d.t_end = sim.t_end, d.rtol = sim.rtol, d.step = sim.output_interval;
  Circuit circuit = elaborate(model.netlist, model.registry);
  add_outputs(circuit, selection, model.path, d);
  const System system(std::move(circuit));
  add_inputs(system, selection, model.path, d);
  add_parameters(model.netlist, d);
  return d;
}

std::string selection_text(const Selection& s) {
  std::string out;
  for (const auto& n : s.inputs) out += "input " + n + "\n";
  for (const auto& n : s.outputs) out += "output " + n + "\n";
  return out;
}

Selection parse_selection(const std::string& text) {
  Selection s;
  std::istringstream in(text);
  std::string kind, name;
  while (in >> kind >> name) (kind == "input" ? s.inputs : s.outputs).push_back(name);
  return s;
}

}  // namespace pneumo::fmi
