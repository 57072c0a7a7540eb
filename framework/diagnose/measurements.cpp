// Measured runs: DIR/NAME.yaml (data, role, operating_point) + NAME.csv.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "framework/core/text.hpp"
#include "framework/diagnose/diagnose.hpp"
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

void read_csv_into(MeasuredRun& run, const std::string& path, const Netlist& model) {
  std::ifstream in(path);
  if (!in) throw InputError(SourceLocation{path, 0, 0}, "", "", "cannot open the measured data file");
  std::string line;
  int lineno = 0;
  std::vector<std::string> header;
  while (std::getline(in, line)) {
    ++lineno;
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    header = split_trimmed(line, ',');
    break;
  }
  if (header.empty()) throw InputError(SourceLocation{path, 0, 0}, "", "", "the file is empty (expected a header t,<output>,...)");
  auto bare = [](const std::string& h) {  // "p_A [Pa]" -> "p_A"
    const auto b = h.find(" [");
    return trim(b == std::string::npos ? h : h.substr(0, b));
  };
  if (bare(header[0]) != "t")
    throw InputError(SourceLocation{path, lineno, 1}, "", bare(header[0]), "the first column must be 't' (time in s)");
  std::set<std::string> seen;
  std::string valid;
  for (const auto& o : model.outputs) valid += (valid.empty() ? "" : ", ") + o.name;
  int col = static_cast<int>(header[0].size()) + 2;
  for (std::size_t k = 1; k < header.size(); ++k) {
    const std::string name = bare(header[k]);
    bool known = false;
    for (const auto& o : model.outputs) known = known || o.name == name;
    if (!known)
      throw InputError(SourceLocation{path, lineno, col}, "", name,
                       "unknown output name '" + name + "' (the model's outputs: " + valid + ")");
    if (!seen.insert(name).second)
      throw InputError(SourceLocation{path, lineno, col}, "", name, "column '" + name + "' appears twice");
    run.signals.push_back(name);
    col += static_cast<int>(header[k].size()) + 1;
  }
  if (run.signals.empty())
    throw InputError(SourceLocation{path, lineno, 1}, "", "", "no measured signal: the header has only 't'");
  run.y.assign(run.signals.size(), {});
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
                         "column '" + cname + "': '" + cells[k] + "' is not a finite number");
    }
    if (!run.t.empty() && !(v[0] > run.t.back()))
      throw InputError(SourceLocation{path, lineno, 1}, "", "t",
                       "time must increase strictly: t = " + cells[0] + " s follows t = " +
                           std::to_string(run.t.back()) + " s");
    run.t.push_back(v[0]);
    for (std::size_t k = 1; k < v.size(); ++k) run.y[k - 1].push_back(v[k]);
  }
  if (run.t.size() < 10)
    throw InputError(SourceLocation{path, lineno, 1}, "", "", "fewer than 10 samples: nothing to diagnose");
  for (const auto& y : run.y) run.sigma.push_back(estimate_noise(y));
}

}  // namespace

std::vector<MeasuredRun> load_runs(const std::string& dir, const Netlist& model) {
  if (!fs::is_directory(dir)) throw InputError(SourceLocation{dir, 0, 0}, "", "", "runs directory does not exist");
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".yaml" || e.path().extension() == ".yml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<MeasuredRun> runs;
  for (const auto& f : files) {
    const std::string path = f.string();
    YAML::Node y;
    try {
      y = YAML::LoadFile(path);
    } catch (const YAML::ParserException& ex) {
      throw InputError(SourceLocation{path, ex.mark.line + 1, ex.mark.column + 1}, "", "", ex.msg);
    }
    auto at = [&](const YAML::Node& n) { return location_of(path, n); };
    if (!y.IsMap()) throw InputError(SourceLocation{path, 1, 1}, "", "", "a run file is a map: data, role, operating_point");
    for (auto it = y.begin(); it != y.end(); ++it) {
      const auto k = plain_text(path, it->first, "", "", "a key");
      if (k != "data" && k != "role" && k != "operating_point" && k != "description")
        throw InputError(at(it->first), "", k, "unknown key '" + k + "' (data, role, operating_point, description)");
    }
    MeasuredRun run;
    run.name = f.stem().string();
    if (!y["data"]) throw InputError(SourceLocation{path, 1, 1}, "", "data", "missing 'data: NAME.csv'");
    if (!y["role"]) throw InputError(SourceLocation{path, 1, 1}, "", "role", "missing 'role: calibration|validation'");
    const auto role = plain_text(path, y["role"], "", "role", "'role'");
    if (role == "calibration") run.role = Role::calibration;
    else if (role == "validation") run.role = Role::validation;
    else throw InputError(at(y["role"]), "", "role", "role must be 'calibration' or 'validation', not '" + role + "'");
    if (y["operating_point"]) {
      const auto& op = y["operating_point"];
      if (!op.IsMap()) throw InputError(at(op), "", "operating_point", "operating_point maps parameter names to SI values");
      for (auto it = op.begin(); it != op.end(); ++it) {
        const auto name = plain_text(path, it->first, "", "", "a parameter's name");
        if (!model.parameter(name)) {
          std::string valid;
          for (const auto& p : model.parameters) valid += (valid.empty() ? "" : ", ") + p.name;
          throw InputError(at(it->first), "", name,
                           "operating_point: the model has no top-level parameter '" + name + "' (it has: " + valid + ")");
        }
        if (!it->second.IsScalar())
          throw InputError(at(it->second), "", name, "operating_point: the value must be a number (SI)");
        run.operating_point.emplace_back(name, it->second.Scalar());
        Netlist probe = model;  // checks the value now, pointing at the run file
        try {
          apply_override(probe, name + "=" + it->second.Scalar());
        } catch (const InputError& ex) {
          throw InputError(at(it->second), "", name, "operating_point: " + ex.message());
        }
      }
    }
    run.csv_file = (f.parent_path() / plain_text(path, y["data"], "", "data", "'data'")).string();
    read_csv_into(run, run.csv_file, model);
    runs.push_back(std::move(run));
  }
  int ncal = 0, nval = 0;
  for (const auto& r : runs) (r.role == Role::calibration ? ncal : nval)++;
  if (ncal == 0 || nval == 0)
    throw InputError(SourceLocation{dir, 0, 0}, "", "",
                     "need at least one calibration and one validation run (found " + std::to_string(ncal) +
                         " calibration, " + std::to_string(nval) + " validation)");
  return runs;
}

}  // namespace pneumo::diagnose
