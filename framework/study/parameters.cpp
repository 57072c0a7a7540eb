#include "framework/study/parameters.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "framework/core/text.hpp"
#include "framework/core/units.hpp"
#include "framework/io/files.hpp"

namespace pneumo::study {

namespace {

SourceLocation netlist_where(const Netlist& nl) {
  return nl.parameters_where.known() ? nl.parameters_where : SourceLocation{nl.file, 1, 1};
}

// Runs a study plans at most: beyond, a typing error, not a study (and the
// plan alone would take gigabytes).
constexpr int kMaxRuns = 10000000;

std::string count_text(double n) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", n);
  return buf;
}

}  // namespace

void set_display_unit(StudyParameter& p, const std::string& unit_text, double ambient);

StudyParameter resolve_parameter(const Netlist& nl, const Registry& registry, const std::string& name) {
  StudyParameter p;
  p.name = name;
  const auto dot = name.find('.');
  if (dot == std::string::npos) {
    const TopParameter* tp = nl.parameter(name);
    if (!tp) {
      std::string names;
      for (const auto& t : nl.parameters) names += (names.empty() ? "" : ", ") + t.name;
      throw InputError(netlist_where(nl), "", name,
                       "no top-level parameter '" + name + "' in " + nl.file + " (top-level parameters: " +
                           (names.empty() ? "none" : names) +
                           "); a component's parameter is named COMPONENT.PARAMETER, e.g. cylinder.friction_scale");
    }
    p.parameter = name;
    p.unit = units::si_unit_name(tp->dim);
    set_display_unit(p, "", nl.gas.p_ambient);
    return p;
  }
  p.component = name.substr(0, dot);
  p.parameter = name.substr(dot + 1);
  const ComponentDecl* decl = nl.component(p.component);
  if (!decl) throw InputError(netlist_where(nl), p.component, "", "no component '" + p.component + "' in " + nl.file);
  const auto* entry = registry.find(decl->type);
  const ParameterSpec* spec = entry ? entry->info->parameter(p.parameter) : nullptr;
  if (!spec || spec->kind != ParameterKind::scalar)
    throw InputError(decl->where, p.component, p.parameter,
                     "component type '" + decl->type + "' has no scalar parameter '" + p.parameter +
                         "' (see 'pneumo components " + decl->type + "')");
  p.unit = spec->unit;
  set_display_unit(p, "", nl.gas.p_ambient);
  return p;
}

double parse_value(const Netlist& nl, const Registry& registry, const StudyParameter& p, const std::string& text,
                   const std::string& option) {
  (void)registry;
  units::Quantity q{};
  try {
    q = units::parse_quantity(trim(text), nl.gas.p_ambient);
  } catch (const units::ParseError& e) {
    throw InputError(netlist_where(nl), p.component, p.parameter, option + ": cannot read '" + text + "': " + e.what());
  }
  if (q.had_unit && !(q.dim == units::dimension_of(p.unit)))
    throw InputError(netlist_where(nl), p.component, p.parameter,
                     option + ": '" + text + "' has dimension " + q.dim.to_string() + " but " + p.name + " is in " +
                         p.unit);
  return q.si_value;
}

void refuse_repeated(const Netlist& nl, const std::vector<StudyParameter>& ps, const std::string& what) {
  auto key = [](const StudyParameter& p) { return p.component.empty() ? p.parameter : p.component + "." + p.parameter; };
  for (std::size_t i = 0; i < ps.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (key(ps[i]) == key(ps[j]))
        throw InputError(netlist_where(nl), ps[i].component, ps[i].parameter,
                         what + ": '" + key(ps[i]) + "' is given twice" +
                             (ps[i].name == ps[j].name ? "" : " (as '" + ps[j].name + "' and '" + ps[i].name + "')") +
                             "; give each parameter once");
}

// Results show `p` in `unit_text` when it names a unit of the parameter's
// dimension (what the user wrote); otherwise in the unit engineers read.
void set_display_unit(StudyParameter& p, const std::string& unit_text, double ambient) {
  const units::Dimension dim = units::dimension_of(p.unit);
  p.display_unit = units::si_unit_name(dim);
  if (dim == units::dims::sonic_conductance) {
    p.display_unit = "dm3/(s*bar)";
    p.display_scale = 1e-8;
  }
  if (unit_text.empty()) return;
  try {
    const units::DisplayUnit d = units::display_unit(unit_text, dim, ambient);
    p.display_unit = d.unit;
    p.display_scale = d.scale;
    p.display_offset = d.offset;
  } catch (const std::exception&) {  // not a unit of this parameter: SI
  }
}

// The unit part of a quantity's text ("8bar" -> "bar"); "" for a plain number.
std::string unit_part(const std::string& text) {
  const std::string t = trim(text);
  char* end = nullptr;
  std::strtod(t.c_str(), &end);
  return trim(std::string(end));
}

Design grid_design(const Netlist& nl, const Registry& registry, const std::vector<std::string>& specs) {
  Design d;
  std::vector<std::vector<double>> axes;
  for (const auto& spec : specs) {
    const std::string option = "--grid " + spec;
    const auto eq = spec.find('=');
    const auto parts = eq == std::string::npos ? std::vector<std::string>{} : split_trimmed(spec.substr(eq + 1), ':');
    if (eq == std::string::npos || eq == 0 || parts.size() != 3)
      throw InputError(netlist_where(nl), "", "", option + ": expected NAME=FROM:TO:COUNT, e.g. p_supply=5bar:8bar:4");
    StudyParameter p = resolve_parameter(nl, registry, trim(spec.substr(0, eq)));
    set_display_unit(p, unit_part(parts[0]), nl.gas.p_ambient);
    const double a = parse_value(nl, registry, p, parts[0], option);
    const double b = parse_value(nl, registry, p, parts[1], option);
    int n = 0;
    try {
      std::size_t used = 0;
      n = std::stoi(parts[2], &used);
      if (used != parts[2].size()) n = 0;
    } catch (const std::exception&) {
      n = 0;
    }
    if (n < 1 || n > kMaxRuns)
      throw InputError(netlist_where(nl), p.component, p.parameter,
                       option + ": COUNT must be a whole number from 1 to " + std::to_string(kMaxRuns));
    std::vector<double> axis(n);
    for (int i = 0; i < n; ++i) axis[i] = n == 1 ? a : a + (b - a) * i / (n - 1);
    if (n > 1) axis[n - 1] = b;
    d.parameters.push_back(p);
    axes.push_back(std::move(axis));
  }
  refuse_repeated(nl, d.parameters, "--grid");
  double runs = axes.empty() ? 0 : 1;  // in double: the product of large counts overflows an integer
  for (const auto& a : axes) runs *= static_cast<double>(a.size());
  if (runs > kMaxRuns)
    throw InputError(netlist_where(nl), "", "",
                     "--grid: the full factorial grid has " + count_text(runs) + " runs, more than the " +
                         std::to_string(kMaxRuns) + " a sweep takes; use fewer points per axis or --samples");
  const auto total = static_cast<std::size_t>(runs);
  d.samples.reserve(total);
  for (std::size_t k = 0; k < total; ++k) {
    Sample s(axes.size());
    std::size_t rest = k;
    for (std::size_t j = axes.size(); j-- > 0;) {
      s[j] = axes[j][rest % axes[j].size()];
      rest /= axes[j].size();
    }
    d.samples.push_back(std::move(s));
  }
  return d;
}

Design samples_design(const Netlist& nl, const Registry& registry, const std::string& path) {
  try {
    check_input_file(path, "samples file");
  } catch (const std::invalid_argument& e) {
    throw InputError(SourceLocation{path, 0, 0}, "", "", e.what());
  }
  std::ifstream in(path);
  if (!in) throw InputError(SourceLocation{path, 0, 0}, "", "", "cannot open the samples file");
  Design d;
  std::vector<double> scale;
  std::vector<std::string> unit_text;
  std::string line;
  int line_no = 0;
  bool header = false;
  while (std::getline(in, line)) {
    ++line_no;
    // A UTF-8 byte order mark (as spreadsheets write) is not part of the first name.
    if (line_no == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    const auto cells = split_trimmed(line, ',');
    const SourceLocation where{path, line_no, 1};
    if (!header) {
      for (const auto& cell : cells) {
        std::string name = cell, unit;
        const auto open = cell.find('[');
        if (open != std::string::npos && cell.back() == ']') {
          name = trim(cell.substr(0, open));
          unit = trim(cell.substr(open + 1, cell.size() - open - 2));
        }
        try {
          d.parameters.push_back(resolve_parameter(nl, registry, name));
          set_display_unit(d.parameters.back(), unit, nl.gas.p_ambient);
        } catch (const InputError& e) {
          throw InputError(where, "", name, "column '" + cell + "': " + e.message());
        }
        unit_text.push_back(unit);
      }
      try {
        refuse_repeated(nl, d.parameters, "the header");
      } catch (const InputError& e) {
        throw InputError(where, e.component(), e.parameter(), e.message());
      }
      header = true;
      continue;
    }
    if (cells.size() != d.parameters.size())
      throw InputError(where, "", "", "expected " + std::to_string(d.parameters.size()) + " values, found " +
                                          std::to_string(cells.size()));
    Sample s;
    for (std::size_t j = 0; j < cells.size(); ++j) {
      const std::string text = unit_text[j].empty() ? cells[j] : cells[j] + " " + unit_text[j];
      try {
        s.push_back(parse_value(nl, registry, d.parameters[j], text, "samples"));
      } catch (const InputError& e) {
        throw InputError(where, d.parameters[j].component, d.parameters[j].parameter, e.message());
      }
    }
    d.samples.push_back(std::move(s));
    if (d.samples.size() > static_cast<std::size_t>(kMaxRuns))
      throw InputError(where, "", "", "more than " + std::to_string(kMaxRuns) + " runs; split the samples file");
  }
  if (!header) throw InputError(SourceLocation{path, 1, 1}, "", "", "no header line naming the parameters");
  return d;
}

std::vector<Range> parse_ranges(const Netlist& nl, const Registry& registry, const std::vector<std::string>& specs,
                                const std::string& flag) {
  std::vector<Range> out;
  for (const auto& spec : specs) {
    const std::string option = flag + " " + spec;
    const auto eq = spec.find('=');
    const auto parts = eq == std::string::npos ? std::vector<std::string>{} : split_trimmed(spec.substr(eq + 1), ':');
    if (eq == std::string::npos || eq == 0 || parts.size() != 2)
      throw InputError(netlist_where(nl), "", "", option + ": expected NAME=LOW:HIGH, e.g. m_load=2kg:6kg");
    Range r;
    r.parameter = resolve_parameter(nl, registry, trim(spec.substr(0, eq)));
    r.lo = parse_value(nl, registry, r.parameter, parts[0], option);
    r.hi = parse_value(nl, registry, r.parameter, parts[1], option);
    if (!(r.hi > r.lo))
      throw InputError(netlist_where(nl), r.parameter.component, r.parameter.parameter,
                       option + ": HIGH must be greater than LOW");
    out.push_back(r);
  }
  std::vector<StudyParameter> ps;
  for (const auto& r : out) ps.push_back(r.parameter);
  refuse_repeated(nl, ps, flag);
  return out;
}

}  // namespace pneumo::study
