// Elaboration: a Netlist's declarations made into component instances with
// SI parameters (converted, defaulted and range checked), connections of
// resolved ports and output probes.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <utility>

#include "framework/core/expression.hpp"
#include "framework/model/signal_loops.hpp"
#include "framework/model/start_conflicts.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/netlist/reader.hpp"

namespace pneumo {

using namespace netlist_detail;

namespace {

Dimension spec_dimension(const ParameterSpec& spec) { return units::dimension_of(spec.unit); }

// How a scalar was written, `what` naming it for the message. A gauge unit
// gives only absolute pressures (ParameterSpec::is_absolute). A bare number
// is SI, refused where that is implausible for the parameter's dimension
// (`bore: 40` would be 40 m): the message gives the unit to write.
void check_written(const Reader& r, const ValueDecl& node, const ComponentDecl& c, const ParameterSpec& spec,
                   const units::Quantity& q, const std::string& what, const std::string& number) {
  if (q.gauge && !spec.is_absolute)
    r.fail(node, c.name, spec.name,
           what + " is a gauge pressure, but '" + spec.name +
               "' is a pressure difference: write it in bar (e.g. '0.2 bar'), not barg or psig");
  if (q.had_unit || (spec.bare_max > 0 && std::abs(q.si_value) <= spec.bare_max)) return;
  const std::string unit = units::habitual_unit_if_implausible(q.si_value, spec_dimension(spec));
  if (!unit.empty())
    r.fail(node, c.name, spec.name,
           what + " has no unit, so it is read as " + units::format_si(q.si_value, spec_dimension(spec)) +
               ", which is not plausible for '" + spec.name + "'; write its unit, e.g. '" +
               number + " " + unit + "'");
}

}  // namespace

double parameter_value(const Netlist& nl, const ComponentDecl& c, const ParameterSpec& spec,
                       const ValueDecl& node) {
  Reader r(nl.file);
  if (node.si) return *node.si;
  const std::string text = r.scalar_text(node, c.name, spec.name, "the value");
  const Dimension dim = spec_dimension(spec);
  if (is_identifier(text)) {
    const TopParameter* tp = nl.parameter(text);
    if (!tp) {
      std::vector<std::string> names;
      for (const auto& p : nl.parameters) names.push_back(p.name);
      r.fail(node, c.name, spec.name,
             "'" + text + "' is not a number, a quantity with unit (e.g. '2 " + (spec.unit.empty() ? "1" : spec.unit) +
                 "') or the name of a top-level parameter; " +
                 (names.empty() ? std::string("the netlist declares no top-level parameters")
                                : "top-level parameters: " + choices_hint(text, names)));
    }
    if (tp->had_unit && !(tp->dim == dim))
      r.fail(node, c.name, spec.name,
             "top-level parameter '" + text + "' (" + tp->where.to_string() + ") has dimension " +
                 tp->dim.to_string() + " but this parameter needs " + spec.unit + " (" + dim.to_string() + ")");
    check_written(r, node, c, spec, {tp->si_value, tp->dim, tp->had_unit, tp->gauge},
                  "top-level parameter '" + text + "' (" + tp->where.to_string() + ")", units::format_si(tp->si_value, {}));
    return tp->si_value;
  }
  const double v = r.quantity(node, nl.gas.p_ambient, dim, spec.unit, c.name, spec.name);
  check_written(r, node, c, spec, units::parse_quantity(text, nl.gas.p_ambient), "'" + text + "'", text);
  return v;
}

namespace {

// A component's registry entry; an unknown type is an error at its line.
const Registry::Entry& entry_of(const Registry& registry, const ComponentDecl& c) {
  const Registry::Entry* entry = registry.find(c.type);
  if (!entry)
    throw InputError(c.type_where.line > 0 ? c.type_where : c.where, c.name, "type",
                     "unknown component type '" + c.type + "'; " + choices_hint(c.type, registry.types()) +
                         " (run 'pneumo components' for the list)");
  return *entry;
}

double scalar_parameter(const Reader& r, const Netlist& nl, const ComponentDecl& c, const ParameterSpec& spec,
                        const ValueDecl& pnode) {
  const std::string& pname = spec.name;
  const double v = parameter_value(nl, c, spec, pnode);
  if (!spec.in_range(v)) {
    std::string from;
    if (pnode.shape == ValueDecl::Shape::scalar && !pnode.si && is_identifier(pnode.text))
      if (const TopParameter* tp = nl.parameter(pnode.text))
        from = " (from top-level parameter '" + tp->name + "' at " + tp->where.to_string() + ")";
    r.fail(pnode, c.name, pname, "value " + units::format_si(v, spec_dimension(spec)) + from +
                                     " is out of range; valid: " + spec.range_text() + " (" + spec.unit + ")");
  }
  return v;
}

// A table: rows of the spec's columns, each cell converted and range checked.
Table table_parameter(const Reader& r, const Netlist& nl, const ComponentDecl& c, const ParameterSpec& spec,
                      const ValueDecl& pnode) {
  const std::string& pname = spec.name;
  if (pnode.shape != ValueDecl::Shape::list || pnode.items.empty())
    r.fail(pnode, c.name, pname, "a table is a list of rows, e.g. [[0, 0], [1.5, 0.12 dm3/(s*bar)]]");
  Table t;
  for (const auto& row : pnode.items) {
    if (row.shape != ValueDecl::Shape::list || row.items.size() != spec.columns.size())
      r.fail(row, c.name, pname,
             "each row needs " + std::to_string(spec.columns.size()) + " values (" + join(spec.columns) + ")");
    std::vector<double> vals;
    std::size_t col = 0;
    for (const auto& cell : row.items) {
      ParameterSpec cs = ParameterSpec::scalar(pname, spec.columns[col++], "");
      const double v = parameter_value(nl, c, cs, cell);
      if (!cs.in_range(v))
        r.fail(cell, c.name, pname,
               "row " + std::to_string(t.size() + 1) + ", column " + std::to_string(col) + ": value " +
                   units::format_si(v, spec_dimension(cs)) + " is out of range; valid: " + cs.range_text() +
                   " (" + cs.unit + ")");
      vals.push_back(v);
    }
    t.push_back(std::move(vals));
  }
  return t;
}

std::string text_parameter(const Reader& r, const Netlist& nl, const ComponentDecl& c, const ParameterSpec& spec,
                           const ValueDecl& pnode) {
  const std::string& pname = spec.name;
  const std::string v = r.scalar_text(pnode, c.name, pname, "the value");
  if (!spec.choices.empty() &&
      std::find(spec.choices.begin(), spec.choices.end(), v) == spec.choices.end())
    r.fail(pnode, c.name, pname, "'" + v + "' is not allowed; " + choices_hint(v, spec.choices));
  if (spec.is_path && !v.empty() && std::filesystem::path(v).is_relative())
    return (std::filesystem::path(nl.file).parent_path() / v).lexically_normal().string();
  return v;
}

// One parameter the declaration gives, converted by its spec.
void given_parameter(const Reader& r, const Netlist& nl, const ComponentDecl& c, const ComponentInfo& info,
                     const std::string& pname, const ValueDecl& pnode, ParameterValues& out) {
  const ParameterSpec* spec = info.parameter(pname);
  if (!spec) {
    std::vector<std::string> names;
    for (const auto& s : info.parameters) names.push_back(s.name);
    throw InputError(c.where_of(pname), c.name, pname,
                     "unknown parameter of type '" + c.type + "'; " + choices_hint(pname, names) +
                         " (run 'pneumo components " + c.type + "')");
  }
  switch (spec->kind) {
    case ParameterKind::scalar: out.set_scalar(pname, scalar_parameter(r, nl, c, *spec, pnode)); break;
    case ParameterKind::table: out.set_table(pname, table_parameter(r, nl, c, *spec, pnode)); break;
    case ParameterKind::text: out.set_text(pname, text_parameter(r, nl, c, *spec, pnode)); break;
  }
}

// The parameters the declaration gives. A value from the command line
// (--set C.P=V) is checked as a written one; its errors say where it came from.
std::set<std::string> given_parameters(const Reader& r, const Netlist& nl, const ComponentDecl& c,
                                       const ComponentInfo& info, ParameterValues& out) {
  std::set<std::string> given;
  for (const auto& [pname, pnode] : c.parameters) {
    try {
      given_parameter(r, nl, c, info, pname, pnode, out);
    } catch (const InputError& e) {
      const std::string prefix = pnode.given_by + ": ";
      if (pnode.given_by.empty() || e.message().rfind(prefix, 0) == 0) throw;
      throw InputError(e.where(), e.component(), e.parameter(), prefix + e.message());
    }
    given.insert(pname);
  }
  return given;
}

// Defaults of the parameters not given; a required one missing is an error.
void default_parameters(const Netlist& nl, const ComponentDecl& c, const ComponentInfo& info,
                        const std::set<std::string>& given, ParameterValues& out) {
  for (const auto& spec : info.parameters) {
    if (given.count(spec.name)) continue;
    if (spec.kind == ParameterKind::scalar && spec.default_value) {
      out.set_scalar(spec.name, *spec.default_at(nl.gas.p_ambient, nl.gas.T_ambient));
    } else if (spec.kind == ParameterKind::text && spec.default_text) {
      out.set_text(spec.name, *spec.default_text);
    } else if (spec.is_optional || (spec.kind == ParameterKind::table && !spec.required_table)) {
      // optional: absent
    } else {
      throw InputError(c.where, c.name, spec.name,
                       "missing required parameter '" + spec.name + "' of type '" + c.type + "' (" +
                           (spec.kind == ParameterKind::table ? std::string("table") : spec.unit) + ", " +
                           spec.description + "); add it, e.g. {type: " + c.type + ", " + spec.name + ": ...}");
    }
  }
}

ParameterValues resolved(const Reader& r, const Netlist& nl, const ComponentDecl& c, const ComponentInfo& info) {
  ParameterValues values;
  const auto given = given_parameters(r, nl, c, info, values);
  default_parameters(nl, c, info, given, values);
  return values;
}

std::unique_ptr<Component> make_component(const Reader& r, const Netlist& nl, const ComponentDecl& c,
                                          const Registry& registry) {
  const Registry::Entry& entry = entry_of(registry, c);
  Construction k;
  k.name = c.name;
  k.params = resolved(r, nl, c, *entry.info);
  try {
    k.info = entry.instance_info(k.params);
    return entry.make(k);
  } catch (const ParameterError& e) {
    SourceLocation w = c.where;
    std::string given_by;
    for (const auto& [pname, pnode] : c.parameters)
      if (pname == e.parameter()) {
        w = pnode.where;
        given_by = pnode.given_by.empty() ? "" : pnode.given_by + ": ";
      }
    throw InputError(w, c.name, e.parameter(), given_by + e.what());
  }
}

PortId resolve_port(const Circuit& circuit, const std::map<std::string, int>& index, const PortRefDecl& ref) {
  auto it = index.find(ref.component);
  if (it == index.end()) {
    std::vector<std::string> names;
    for (const auto& [n, i] : index) names.push_back(n);
    throw InputError(ref.where, ref.component, "", "no component named '" + ref.component + "'; " +
                                                       choices_hint(ref.component, names));
  }
  const auto& info = circuit.components[it->second]->info();
  const int port = info.port_index(ref.port);
  if (port < 0) {
    std::vector<std::string> names;
    for (const auto& p : info.ports) names.push_back(p.name);
    throw InputError(ref.where, ref.component, "",
                     "type '" + info.type + "' has no port '" + ref.port + "'; " + choices_hint(ref.port, names));
  }
  return {it->second, port};
}

// The probe behind an output: an observable, a local variable, or a signal
// port by its name alone (source.y for the value of port y).
Probe make_probe(const Netlist& nl, const Circuit& circuit, const std::map<std::string, int>& index,
                 const OutputDecl& o) {
  auto it = index.find(o.component);
  if (it == index.end()) {
    std::vector<std::string> names;
    for (const auto& [n, i] : index) names.push_back(n);
    throw InputError(o.where, o.component, "", "output '" + o.name + "': no component named '" + o.component +
                                                   "'; " + choices_hint(o.component, names));
  }
  const Component& comp = *circuit.components[it->second];
  Probe probe = find_probe(circuit, it->second, o.quantity);
  probe.name = o.name;
  if (probe.index < 0) {
    std::vector<std::string> valid;
    for (const auto& ob : comp.info().observables) valid.push_back(ob.name);
    for (const auto& n : local_variable_names(comp)) valid.push_back(n);
    throw InputError(o.where, o.component, "", "output '" + o.name + "': type '" + comp.info().type +
                                                   "' has no variable '" + o.quantity + "'; " +
                                                   choices_hint(o.quantity, valid));
  }
  if (o.integral) {
    probe.integral = true;
    probe.unit = probe.unit == "W"                              ? "J"
                 : probe.unit == "kg/s"                         ? "kg"
                 : probe.unit.find('/') != std::string::npos ? "(" + probe.unit + ")*s"  // "m/s*s" is ambiguous
                                                                : probe.unit + "*s";
  }
  if (!o.unit.empty()) {
    try {
      probe.display = units::display_unit(o.unit, units::dimension_of(probe.unit), nl.gas.p_ambient);
    } catch (const units::DimensionMismatch& e) {
      throw InputError(o.unit_where, o.component, "",
                       "output '" + o.name + "': unit '" + o.unit + "' does not fit '" + o.quantity + "' in " + probe.unit +
                           ": " + e.what());
    }
  } else if (!nl.display.empty()) {
    try {  // a variable's unit text (a plugin's) that is no unit expression has no default display
      const units::Dimension dim = units::dimension_of(probe.unit);
      if (const std::string unit = nl.display_unit_for(dim); !unit.empty())
        probe.display = units::display_unit(unit, dim, nl.gas.p_ambient);
    } catch (const units::ParseError&) {
    }
  }
  return probe;
}

// The events a metric names, as (component, tag): its window and instant,
// its {event: ...}, and the COMPONENT.TAG names of its expression.
std::vector<std::pair<std::string, std::string>> named_events(const MetricDecl& m, const Netlist& nl) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto* ref : {m.from ? &*m.from : nullptr, m.to ? &*m.to : nullptr, m.at ? &*m.at : nullptr,
                          m.kind == MetricDecl::Kind::event_time ? &m.event : nullptr})
    if (ref && ref->is_event()) out.emplace_back(ref->component, ref->tag);
  if (m.kind != MetricDecl::Kind::expression) return out;
  for (const auto& n : Expression(m.expression).names()) {
    const auto dot = n.find('.');
    const bool metric = std::any_of(nl.metrics.begin(), nl.metrics.end(), [&](const MetricDecl& d) { return d.name == n; });
    if (!metric && dot != std::string::npos) out.emplace_back(n.substr(0, dot), n.substr(dot + 1));
  }
  return out;
}

// A misspelt tag would otherwise make a metric of nan in a run that succeeds.
void check_named_events(const Netlist& nl, const Circuit& circuit, const std::map<std::string, int>& index) {
  for (const auto& m : nl.metrics)
    for (const auto& [component, tag] : named_events(m, nl)) {
      const ComponentInfo& info = circuit.components[static_cast<std::size_t>(index.at(component))]->info();
      if (!info.raises(tag))
        throw InputError(m.where, component, "metrics." + m.name,
                         "metric '" + m.name + "': component '" + component + "' (" + info.type +
                             ") raises no event '" + tag + "'; its events: " + info.event_list());
    }
}

}  // namespace

ParameterValues resolved_parameters(const Netlist& nl, const ComponentDecl& c, const Registry& registry) {
  return resolved(Reader(nl.file), nl, c, *entry_of(registry, c).info);
}

Circuit elaborate(const Netlist& nl, const Registry& registry) {
  const Reader r(nl.file);
  Circuit circuit;
  circuit.gas = nl.gas;
  std::map<std::string, int> index;
  for (const auto& c : nl.components) {
    circuit.components.push_back(make_component(r, nl, c, registry));
    circuit.component_where.push_back(c.where);
    index[c.name] = static_cast<int>(circuit.components.size()) - 1;
  }
  for (const auto& conn : nl.connections) {
    Connection c;
    c.where = conn.where;
    for (const auto& ref : conn.ports) {
      const PortId id = resolve_port(circuit, index, ref);
      if (std::find(c.ports.begin(), c.ports.end(), id) != c.ports.end())
        throw InputError(ref.where, ref.component, "", "port '" + ref.port + "' appears twice in one connection");
      c.ports.push_back(id);
    }
    circuit.connections.push_back(std::move(c));
  }
  check_signal_loops(circuit);
  check_start_conflicts(circuit);
  for (const auto& o : nl.outputs) circuit.probes.push_back(make_probe(nl, circuit, index, o));
  check_named_events(nl, circuit, index);
  return circuit;
}

void add_output(const Netlist& nl, Circuit& circuit, const OutputDecl& output) {
  std::map<std::string, int> index;
  for (std::size_t i = 0; i < circuit.components.size(); ++i)
    index[circuit.components[i]->name()] = static_cast<int>(i);
  circuit.probes.push_back(make_probe(nl, circuit, index, output));
}

}  // namespace pneumo
