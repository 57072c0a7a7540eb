#include "framework/diagnose/catalogue.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "framework/assembly/system.hpp"
#include "framework/core/expression.hpp"
#include "framework/diagnose/yaml_file.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/netlist/reader.hpp"
#include "framework/netlist/yaml_location.hpp"

namespace pneumo::diagnose {

int Effect::parameter_index(const std::string& n) const {
  for (std::size_t i = 0; i < parameters.size(); ++i)
    if (parameters[i].name == n) return static_cast<int>(i);
  return -1;
}

std::vector<double> Effect::initial_values() const {
  std::vector<double> v;
  for (const auto& p : parameters) v.push_back(p.initial);
  return v;
}

std::vector<double> Effect::null_values() const {
  std::vector<double> v;
  for (const auto& p : parameters) {
    if (!p.null_value) return {};
    v.push_back(*p.null_value);
  }
  return v;
}

const Effect* Catalogue::find(const std::string& name) const {
  for (const auto& e : effects)
    if (e.name == name) return &e;
  return nullptr;
}

namespace {

using netlist_detail::Reader;

std::string format_number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The value of an arithmetic expression over the effect's parameters and
// numbers (framework/core/expression.hpp: + - * /, parentheses, unary
// minus), so that one free parameter can move several coefficients, e.g.
// "${w * 0.26}" or "${(1 - w) * 2.776 + w * 9.66}": the parameters' `values`,
// or their initial values when there are none.
double evaluate(const std::string& text, const Effect& effect, const std::vector<double>* values) {
  return pneumo::Expression(text).evaluate([&](const std::string& name) {
    const int k = effect.parameter_index(name);
    if (k < 0) throw std::invalid_argument("'" + name + "' is not one of the effect's parameters");
    return values ? (*values)[k] : effect.parameters[k].initial;
  });
}

// One ${...} in a text: [begin, end) spans it, `expr` is what it holds.
struct Template {
  std::size_t begin = 0, end = 0;
  std::string expr;
  bool closed = true;
};

std::vector<Template> templates_in(const std::string& s) {
  std::vector<Template> out;
  for (std::size_t pos = s.find("${"); pos != std::string::npos; pos = s.find("${", out.back().end)) {
    const std::size_t close = s.find('}', pos);
    if (close == std::string::npos) {
      out.push_back({pos, s.size(), s.substr(pos + 2), false});
      break;
    }
    out.push_back({pos, close + 1, s.substr(pos + 2, close - pos - 2), true});
  }
  return out;
}

// A template's value (`values`, or the initial values when null); an error
// names `where`, the effect and the expression.
double template_value(const Template& t, const Effect& effect, const std::vector<double>* values,
                      const SourceLocation& where) {
  try {
    if (!t.closed) throw std::invalid_argument("missing '}'");
    return evaluate(t.expr, effect, values);
  } catch (const std::exception& ex) {
    throw InputError(where, "", t.expr, "effect '" + effect.name + "': '${" + t.expr + "}': " + ex.what());
  }
}

// `v` with its ${...} replaced by their values. A value that is exactly one
// ${expr} becomes its SI number (its text, the number written out, serves a
// text parameter). A ${...} inside a longer text ("${w * 0.26} N/bar") is
// written into the text with 17 digits, which read back to the same double,
// so that the netlist reads the quantity with its unit. A value that is not
// finite stays text: elaborating it fails, as a run that cannot be made.
ValueDecl substitute(const ValueDecl& v, const Effect& effect, const std::vector<double>& values) {
  ValueDecl out = v;
  for (auto& item : out.items) item = substitute(item, effect, values);
  if (v.shape != ValueDecl::Shape::scalar || v.si) return out;
  const auto ts = templates_in(v.text);
  if (ts.size() == 1 && ts[0].begin == 0 && ts[0].end == v.text.size()) {
    const double x = template_value(ts[0], effect, &values, v.where);
    out.text = format_number(x);
    if (std::isfinite(x)) out.si = x;
    return out;
  }
  out.text.clear();
  std::size_t copied = 0;
  for (const auto& t : ts) {
    out.text += v.text.substr(copied, t.begin - copied) + format_number(template_value(t, effect, &values, v.where));
    copied = t.end;
  }
  out.text += v.text.substr(copied);
  return out;
}

ComponentDecl substitute(ComponentDecl c, const Effect& effect, const std::vector<double>& values) {
  for (auto& [name, value] : c.parameters) value = substitute(value, effect, values);
  return c;
}

[[noreturn]] void fail(const SourceLocation& where, const std::string& effect, const std::string& parameter,
                       const std::string& msg) {
  throw InputError(where, "", parameter, (effect.empty() ? "" : "effect '" + effect + "': ") + msg);
}

[[noreturn]] void fail(const std::string& file, const YAML::Node& n, const std::string& effect,
                       const std::string& parameter, const std::string& msg) {
  fail(location_of(file, n), effect, parameter, msg);
}

double number(const std::string& file, const YAML::Node& n, const std::string& effect, const std::string& param,
              const std::string& key) {
  if (!n || !n.IsScalar()) fail(file, n, effect, param, "'" + key + "' must be an SI number");
  try {
    return n.as<double>();
  } catch (const YAML::Exception&) {
    fail(file, n, effect, param, "'" + key + "': '" + n.Scalar() + "' is not a number (SI values)");
  }
}

// A name or text where the catalogue expects one (a key, a type, a
// description): a map or list there is an error at its line.
std::string name_text(const std::string& file, const YAML::Node& n, const std::string& effect,
                      const std::string& param, const std::string& what) {
  return plain_text(file, n, "", param, (effect.empty() ? "" : "effect '" + effect + "': ") + what);
}

// A measurement model's value (`key`: lag, offset, gain) after
// substitution: an SI number.
double measure_number(const ValueDecl& v, const std::string& effect, const std::string& output, const char* key) {
  if (v.si) return *v.si;
  if (v.shape != ValueDecl::Shape::scalar) fail(v.where, effect, output, std::string("'") + key + "' must be an SI number");
  try {
    std::size_t used = 0;
    const double x = std::stod(v.text, &used);
    if (used == v.text.size()) return x;
  } catch (const std::exception&) {
  }
  fail(v.where, effect, output, std::string("'") + key + "': '" + v.text + "' is not a number (SI values)");
}

// Every ${...} in the patch must name the effect's parameters (or be an
// expression of them that parses).
void check_references(const std::string& file, const YAML::Node& node, const Effect& effect) {
  if (node.IsScalar()) {
    for (const auto& t : templates_in(node.Scalar())) (void)template_value(t, effect, nullptr, location_of(file, node));
  } else if (node.IsSequence()) {
    for (const auto& c : node) check_references(file, c, effect);
  } else if (node.IsMap()) {
    for (auto it = node.begin(); it != node.end(); ++it) check_references(file, it->second, effect);
  }
}

std::set<std::pair<std::string, std::string>> port_set(const ConnectionDecl& c) {
  std::set<std::pair<std::string, std::string>> s;
  for (const auto& p : c.ports) s.emplace(p.component, p.port);
  return s;
}

// A top-level parameter set by an effect: an SI number (as a plain number
// in the netlist, without unit), or a quantity read from the text; written
// where the catalogue sets it.
void set_top_parameter(TopParameter& p, const ValueDecl& v, double p_ambient, const std::string& effect) {
  p.where = v.where;
  if (v.si) {
    p.si_value = *v.si;
    p.dim = {};
    p.had_unit = false;
    return;
  }
  if (v.shape != ValueDecl::Shape::scalar) fail(v.where, effect, p.name, "set: a top-level parameter is a single value");
  try {
    const auto q = units::parse_quantity(v.text, p_ambient);
    p.si_value = q.si_value;
    p.dim = q.dim;
    p.had_unit = q.had_unit;
  } catch (const units::ParseError& err) {
    fail(v.where, effect, p.name, "set: cannot read '" + v.text + "': " + err.what());
  }
}

void apply_set(Netlist& out, const SetPatch& s, const Effect& e, const std::vector<double>& values,
               std::vector<RunFactor>* run_factors) {
  if (!s.per_run_of.empty()) {
    const RunFactor f{ParameterPath::parse(s.target), s.per_run_of, *substitute(s.value, e, values).si};
    if (run_factors) run_factors->push_back(f);
    else apply_run_factors(out, {f});
    return;
  }
  const auto dot = s.target.find('.');
  if (dot == std::string::npos)
    fail(s.where, e.name, s.target, "set: key must be COMPONENT.PARAMETER or parameters.NAME");
  const std::string comp = s.target.substr(0, dot), param = s.target.substr(dot + 1);
  if (comp == "parameters") {
    auto it = std::find_if(out.parameters.begin(), out.parameters.end(),
                           [&](const TopParameter& p) { return p.name == param; });
    if (it == out.parameters.end())
      fail(s.where, e.name, param, "set: the model has no top-level parameter '" + param + "'");
    set_top_parameter(*it, substitute(s.value, e, values), out.gas.p_ambient, e.name);
    return;
  }
  ComponentDecl* c = out.component(comp);
  if (!c) fail(s.where, e.name, param, "set: the model has no component '" + comp + "'");
  ValueDecl v = substitute(s.value, e, values);  // pointing at the catalogue's line
  if (param != "type") return set_value(out, {comp, param}, std::move(v));
  c->type = v.text;
  c->type_where = v.where;
}

void apply_effect(Netlist& out, const EffectInstance& inst, MeasurementModel* measurement,
                  std::vector<RunFactor>* run_factors) {
  const Effect& e = *inst.effect;
  for (const auto& d : e.disconnect) {
    const auto want = port_set(d);
    const auto it = std::find_if(out.connections.begin(), out.connections.end(),
                                 [&](const ConnectionDecl& c) { return port_set(c) == want; });
    if (it == out.connections.end())
      fail(d.where, e.name, "", "disconnect: the model has no connection with exactly these ports");
    out.connections.erase(it);
  }
  for (const auto& c : e.add_components) {
    if (out.component(c.name))
      fail(c.where, e.name, "", "add_components: the model already has a component '" + c.name + "'");
    out.components.push_back(substitute(c, e, inst.values));
  }
  for (const auto& c : e.replace_components) {
    ComponentDecl* old = out.component(c.name);
    if (!old) fail(c.where, e.name, "", "replace_components: the model has no component '" + c.name + "'");
    *old = substitute(c, e, inst.values);
  }
  for (const auto& s : e.set) apply_set(out, s, e, inst.values, run_factors);
  out.connections.insert(out.connections.end(), e.connect.begin(), e.connect.end());
  if (measurement)
    for (const auto& m : e.measure)
      for (const auto& [key, value, into] :
           {std::tuple{"lag", &m.lag, &measurement->lag}, {"offset", &m.offset, &measurement->offset},
            {"gain", &m.gain, &measurement->gain}})
        if (*value) (*into)[m.output] = measure_number(substitute(**value, e, inst.values), e.name, m.output, key);
}

}  // namespace

Netlist apply_effects(const Netlist& model, const std::vector<EffectInstance>& effects,
                      MeasurementModel* measurement, std::vector<RunFactor>* run_factors) {
  Netlist out = model;
  for (const auto& inst : effects) apply_effect(out, inst, measurement, run_factors);
  return out;
}

void apply_run_factors(Netlist& run, const std::vector<RunFactor>& run_factors) {
  for (const auto& f : run_factors) set_si_value(run, f.target, f.factor * run.parameter(f.of)->si_value);
}

bool effects_conflict(const Effect& a, const Effect& b) {
  auto keys = [](const Effect& e) {
    std::set<std::string> k;
    for (const auto& s : e.set) k.insert("set:" + s.target);
    for (const auto& c : e.replace_components) k.insert("replace:" + c.name);
    for (const auto& d : e.disconnect)
      for (const auto& p : d.ports) k.insert("disconnect:" + p.component + "." + p.port);
    for (const auto& m : e.measure)
      for (const auto& [key, value] : {std::pair{"lag", &m.lag}, {"offset", &m.offset}, {"gain", &m.gain}})
        if (*value) k.insert("measure:" + m.output + "." + key);
    return k;
  };
  const auto ka = keys(a), kb = keys(b);
  for (const auto& k : ka)
    if (kb.count(k)) return true;
  return false;
}

bool vanishes_at_null(const Effect& e, const Netlist& model, const Registry& registry) {
  const auto null = e.null_values();
  if (null.size() != e.parameters.size() || !e.add_components.empty() || !e.replace_components.empty() ||
      !e.connect.empty() || !e.disconnect.empty())
    return false;
  MeasurementModel mm;
  const Netlist at_null = apply_effects(model, {EffectInstance{&e, null}}, &mm);
  for (const auto& [signal, lag] : mm.lag)
    if (lag > 0) return false;
  for (const auto& [signal, offset] : mm.offset)
    if (offset != 0.0) return false;
  for (const auto& [signal, gain] : mm.gain)
    if (gain != 1.0) return false;
  for (const auto& s : e.set) try {
    const auto dot = s.target.find('.');
    const std::string comp = s.target.substr(0, dot), name = s.target.substr(dot + 1);
    if (comp == "parameters") {
      if (at_null.parameter(name)->si_value != model.parameter(name)->si_value) return false;
      continue;
    }
    const ComponentDecl *now = at_null.component(comp), *before = model.component(comp);
    if (!now || !before || now->type != before->type ||
        !resolved_parameters(at_null, *now, registry).same_bits(resolved_parameters(model, *before, registry)))
      return false;  // a simulation setting, another type or other values
  } catch (const std::exception&) {
    return false;  // a null the component refuses is no null to leave out
  }
  return true;
}

namespace {

// A phase starting at COMPONENT.TAG: the component's type must raise TAG,
// or the phase would silently never start. Empty if it does.
std::string event_problem(const std::string& from, const Netlist& model, const Registry& registry) {
  const auto dot = from.find('.');
  const ComponentDecl* decl = model.component(from.substr(0, dot));
  const auto* entry = registry.find(decl->type);
  if (!entry || entry->info->raises(from.substr(dot + 1))) return "";
  return "component '" + decl->name + "' (" + decl->type + ") raises no event '" + from.substr(dot + 1) +
         "'; its events: " + entry->info->event_list();
}

// phases: [{name: NAME, from: start | COMPONENT.TAG | METRIC}, ...]
std::vector<PhaseDecl> read_phases(const std::string& path, const YAML::Node& list, const Netlist& model,
                                   const Registry& registry) {
  if (!list.IsSequence()) fail(path, list, "", "", "'phases' must be a list of {name, from}");
  std::vector<PhaseDecl> out;
  for (const YAML::Node item : list) {
    if (!item.IsMap() || !item["name"] || !item["from"])
      fail(path, item, "", "", "a phase is {name: NAME, from: start | COMPONENT.TAG | METRIC}");
    PhaseDecl ph{name_text(path, item["name"], "", "", "a phase's 'name'"),
                 name_text(path, item["from"], "", "", "a phase's 'from'"), location_of(path, item)};
    const auto dot = ph.from.find('.');
    const bool is_metric = std::any_of(model.metrics.begin(), model.metrics.end(),
                                       [&](const MetricDecl& m) { return m.name == ph.from; });
    const bool is_event = dot != std::string::npos && model.component(ph.from.substr(0, dot));
    if (ph.from != "start" && !is_metric && !is_event)
      fail(path, item["from"], "", "phases." + ph.name,
           "phase '" + ph.name + "' starts at '" + ph.from +
               "', which is neither 'start', an event COMPONENT.TAG of the model nor one of its metrics");
    if (is_event && !is_metric)
      if (const std::string problem = event_problem(ph.from, model, registry); !problem.empty())
        fail(path, item["from"], ph.from.substr(0, dot), "phases." + ph.name,
             "phase '" + ph.name + "' starts at '" + ph.from + "': " + problem);
    out.push_back(std::move(ph));
  }
  return out;
}

// The netlist's own value of a re-calibration candidate (a top-level NAME
// or COMPONENT.PARAMETER), its unit, the `set` key that changes it and the
// range the component accepts.
struct NetlistValue {
  double value = 0, min = -INFINITY, max = INFINITY;
  bool min_exclusive = false, max_exclusive = false, difference = false;
  std::string unit, set_key;
};

NetlistValue netlist_value(const std::string& path, const YAML::Node& key_node, const Netlist& nl,
                           const Registry& registry) {
  const std::string key = name_text(path, key_node, "", "", "a 'recalibrate' entry's name");
  const auto dot = key.find('.');
  NetlistValue v;
  if (dot == std::string::npos) {
    const TopParameter* tp = nl.parameter(key);
    if (!tp)
      fail(path, key_node, key, key,
           "recalibrate: the model has no top-level parameter '" + key + "' (write NAME or COMPONENT.PARAMETER)");
    v.value = tp->si_value;
    v.unit = units::si_unit_name(tp->dim);
    v.set_key = "parameters." + key;
    return v;
  }
  const std::string comp = key.substr(0, dot), name = key.substr(dot + 1);
  const ComponentDecl* decl = nl.component(comp);
  if (!decl) fail(path, key_node, key, name, "recalibrate: the model has no component '" + comp + "'");
  const auto* entry = registry.find(decl->type);
  const ParameterSpec* spec = entry ? entry->info->parameter(name) : nullptr;
  if (!spec)
    fail(path, key_node, key, name, "recalibrate: component '" + comp + "' (" + decl->type + ") has no parameter '" + name + "'");
  if (spec->kind != ParameterKind::scalar)
    fail(path, key_node, key, name, "recalibrate: '" + key + "' is not a scalar parameter (a table or a text)");
  if (const ValueDecl* written = decl->written(name)) {
    const ValueDecl& given = *written;
    if (given.shape == ValueDecl::Shape::scalar && !given.si && nl.parameter(given.text))
      fail(path, key_node, key, name,
           "recalibrate: the netlist gives '" + key + "' as the top-level parameter '" + given.text +
               "': re-calibrate that parameter");
    v.value = parameter_value(nl, *decl, *spec, given);
  } else if (spec->default_value) {
    v.value = *spec->default_at(nl.gas.p_ambient, nl.gas.T_ambient);
  } else {
    fail(path, key_node, key, name, "recalibrate: the netlist gives no value for '" + key + "'");
  }
  v.unit = spec->unit;
  v.difference = units::dimension_of(spec->unit) == units::dims::pressure && !spec->is_absolute;
  v.min = spec->min, v.max = spec->max;
  v.min_exclusive = spec->min_exclusive, v.max_exclusive = spec->max_exclusive;
  v.set_key = key;
  return v;
}

// recalibrate: {NAME | COMPONENT.PARAMETER: {lower, upper, scale, description}}
// -> an effect with one free parameter that `set`s the netlist's parameter;
// null and initial value are the netlist's own, so that a wrong data-sheet
// value is found as such rather than mimicked by an effect.
Effect recalibration(const std::string& path, const YAML::Node& key_node, const YAML::Node& body, const Netlist& nl,
                     const Registry& registry) {
  Effect e;
  e.name = name_text(path, key_node, "", "", "a 'recalibrate' entry's name");
  e.where = location_of(path, key_node);
  if (body && !body.IsNull() && !body.IsMap())
    fail(path, key_node, e.name, "", "recalibrate: each entry is a map {lower, upper, scale, description} (or {})");
  for (auto k = body.begin(); body.IsMap() && k != body.end(); ++k) {
    const auto key = name_text(path, k->first, e.name, "", "a key");
    if (key != "lower" && key != "upper" && key != "scale" && key != "description")
      fail(path, k->first, e.name, "", "recalibrate: unknown key '" + key + "' (lower, upper, scale, description)");
  }
  const NetlistValue v = netlist_value(path, key_node, nl, registry);
  EffectParameter ep;
  ep.name = e.name.substr(e.name.find('.') + 1);
  ep.where = e.where;
  ep.unit = v.unit;
  ep.difference = v.difference;
  ep.initial = v.value;
  ep.null_value = v.value;
  const std::string scale =
      body.IsMap() && body["scale"] ? name_text(path, body["scale"], e.name, ep.name, "'scale'") : "log";
  if (scale != "log" && scale != "linear") fail(path, body["scale"], e.name, ep.name, "scale must be 'linear' or 'log'");
  ep.log_scale = scale == "log";
  // A bound: an SI number, or a factor of the netlist's value ("0.5x").
  auto bound = [&](const char* which, double factor) {
    const YAML::Node b = body.IsMap() ? body[which] : YAML::Node();
    std::string text = b ? b.Scalar() : "";
    if (b && (text.empty() || text.back() != 'x')) return number(path, b, e.name, ep.name, which);
    if (b) {
      try {
        std::size_t used = 0;
        factor = std::stod(text.substr(0, text.size() - 1), &used);
        if (used != text.size() - 1) throw std::invalid_argument(text);
      } catch (const std::exception&) {
        fail(path, b, e.name, ep.name, std::string("'") + which + "': '" + text + "' is neither an SI number nor a factor like 0.5x");
      }
    }
    if (!(v.value > 0))
      fail(path, b ? b : key_node, e.name, ep.name,
           "the netlist's value is " + format_number(v.value) + ": give 'lower' and 'upper' as SI numbers");
    return factor * v.value;
  };
  ep.lower = bound("lower", 0.25);
  ep.upper = bound("upper", 4.0);
  // Within what the component accepts (an exclusive limit is kept off by a hair).
  if (ep.lower <= v.min) ep.lower = v.min_exclusive ? v.min + 1e-6 * (ep.upper - v.min) : v.min;
  if (ep.upper >= v.max) ep.upper = v.max_exclusive ? v.max - 1e-6 * (v.max - ep.lower) : v.max;
  if (!(ep.lower < ep.upper)) fail(path, key_node, e.name, ep.name, "lower must be below upper");
  if (ep.initial < ep.lower || ep.initial > ep.upper)
    fail(path, key_node, e.name, ep.name,
         "the netlist's value " + format_number(ep.initial) + " lies outside [lower, upper]");
  if (ep.log_scale && ep.lower <= 0) fail(path, key_node, e.name, ep.name, "scale: log needs lower > 0");
  e.description = body.IsMap() && body["description"]
                      ? name_text(path, body["description"], e.name, "", "'description'")
                      : "re-calibrated model parameter " + e.name + " (netlist: " + format_number(v.value) + " " + v.unit + ")";
  e.recalibrates = e.name;
  ValueDecl value;
  value.text = "${" + ep.name + "}";
  value.where = e.where;
  e.set.push_back({v.set_key, e.where, value});
  e.parameters.push_back(ep);
  return e;
}

// A patch the netlist does not accept, reported at the effect's line.
InputError does_not_apply(const Effect& e, const std::string& model_file, const InputError& ex) {
  return InputError(e.where, ex.component(), ex.parameter(),
                    "effect '" + e.name + "' does not apply to " + model_file + ": " + ex.message());
}

// The patch applied at the initial values, at the null and at every
// parameter's lower and upper bound (the others at their initial values),
// elaborated and assembled (its ports all connected, its equations
// structurally solvable, every value in its component's range), so that a
// broken patch - a dangling port, two sources joined, a bound the component
// refuses - is an error at load time with the catalogue's file:line, not a
// candidate whose runs fail there.
void check_applies(const Effect& e, const Netlist& model, const Registry& registry) {
  std::vector<std::pair<std::string, std::vector<double>>> points = {{"initial values", e.initial_values()}};
  if (const auto null = e.null_values(); !null.empty()) points.push_back({"null", null});
  for (std::size_t k = 0; k < e.parameters.size(); ++k)
    for (const bool upper : {false, true}) {
      auto values = e.initial_values();
      values[k] = upper ? e.parameters[k].upper : e.parameters[k].lower;
      points.push_back({std::string(upper ? "upper" : "lower") + " bound of " + e.parameters[k].name, values});
    }
  for (const auto& [what, values] : points) {
    MeasurementModel mm;
    const Netlist patched = apply_effects(model, {EffectInstance{&e, values}}, &mm);
    const std::string at = points.size() > 1 ? " (at the " + what + ")" : "";
    try {
      const System assembled(elaborate(patched, registry));
    } catch (const InputError& ex) {
      throw InputError(e.where, ex.component(), ex.parameter(),
                       "effect '" + e.name + "' does not apply to " + model.file + at + ": " + ex.message());
    } catch (const StructureError& ex) {
      throw InputError(e.where, "", "", "effect '" + e.name + "' does not apply to " + model.file + at + ": " + ex.what());
    }
  }
}

// The ports of a `disconnect:` entry, split at their first dot like the
// netlist's; one that is not COMPONENT.PORT matches no connection.
ConnectionDecl ports_to_disconnect(const Reader& r, const YAML::Node& item) {
  ConnectionDecl d;
  d.where = r.at(item);
  for (const auto& pn : item) {
    const std::string s = r.scalar_text(pn, "", "", "a port reference");
    const auto dot = s.find('.');
    d.ports.push_back({s.substr(0, dot), dot == std::string::npos ? "" : s.substr(dot + 1), r.at(pn)});
  }
  return d;
}

// The effect's patch as typed declarations (its structure checked before).
// A component or connection the netlist's reader refuses is a patch that
// does not apply: that error is returned, for the caller to report if the
// effect is available (an unavailable effect is never applied).
std::optional<InputError> read_patch(const Reader& r, const YAML::Node& body, Effect& e) {
  std::optional<InputError> refused;
  auto keep = [&](auto read) {
    try {
      read();
    } catch (const InputError& ex) {
      if (!refused) refused.emplace(ex);
    }
  };
  for (const auto& patch : {std::pair{"add_components", &e.add_components}, {"replace_components", &e.replace_components}})
    if (body[patch.first])
      for (auto c = body[patch.first].begin(); c != body[patch.first].end(); ++c)
        keep([&] { patch.second->push_back(read_component(r, c->first.Scalar(), c->first, c->second)); });
  if (body["connect"])
    for (const auto& c : body["connect"]) keep([&] { e.connect.push_back(read_connection(r, c)); });
  if (body["disconnect"])
    for (const auto& d : body["disconnect"]) e.disconnect.push_back(ports_to_disconnect(r, d));
  if (body["set"])
    for (auto it = body["set"].begin(); it != body["set"].end(); ++it)
      e.set.push_back({r.scalar_text(it->first, "", "", "a set: key"), r.at(it->first), r.value(it->second)});
  if (body["measure"])
    for (auto m = body["measure"].begin(); m != body["measure"].end(); ++m) {
      MeasurePatch mp{m->first.Scalar(), {}, {}, {}};
      if (m->second["lag"]) mp.lag = r.value(m->second["lag"]);
      if (m->second["offset"]) mp.offset = r.value(m->second["offset"]);
      if (m->second["gain"]) mp.gain = r.value(m->second["gain"]);
      e.measure.push_back(std::move(mp));
    }
  return refused;
}

// The catalogue file's root node, its top-level keys checked.
YAML::Node read_root(const std::string& path) {
  const YAML::Node root = load_yaml_document(path, "catalogue file");
  if (!root.IsMap() || !(root["effects"] || root["recalibrate"]) || (root["effects"] && !root["effects"].IsMap()))
    throw InputError(SourceLocation{path, 1, 1}, "", "",
                     "a catalogue needs 'effects:', a map of effect name -> patch, or 'recalibrate:'");
  for (auto it = root.begin(); it != root.end(); ++it)
    if (const auto k = name_text(path, it->first, "", "", "a key"); k != "effects" && k != "phases" && k != "recalibrate")
      fail(path, it->first, "", "", "unknown key '" + k + "' (valid: effects, recalibrate, phases)");
  return root;
}

// One entry of an effect's 'parameters:' map, with its bounds checked.
EffectParameter read_effect_parameter(const std::string& path, const std::string& effect, const YAML::Node& key,
                                      const YAML::Node& s) {
  EffectParameter ep;
  ep.name = name_text(path, key, effect, "", "a parameter's name");
  ep.where = location_of(path, key);
  if (!s.IsMap()) fail(path, key, effect, ep.name, "needs {initial, lower, upper, null, unit}");
  // yaml-cpp parses the plain key `null` as a Null node, which s["null"]
  // does not find: the entry is taken from the iteration.
  std::optional<YAML::Node> null_node;
  for (auto k = s.begin(); k != s.end(); ++k) {
    const auto name = name_text(path, k->first, effect, ep.name, "a key");
    if (name == "null") null_node.emplace(k->second);
    if (name != "initial" && name != "lower" && name != "upper" && name != "null" && name != "unit" &&
        name != "scale")
      fail(path, k->first, effect, ep.name, "unknown key '" + name + "' (initial, lower, upper, null, unit, scale)");
  }
  for (const char* req : {"initial", "lower", "upper"})
    if (!s[req]) fail(path, key, effect, ep.name, std::string("missing '") + req + "'");
  ep.initial = number(path, s["initial"], effect, ep.name, "initial");
  ep.lower = number(path, s["lower"], effect, ep.name, "lower");
  ep.upper = number(path, s["upper"], effect, ep.name, "upper");
  if (null_node) ep.null_value = number(path, *null_node, effect, ep.name, "null");
  if (s["unit"]) ep.unit = name_text(path, s["unit"], effect, ep.name, "'unit'");
  if (s["scale"]) {
    const auto sc = name_text(path, s["scale"], effect, ep.name, "'scale'");
    if (sc != "log" && sc != "linear") fail(path, s["scale"], effect, ep.name, "scale must be 'linear' or 'log'");
    ep.log_scale = sc == "log";
  }
  if (!(ep.lower < ep.upper)) fail(path, key, effect, ep.name, "lower must be below upper");
  if (ep.initial < ep.lower || ep.initial > ep.upper)
    fail(path, s["initial"], effect, ep.name, "initial lies outside [lower, upper]");
  if (ep.null_value && (*ep.null_value < ep.lower || *ep.null_value > ep.upper))
    fail(path, *null_node, effect, ep.name, "null lies outside [lower, upper]");
  if (ep.log_scale && ep.lower <= 0) fail(path, s["lower"], effect, ep.name, "scale: log needs lower > 0");
  return ep;
}

// The shape of an effect's patch keys (maps, lists of port lists, measured
// outputs the model has), checked before any of them is read.
void check_patch_shape(const std::string& path, const YAML::Node& body, const std::string& effect,
                       const Netlist& model) {
  for (const char* key : {"add_components", "replace_components", "set", "measure"})
    if (body[key] && !body[key].IsMap()) fail(path, body[key], effect, "", std::string("'") + key + "' must be a map");
  for (const char* key : {"disconnect", "connect"})
    if (body[key]) {
      if (!body[key].IsSequence()) fail(path, body[key], effect, "", std::string("'") + key + "' must be a list of lists");
      for (const auto& c : body[key])
        if (!c.IsSequence() || c.size() < 2)
          fail(path, c, effect, "", std::string("'") + key + "': each entry is a list of two or more ports");
    }
  if (body["measure"])
    for (auto m = body["measure"].begin(); m != body["measure"].end(); ++m) {
      const auto out = name_text(path, m->first, effect, "", "a measured output's name");
      if (std::none_of(model.outputs.begin(), model.outputs.end(), [&](const OutputDecl& o) { return o.name == out; }))
        fail(path, m->first, effect, out, "measure: the model has no output '" + out + "'");
      if (!m->second.IsMap() || m->second.size() == 0)
        fail(path, m->first, effect, out, "measure: write {lag: SECONDS, offset: SI VALUE, gain: FACTOR} (any of them)");
      for (auto k = m->second.begin(); k != m->second.end(); ++k)
        if (const auto key = name_text(path, k->first, effect, out, "a key"); key != "lag" && key != "offset" && key != "gain")
          fail(path, k->first, effect, out, "measure: unknown key '" + key + "' (lag, offset, gain)");
    }
}

// Availability: the component types, parameters and ports the patch relies
// on. The first one missing marks the effect unavailable (not an error: a
// catalogue may list effects for components this build lacks).
void check_availability(const std::string& path, const YAML::Node& body, Effect& e, const Registry& registry) {
  auto check_type = [&](const std::string& type) {
    if (e.unavailable.empty() && !registry.find(type)) e.unavailable = "unavailable: type " + type + " not registered";
  };
  for (const char* key : {"add_components", "replace_components"})
    if (body[key]) {
      if (!body[key].IsMap())
        fail(path, body[key], e.name, "", std::string(key) + " must be a map: NAME: {type: TYPE, PARAMETER: VALUE}");
      for (auto c = body[key].begin(); c != body[key].end(); ++c) {
        (void)name_text(path, c->first, e.name, "", std::string("a component's name in ") + key);
        // Checked here, before any node is subscripted: a scalar would throw yaml-cpp's own error.
        if (!c->second.IsMap() || (c->second["type"] && !c->second["type"].IsScalar()))
          fail(path, c->first, e.name, "",
               "component '" + c->first.Scalar() + "' in " + key + " must be a map {type: TYPE, PARAMETER: VALUE}");
        if (c->second["type"]) check_type(c->second["type"].as<std::string>());
      }
    }
  const auto& req = body["requires"];
  if (!req) return;
  if (!req.IsMap()) fail(path, req, e.name, "", "'requires' must be a map {types, parameters, ports}");
  for (const char* kind : {"types", "parameters", "ports"})
    if (req[kind] && !req[kind].IsSequence())
      fail(path, req[kind], e.name, "", std::string("requires: '") + kind + "' must be a list");
  if (req["types"])
    for (const auto& t : req["types"]) check_type(name_text(path, t, e.name, "", "requires: a type"));
  for (const char* kind : {"parameters", "ports"})
    if (req[kind])
      for (const auto& q : req[kind]) {
        const auto s = name_text(path, q, e.name, "", std::string("requires: an entry of '") + kind + "'");
        const auto dot = s.find('.');
        if (dot == std::string::npos) fail(path, q, e.name, "", "requires: write TYPE.NAME");
        const auto* entry = registry.find(s.substr(0, dot));
        bool ok = entry != nullptr;
        if (ok && std::string(kind) == "parameters") ok = entry->info->parameter(s.substr(dot + 1)) != nullptr;
        if (ok && std::string(kind) == "ports") ok = entry->info->port_index(s.substr(dot + 1)) >= 0;
        if (!ok && e.unavailable.empty())
          e.unavailable = std::string("unavailable: ") + (kind[1] == 'a' ? "parameter " : "port ") + s + " not registered";
      }
}

// One entry of 'effects:': its keys, parameters, patch shape and
// availability checked, the patch read, and an available effect checked to
// apply to the model.
Effect read_effect(const std::string& path, const Reader& reader, const YAML::Node& key, const YAML::Node& body,
                   const Netlist& model, const Registry& registry) {
  static const std::set<std::string> kKeys = {"description",        "parameters", "requires", "add_components",
                                              "replace_components", "set",        "disconnect", "connect",
                                              "measure"};
  Effect e;
  e.name = name_text(path, key, "", "", "an effect's name");
  e.where = location_of(path, key);
  if (!body.IsMap()) fail(path, key, e.name, "", "an effect must be a map (parameters, set, connect, ...)");
  for (auto k = body.begin(); k != body.end(); ++k)
    if (const auto name = name_text(path, k->first, e.name, "", "a key"); !kKeys.count(name))
      fail(path, k->first, e.name, "",
           "unknown key '" + name +
               "' (valid: description, parameters, requires, add_components, replace_components, set, disconnect, "
               "connect, measure)");
  if (body["description"]) e.description = name_text(path, body["description"], e.name, "", "'description'");
  if (body["parameters"]) {
    if (!body["parameters"].IsMap()) fail(path, body["parameters"], e.name, "", "'parameters' must be a map");
    for (auto p = body["parameters"].begin(); p != body["parameters"].end(); ++p)
      e.parameters.push_back(read_effect_parameter(path, e.name, p->first, p->second));
  }
  check_patch_shape(path, body, e.name, model);
  check_availability(path, body, e, registry);
  for (const char* k : {"add_components", "replace_components", "set", "disconnect", "connect", "measure"})
    if (body[k]) check_references(path, body[k], e);
  const std::optional<InputError> refused = read_patch(reader, body, e);
  if (e.unavailable.empty()) {
    if (refused) throw does_not_apply(e, model.file, *refused);
    check_applies(e, model, registry);
  }
  return e;
}

Catalogue read_catalogue(const std::string& path, const Netlist& model, const Registry& registry) {
  Catalogue cat;
  cat.file = path;
  const Reader reader(path);
  const YAML::Node root = read_root(path);
  if (root["phases"]) cat.phases = read_phases(path, root["phases"], model, registry);
  const YAML::Node effects = root["effects"] ? root["effects"] : YAML::Node(YAML::NodeType::Map);
  for (auto it = effects.begin(); it != effects.end(); ++it) {
    const YAML::Node body = it->second;  // a copy: the iterator's pair is a temporary
    cat.effects.push_back(read_effect(path, reader, it->first, body, model, registry));
  }
  if (const YAML::Node re = root["recalibrate"]) {
    if (!re.IsMap()) fail(path, re, "", "", "'recalibrate' must be a map {NAME | COMPONENT.PARAMETER: {lower, upper}}");
    for (auto it = re.begin(); it != re.end(); ++it) {
      Effect e = recalibration(path, it->first, it->second, model, registry);
      if (cat.find(e.name)) fail(path, it->first, e.name, "", "an effect of this name exists already");
      check_applies(e, model, registry);
      cat.effects.push_back(std::move(e));
    }
  }
  return cat;
}

}  // namespace

Catalogue load_catalogue(const std::string& path, const Netlist& model, const Registry& registry) {
  // The readers above check a node's shape before reading it; a shape they
  // miss still ends as an input error at its line, not as yaml-cpp's exception.
  try {
    return read_catalogue(path, model, registry);
  } catch (const YAML::Exception& ex) {
    throw InputError(SourceLocation{path, ex.mark.line + 1, ex.mark.column + 1}, "", "",
                     "unexpected YAML shape: " + ex.msg);
  }
}

namespace {

// The SI value the netlist gives component parameter `spec` of `decl` (its
// default when left out); nullopt, with `why`, when a factor cannot act on
// it: no value, not a positive number, or set by the runs' operating points
// as COMPONENT.PARAMETER (the run's value would replace the factor's). A
// parameter written as a top-level parameter that the runs' operating
// points set (a load `m: m_load`) is moved per run, its name in
// `per_run_of`: a heavier tool weighs on every load the runs were made with.
std::optional<double> factor_base(const Netlist& nl, const ComponentDecl& decl, const ParameterSpec& spec,
                                  const std::vector<std::string>& per_run, std::string& why,
                                  std::string& per_run_of) {
  const std::string path = decl.name + "." + spec.name;
  if (std::find(per_run.begin(), per_run.end(), path) != per_run.end()) {
    why = path + " is set by the runs' operating points";
    return std::nullopt;
  }
  double v = 0;
  if (const ValueDecl* written = decl.written(spec.name)) {
    const ValueDecl& given = *written;
    if (given.shape == ValueDecl::Shape::scalar && !given.si &&
        std::find(per_run.begin(), per_run.end(), given.text) != per_run.end())
      per_run_of = given.text;
    v = parameter_value(nl, decl, spec, given);
  } else if (spec.default_value) {
    v = *spec.default_value;
  } else {
    why = "the netlist gives no value for " + spec.name;
    return std::nullopt;
  }
  if (!(v > 0) || !std::isfinite(v)) {
    why = spec.name + " is " + format_number(v) + ", which a factor cannot move";
    return std::nullopt;
  }
  return v;
}

// A declared fault parameter as the effect's: the range kept within what the
// component accepts (an exclusive limit kept off by a hair), and the `set`
// that writes it (a factor: its product with the netlist's value, or with
// each run's value of the top-level parameter `per_run_of`).
void add_fault_parameter(Effect& e, const FaultParameterSpec& fp, const ParameterSpec& spec, double base,
                         const std::string& per_run_of) {
  EffectParameter ep;
  ep.name = fp.name;
  ep.unit = fp.unit;
  ep.where = e.where;
  ep.null_value = fp.null_value;
  ep.log_scale = fp.log_scale;
  const double lo = fp.factor ? spec.min / base : spec.min, hi = fp.factor ? spec.max / base : spec.max;
  ep.lower = std::max(fp.lower, spec.min_exclusive ? lo + 1e-6 * (fp.upper - lo) : lo);
  ep.upper = std::min(fp.upper, spec.max_exclusive ? hi - 1e-6 * (hi - fp.lower) : hi);
  ep.initial = std::clamp(fp.initial, ep.lower, ep.upper);
  if (!(ep.lower < ep.upper) || *ep.null_value < ep.lower || *ep.null_value > ep.upper ||
      (ep.log_scale && !(ep.lower > 0))) {
    if (e.unavailable.empty()) e.unavailable = "unavailable: " + fp.parameter + "'s range leaves the fault no room";
    return;
  }
  ValueDecl value;
  value.text = fp.factor && per_run_of.empty() ? "${" + fp.name + " * " + format_number(base) + "}" : "${" + fp.name + "}";
  value.where = e.where;
  e.set.push_back({e.component + "." + fp.parameter, e.where, value, per_run_of});
  e.parameters.push_back(ep);
}

// Why the optional part a fault belongs to is absent from this instance
// ("" when present): neither the parameter that gives the part is written
// nor the port that drives it is connected (a fault that names both is
// there with either: a valve's delays act on a schedule or on a command
// signal).
std::string missing_part(const Netlist& nl, const ComponentDecl& decl, const FaultSpec& f) {
  if (!f.needs_parameter.empty() && decl.written(f.needs_parameter)) return "";
  if (!f.needs_port.empty())
    for (const auto& c : nl.connections)
      for (const auto& p : c.ports)
        if (p.component == decl.name && p.port == f.needs_port) return "";
  if (f.needs_parameter.empty() && f.needs_port.empty()) return "";
  if (f.needs_port.empty()) return "the netlist gives no " + f.needs_parameter + " (the part this fault belongs to)";
  if (f.needs_parameter.empty()) return "port " + f.needs_port + " is not connected (the fault acts on what it carries)";
  return "the netlist gives no " + f.needs_parameter + " and port " + f.needs_port +
         " is not connected (the fault acts on what they command)";
}

Effect component_fault(const Netlist& nl, const ComponentDecl& decl, const ComponentInfo& info, const FaultSpec& f,
                       const std::vector<std::string>& per_run) {
  Effect e;
  e.name = decl.name + "." + f.name;
  e.description = f.description;
  e.where = decl.where;
  e.component = decl.name;
  e.fault = f.name;
  e.setting = f.setting;
  if (const std::string why = missing_part(nl, decl, f); !why.empty()) e.unavailable = "unavailable: " + why;
  for (const auto& fp : f.parameters) {
    const ParameterSpec* spec = info.parameter(fp.parameter);
    std::string why, per_run_of;
    std::optional<double> base = 1.0;
    if (!spec || spec->kind != ParameterKind::scalar)
      why = "type " + info.type + " declares it on '" + fp.parameter + "', which is not one of its scalar parameters";
    else if (fp.factor)
      base = factor_base(nl, decl, *spec, per_run, why, per_run_of);
    if (!why.empty() || !base) {
      if (e.unavailable.empty()) e.unavailable = "unavailable: " + why;
      continue;
    }
    add_fault_parameter(e, fp, *spec, *base, per_run_of);
  }
  return e;
}

// OUTPUT.offset, OUTPUT.gain, OUTPUT.lag of a measured signal.

}  // namespace

std::vector<Effect> measurement_faults(const MeasuredSignal& s, const SourceLocation& where, double t_span) {
  struct Kind {
    const char* name;
    const char* description;
    EffectParameter p;
  };
  const double span = s.span > 0 ? s.span : 1.0;
  const double tau_max = std::clamp(t_span / 20, 1e-3, 0.2);
  const std::vector<Kind> kinds = {
      {"offset", "zero offset of the measured signal (transducer drift, wrong zero)",
       {"offset", 0.02 * span, -0.2 * span, 0.2 * span, 0.0, s.unit, false, where}},
      {"gain", "gain error of the measured signal (transducer calibration)",
       {"gain", 1.02, 0.8, 1.25, 1.0, "1", true, where}},
      {"lag", "measured signal lags (a slow transducer, a long tube, a filter)",
       {"tau", 0.1 * tau_max, 0.0, tau_max, 0.0, "s", false, where}},
  };
  std::vector<Effect> out;
  for (const auto& k : kinds) {
    Effect e;
    e.name = s.name + "." + k.name;
    e.description = k.description;
    e.where = where;
    e.component = s.name;
    e.fault = k.name;
    e.parameters.push_back(k.p);
    ValueDecl value;
    value.text = "${" + k.p.name + "}";
    value.where = where;
    MeasurePatch m{s.name, {}, {}, {}};
    (k.name[0] == 'o' ? m.offset : k.name[0] == 'g' ? m.gain : m.lag) = value;
    e.measure.push_back(std::move(m));
    out.push_back(std::move(e));
  }
  return out;
}


Catalogue declared_faults(const Netlist& model, const Registry& registry, const std::vector<MeasuredSignal>& signals,
                          const std::vector<std::string>& per_run) {
  Catalogue cat;
  cat.file = "(declared faults)";
  std::set<std::string> own_offset;  // components whose readings have an offset fault of their own
  for (const auto& decl : model.components) {
    const auto* entry = registry.find(decl.type);
    if (!entry) continue;
    for (const auto& f : entry->info->faults) {
      if (f.name == "offset") own_offset.insert(decl.name);
      Effect e = component_fault(model, decl, *entry->info, f, per_run);
      if (e.unavailable.empty()) {
        try {
          check_applies(e, model, registry);
        } catch (const InputError& ex) {
          e.unavailable = "unavailable: " + ex.message();
        }
      }
      cat.effects.push_back(std::move(e));
    }
  }
  const double t_span = model.simulation.t_end - model.simulation.t_start;
  for (const auto& s : signals) {
    const auto o = std::find_if(model.outputs.begin(), model.outputs.end(), [&](const OutputDecl& d) { return d.name == s.name; });
    if (o == model.outputs.end() || own_offset.count(o->component)) continue;
    for (auto& e : measurement_faults(s, o->where, t_span)) cat.effects.push_back(std::move(e));
  }
  return cat;
}

Effect recalibration(const std::string& key, const std::string& lower, const std::string& upper, const Netlist& model,
                     const Registry& registry, const std::string& origin) {
  YAML::Node body(YAML::NodeType::Map);
  if (!lower.empty()) body["lower"] = lower;
  if (!upper.empty()) body["upper"] = upper;
  auto is_number = [](const std::string& t) {
    std::size_t used = 0;
    try {
      (void)std::stod(t, &used);
    } catch (const std::exception&) {
      return false;
    }
    return used == t.size();
  };
  if (is_number(lower) && std::stod(lower) <= 0) body["scale"] = "linear";
  return recalibration(origin, YAML::Node(key), body, model, registry);
}

void recalibrate_each_runs_value(Effect& e) {
  EffectParameter& p = e.parameters.at(0);
  const double netlist = *p.null_value;
  if (!(netlist > 0))
    throw InputError(e.where, "", e.recalibrates,
                     "recalibrate: '" + e.recalibrates + "' is set by the runs' operating points and is " +
                         format_number(netlist) + " in the netlist, so it cannot be re-calibrated as a factor");
  e.description = e.recalibrates + " off by one factor in every run (the runs set it; netlist " +
                  format_number(netlist) + " " + p.unit + ")";
  p.name = "k";
  p.unit = "1";
  p.lower /= netlist, p.upper /= netlist;
  p.initial = 1.0, p.null_value = 1.0;
  ValueDecl value;
  value.text = "${k}";
  value.where = e.where;
  e.set = {{e.recalibrates, e.where, value, e.recalibrates}};
  e.recalibrates.clear();
}

Catalogue merge_catalogues(Catalogue base, const Catalogue& extra) {
  for (const auto& e : extra.effects) {
    const auto same = std::find_if(base.effects.begin(), base.effects.end(), [&](const Effect& b) { return b.name == e.name; });
    if (same != base.effects.end()) *same = e;
    else base.effects.push_back(e);
  }
  if (!extra.phases.empty()) base.phases = extra.phases;
  base.file = extra.file.empty() ? base.file : base.file + " + " + extra.file;
  return base;
}

Catalogue narrow_catalogue(Catalogue cat, const std::vector<std::string>& keep) {
  auto matches = [](const Effect& e, const std::string& k) { return e.name == k || e.component == k || e.fault == k; };
  for (const auto& k : keep)
    if (std::none_of(cat.effects.begin(), cat.effects.end(), [&](const Effect& e) { return matches(e, k); }))
      throw InputError(SourceLocation{"--faults", 0, 0}, "", k,
                       "'" + k + "' names no candidate (write COMPONENT.FAULT, a component, an output or a fault name)");
  std::vector<Effect> kept;
  for (auto& e : cat.effects)
    if (std::any_of(keep.begin(), keep.end(), [&](const std::string& k) { return matches(e, k); }))
      kept.push_back(std::move(e));
  cat.effects = std::move(kept);
  return cat;
}

}  // namespace pneumo::diagnose
