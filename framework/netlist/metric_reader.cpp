#include "framework/netlist/metric_reader.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "framework/core/expression.hpp"
#include "framework/netlist/reader.hpp"

namespace pneumo {

namespace {

const std::vector<std::string> kKinds = {"max", "min", "value", "final", "of", "event", "integral", "expr", "audit"};
const std::vector<std::string> kModifiers = {"from", "to", "at", "crosses", "direction", "n", "unit"};

class MetricReader {
 public:
  MetricReader(const Netlist& nl, const std::string& name, const YAML::Node& key)
      : nl_(nl), name_(name), key_(key) {}

  [[noreturn]] void fail(const YAML::Node& n, const std::string& message) const {
    throw InputError(location_of(nl_.file, n), "", "metrics." + name_, "metric '" + name_ + "': " + message);
  }

  std::string text(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) fail(n, what + " must be a single value");
    return n.Scalar();
  }

  // COMPONENT.NAME, the component declared in the netlist.
  std::pair<std::string, std::string> reference(const YAML::Node& n, const std::string& what) const {
    const std::string s = text(n, what);
    const auto dot = s.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == s.size()) fail(n, what + " '" + s + "' must be COMPONENT.NAME");
    const std::string comp = s.substr(0, dot);
    if (!component_known(comp)) fail(n, "no component '" + comp + "' in the netlist (" + what + " '" + s + "')");
    return {comp, s.substr(dot + 1)};
  }

  bool component_known(const std::string& c) const {
    return std::any_of(nl_.components.begin(), nl_.components.end(), [&](const ComponentDecl& d) { return d.name == c; });
  }

  std::string output(const YAML::Node& n) const {
    const std::string s = text(n, "an output name");
    const bool known =
        std::any_of(nl_.outputs.begin(), nl_.outputs.end(), [&](const OutputDecl& o) { return o.name == s; });
    if (!known) fail(n, "'" + s + "' is not one of the netlist's outputs (metrics read the columns of 'outputs:')");
    return s;
  }

  // `0.2 s` or an event COMPONENT.TAG (`COMPONENT.TAG#2` for its second occurrence).
  TimeRef time(const YAML::Node& n, const std::string& what) const {
    const std::string s = text(n, what);
    TimeRef r;
    try {
      const auto q = units::parse_quantity(s);
      if (q.had_unit && !(q.dim == units::dims::time)) fail(n, what + " '" + s + "' is not a time");
      r.t = q.si_value;
      if (!std::isfinite(r.t) || r.t < nl_.simulation.t_start)
        fail(n, what + " '" + s + "' is before the run starts (t_start = " + std::to_string(nl_.simulation.t_start) +
                    " s); give a time within the run or an event COMPONENT.TAG");
      return r;
    } catch (const units::ParseError&) {
    }
    std::string ref = s;
    if (const auto hash = s.find('#'); hash != std::string::npos) {
      ref = s.substr(0, hash);
      r.occurrence = positive_int(n, s.substr(hash + 1), what);
    }
    const auto dot = ref.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == ref.size())
      fail(n, what + " '" + s + "' must be a time (0.2 s) or an event COMPONENT.TAG");
    r.component = ref.substr(0, dot);
    r.tag = ref.substr(dot + 1);
    if (!component_known(r.component)) fail(n, "no component '" + r.component + "' in the netlist (" + what + ")");
    return r;
  }

  // The expression quoted, or for a long one the part around `column`, with
  // the column (1-based) so that the user finds the place.
  static std::string excerpt(const std::string& expr, std::size_t column) {
    constexpr std::size_t kShown = 60;
    if (expr.size() <= kShown) return "'" + expr + "' (column " + std::to_string(column + 1) + ")";
    const std::size_t from = column > kShown / 2 ? std::min(column - kShown / 2, expr.size() - kShown) : 0;
    return "'..." + expr.substr(from, kShown) + "...' (column " + std::to_string(column + 1) + " of " +
           std::to_string(expr.size()) + ")";
  }

  int positive_int(const YAML::Node& n, const std::string& s, const std::string& what) const {
    char* end = nullptr;
    const long v = std::strtol(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0' || v < 1 || v > 1000000) fail(n, what + ": '" + s + "' must be a whole number >= 1");
    return static_cast<int>(v);
  }

  MetricDecl read(const YAML::Node& body) const {
    MetricDecl m;
    m.name = name_;
    m.where = location_of(nl_.file, key_);
    std::string kind;
    auto keys = keys_of(body, kind);
    read_kind(kind, keys[kind], keys, m);
    read_modifiers(keys, m);
    return m;
  }

  // The metric's keys, checked: one kind (max, min, ...) and known modifiers.
  std::map<std::string, YAML::Node> keys_of(const YAML::Node& body, std::string& kind) const {
    if (!body.IsMap()) fail(body, "must be a mapping, e.g. {max: p_cap} or {event: cylinder.cap_impact}");
    std::map<std::string, YAML::Node> keys;
    for (auto it = body.begin(); it != body.end(); ++it) {
      const std::string k = text(it->first, "a key");
      const bool is_kind = std::find(kKinds.begin(), kKinds.end(), k) != kKinds.end();
      if (!is_kind && std::find(kModifiers.begin(), kModifiers.end(), k) == kModifiers.end())
        fail(it->first, "unknown key '" + k + "'; a metric is one of max, min, value, final, of (with crosses), "
                                             "event, integral, expr, audit, with from, to, at, direction, n, unit");
      if (is_kind && !kind.empty()) fail(it->first, "has both '" + kind + "' and '" + k + "'; give one");
      if (is_kind) kind = k;
      if (keys.count(k)) fail(it->first, "'" + k + "' is given twice; give it once");
      keys[k] = it->second;
    }
    if (kind.empty()) fail(body, "says what to compute with one of max, min, value, final, of, event, integral, expr, audit");
    return keys;
  }

  // What the kind's value names: an output, an event, an integrand, an expression.
  void read_kind(const std::string& kind, const YAML::Node& v, std::map<std::string, YAML::Node>& keys,
                 MetricDecl& m) const {
    using K = MetricDecl::Kind;
    if (kind == "max" || kind == "min" || kind == "value" || kind == "final" || kind == "of") m.output = output(v);
    if (kind == "max") m.kind = K::max;
    if (kind == "min") m.kind = K::min;
    if (kind == "final") m.kind = K::final_value;
    if (kind == "value") {
      m.kind = K::value;
      if (!keys.count("at")) fail(v, "{value: OUTPUT} needs at: a time or an event COMPONENT.TAG");
    }
    if (kind == "of") {
      m.kind = K::crossing;
      if (!keys.count("crosses")) fail(v, "{of: OUTPUT} needs crosses: LEVEL (with its unit, e.g. 190 mm)");
      read_level(keys["crosses"], m);
      if (keys.count("direction")) {
        const std::string d = text(keys["direction"], "direction");
        if (d == "rising" || d == "up") m.direction = 1;
        else if (d == "falling" || d == "down") m.direction = -1;
        else if (d == "any" || d == "either") m.direction = 0;
        else fail(keys["direction"], "direction '" + d + "': valid are rising, falling, any");
      }
    }
    if (kind == "event") {
      m.kind = K::event_time;
      m.event = time(v, "the event");
      if (!m.event.is_event()) fail(v, "{event: ...} names an event COMPONENT.TAG, not a time");
    }
    if (kind == "integral" || kind == "audit") {
      const auto [comp, quantity] = reference(v, kind == "audit" ? "the audit term" : "the integrand");
      m.kind = kind == "audit" ? K::audit : K::integral;
      m.output = comp + "." + quantity;
    }
    if (kind == "expr") {
      m.kind = K::expression;
      m.expression = text(v, "the expression");
      try {
        (void)Expression(m.expression);
      } catch (const ExpressionError& e) {
        fail(v, "cannot read the expression " + excerpt(m.expression, e.column) + ": " + e.what());
      }
    }
    if (keys.count("unit")) {
      m.unit = text(keys["unit"], "unit");
      try {
        (void)units::parse_unit(m.unit);
      } catch (const units::ParseError& e) {
        fail(keys["unit"], "unit '" + m.unit + "': " + e.what());
      }
    }
  }

  // n, from/to, at, crosses and direction, each only where it means something.
  void read_modifiers(std::map<std::string, YAML::Node>& keys, MetricDecl& m) const {
    using K = MetricDecl::Kind;
    if (keys.count("n")) {
      if (m.kind != K::crossing && m.kind != K::event_time) fail(keys["n"], "n (which occurrence) is for 'of' and 'event'");
      const int n = positive_int(keys["n"], text(keys["n"], "n"), "n");
      (m.kind == K::event_time ? m.event.occurrence : m.occurrence) = n;
    }
    const bool windowed = m.kind == K::max || m.kind == K::min || m.kind == K::crossing || m.kind == K::integral;
    for (const char* w : {"from", "to"})
      if (keys.count(w)) {
        if (!windowed) fail(keys[w], std::string(w) + " limits max, min, of and integral only");
        (std::string(w) == "from" ? m.from : m.to) = time(keys[w], w);
      }
    if (m.from && m.to && !m.from->is_event() && !m.to->is_event() && m.from->t > m.to->t)
      fail(keys["from"], "from (" + text(keys["from"], "from") + ") is after to (" + text(keys["to"], "to") +
                             "); the window would be empty");
    if (keys.count("at")) {
      if (m.kind != K::value) fail(keys["at"], "at is for {value: OUTPUT}");
      m.at = time(keys["at"], "at");
    }
    if (keys.count("crosses") && m.kind != K::crossing) fail(keys["crosses"], "crosses goes with {of: OUTPUT}");
    if (keys.count("direction") && m.kind != K::crossing) fail(keys["direction"], "direction goes with {of: OUTPUT}");
  }

 private:
  void read_level(const YAML::Node& n, MetricDecl& m) const {
    const std::string s = text(n, "the level");
    try {
      m.level = units::parse_quantity(s, nl_.gas.p_ambient);
    } catch (const units::ParseError& e) {
      fail(n, "cannot read the level '" + s + "': " + e.what());
    }
  }

  const Netlist& nl_;
  std::string name_;
  YAML::Node key_;
};

// Expressions name declared metrics or events; no metric may depend on itself.
void check_expressions(const std::vector<MetricDecl>& ms, const Netlist& nl, const std::map<std::string, YAML::Node>& where) {
  std::map<std::string, const MetricDecl*> by_name;
  for (const auto& m : ms) by_name[m.name] = &m;
  for (const auto& m : ms) {
    if (m.kind != MetricDecl::Kind::expression) continue;
    for (const auto& n : Expression(m.expression).names()) {
      if (by_name.count(n)) continue;
      const auto dot = n.find('.');
      const bool event = dot != std::string::npos &&
                         std::any_of(nl.components.begin(), nl.components.end(),
                                     [&](const ComponentDecl& d) { return d.name == n.substr(0, dot); });
      if (!event)
        throw InputError(location_of(nl.file, where.at(m.name)), "", "metrics." + m.name,
                         "metric '" + m.name + "': '" + n +
                             "' in the expression is neither a metric of this netlist nor an event COMPONENT.TAG");
    }
  }
  std::set<std::string> done, active;
  std::function<void(const MetricDecl&)> visit = [&](const MetricDecl& m) {
    if (done.count(m.name)) return;
    if (!active.insert(m.name).second)
      throw InputError(location_of(nl.file, where.at(m.name)), "", "metrics." + m.name,
                       "metric '" + m.name + "' depends on itself through its expression");
    if (m.kind == MetricDecl::Kind::expression)
      for (const auto& n : Expression(m.expression).names())
        if (by_name.count(n)) visit(*by_name[n]);
    active.erase(m.name);
    done.insert(m.name);
  };
  for (const auto& m : ms) visit(m);
}

}  // namespace

std::vector<MetricDecl> read_metrics(const YAML::Node& section, const Netlist& nl) {
  std::vector<MetricDecl> out;
  if (!section.IsDefined() || section.IsNull()) return out;
  if (!section.IsMap())
    throw InputError(location_of(nl.file, section), "", "", "metrics must be a mapping NAME: {max: OUTPUT} ...");
  std::map<std::string, YAML::Node> where;
  for (auto it = section.begin(); it != section.end(); ++it) {
    if (!it->first.IsScalar()) throw InputError(location_of(nl.file, it->first), "", "", "metric names must be plain names");
    const std::string name = it->first.Scalar();
    if (where.count(name))
      throw InputError(location_of(nl.file, it->first), "", "metrics." + name, "duplicate metric '" + name + "'");
    if (const std::string why = netlist_detail::column_name_problem(name); !why.empty())
      throw InputError(location_of(nl.file, it->first), "", "metrics." + name,
                       "metric name '" + name + "' " + why +
                           "; it heads a column of the results CSV: use letters, digits and _");
    where[name] = it->first;
    out.push_back(MetricReader(nl, name, it->first).read(it->second));
  }
  check_expressions(out, nl, where);
  return out;
}

}  // namespace pneumo
