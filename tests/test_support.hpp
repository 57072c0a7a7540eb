// Helpers the test files share: reading a file, writing numbers into netlist
// text, running a netlist text, reading result columns, a temporary
// directory, running the CLI.
// Header-only and test-only; every test file is built into one executable,
// so these are inline.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "components/builtin.hpp"
#include "framework/core/units.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo::test_support {

// Small circuits several test files check from different sides.
// Three tanks at different pressures and temperatures joined by throttles
// at one node: the framework's stream mixing, with flows both ways.
inline const std::string kThreePortMixingCircuit = R"(
components:
  a:  {type: volume, V: 1 L, p0: 6 bar, T0: 350 K}
  b:  {type: volume, V: 0.5 L, p0: 2 bar, T0: 300 K}
  c:  {type: volume, V: 2 L, p0: 1 bar, T0: 260 K}
  va: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.3}
  vb: {type: iso6358_throttle, C: 0.1 dm3/(s*bar), b: 0.4}
  vc: {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.2}
connections:
  - [a.port, va.a]
  - [b.port, vb.a]
  - [c.port, vc.a]
  - [va.b, vb.b, vc.b]
)";
// A tank filled from a source and vented to the atmosphere at once, its gas
// exchanging heat with a wall that starts warmer.
inline const std::string kTankWithWallCircuit = R"(
components:
  source: {type: pressure_source, p: 6 bar, T: 300 K}
  inlet:  {type: iso6358_throttle, C: 0.3 dm3/(s*bar), b: 0.3}
  tank:   {type: volume, V: 0.5 L, p0: 2 bar, T0: 293.15 K}
  outlet: {type: iso6358_throttle, C: 0.2 dm3/(s*bar), b: 0.5}
  air:    {type: atmosphere}
  film:   {type: heat_convection, alpha: 50 W/(m2*K), A: 0.02 m2}
  wall:   {type: thermal_mass, C: 200 J/K, T0: 330 K}
connections:
  - [source.port, inlet.a]
  - [inlet.b, tank.port]
  - [tank.port, outlet.a]
  - [outlet.b, air.port]
  - [tank.heat, film.a]
  - [film.b, wall.port]
)";

// The whole file as text ("" if it cannot be read).
inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A number for netlist text, with all 17 significant digits so that the
// parsed value is the double the test computed.
inline std::string num(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}

// `s` with the first `from` replaced by `to`; a `from` that is not there
// fails the test (an edit of a shipped netlist that no longer applies).
inline std::string replace_once(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// A number a results or sweep file shows in `unit` (its header's "[barg]",
// "[mm]", "[degC]"), back in SI; gauge pressures on `ambient_pa`.
inline double to_si(double shown, const std::string& unit, double ambient_pa = 101325.0) {
  if (unit.empty()) return shown;
  return units::to_si(units::parse_unit(unit), shown, ambient_pa);
}

inline double rel_err(double actual, double expected) { return std::abs(actual - expected) / std::abs(expected); }

// The time of the first event with `tag` after t (NAN: none).
inline double first_after(const SolverResult& r, const std::string& tag, double t) {
  for (const auto& e : r.events)
    if (e.tag == tag && e.t > t) return e.t;
  return NAN;
}

// A cylinder's strokes in `run` take the time they take in `like` (within
// the fraction tol): the extension from the command at t_out to the first
// "extended" after it, the retraction from t_back to "retracted".
inline void expect_strokes_like(const SolverResult& run, const SolverResult& like, double t_out, double t_back,
                                double tol) {
  const double ext = first_after(run, "extended", t_out) - t_out, ext_like = first_after(like, "extended", t_out) - t_out;
  const double ret = first_after(run, "retracted", t_back) - t_back;
  const double ret_like = first_after(like, "retracted", t_back) - t_back;
  ASSERT_TRUE(std::isfinite(ext) && std::isfinite(ret)) << "the piston did not stroke";
  EXPECT_NEAR(ext / ext_like, 1.0, tol) << ext << " s against " << ext_like << " s";
  EXPECT_NEAR(ret / ret_like, 1.0, tol) << ret << " s against " << ret_like << " s";
}

// Runs a netlist text with the built-in components; a failed solve fails the
// test (the partial result is returned for the report).
inline RunResult run_text(const std::string& text, const std::string& name) {
  const Netlist nl = parse_netlist(text, name);
  RunResult r = run_simulation(nl, builtin_registry());
  EXPECT_TRUE(r.solver.ok) << name << ": " << r.solver.message;
  return r;
}

// The value of column c of a run's rows at time t, linear between rows.
inline double value_at(const RunResult& r, int c, double t) {
  const auto& rows = r.table.rows;
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (rows[i][0] >= t) {
      const double w = rows[i][0] > rows[i - 1][0] ? (t - rows[i - 1][0]) / (rows[i][0] - rows[i - 1][0]) : 1.0;
      return rows[i - 1][c] + w * (rows[i][c] - rows[i - 1][c]);
    }
  return rows.back()[c];
}

// Column `name` over all output rows; a missing column throws (fails the test).
inline std::vector<double> column(const ResultsTable& table, const std::string& name) {
  const int col = table.column(name);
  if (col < 0) throw std::runtime_error("no column " + name);
  std::vector<double> out;
  for (const auto& row : table.rows) out.push_back(row[col]);
  return out;
}

// The value of column `name` in the row at time t (outputs fall on a grid).
inline double at(const ResultsTable& table, const std::string& name, double t) {
  const int col = table.column(name);
  if (col < 0) throw std::runtime_error("no column " + name);
  for (const auto& row : table.rows)
    if (std::abs(row[0] - t) < 1e-9) return row[col];
  throw std::runtime_error("no row at t = " + std::to_string(t));
}

// A measured run for a diagnosis: `truth` run at the operating point
// `parameter` = `value` (SI), each signal with Gaussian noise of its sd
// drawn from `rng`, written as DIR/NAME.csv with DIR/NAME.yaml (its role
// and operating point).
struct NoisySignal {
  std::string name;
  double sd;
};
inline void write_measured_run(const std::filesystem::path& dir, const std::string& name, const std::string& role,
                               const std::string& truth, const std::string& parameter, double value,
                               const std::vector<NoisySignal>& signals, std::mt19937& rng) {
  Netlist nl = parse_netlist(truth, "truth.yaml");
  apply_override(nl, parameter + "=" + num(value));
  const RunResult res = run_simulation(nl, builtin_registry());
  ASSERT_TRUE(res.solver.ok) << res.solver.message;
  std::filesystem::create_directories(dir);
  std::ofstream csv(dir / (name + ".csv"));
  csv << "t";
  for (const auto& s : signals) csv << "," << s.name;
  csv << "\n";
  csv.precision(10);
  for (const auto& row : res.table.rows) {
    csv << row[0];
    for (const auto& s : signals) csv << "," << row[res.table.column(s.name)] + std::normal_distribution<double>(0, s.sd)(rng);
    csv << "\n";
  }
  std::ofstream(dir / (name + ".yaml")) << "data: " << name << ".csv\nrole: " << role << "\noperating_point:\n  "
                                        << parameter << ": " << num(value) << "\n";
}

// A fresh directory for the running test, removed with its contents
// afterwards; named after the test, the process and a counter.
class TempDir {
 public:
  TempDir() {
    static int counter = 0;
    std::string name = "pneumo_";
    if (const auto* info = ::testing::UnitTest::GetInstance()->current_test_info())
      name += std::string(info->test_suite_name()) + "_" + info->name() + "_";
    name += std::to_string(::getpid()) + "_" + std::to_string(counter++);
    for (auto& ch : name)
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_') ch = '_';
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // Writes `text` to the file `name` in this directory; returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name) << text;
    return (path_ / name).string();
  }

 private:
  std::filesystem::path path_;
};

#ifdef PNEUMO_BINARY
// Runs `pneumo ARGS` (stderr joined to stdout): {exit status, output};
// status -1 when the process did not exit normally.
inline std::pair<int, std::string> run_cli(const std::string& args) {
  const std::string cmd = std::string("'") + PNEUMO_BINARY + "' " + args + " 2>&1";
  FILE* f = popen(cmd.c_str(), "r");
  std::string out;
  char buf[512];
  while (f && fgets(buf, sizeof buf, f)) out += buf;
  const int st = f ? pclose(f) : -1;
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}
#endif

}  // namespace pneumo::test_support
