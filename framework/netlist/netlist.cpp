#include "framework/netlist/netlist.hpp"

#include "framework/core/text.hpp"
#include "framework/io/files.hpp"
#include "framework/model/gas_parameters.hpp"
#include "framework/netlist/metric_reader.hpp"
#include "framework/netlist/reader.hpp"
#include "framework/netlist/yaml_location.hpp"

#include <yaml-cpp/depthguard.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <set>
#include <sstream>
#include <utility>

#include <yaml-cpp/eventhandler.h>

namespace pneumo {

using namespace netlist_detail;


SourceLocation ComponentDecl::where_of(const std::string& parameter) const {
  for (std::size_t i = 0; i < parameters.size(); ++i)
    if (parameters[i].first == parameter) {
      if (i < parameter_where.size()) return parameter_where[i];
      const SourceLocation& w = parameters[i].second.where;
      return w.line > 0 ? w : where;
    }
  return where;
}

SourceLocation location_of(const std::string& file, const YAML::Node& node) {
  SourceLocation w;
  w.file = file;
  if (node.IsDefined() && node.Mark().line >= 0) {
    w.line = node.Mark().line + 1;
    w.column = node.Mark().column + 1;
  }
  return w;
}

void check_no_nul(const std::string& file, const std::string& text) {
  const std::size_t at = text.find('\0');
  if (at == std::string::npos) return;
  const std::size_t line_start = text.rfind('\n', at) == std::string::npos ? 0 : text.rfind('\n', at) + 1;
  const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
  throw InputError(SourceLocation{file, static_cast<int>(line), static_cast<int>(at - line_start) + 1}, "", "",
                   "a NUL byte: the file holds binary data, not YAML text");
}

namespace {

// Notes where a second document's first node is; builds nothing.
class DocumentFinder final : public YAML::EventHandler {
 public:
  int documents = 0, second_line = 0;
  void OnDocumentStart(const YAML::Mark&) override { ++documents; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark& m, YAML::anchor_t) override { content(m); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t, const std::string&) override { content(m); }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    content(m);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    content(m);
  }
  void OnMapEnd() override {}

 private:
  void content(const YAML::Mark& m) {
    if (documents == 2 && second_line == 0) second_line = m.line + 1;
  }
};

}  // namespace

FirstDocument load_first_document(const std::string& text) {
  FirstDocument d;
  d.root = YAML::Load(text);
  std::istringstream in(text);
  YAML::Parser parser(in);
  DocumentFinder finder;
  while (finder.documents < 2 && parser.HandleNextDocument(finder)) {
  }
  d.second_line = finder.second_line;
  return d;
}

void check_expanded_size(const std::string& file, const YAML::Node& root) {
  std::vector<YAML::Node> pending{root};
  std::size_t values = 0;
  while (!pending.empty()) {
    const YAML::Node n = pending.back();
    pending.pop_back();
    if (++values > kMaxYamlValues)
      throw InputError(SourceLocation{file, 1, 1}, "", "",
                       "with its aliases (*name) expanded, the YAML holds more than " +
                           std::to_string(kMaxYamlValues) +
                           " values, more than any circuit needs; an alias that repeats a large list or mapping "
                           "many times is the likely cause");
    if (n.IsSequence()) {
      for (const auto& item : n) pending.push_back(item);
    } else if (n.IsMap()) {
      for (const auto& entry : n) pending.push_back(entry.first), pending.push_back(entry.second);
    }
  }
}

std::string plain_text(const std::string& file, const YAML::Node& node, const std::string& component,
                       const std::string& parameter, const std::string& what) {
  if (!node.IsDefined()) throw InputError(SourceLocation{file, 0, 0}, component, parameter, what + " is missing");
  if (node.IsNull()) return "null";
  if (!node.IsScalar())
    throw InputError(location_of(file, node), component, parameter, what + " must be plain text, not a list or mapping");
  return node.Scalar();
}

const TopParameter* Netlist::parameter(const std::string& name) const {
  for (const auto& p : parameters)
    if (p.name == name) return &p;
  return nullptr;
}

const ComponentDecl* Netlist::component(const std::string& name) const {
  for (const auto& c : components)
    if (c.name == name) return &c;
  return nullptr;
}

ComponentDecl* Netlist::component(const std::string& name) {
  return const_cast<ComponentDecl*>(std::as_const(*this).component(name));
}

const ValueDecl* ComponentDecl::written(const std::string& parameter) const {
  for (const auto& [key, v] : parameters)
    if (key == parameter) return &v;
  return nullptr;
}

void ComponentDecl::write(const std::string& parameter, ValueDecl value, const SourceLocation& key) {
  const bool keyed = parameter_where.size() == parameters.size();
  for (std::size_t i = 0; i < parameters.size(); ++i)
    if (parameters[i].first == parameter) {
      parameters[i].second = std::move(value);
      if (keyed) parameter_where[i] = key;
      return;
    }
  parameters.emplace_back(parameter, std::move(value));
  if (keyed) parameter_where.push_back(key);
}

std::string Netlist::display_unit_for(units::Dimension dim) const {
  for (const auto& d : display)
    if (d.dim == dim) return d.unit;
  return "";
}

Netlist load_netlist(const std::string& path) {
  // There is no line to point at: the message names the file only.
  const SourceLocation where{path, 0, 0};
  try {
    check_input_file(path, "netlist");
  } catch (const std::invalid_argument& e) {
    throw InputError(where, "", "", std::string("cannot open the netlist file (") + e.what() + ")");
  }
  errno = 0;
  std::ifstream in(path);
  if (!in)
    throw InputError(where, "", "", std::string("cannot open the netlist file: ") +
                                        (errno ? std::strerror(errno) : "unknown reason"));
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(where, "", "", "error while reading the netlist file");
  return parse_netlist(buffer.str(), path);
}

namespace {

// yaml-cpp reports an unclosed '[', '{' or quote where it gives up, often
// lines later. Find where the unclosed thing was opened (a heuristic scan of
// the text before the error; returns line 0 if it finds nothing).
struct Unclosed {
  int line = 0, column = 0;
  std::string what;
};
Unclosed find_unclosed(const std::string& text, std::size_t end) {
  struct Open {
    char c;
    int line, column;
  };
  std::vector<Open> stack;
  char quote = 0;
  Open quote_at{};
  int line = 1, column = 0;
  char prev = '\n';  // previous non-blank character on this line, '\n' at line start
  end = std::min(end, text.size());
  for (std::size_t i = 0; i < end; ++i) {
    const char ch = text[i];
    ++column;
    if (ch == '\n') {
      ++line, column = 0, prev = '\n';
      if (quote == '\'' || quote == '"') continue;  // quoted scalars may span lines
      continue;
    }
    if (quote) {
      if (quote == '"' && ch == '\\') {
        ++i, ++column;
      } else if (ch == quote) {
        if (quote == '\'' && i + 1 < end && text[i + 1] == '\'') ++i, ++column;  // '' inside '...'
        else quote = 0;
      }
      prev = ch;
      continue;
    }
    const bool value_start = prev == '\n' || prev == ':' || prev == '-' || prev == ',' || prev == '[' ||
                             prev == '{' || prev == '?';
    if (ch == ' ' || ch == '\t' || ch == '\r') continue;
    const bool after_blank = column == 1 || text[i - 1] == ' ' || text[i - 1] == '\t';
    if (ch == '#' && after_blank) {
      while (i + 1 < end && text[i + 1] != '\n') ++i, ++column;
      continue;
    }
    if ((ch == '"' || ch == '\'') && value_start) {
      quote = ch;
      quote_at = {ch, line, column};
    } else if ((ch == '[' || ch == '{') && (value_start || !stack.empty())) {
      stack.push_back({ch, line, column});
    } else if ((ch == ']' || ch == '}') && !stack.empty()) {
      stack.pop_back();
    }
    prev = ch;
  }
  if (quote) return {quote_at.line, quote_at.column, std::string("the quoted value opened by ") + quote + " here"};
  if (!stack.empty())
    return {stack.back().line, stack.back().column,
            std::string("the ") + (stack.back().c == '[' ? "list '['" : "mapping '{'") + " opened here"};
  return {};
}

}  // namespace

namespace netlist_detail {

// One component NAME: {type: ..., parameters}; the parameters stay as
// written (ValueDecl) until elaborate() converts them against the
// registry's specs.
ComponentDecl read_component(const Reader& r, const std::string& name, const YAML::Node& key_node,
                             const YAML::Node& value) {
  if (!is_identifier(name)) r.fail(key_node, name, "", "component names must be identifiers (letters, digits, _)");
  ComponentDecl c;
  c.name = name;
  c.where = r.at(key_node);
  bool has_type = false;
  if (!value.IsMap())
    r.fail(value.IsNull() ? key_node : value, name, "",
           "a component is a mapping with a 'type' and its parameters, e.g. " + name + ": {type: volume, V: 1 L}");
  for (const auto& pe : r.mapping(value, "component '" + name + "'", name, Reader::Keys::parameters)) {
    if (pe.key == "<<")
      r.fail(pe.key_node, name, "",
             "YAML merge keys (<<) are not supported in a component; write its type and parameters out");
    if (pe.key == "type") {
      c.type = r.scalar_text(pe.value, name, "type", "the type");
      c.type_where = r.at(pe.value);
      has_type = true;
    } else {
      c.parameters.emplace_back(pe.key, r.value(pe.value));
      c.parameter_where.push_back(r.at(pe.key_node));
    }
  }
  if (!has_type) r.fail(key_node, name, "type", "the component has no 'type' (run 'pneumo components' for the list)");
  return c;
}

// One connection: a list of two or more component.port.
ConnectionDecl read_connection(const Reader& r, const YAML::Node& item) {
  if (!item.IsSequence() || item.size() < 2)
    r.fail(item, "", "", "each connection is a list of two or more ports, e.g. [source.port, valve.a]");
  ConnectionDecl conn;
  conn.where = r.at(item);
  for (const auto& pn : item) {
    const std::string s = r.scalar_text(pn, "", "", "a port reference");
    const auto dot = s.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == s.size())
      r.fail(pn, "", "", "port reference '" + s + "' must be component.port");
    conn.ports.push_back({s.substr(0, dot), s.substr(dot + 1), r.at(pn)});
  }
  return conn;
}

}  // namespace netlist_detail

namespace {

// The `simulation:` section: every key a row of simulation_options(), read
// in its unit and checked against its range.
void read_simulation(Reader& r, const YAML::Node& section, Netlist& nl) {
  auto& s = nl.simulation;
  const auto& table = simulation_options();
  std::vector<std::string> keys;
  for (const auto& o : table) keys.push_back(o.spec.name);
  YAML::Node t_end_node = section;
  for (const auto& e : r.mapping(section, "simulation", "", Reader::Keys::parameters, "simulation.")) {
    const std::string p = "simulation." + e.key;
    auto o = std::find_if(table.begin(), table.end(), [&](const SimulationOption& x) { return x.spec.name == e.key; });
    if (o == table.end())
      r.fail(e.key_node, "", p, "unknown key '" + e.key + "' in simulation; " + choices_hint(e.key, keys));
    const ParameterSpec& spec = o->spec;
    if (o->flag) {
      const std::string text = r.scalar_text(e.value, "", p, e.key);
      if (text != "true" && text != "false")
        r.fail(e.value, "", p, e.key + " must be true or false, not '" + text + "'");
      s.*(o->flag) = text == "true";
      continue;
    }
    const Dimension dim = units::dimension_of(spec.unit);
    const double v = r.quantity(e.value, nl.gas.p_ambient, dim, spec.unit, "", p);
    if (!spec.in_range(v))
      r.fail(e.value, "", p, e.key + " = " + units::format_si(v, dim) + " is out of range; valid: " +
                                 spec.range_text() + " (" + spec.unit + ")");
    s.*(o->number) = v;
    if (e.key == "t_end") t_end_node = e.value;
  }
  if (const std::string problem = simulation_settings_problem(s); !problem.empty())
    r.fail(t_end_node, "", "simulation.t_end", problem);
}


// The line of the '---' that opens the document whose first node is on
// `node_line` (the node's own line if no such marker is found).
int second_document_line(const std::string& text, int node_line) {
  int line = 1, marker = 0;
  for (std::size_t i = 0; i < text.size() && line <= node_line; ++line) {
    if (text.compare(i, 3, "---") == 0) marker = line;
    const std::size_t nl = text.find('\n', i);
    if (nl == std::string::npos) break;
    i = nl + 1;
  }
  return marker > 0 ? marker : node_line;
}

// The text as YAML reads it: without a UTF-8 byte order mark (editors on
// Windows write one, YAML would make it part of the first key) and with
// old Mac line ends (CR alone) as line ends; line numbers stay the same.
std::string normalised(std::string text) {
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
  for (std::size_t i = 0; i < text.size(); ++i)
    if (text[i] == '\r' && (i + 1 == text.size() || text[i + 1] != '\n')) text[i] = '\n';
  return text;
}

// The YAML tree of a netlist text; syntax errors at their line, with the
// unclosed bracket or quote and tab indentation named.
YAML::Node load_root(const std::string& text, const std::string& file_name) {
  check_no_nul(file_name, text);
  FirstDocument document;
  try {
    document = load_first_document(text);
  } catch (const YAML::DeepRecursion& e) {
    throw InputError(SourceLocation{file_name, e.mark.line + 1, e.mark.column + 1}, "", "",
                     "YAML nested too deeply: more than " + std::to_string(e.depth() - 1) +
                         " lists or mappings inside each other here; a netlist needs only a few levels");
  } catch (const YAML::ParserException& e) {
    SourceLocation where{file_name, e.mark.line + 1, e.mark.column + 1};
    std::string message = "YAML syntax error: " + e.msg;
    if (e.msg.find("flow") != std::string::npos || e.msg.find("quote") != std::string::npos) {
      const Unclosed u = find_unclosed(text, e.mark.pos >= 0 ? static_cast<std::size_t>(e.mark.pos) : text.size());
      if (u.line > 0 && u.line <= where.line) {
        message = "YAML syntax error: " + u.what + " is never closed (the parser gave up at line " +
                  std::to_string(where.line) + ", column " + std::to_string(where.column) + ": " + e.msg + ")";
        where.line = u.line;
        where.column = u.column;
      }
    }
    // Tabs cannot indent YAML; the parser's message does not say so.
    std::size_t line_start = 0;
    for (int l = 1; l < where.line && line_start != std::string::npos; ++l) {
      line_start = text.find('\n', line_start);
      if (line_start != std::string::npos) ++line_start;
    }
    if (line_start != std::string::npos) {
      const std::size_t first = text.find_first_not_of(' ', line_start);
      if (first != std::string::npos && text[first] == '\t')
        message += " (line " + std::to_string(where.line) + " is indented with a tab; YAML allows only spaces)";
    }
    throw InputError(where, "", "", message);
  }
  if (document.second_line > 0)
    throw InputError(SourceLocation{file_name, second_document_line(text, document.second_line), 1}, "", "",
                     "a second YAML document starts here ('---'); a netlist is one document: remove the '---' "
                     "line, or move what follows into the first document");
  check_expanded_size(file_name, document.root);
  return document.root;
}

// One section of gas constants (gas:, ambient:), each checked against its
// declared unit and range (framework/model/gas_parameters.hpp).
void read_gas_section(Reader& r, const YAML::Node& node, const std::string& section,
                      const std::vector<GasParameter>& specs, Netlist& nl) {
  std::string valid;
  for (const auto& g : specs) valid += (valid.empty() ? "" : ", ") + g.spec.name;
  for (const auto& e : r.mapping(node, section, "", Reader::Keys::parameters, section + ".")) {
    const std::string name = section + "." + e.key;
    const auto it = std::find_if(specs.begin(), specs.end(), [&](const GasParameter& g) { return g.spec.name == e.key; });
    if (it == specs.end()) r.fail(e.key_node, "", name, "unknown key '" + e.key + "' in " + section + "; valid: " + valid);
    const ParameterSpec& spec = it->spec;
    const units::Dimension dim = units::dimension_of(spec.unit);
    const double v = r.quantity(e.value, nl.gas.p_ambient, dim, spec.unit, "", name);
    if (dim == units::dims::pressure && units::parse_quantity(e.value.Scalar()).gauge)
      r.fail(e.value, "", name,
             "'" + e.value.Scalar() + "' is a gauge pressure, but the ambient pressure is the datum of gauge "
             "pressures: give it absolute, e.g. 1.01325 bar or 101325 Pa");
    if (!spec.in_range(v))
      r.fail(e.value, "", name, "value " + units::format_si(v, dim) + " is out of range; valid: " + spec.range_text() +
                                    " (" + spec.unit + ")");
    nl.gas.*(it->field) = v;
  }
}

// ambient: the atmosphere, the datum of gauge pressures.
void read_ambient(Reader& r, const YAML::Node& node, Netlist& nl) {
  read_gas_section(r, node, "ambient", ambient_parameters(), nl);
}

// gas: the ideal gas and the ISO 6358 reference state.
void read_gas(Reader& r, const YAML::Node& node, Netlist& nl) {
  read_gas_section(r, node, "gas", gas_parameters(), nl);
}

// parameters: top-level values with units, --set-able, referenced by name.
void read_parameters(Reader& r, const YAML::Node& node, Netlist& nl) {
  for (const auto& e : r.mapping(node, "parameters", "", Reader::Keys::parameters)) {
    if (!is_identifier(e.key)) r.fail(e.key_node, "", e.key, "parameter names must be identifiers");
    const std::string text = r.scalar_text(e.value, "", e.key, "a top-level parameter");
    TopParameter p;
    p.name = e.key;
    p.where = r.at(e.value);
    try {
      const auto q = units::parse_quantity(text, nl.gas.p_ambient);
      p.si_value = q.si_value;
      p.dim = q.dim;
      p.had_unit = q.had_unit;
      p.gauge = q.gauge;
    } catch (const units::ParseError& err) {
      if (is_identifier(text))
        r.fail(e.value, "", e.key,
               "'" + text + "': a top-level parameter is a value with its unit (5 bar); it cannot refer to another "
               "parameter (components can refer to top-level parameters by name)");
      r.fail(e.value, "", e.key, std::string("cannot read '") + text + "': " + err.what());
    }
    nl.parameters.push_back(p);
  }
}

// components: NAME: {type: ..., parameters}.
void read_components(Reader& r, const YAML::Node& node, Netlist& nl) {
  for (const auto& e : r.mapping(node, "components", "", Reader::Keys::components))
    nl.components.push_back(read_component(r, e.key, e.key_node, e.value));
}

// connections: lists of component.port.
void read_connections(Reader& r, const YAML::Node& node, Netlist& nl) {
  if (!node.IsSequence()) r.fail(node, "", "", "connections must be a list of lists of ports, e.g. - [a.port, b.port]");
  for (const auto& item : node) nl.connections.push_back(read_connection(r, item));
}

// outputs: name: comp.var, {var: comp.var, unit: U} or {integral: comp.var}.
void read_outputs(Reader& r, const YAML::Node& node, Netlist& nl) {
  const auto& os = node;
  auto add = [&](const std::string& name, const YAML::Node& where, const YAML::Node& ref_node) {
    // name: comp.var, or name: {integral: comp.var} for its time integral
    // (energy from a power, mass from a mass flow), integrated by the solver.
    // Either form may name a display unit: {var: comp.var, unit: barg}.
    if (const std::string why = column_name_problem(name); !why.empty())
      r.fail(where, "", "", "output name '" + name + "' " + why +
                                "; it heads a column of the results CSV: use letters, digits, _ . [ ] and spaces");
    YAML::Node ref = ref_node;
    bool integral = false;
    std::string unit;
    SourceLocation unit_where;
    if (ref_node.IsMap()) {
      for (const auto& e : r.mapping(ref_node, "output '" + name + "'")) {
        if (e.key == "unit") {
          unit = r.scalar_text(e.value, "", "", "a display unit");
          unit_where = r.at(e.value);
          try {
            units::parse_unit(unit);
          } catch (const units::ParseError& err) {
            r.fail(e.value, "", "", "output '" + name + "': unit '" + unit + "': " + err.what());
          }
        } else if (e.key != "var" && e.key != "integral") {
          r.fail(e.key_node, "", "", "output '" + name + "': unknown key '" + e.key + "'; " +
                                         choices_hint(e.key, {"var", "integral", "unit"}));
        }
      }
      if (!ref_node["var"] == !ref_node["integral"])
        r.fail(ref_node, "", "",
               "output '" + name + "': write {var: component.variable} or {integral: component.variable}, "
               "optionally with unit: (e.g. {var: cyl.p_cap, unit: barg})");
      integral = static_cast<bool>(ref_node["integral"]);
      ref = integral ? ref_node["integral"] : ref_node["var"];
    }
    const std::string s = r.scalar_text(ref, "", "", "an output reference");
    const auto dot = s.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == s.size())
      r.fail(ref, "", "", "output '" + s + "' must be component.variable");
    for (const auto& o : nl.outputs)
      if (o.name == name) r.fail(where, "", "", "duplicate output name '" + name + "'");
    nl.outputs.push_back({name, s.substr(0, dot), s.substr(dot + 1), r.at(ref), integral, unit, unit_where});
  };
  if (os.IsMap()) {
    for (const auto& e : r.mapping(os, "outputs")) add(e.key, e.key_node, e.value);
  } else if (os.IsSequence()) {
    for (const auto& item : os) add(r.scalar_text(item, "", "", "an output"), item, item);
  } else {
    r.fail(os, "", "", "outputs must be a mapping name: component.variable");
  }
}

// display: {pressure: barg, length: mm, temperature: degC, ...}: each key
// a quantity, each unit one of that quantity's.
void read_display(Reader& r, const YAML::Node& node, Netlist& nl) {
  std::vector<std::string> names;
  for (const auto& q : units::named_quantities()) names.push_back(q.name);
  for (const auto& e : r.mapping(node, "display")) {
    const auto q = std::find_if(units::named_quantities().begin(), units::named_quantities().end(),
                                [&](const units::NamedQuantity& n) { return e.key == n.name; });
    if (q == units::named_quantities().end())
      r.fail(e.key_node, "", "", "display: unknown quantity '" + e.key + "'; " + choices_hint(e.key, names));
    const std::string unit = r.scalar_text(e.value, "", "", "a display unit");
    try {
      units::display_unit(unit, q->dim, nl.gas.p_ambient);
    } catch (const std::exception& err) {  // an unknown unit, or one of another quantity
      r.fail(e.value, "", "", "display: " + e.key + ": " + err.what());
    }
    nl.display.push_back({e.key, q->dim, unit, r.at(e.value)});
  }
}

// plugins: shared libraries, relative to the netlist's folder.
void read_plugins(Reader& r, const YAML::Node& node, Netlist& nl) {
  const auto& ps = node;
  if (!ps.IsSequence()) r.fail(ps, "", "", "plugins must be a list of shared libraries, e.g. [build/my_components.so]");
  for (const auto& item : ps) {
    PluginDecl d;
    d.path = r.scalar_text(item, "", "", "a plugin path");
    if (d.path.empty()) r.fail(item, "", "", "a plugin path must not be empty");
    const std::filesystem::path p(d.path);
    d.resolved = (p.is_absolute() ? p : std::filesystem::path(nl.file).parent_path() / p).lexically_normal().string();
    d.where = r.at(item);
    nl.plugins.push_back(std::move(d));
  }
}

}  // namespace

Netlist parse_netlist(const std::string& text, const std::string& file_name) {
  Reader r(file_name);
  const YAML::Node root = load_root(normalised(text), file_name);
  if (!root.IsDefined() || root.IsNull())
    throw InputError(SourceLocation{file_name, 1, 1}, "", "", "the netlist is empty");

  Netlist nl;
  nl.file = file_name;
  nl.parameters_where = SourceLocation{file_name, 1, 1};
  static const std::vector<std::string> kTopKeys{"title",      "description", "gas",     "ambient",
                                                 "parameters", "components",  "connections", "outputs",
                                                 "simulation", "plugins",     "metrics",
                                                 "display"};
  std::map<std::string, YAML::Node> top;
  std::map<std::string, YAML::Node> top_key;
  for (const auto& e : r.mapping(root, "the netlist")) {
    if (std::find(kTopKeys.begin(), kTopKeys.end(), e.key) == kTopKeys.end())
      r.fail(e.key_node, "", "", "unknown section '" + e.key + "'; " + choices_hint(e.key, kTopKeys));
    top[e.key] = e.value;
    top_key[e.key] = e.key_node;
  }
  if (top_key.count("parameters")) nl.parameters_where = r.at(top_key["parameters"]);

  // ambient first: gauge pressures everywhere else are relative to it.
  if (top.count("ambient")) read_ambient(r, top["ambient"], nl);
  if (top.count("gas")) read_gas(r, top["gas"], nl);
  if (top.count("parameters") && !top["parameters"].IsNull()) read_parameters(r, top["parameters"], nl);
  if (!top.count("components") || top["components"].IsNull())
    throw InputError(SourceLocation{file_name, 1, 1}, "", "", "the netlist has no 'components' section");
  read_components(r, top["components"], nl);
  if (top.count("connections") && !top["connections"].IsNull()) read_connections(r, top["connections"], nl);
  if (top.count("outputs") && !top["outputs"].IsNull()) read_outputs(r, top["outputs"], nl);
  if (top.count("plugins") && !top["plugins"].IsNull()) read_plugins(r, top["plugins"], nl);
  if (top.count("display") && !top["display"].IsNull()) read_display(r, top["display"], nl);
  if (top.count("simulation") && !top["simulation"].IsNull()) read_simulation(r, top["simulation"], nl);
  if (top.count("metrics")) nl.metrics = read_metrics(top["metrics"], nl);
  return nl;
}

namespace {

// --set COMPONENT.PARAMETER=VALUE: the text replaces what the netlist wrote
// (or stands in for the default), so that elaboration reads and checks it as
// it checks a written value - unit, range, plausibility - and its errors say
// that it came from the command line.
void override_component_parameter(Netlist& nl, const std::string& name, const std::string& text,
                                  const std::string& option, const SourceLocation& netlist_where) {
  const auto dot = name.find('.');
  const std::string component = name.substr(0, dot), parameter = name.substr(dot + 1);
  ComponentDecl* c = nl.component(component);
  if (!c) {
    std::vector<std::string> names;
    for (const auto& d : nl.components) names.push_back(d.name);
    throw InputError(netlist_where, component, "",
                     option + ": no component '" + component + "' in " + nl.file + "; " + choices_hint(component, names));
  }
  if (parameter.empty() || parameter.find('.') != std::string::npos)
    throw InputError(c->where, component, parameter,
                     option + ": expected COMPONENT.PARAMETER=VALUE, e.g. --set '" + component + ".PARAMETER=2 mm'");
  ValueDecl v;
  v.text = trim(text);
  v.given_by = option;
  const ValueDecl* before = c->written(parameter);
  v.where = before ? before->where : c->where;
  c->write(parameter, std::move(v), c->where_of(parameter));
}

}  // namespace

ParameterPath ParameterPath::parse(const std::string& name) {
  const auto dot = name.find('.');
  if (dot == std::string::npos) return {"", name};
  return {name.substr(0, dot), name.substr(dot + 1)};
}

void set_value(Netlist& nl, const ParameterPath& path, const std::string& text, const std::string& origin) {
  // The mistake is in the option or the run file, but the place to compare
  // it with is the netlist: errors point at the declaration (or at 'parameters:').
  const SourceLocation netlist_where =
      nl.parameters_where.known() ? nl.parameters_where : SourceLocation{nl.file, 1, 1};
  const std::string name = path.text();
  if (path.component == "simulation" &&
      apply_simulation_override(nl.simulation, name + "=" + text, netlist_where))
    return;
  if (!path.component.empty()) return override_component_parameter(nl, name, text, origin, netlist_where);
  TopParameter* p = nullptr;
  for (auto& tp : nl.parameters)
    if (tp.name == name) p = &tp;
  if (!p) {
    std::vector<std::string> names;
    for (const auto& tp : nl.parameters) names.push_back(tp.name);
    throw InputError(netlist_where, "", name,
                     origin + ": no top-level parameter '" + name + "' under 'parameters:' in " + nl.file +
                         "; only those can be set; " + choices_hint(name, names));
  }
  units::Quantity q{};
  try {
    q = units::parse_quantity(text, nl.gas.p_ambient);
  } catch (const units::ParseError& e) {
    throw InputError(p->where, "", name, origin + ": cannot read '" + text + "': " + e.what());
  }
  if (q.had_unit && p->had_unit && !(q.dim == p->dim))
    throw InputError(p->where, "", name,
                     origin + ": '" + text + "' has dimension " + q.dim.to_string() + " but '" + name +
                         "' is declared here with dimension " + p->dim.to_string());
  if (!q.had_unit && p->had_unit)
    if (const std::string unit = units::habitual_unit_if_implausible(q.si_value, p->dim); !unit.empty())
      throw InputError(p->where, "", name,
                       origin + ": '" + text + "' has no unit, so it would be " + units::format_si(q.si_value, p->dim) +
                           "; write the unit, e.g. --set '" + name + "=" + text + " " + unit + "'");
  p->si_value = q.si_value;
  if (q.had_unit) {
    p->dim = q.dim;
    p->had_unit = true;
    p->gauge = q.gauge;
  }
}

void set_si_value(Netlist& nl, const ParameterPath& path, double si_value) {
  const SourceLocation netlist_where =
      nl.parameters_where.known() ? nl.parameters_where : SourceLocation{nl.file, 1, 1};
  if (path.component.empty()) {
    for (auto& tp : nl.parameters)
      if (tp.name == path.parameter) {
        tp.si_value = si_value;
        return;
      }
    throw InputError(netlist_where, "", path.parameter, "no top-level parameter '" + path.parameter + "'");
  }
  ComponentDecl* c = nl.component(path.component);
  if (!c) throw InputError(netlist_where, path.component, "", "no component '" + path.component + "'");
  const ValueDecl* before = c->written(path.parameter);
  c->write(path.parameter, ValueDecl::number(si_value, before ? before->where : c->where), c->where_of(path.parameter));
}

void set_value(Netlist& nl, const ParameterPath& path, ValueDecl v) {
  ComponentDecl* c = nl.component(path.component);
  if (!c) throw InputError(v.where, path.component, path.parameter, "the model has no component '" + path.component + "'");
  const SourceLocation key = v.where;
  c->write(path.parameter, std::move(v), key);
}

const ValueDecl* value_of(const Netlist& nl, const ParameterPath& path) {
  const ComponentDecl* c = nl.component(path.component);
  return c ? c->written(path.parameter) : nullptr;
}

void apply_override(Netlist& nl, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    const SourceLocation netlist_where =
        nl.parameters_where.known() ? nl.parameters_where : SourceLocation{nl.file, 1, 1};
    throw InputError(netlist_where, "", "",
                     "--set " + assignment + ": expected NAME=VALUE, e.g. --set p_supply=7e5 or --set p_supply='7 bar'");
  }
  set_value(nl, ParameterPath::parse(assignment.substr(0, eq)), assignment.substr(eq + 1), "--set " + assignment);
}

}  // namespace pneumo
