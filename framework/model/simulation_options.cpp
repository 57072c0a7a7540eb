#include "framework/model/simulation_options.hpp"

#include <algorithm>
#include <sstream>

#include "framework/core/units.hpp"

namespace pneumo {

namespace {

using S = SimulationSettings;

// A quantity; its default is SimulationSettings' initialiser.
SimulationOption number(double S::*member, const char* name, const char* unit, const char* description) {
  return {ParameterSpec::scalar(name, unit, description, S{}.*member), member, nullptr};
}
SimulationOption positive(SimulationOption o) {
  o.spec = std::move(o.spec).positive();
  return o;
}
SimulationOption non_negative(SimulationOption o) {
  o.spec = std::move(o.spec).non_negative();
  return o;
}
SimulationOption open_range(SimulationOption o, double lo, double hi) {
  o.spec = std::move(o.spec).open_range(lo, hi);
  return o;
}

SimulationOption flag(bool S::*member, const char* name, const char* description) {
  return {ParameterSpec::text(name, {"true", "false"}, description, S{}.*member ? "true" : "false"), nullptr, member};
}

}  // namespace

const std::vector<SimulationOption>& simulation_options() {
  static const std::vector<SimulationOption> table{
      number(&S::t_start, "t_start", "s", "start time"),
      number(&S::t_end, "t_end", "s", "end time; must be after t_start"),
      open_range(number(&S::rtol, "rtol", "1", "relative tolerance of IDA's error test"), 0.0, 1.0),
      open_range(number(&S::atol, "atol", "1",
                        "absolute tolerance as a fraction of each unknown's typical magnitude (pressures ~1e5 Pa "
                        "and chamber masses ~1e-6 kg cannot share one number)"),
                 0.0, 1.0),
      positive(number(&S::output_interval, "output_interval", "s", "time between output rows")),
      non_negative(number(&S::max_step, "max_step", "s", "largest step IDA may take; 0: the solver's choice")),
      flag(&S::jacobian_reuse, "jacobian_reuse",
           "answer IDA's requests for a Newton matrix that only follow a change of its step size by recombining "
           "the last evaluation's parts dF/dy, dF/dy'; false: every matrix evaluated afresh, as IDA alone does"),
      flag(&S::steady_start, "steady_start",
           "start from the rest state the circuit settles into with every input held at t_start (valves in their "
           "initial positions, no time events): pressures, positions, the piston against its stop or in force "
           "equilibrium, the gas at the ambient temperature; start values are where the settling starts"),
  };
  return table;
}

// Output rows are held in memory and counted in a long: a run may ask for
// at most 1e8 of them (about 1 GB of a few columns).
constexpr double kMaxOutputRows = 1e8;

std::string simulation_settings_problem(const SimulationSettings& s) {
  if (!(s.t_end > s.t_start))
    return "t_end (" + units::format_si(s.t_end, units::dims::time) + ") must be > t_start (" +
           units::format_si(s.t_start, units::dims::time) + ")";
  const double rows = (s.t_end - s.t_start) / s.output_interval;
  if (!(rows <= kMaxOutputRows))
    return "t_end - t_start over output_interval asks for " + units::format_si(rows, units::dims::none) +
           " output rows; at most 1e8 are written (raise output_interval)";
  return "";
}

bool apply_simulation_override(SimulationSettings& s, const std::string& assignment, const SourceLocation& where) {
  const std::string prefix = "simulation.";
  if (assignment.rfind(prefix, 0) != 0) return false;
  const std::string option = "--set " + assignment;
  const auto eq = assignment.find('=');
  const std::string key = assignment.substr(prefix.size(), eq == std::string::npos ? eq : eq - prefix.size());
  const std::string text = eq == std::string::npos ? "" : assignment.substr(eq + 1);
  const auto& table = simulation_options();
  auto o = std::find_if(table.begin(), table.end(), [&](const SimulationOption& x) { return x.spec.name == key; });
  std::string keys;
  for (const auto& x : table) keys += (keys.empty() ? "" : ", ") + x.spec.name;
  if (o == table.end() || eq == std::string::npos)
    throw InputError(where, "", prefix + key, option + ": expected simulation.KEY=VALUE, KEY one of " + keys);
  auto fail = [&](const std::string& why) { throw InputError(where, "", prefix + key, option + ": " + why); };
  if (o->flag) {
    if (text != "true" && text != "false") fail(key + " must be true or false, not '" + text + "'");
    s.*(o->flag) = text == "true";
    return true;
  }
  units::Quantity q{};
  try {
    q = units::parse_quantity(text);
  } catch (const units::ParseError& e) {
    fail("cannot read '" + text + "': " + e.what());
  }
  const units::Dimension dim = units::dimension_of(o->spec.unit);
  if (q.had_unit && !(q.dim == dim)) fail("'" + text + "' is not in " + o->spec.unit);
  if (!o->spec.in_range(q.si_value))
    fail(key + " = " + units::format_si(q.si_value, dim) + " is out of range; valid: " + o->spec.range_text() + " (" +
         o->spec.unit + ")");
  s.*(o->number) = q.si_value;
  if (const std::string problem = simulation_settings_problem(s); !problem.empty()) fail(problem);
  return true;
}

std::string simulation_options_help() {
  std::ostringstream out;
  for (const auto& o : simulation_options()) {
    const ParameterSpec& s = o.spec;
    out << "  " << s.name;
    if (o.number) out << " [" << s.unit << "]  default " << *s.default_value << ", " << s.range_text();
    else out << " [true|false]  default " << *s.default_text;
    out << ": " << s.description << "\n";
  }
  return out.str();
}

}  // namespace pneumo
