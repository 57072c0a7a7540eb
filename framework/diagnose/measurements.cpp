// Measured runs: DIR/NAME.yaml (data, role, operating_point) + NAME.csv.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "framework/core/text.hpp"
#include "framework/core/units.hpp"
#include "framework/diagnose/data_spec.hpp"
#include "framework/diagnose/diagnose.hpp"
#include "framework/diagnose/yaml_file.hpp"
#include "framework/netlist/yaml_location.hpp"

namespace pneumo::diagnose {

namespace fs = std::filesystem;

double estimate_noise(const std::vector<double>& y) {
  const std::size_t n = y.size();
  if (n < 5) return 0.0;
  std::vector<double> d2;
  d2.reserve(n);
  // Third differences: a smooth signal's curvature cancels, white noise
  // keeps variance 20 sigma^2.
  for (std::size_t i = 0; i + 3 < n; ++i) d2.push_back(y[i + 3] - 3 * y[i + 2] + 3 * y[i + 1] - y[i]);
  std::vector<double> a = d2;
  std::nth_element(a.begin(), a.begin() + a.size() / 2, a.end());
  const double med = a[a.size() / 2];
  for (auto& v : a) v = std::abs(v - med);
  std::nth_element(a.begin(), a.begin() + a.size() / 2, a.end());
  double sigma = 1.4826 * a[a.size() / 2] / std::sqrt(20.0);
  // Quantised signals with little noise: the step is the resolution.
  double q = INFINITY, lo = y[0], hi = y[0];
  for (std::size_t i = 1; i < n; ++i) {
    const double d = std::abs(y[i] - y[i - 1]);
    if (d > 0) q = std::min(q, d);
    lo = std::min(lo, y[i]);
    hi = std::max(hi, y[i]);
  }
  if (std::isfinite(q)) sigma = std::max(sigma, q / std::sqrt(12.0));
  sigma = std::max(sigma, 1e-9 * std::max(std::abs(hi), std::abs(lo)) + 1e-300);
  return sigma;
}

namespace {

// One header cell: "NAME" or "NAME [UNIT]", at 1-based `column` of its line.
struct HeaderCell {
  std::string name, unit;
  bool has_unit = false;  // written in brackets (possibly "[]" or "[1]": dimensionless)
  int column = 1;
};

// The cells of a header line with their columns (for file:line:column).
std::vector<HeaderCell> header_cells(const std::string& line, const std::string& path, int lineno) {
  std::vector<HeaderCell> out;
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = line.find(',', begin);
    const std::string raw = line.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin);
    HeaderCell c;
    const auto first = raw.find_first_not_of(" \t\r");
    c.column = static_cast<int>(begin + (first == std::string::npos ? 0 : first)) + 1;
    const std::string cell = trim(raw);
    if (const auto lb = cell.find('['); lb != std::string::npos) {
      if (cell.back() != ']')
        throw InputError(SourceLocation{path, lineno, c.column}, "", "",
                         "header cell '" + quoted_cell(cell) + "': write the unit in brackets at its end, e.g. 'p [bar]'");
      c.name = trim(cell.substr(0, lb));
      c.unit = trim(cell.substr(lb + 1, cell.size() - lb - 2));
      c.has_unit = true;
    } else {
      c.name = cell;
    }
    out.push_back(c);
    if (comma == std::string::npos) break;
    begin = comma + 1;
  }
  return out;
}

// A column's unit, checked against the dimension the model's quantity has
// (SI inside: a column without a unit is SI).
units::Unit column_unit(const HeaderCell& c, const std::string& si_unit, const std::string& path, int lineno) {
  const SourceLocation at{path, lineno, c.column};
  if (!c.has_unit) return units::Unit{};  // SI
  units::Unit u;
  try {
    u = units::parse_unit(c.unit);
  } catch (const std::exception& ex) {
    throw InputError(at, "", quoted_cell(c.name),
                     "column '" + quoted_cell(c.name) + "': unit '" + quoted_cell(c.unit) + "': " + ex.what());
  }
  units::Dimension want;
  try {
    want = units::dimension_of(si_unit);
  } catch (const std::exception&) {
    return u;  // a model unit the parser does not know: nothing to check against
  }
  if (!(u.dim == want))
    throw InputError(at, "", quoted_cell(c.name),
                     "column '" + quoted_cell(c.name) + "': unit '" + quoted_cell(c.unit) + "' (" +
                         u.dim.to_string() + ") does not fit the model's " +
                         (c.name == "t" ? std::string("time") : "output '" + c.name + "'") + " in " + si_unit +
                         " (" + want.to_string() + ")");
  return u;
}

// The model's SI unit of each output, by name.
std::string si_unit_of(const std::vector<Probe>& probes, const std::string& name) {
  for (const auto& p : probes)
    if (p.name == name) return p.unit;
  return "";
}

// A run is simulated from the model's t_start to its last sample: its
// samples must lie within the model's [t_start, t_end] - a run past t_end
// or before t_start, or one spanning less than kMinSpanShare of it, is most
// often a time column in another unit than its header says.
constexpr double kMinSpanShare = 0.1;

std::string seconds(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", t);
  return buf;
}

void check_time_span(const MeasuredRun& run, const Netlist& model, const std::string& path, int first_line,
                     int last_line, const units::Unit& t_unit) {
  const double t0 = model.simulation.t_start, t1 = model.simulation.t_end;
  const double dt = (run.t.back() - run.t.front()) / static_cast<double>(run.t.size() - 1);
  const double tol = 0.5 * dt + 1e-9 * std::max(1.0, std::abs(t1));
  const std::string unit_hint =
      t_unit.scale == 1 ? " If the time column is not in seconds, give its unit in the header (e.g. 't [ms]')."
                        : " Check the time column's unit in the header.";
  const std::string model_span = "the model " + model.file + " simulates t = " + seconds(t0) + " s to t_end = " +
                                 seconds(t1) + " s";
  if (run.t.front() < t0 - tol)
    throw InputError(SourceLocation{path, first_line, 1}, "", "t",
                     "the measured run starts at t = " + seconds(run.t.front()) + " s, before the simulation: " +
                         model_span + "." + unit_hint);
  if (run.t.back() > t1 + tol)
    throw InputError(SourceLocation{path, last_line, 1}, "", "t",
                     "the measured run ends at t = " + seconds(run.t.back()) + " s, after the simulation: " +
                         model_span + "; raise simulation.t_end to the measured span or cut the data." + unit_hint);
  if (run.t.back() - run.t.front() < kMinSpanShare * (t1 - t0))
    throw InputError(SourceLocation{path, last_line, 1}, "", "t",
                     "the measured run spans only t = " + seconds(run.t.front()) + " s to " +
                         seconds(run.t.back()) + " s, less than a tenth of the simulation: " + model_span +
                         "; set simulation.t_end to the measured span." + unit_hint);
}

void read_csv_into(MeasuredRun& run, const std::string& path, const Netlist& model, const std::vector<Probe>& probes) {
  std::ifstream in(path);
  if (!in) throw InputError(SourceLocation{path, 0, 0}, "", "", "cannot open the measured data file");
  std::string line;
  int lineno = 0;
  std::vector<HeaderCell> header;
  while (std::getline(in, line)) {
    ++lineno;
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    header = header_cells(line, path, lineno);
    break;
  }
  if (header.empty()) throw InputError(SourceLocation{path, 0, 0}, "", "", "the file is empty (expected a header t,<output>,...)");
  if (header[0].name != "t")
    throw InputError(SourceLocation{path, lineno, header[0].column}, "", quoted_cell(header[0].name),
                     "the first column must be 't' (time; in s, or give its unit: 't [ms]')");
  std::vector<units::Unit> col_units = {column_unit(header[0], "s", path, lineno)};
  std::set<std::string> seen;
  std::string valid;
  for (const auto& o : model.outputs) valid += (valid.empty() ? "" : ", ") + o.name;
  for (std::size_t k = 1; k < header.size(); ++k) {
    const std::string& name = header[k].name;
    const SourceLocation at{path, lineno, header[k].column};
    bool known = false;
    for (const auto& o : model.outputs) known = known || o.name == name;
    if (!known)
      throw InputError(at, "", quoted_cell(name),
                       "unknown output name '" + quoted_cell(name) + "' (the model's outputs: " + valid + ")");
    if (!seen.insert(name).second) throw InputError(at, "", name, "column '" + name + "' appears twice");
    col_units.push_back(column_unit(header[k], si_unit_of(probes, name), path, lineno));
    run.signals.push_back(name);
  }
  if (run.signals.empty())
    throw InputError(SourceLocation{path, lineno, 1}, "", "", "no measured signal: the header has only 't'");
  run.y.assign(run.signals.size(), {});
  int first_line = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    const auto cells = split_trimmed(line, ',');
    if (cells.size() != header.size())
      throw InputError(SourceLocation{path, lineno, 1}, "", "",
                       "expected " + std::to_string(header.size()) + " values (" + std::to_string(header.size()) +
                           " columns in the header), found " + std::to_string(cells.size()) + " - missing column?");
    std::vector<double> v(cells.size());
    for (std::size_t k = 0; k < cells.size(); ++k) {
      const std::string cname = k == 0 ? "t" : run.signals[k - 1];
      char* end = nullptr;
      v[k] = std::strtod(cells[k].c_str(), &end);
      if (cells[k].empty() || end == cells[k].c_str() || *end != '\0' || !std::isfinite(v[k]))
        throw InputError(SourceLocation{path, lineno, 1}, "", cname,
                         "column '" + cname + "': '" + quoted_cell(cells[k]) + "' is not a finite number");
      v[k] = units::to_si(col_units[k], v[k], model.gas.p_ambient);
    }
    if (!run.t.empty() && !(v[0] > run.t.back()))
      throw InputError(SourceLocation{path, lineno, 1}, "", "t",
                       "time must increase strictly: t = " + quoted_cell(cells[0]) + " (" + rounded(v[0], 9) +
                           " s) follows t = " + rounded(run.t.back(), 9) + " s");
    if (run.t.empty()) first_line = lineno;
    run.t.push_back(v[0]);
    for (std::size_t k = 1; k < v.size(); ++k) run.y[k - 1].push_back(v[k]);
  }
  if (run.t.size() < 10)
    throw InputError(SourceLocation{path, lineno, 1}, "", "", "fewer than 10 samples: nothing to diagnose");
  check_time_span(run, model, path, first_line, lineno, col_units[0]);
  for (const auto& y : run.y) run.sigma.push_back(estimate_noise(y));
}

// A run whose `data:` describes a lab file as it comes (data_spec.hpp): a
// column 't' and columns named as the model's outputs.
void read_described_into(MeasuredRun& run, const DataFileSpec& spec, const Netlist& model,
                         const std::vector<Probe>& probes) {
  const DataColumns d = read_data_file(spec, model.gas.p_ambient);
  const int ct = d.column("t");
  if (ct < 0) throw InputError(spec.described_at, "", "columns", "the data description needs a time column 't'");
  std::string valid;
  for (const auto& o : model.outputs) valid += (valid.empty() ? "" : ", ") + o.name;
  for (std::size_t k = 0; k < d.names.size(); ++k) {
    if (static_cast<int>(k) == ct) continue;
    if (si_unit_of(probes, d.names[k]).empty() &&
        std::none_of(model.outputs.begin(), model.outputs.end(), [&](const auto& o) { return o.name == d.names[k]; }))
      throw InputError(spec.described_at, "", d.names[k],
                       "column '" + d.names[k] + "' is no output of the model (its outputs: " + valid + ")");
    run.signals.push_back(d.names[k]);
    run.y.push_back(d.values[k]);
  }
  if (run.signals.empty())
    throw InputError(spec.described_at, "", "columns", "no measured signal: the description names only 't'");
  run.t = d.values[static_cast<std::size_t>(ct)];
  for (std::size_t i = 1; i < run.t.size(); ++i)
    if (!(run.t[i] > run.t[i - 1]))
      throw InputError(SourceLocation{spec.file, d.lines[i], 1}, "", "t",
                       "time must increase strictly: t = " + rounded(run.t[i], 9) + " s follows t = " +
                           rounded(run.t[i - 1], 9) + " s (check the time column's unit and thousands separator)");
  if (run.t.size() < 10)
    throw InputError(SourceLocation{spec.file, d.lines.back(), 1}, "", "", "fewer than 10 samples: nothing to diagnose");
  units::Unit t_unit;
  for (const auto& c : spec.columns)
    if (c.name == "t") t_unit = units::parse_unit(c.unit);
  check_time_span(run, model, spec.file, d.lines.front(), d.lines.back(), t_unit);
  for (const auto& y : run.y) run.sigma.push_back(estimate_noise(y));
}

// The data file a run file's `data:` names: a relative path that stays
// inside the runs folder once links and '..' are resolved, and a regular
// file (a device or FIFO would be read forever). Returns its resolved path.
std::string data_file(const fs::path& runs_dir, const std::string& run_file, const YAML::Node& node) {
  const std::string text = plain_text(run_file, node, "", "data", "'data'");
  const SourceLocation at = location_of(run_file, node);
  const fs::path rel(text);
  if (text.empty()) throw InputError(at, "", "data", "'data' is empty: name the run's CSV file in the runs folder");
  if (rel.is_absolute() || rel.has_root_name() || rel.has_root_directory())
    throw InputError(at, "", "data",
                     "data: '" + quoted_cell(text, 200) + "' is an absolute path; name a file inside the runs folder " +
                         runs_dir.string() + ", relative to it");
  std::error_code ec;
  const fs::path base = fs::canonical(runs_dir, ec);
  const fs::path target = ec ? fs::path() : fs::weakly_canonical(base / rel, ec);
  const fs::path inside = target.lexically_relative(base);
  if (ec || inside.empty() || *inside.begin() == "..")
    throw InputError(at, "", "data",
                     "data: '" + quoted_cell(text, 200) + "' lies outside the runs folder " + runs_dir.string() +
                         " (after following links and '..'); put the data file inside it");
  const auto st = fs::status(target, ec);
  if (ec || !fs::exists(st))
    throw InputError(at, "", "data", "data: '" + quoted_cell(text, 200) + "': no such file in the runs folder");
  if (!fs::is_regular_file(st))
    throw InputError(at, "", "data",
                     "data: '" + quoted_cell(text, 200) + "' is not a regular file (a directory, device or FIFO)");
  return target.string();
}

// An operating point's COMPONENT.PARAMETER value, checked as --set checks
// it (pointing at the run file); a file parameter (a replayed input) names
// a file inside the runs folder, as `data:` does, and is given resolved.
std::string component_value(const fs::path& runs_dir, const std::string& run_file, const Netlist& model,
                            const Registry& registry, const std::string& name, const YAML::Node& node) {
  const SourceLocation at = location_of(run_file, node);
  if (!node.IsScalar()) throw InputError(at, "", name, "operating_point: the value must be a number, a quantity or a text");
  std::string value = node.Scalar();
  const auto dot = name.find('.');
  if (const ComponentDecl* c = model.component(name.substr(0, dot)))
    if (const auto* entry = registry.find(c->type))
      if (const ParameterSpec* spec = entry->info->parameter(name.substr(dot + 1)); spec && spec->is_path)
        value = data_file(runs_dir, run_file, node);
  Netlist probe = model;
  try {
    set_value(probe, ParameterPath::parse(name), value, name + ": " + value);
    (void)elaborate(probe, registry);  // a component's value is read and checked here, not at the first run
  } catch (const InputError& ex) {
    throw InputError(at, "", name, "operating_point: " + ex.message());
  }
  return value;
}

}  // namespace

void OperatingValue::apply(Netlist& netlist) const {
  if (si) set_si_value(netlist, path, *si);
  else set_value(netlist, path, text, where.to_string());
}

std::vector<MeasuredRun> load_runs(const std::string& dir, const Netlist& model, const std::vector<Probe>& probes,
                                   const Registry& registry, RunRoles roles) {
  if (!fs::is_directory(dir)) throw InputError(SourceLocation{dir, 0, 0}, "", "", "runs directory does not exist");
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".yaml" || e.path().extension() == ".yml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<MeasuredRun> runs;
  for (const auto& f : files) {
    const std::string path = f.string();
    const YAML::Node y = load_yaml_document(path, "run file");
    auto at = [&](const YAML::Node& n) { return location_of(path, n); };
    if (!y.IsMap()) throw InputError(SourceLocation{path, 1, 1}, "", "", "a run file is a map: data, role, operating_point");
    for (auto it = y.begin(); it != y.end(); ++it) {
      const auto k = plain_text(path, it->first, "", "", "a key");
      if (k != "data" && k != "role" && k != "operating_point" && k != "description")
        throw InputError(at(it->first), "", quoted_cell(k),
                         "unknown key '" + quoted_cell(k) + "' (data, role, operating_point, description)");
    }
    MeasuredRun run;
    run.name = f.stem().string();
    if (!y["data"]) throw InputError(SourceLocation{path, 1, 1}, "", "data", "missing 'data: NAME.csv'");
    if (!y["role"] && roles == RunRoles::both_required)
      throw InputError(SourceLocation{path, 1, 1}, "", "role", "missing 'role: calibration|validation'");
    const auto role = y["role"] ? plain_text(path, y["role"], "", "role", "'role'") : std::string("calibration");
    if (role == "calibration") run.role = Role::calibration;
    else if (role == "validation") run.role = Role::validation;
    else throw InputError(at(y["role"]), "", "role", "role must be 'calibration' or 'validation', not '" + quoted_cell(role) + "'");
    if (y["operating_point"]) {
      const auto& op = y["operating_point"];
      if (!op.IsMap()) throw InputError(at(op), "", "operating_point", "operating_point maps parameter names to SI values");
      for (auto it = op.begin(); it != op.end(); ++it) {
        const auto name = plain_text(path, it->first, "", "", "a parameter's name");
        if (name.find('.') != std::string::npos) {  // COMPONENT.PARAMETER
          run.operating_point.push_back({ParameterPath::parse(name),
                                         component_value(fs::path(dir), path, model, registry, name, it->second),
                                         std::nullopt, at(it->second)});
          continue;
        }
        if (!model.parameter(name)) {
          std::string valid;
          for (const auto& p : model.parameters) valid += (valid.empty() ? "" : ", ") + p.name;
          throw InputError(at(it->first), "", quoted_cell(name),
                           "operating_point: the model has no top-level parameter '" + quoted_cell(name) +
                               "' (it has: " + valid + ")");
        }
        if (!it->second.IsScalar())
          throw InputError(at(it->second), "", name, "operating_point: the value must be a number (SI)");
        Netlist probe = model;  // checks the value now, pointing at the run file
        try {
          set_value(probe, ParameterPath::parse(name), it->second.Scalar(), name + ": " + it->second.Scalar());
        } catch (const InputError& ex) {
          throw InputError(at(it->second), "", name, "operating_point: " + ex.message());
        }
        run.operating_point.push_back(
            {ParameterPath::parse(name), it->second.Scalar(), probe.parameter(name)->si_value, at(it->second)});
      }
    }
    if (y["data"].IsMap()) {
      DataFileSpec spec = data_spec_from_yaml(path, y["data"]);
      spec.file = run.csv_file = data_file(fs::path(dir), path, y["data"]["file"]);
      read_described_into(run, spec, model, probes);
    } else {
      run.csv_file = data_file(fs::path(dir), path, y["data"]);
      read_csv_into(run, run.csv_file, model, probes);
    }
    runs.push_back(std::move(run));
  }
  int ncal = 0, nval = 0;
  for (const auto& r : runs) (r.role == Role::calibration ? ncal : nval)++;
  if (ncal == 0 || (nval == 0 && roles == RunRoles::both_required))
    throw InputError(SourceLocation{dir, 0, 0}, "", "",
                     "need at least one calibration and one validation run (found " + std::to_string(ncal) +
                         " calibration, " + std::to_string(nval) + " validation)");
  return runs;
}

}  // namespace pneumo::diagnose
