#include "framework/netlist/netlist.hpp"

#include "framework/netlist/metric_reader.hpp"
#include "framework/netlist/yaml_location.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <set>
#include <sstream>

namespace pneumo {

namespace {

using units::Dimension;

std::string join(const std::vector<std::string>& v, const std::string& sep = ", ") {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
  return s;
}

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

// Edit distance, for "did you mean" hints.
std::size_t distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  std::iota(prev.begin(), prev.end(), 0);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string choices_hint(const std::string& given, const std::vector<std::string>& valid) {
  std::string best;
  std::size_t best_d = 3;
  for (const auto& v : valid) {
    const auto d = distance(given, v);
    if (d < best_d) best_d = d, best = v;
  }
  std::string s;
  if (!best.empty()) s = "did you mean '" + best + "'? ";
  return s + "valid: " + (valid.empty() ? std::string("none") : join(valid));
}

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  SourceLocation at(const YAML::Node& n) const { return location_of(file_, n); }

  [[noreturn]] void fail(const YAML::Node& n, const std::string& component, const std::string& parameter,
                         const std::string& message) const {
    throw InputError(at(n), component, parameter, message);
  }

  // A mapping whose keys are unique strings; returns (key, key node, value).
  struct Entry {
    std::string key;
    YAML::Node key_node;
    YAML::Node value;
  };
  // What the keys of a mapping name, so that errors about a key can say
  // which component or parameter it is.
  enum class Keys { sections, components, parameters };
  std::vector<Entry> mapping(const YAML::Node& n, const std::string& what, const std::string& component = "",
                             Keys keys = Keys::sections, const std::string& prefix = "") const {
    if (!n.IsMap()) fail(n, component, "", what + " must be a mapping (key: value)");
    std::vector<Entry> out;
    std::map<std::string, YAML::Node> seen;
    for (auto it = n.begin(); it != n.end(); ++it) {
      if (!it->first.IsScalar()) fail(it->first, component, "", "keys of " + what + " must be plain names");
      const std::string key = it->first.Scalar();
      if (seen.count(key)) {
        const std::string comp = keys == Keys::components ? key : component;
        const std::string param = keys == Keys::parameters ? prefix + key : "";
        fail(it->first, comp, param,
             "duplicate key '" + key + "' in " + what + " (first written at " + at(seen[key]).to_string() +
                 "); YAML keys must be unique");
      }
      seen[key] = it->first;
      out.push_back({key, it->first, it->second});
    }
    return out;
  }

  std::string scalar_text(const YAML::Node& n, const std::string& component, const std::string& parameter,
                          const std::string& what) const {
    if (!n.IsScalar()) fail(n, component, parameter, what + " must be a single value, not a list or mapping");
    return n.Scalar();
  }

  // A number or a quantity with unit; `expected` is checked if the text has a unit.
  double quantity(const YAML::Node& n, double ambient, const Dimension& expected, const std::string& expected_unit,
                  const std::string& component, const std::string& parameter) const {
    return quantity(value(n), ambient, expected, expected_unit, component, parameter);
  }

  // The same checks on a value already read into a ValueDecl.
  [[noreturn]] void fail(const ValueDecl& v, const std::string& component, const std::string& parameter,
                         const std::string& message) const {
    throw InputError(v.where, component, parameter, message);
  }
  std::string scalar_text(const ValueDecl& v, const std::string& component, const std::string& parameter,
                          const std::string& what) const {
    if (v.shape != ValueDecl::Shape::scalar) fail(v, component, parameter, what + " must be a single value, not a list or mapping");
    return v.text;
  }
  double quantity(const ValueDecl& v, double ambient, const Dimension& expected, const std::string& expected_unit,
                  const std::string& component, const std::string& parameter) const {
    if (v.si) return *v.si;
    const std::string text = scalar_text(v, component, parameter, "the value");
    units::Quantity q{};
    try {
      q = units::parse_quantity(text, ambient);
    } catch (const units::ParseError& e) {
      SourceLocation w = v.where;
      if (w.column > 0 && !v.quoted) w.column += static_cast<int>(e.column);
      throw InputError(w, component, parameter, std::string("cannot read '") + text + "': " + e.what());
    }
    if (q.had_unit && !(q.dim == expected))
      fail(v, component, parameter,
           "'" + text + "' has dimension " + q.dim.to_string() + " but a value in " + expected_unit + " (" +
               expected.to_string() + ") is expected");
    return q.si_value;
  }

  // A component parameter's value as written. Tables need two levels of
  // lists; anything nested deeper is kept as `other` (an error when read).
  ValueDecl value(const YAML::Node& n, int depth = 0) const {
    ValueDecl v;
    v.where = at(n);
    if (n.IsScalar()) {
      v.text = n.Scalar();
      v.quoted = n.Tag() == "!";
    } else if (n.IsSequence() && depth < 2) {
      v.shape = ValueDecl::Shape::list;
      for (const auto& item : n) v.items.push_back(value(item, depth + 1));
    } else {
      v.shape = ValueDecl::Shape::other;
    }
    return v;
  }

  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

}  // namespace

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

const TopParameter* Netlist::parameter(const std::string& name) const {
  for (const auto& p : parameters)
    if (p.name == name) return &p;
  return nullptr;
}

Netlist load_netlist(const std::string& path) {
  // There is no line to point at: the message names the file only.
  const SourceLocation where{path, 0, 0};
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw InputError(where, "", "", "cannot open the netlist file: no such file");
  if (std::filesystem::is_directory(path, ec))
    throw InputError(where, "", "", "cannot read the netlist: this is a directory, not a file");
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


// The YAML tree of a netlist text; syntax errors at their line, with the
// unclosed bracket or quote and tab indentation named.
YAML::Node load_root(const std::string& text, const std::string& file_name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
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
  return root;
}

// ambient: the atmosphere, the datum of gauge pressures.
void read_ambient(Reader& r, const YAML::Node& node, Netlist& nl) {
  using namespace units::dims;
  std::map<std::string, YAML::Node> value_of;
  for (const auto& e : r.mapping(node, "ambient", "", Reader::Keys::parameters, "ambient.")) {
    value_of[e.key] = e.value;
    if (e.key == "p") nl.gas.p_ambient = r.quantity(e.value, 101325.0, pressure, "Pa", "", "ambient.p");
    else if (e.key == "T") nl.gas.T_ambient = r.quantity(e.value, 0, temperature, "K", "", "ambient.T");
    else r.fail(e.key_node, "", "ambient." + e.key, "unknown key '" + e.key + "' in ambient; valid: p, T");
  }
  if (!(nl.gas.p_ambient > 0))
    r.fail(value_of.count("p") ? value_of["p"] : node, "", "ambient.p", "the ambient pressure must be > 0");
  if (!(nl.gas.T_ambient > 0))
    r.fail(value_of.count("T") ? value_of["T"] : node, "", "ambient.T",
           "the ambient temperature must be > 0 K");
}

// gas: the ideal gas and the ISO 6358 reference state.
void read_gas(Reader& r, const YAML::Node& node, Netlist& nl) {
  using namespace units::dims;
  std::map<std::string, YAML::Node> value_of;
  for (const auto& e : r.mapping(node, "gas", "", Reader::Keys::parameters, "gas.")) {
    value_of[e.key] = e.value;
    const double a = nl.gas.p_ambient;
    if (e.key == "R") nl.gas.R = r.quantity(e.value, a, Dimension{.m = 2, .s = -2, .K = -1}, "J/(kg*K)", "", "gas.R");
    else if (e.key == "kappa") nl.gas.kappa = r.quantity(e.value, a, none, "1", "", "gas.kappa");
    else if (e.key == "rho_ref") nl.gas.rho_ref = r.quantity(e.value, a, density, "kg/m3", "", "gas.rho_ref");
    else if (e.key == "T_ref") nl.gas.T_ref = r.quantity(e.value, a, temperature, "K", "", "gas.T_ref");
    else if (e.key == "m_flow_small") nl.gas.m_flow_small = r.quantity(e.value, a, mass_flow, "kg/s", "", "gas.m_flow_small");
    else r.fail(e.key_node, "", "gas." + e.key, "unknown key '" + e.key + "' in gas; valid: R, kappa, rho_ref, T_ref, m_flow_small");
  }
  auto at_key = [&](const char* k) { return value_of.count(k) ? value_of[k] : node; };
  if (!(nl.gas.R > 0)) r.fail(at_key("R"), "", "gas.R", "R must be > 0");
  if (!(nl.gas.kappa > 1)) r.fail(at_key("kappa"), "", "gas.kappa", "kappa must be > 1");
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

// components: NAME: {type: ..., parameters}; the parameters stay YAML until
// elaborate() converts them against the registry's specs.
void read_components(Reader& r, const YAML::Node& node, Netlist& nl) {
  for (const auto& e : r.mapping(node, "components", "", Reader::Keys::components)) {
    if (!is_identifier(e.key))
      r.fail(e.key_node, e.key, "", "component names must be identifiers (letters, digits, _)");
    ComponentDecl c;
    c.name = e.key;
    c.where = r.at(e.key_node);
    bool has_type = false;
    if (!e.value.IsMap())
      r.fail(e.value.IsNull() ? e.key_node : e.value, e.key, "",
             "a component is a mapping with a 'type' and its parameters, e.g. " + e.key +
                 ": {type: volume, V: 1 L}");
    for (const auto& pe : r.mapping(e.value, "component '" + e.key + "'", e.key, Reader::Keys::parameters)) {
      if (pe.key == "<<")
        r.fail(pe.key_node, e.key, "",
               "YAML merge keys (<<) are not supported in a component; write its type and parameters out");
      if (pe.key == "type") {
        c.type = r.scalar_text(pe.value, e.key, "type", "the type");
        c.type_where = r.at(pe.value);
        has_type = true;
      } else {
        c.parameters.emplace_back(pe.key, r.value(pe.value));
        c.parameter_where.push_back(r.at(pe.key_node));
      }
    }
    if (!has_type)
      r.fail(e.key_node, e.key, "type", "the component has no 'type' (run 'pneumo components' for the list)");
    nl.components.push_back(std::move(c));
  }
}

// connections: lists of component.port.
void read_connections(Reader& r, const YAML::Node& node, Netlist& nl) {
  const auto& cs = node;
  if (!cs.IsSequence()) r.fail(cs, "", "", "connections must be a list of lists of ports, e.g. - [a.port, b.port]");
  for (const auto& item : cs) {
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
    nl.connections.push_back(std::move(conn));
  }
}

// outputs: name: comp.var, {var: comp.var, unit: U} or {integral: comp.var}.
void read_outputs(Reader& r, const YAML::Node& node, Netlist& nl) {
  const auto& os = node;
  auto add = [&](const std::string& name, const YAML::Node& where, const YAML::Node& ref_node) {
    // name: comp.var, or name: {integral: comp.var} for its time integral
    // (energy from a power, mass from a mass flow), integrated by the solver.
    // Either form may name a display unit: {var: comp.var, unit: barg}.
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
  const YAML::Node root = load_root(text, file_name);
  if (!root.IsDefined() || root.IsNull())
    throw InputError(SourceLocation{file_name, 1, 1}, "", "", "the netlist is empty");

  Netlist nl;
  nl.file = file_name;
  nl.parameters_where = SourceLocation{file_name, 1, 1};
  static const std::vector<std::string> kTopKeys{"title",      "description", "gas",     "ambient",
                                                 "parameters", "components",  "connections", "outputs",
                                                 "simulation", "plugins",     "metrics"};
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
  if (top.count("simulation") && !top["simulation"].IsNull()) read_simulation(r, top["simulation"], nl);
  if (top.count("metrics")) nl.metrics = read_metrics(top["metrics"], nl);
  return nl;
}

void apply_override(Netlist& nl, const std::string& assignment) {
  // The mistake is on the command line, but the place to compare it with is
  // the netlist: errors point at the declaration (or at 'parameters:').
  const std::string option = "--set " + assignment;
  const SourceLocation netlist_where =
      nl.parameters_where.known() ? nl.parameters_where : SourceLocation{nl.file, 1, 1};
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(netlist_where, "", "",
                     option + ": expected NAME=VALUE, e.g. --set p_supply=7e5 or --set p_supply='7 bar'");
  const std::string name = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  TopParameter* p = nullptr;
  for (auto& tp : nl.parameters)
    if (tp.name == name) p = &tp;
  if (!p) {
    std::vector<std::string> names;
    for (const auto& tp : nl.parameters) names.push_back(tp.name);
    throw InputError(netlist_where, "", name,
                     option + ": no top-level parameter '" + name + "' under 'parameters:' in " + nl.file +
                         "; only those can be set; " + choices_hint(name, names));
  }
  units::Quantity q{};
  try {
    q = units::parse_quantity(text, nl.gas.p_ambient);
  } catch (const units::ParseError& e) {
    throw InputError(p->where, "", name, option + ": cannot read '" + text + "': " + e.what());
  }
  if (q.had_unit && p->had_unit && !(q.dim == p->dim))
    throw InputError(p->where, "", name,
                     option + ": '" + text + "' has dimension " + q.dim.to_string() + " but '" + name +
                         "' is declared here with dimension " + p->dim.to_string());
  p->si_value = q.si_value;
  if (q.had_unit) {
    p->dim = q.dim;
    p->had_unit = true;
  }
}

namespace {

Dimension spec_dimension(const ParameterSpec& spec) { return units::dimension_of(spec.unit); }

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
    return tp->si_value;
  }
  return r.quantity(node, nl.gas.p_ambient, dim, spec.unit, c.name, spec.name);
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

std::string text_parameter(const Reader& r, const ComponentDecl& c, const ParameterSpec& spec,
                           const ValueDecl& pnode) {
  const std::string& pname = spec.name;
  const std::string v = r.scalar_text(pnode, c.name, pname, "the value");
  if (!spec.choices.empty() &&
      std::find(spec.choices.begin(), spec.choices.end(), v) == spec.choices.end())
    r.fail(pnode, c.name, pname, "'" + v + "' is not allowed; " + choices_hint(v, spec.choices));
  return v;
}

// The parameters the declaration gives, converted by their specs.
std::set<std::string> given_parameters(const Reader& r, const Netlist& nl, const ComponentDecl& c,
                                       const ComponentInfo& info, ParameterValues& out) {
  std::set<std::string> given;
  for (const auto& [pname, pnode] : c.parameters) {
    const ParameterSpec* spec = info.parameter(pname);
    if (!spec) {
      std::vector<std::string> names;
      for (const auto& s : info.parameters) names.push_back(s.name);
      throw InputError(c.where_of(pname), c.name, pname,
                       "unknown parameter of type '" + c.type + "'; " + choices_hint(pname, names) +
                           " (run 'pneumo components " + c.type + "')");
    }
    given.insert(pname);
    switch (spec->kind) {
      case ParameterKind::scalar: out.set_scalar(pname, scalar_parameter(r, nl, c, *spec, pnode)); break;
      case ParameterKind::table: out.set_table(pname, table_parameter(r, nl, c, *spec, pnode)); break;
      case ParameterKind::text: out.set_text(pname, text_parameter(r, c, *spec, pnode)); break;
    }
  }
  return given;
}

// Defaults of the parameters not given; a required one missing is an error.
void default_parameters(const ComponentDecl& c, const ComponentInfo& info, const std::set<std::string>& given,
                        ParameterValues& out) {
  for (const auto& spec : info.parameters) {
    if (given.count(spec.name)) continue;
    if (spec.kind == ParameterKind::scalar && spec.default_value) {
      out.set_scalar(spec.name, *spec.default_value);
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

std::unique_ptr<Component> make_component(const Reader& r, const Netlist& nl, const ComponentDecl& c,
                                          const Registry& registry) {
  const Registry::Entry& entry = entry_of(registry, c);
  Construction k;
  k.name = c.name;
  const auto given = given_parameters(r, nl, c, *entry.info, k.params);
  default_parameters(c, *entry.info, given, k.params);
  try {
    k.info = entry.instance_info(k.params);
    return entry.make(k);
  } catch (const ParameterError& e) {
    SourceLocation w = c.where;
    for (const auto& [pname, pnode] : c.parameters)
      if (pname == e.parameter()) w = pnode.where;
    throw InputError(w, c.name, e.parameter(), e.what());
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
  Probe probe;
  probe.name = o.name;
  probe.component = it->second;
  const auto& obs = comp.info().observables;
  for (std::size_t i = 0; i < obs.size(); ++i)
    if (obs[i].name == o.quantity) {
      probe.kind = Probe::Kind::observable;
      probe.index = static_cast<int>(i);
      probe.unit = obs[i].unit;
    }
  if (probe.index < 0) {
    const auto names = local_variable_names(comp);
    const auto unit_names = local_variable_units(comp);
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == o.quantity) {
        probe.kind = Probe::Kind::local;
        probe.index = static_cast<int>(i);
        probe.unit = unit_names[i];
      }
  }
  // A signal port by its name alone (source.y for the value of port y).
  if (probe.index < 0) {
    const int port = comp.info().port_index(o.quantity);
    if (port >= 0 && comp.info().ports[port].domain == Domain::signal) {
      probe.kind = Probe::Kind::local;
      probe.index = comp.port_offset(port);
      probe.unit = local_variable_units(comp)[probe.index];
    }
  }
  if (probe.index < 0) {
    std::vector<std::string> valid;
    for (const auto& ob : obs) valid.push_back(ob.name);
    for (const auto& n : local_variable_names(comp)) valid.push_back(n);
    throw InputError(o.where, o.component, "", "output '" + o.name + "': type '" + comp.info().type +
                                                   "' has no variable '" + o.quantity + "'; " +
                                                   choices_hint(o.quantity, valid));
  }
  if (o.integral) {
    probe.integral = true;
    probe.unit = probe.unit == "W" ? "J" : probe.unit == "kg/s" ? "kg" : probe.unit + "*s";
  }
  if (!o.unit.empty()) {
    const units::Unit u = units::parse_unit(o.unit);
    if (!(u.dim == units::dimension_of(probe.unit)))
      throw InputError(o.unit_where, o.component, "",
                       "output '" + o.name + "': unit '" + o.unit + "' (" + u.dim.to_string() + ") does not fit '" +
                           o.quantity + "' in " + probe.unit + " (" + units::dimension_of(probe.unit).to_string() +
                           ")");
    probe.display = {o.unit, u.scale, u.offset + (u.gauge ? nl.gas.p_ambient : 0.0)};
  }
  return probe;
}

}  // namespace

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
  for (const auto& o : nl.outputs) circuit.probes.push_back(make_probe(nl, circuit, index, o));
  return circuit;
}

}  // namespace pneumo
