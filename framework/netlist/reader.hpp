// The YAML readers' shared tools (framework/netlist and the effect
// catalogue's reader): "did you mean" hints, identifiers, and Reader - YAML
// nodes and typed values read with errors at their file:line naming the
// component and parameter.
#pragma once

#include <algorithm>
#include <cctype>
#include <map>
#include <string>
#include <vector>

#include "framework/core/error.hpp"
#include "framework/core/units.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/netlist/yaml_location.hpp"

namespace pneumo::netlist_detail {

using units::Dimension;

std::string join(const std::vector<std::string>& v, const std::string& sep = ", ");
bool is_identifier(const std::string& s);
// Why `name` cannot head a column of a results CSV (an output or metric
// name): empty, or holding a comma, a double quote or a control character
// such as a line break, which would split or shift the columns; "" if it can.
std::string column_name_problem(const std::string& name);
// "did you mean 'X'? valid: ..." for a name not among `valid`.
std::string choices_hint(const std::string& given, const std::vector<std::string>& valid);

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
    return scalar_text(value(n), component, parameter, what);
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

// A component NAME: {type: TYPE, PARAMETER: VALUE, ...} and a connection
// [a.port, b.port, ...], as the netlist writes them (an effect catalogue's
// patches too).
ComponentDecl read_component(const Reader& r, const std::string& name, const YAML::Node& key_node,
                             const YAML::Node& value);
ConnectionDecl read_connection(const Reader& r, const YAML::Node& item);

}  // namespace pneumo::netlist_detail
