// Malformed netlists must be rejected with a message that names file:line,
// the component and the parameter, and the CLI must exit with status 2 -
// never crash. Each case is a small file in tests/data/bad_netlists/ whose
// first comment says what is wrong and on which line; the expected line
// numbers below are those of the mistake in that file.
//
// Also: a failed simulation leaves no results file at the -o path, only
// NAME.partial.csv marked "# INCOMPLETE", and removes a stale results file.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/assembly/system.hpp"
#include "framework/core/error.hpp"
#include "framework/io/results.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using test_support::read_file;
using test_support::TempDir;

const std::string kBadDir = std::string(PNEUMO_SOURCE_DIR) + "/tests/data/bad_netlists/";

struct BadCase {
  std::string file;                   // in tests/data/bad_netlists/
  std::vector<std::string> sets;      // --set NAME=VALUE
  int line;                           // of the mistake
  std::string component;              // expected InputError::component()
  std::string parameter;              // expected InputError::parameter()
  std::vector<std::string> contains;  // further words the message must hold
};

std::ostream& operator<<(std::ostream& os, const BadCase& c) {
  os << c.file;
  for (const auto& s : c.sets) os << " --set " << s;
  return os;
}

const std::vector<BadCase>& bad_cases() {
  static const std::vector<BadCase> cases = {
      {"unknown_type.yaml", {}, 5, "tank", "type", {"unknown component type 'volumen'", "did you mean 'volume'"}},
      {"unknown_parameter.yaml", {}, 8, "tank", "Vol", {"unknown parameter", "did you mean 'V'"}},
      {"missing_parameter.yaml", {}, 6, "tank", "V", {"missing required parameter 'V'", "volume"}},
      {"missing_type.yaml", {}, 5, "tank", "type", {"no 'type'"}},
      {"bad_unit.yaml", {}, 6, "tank", "V", {"furlong"}},
      {"wrong_dimension.yaml", {}, 7, "tank", "V", {"'2 bar'", "m3"}},
      {"not_a_number.yaml", {}, 7, "tank", "V", {"'abc' is not a number"}},
      {"malformed_number.yaml", {}, 5, "tank", "V", {"1.2.3 L"}},
      {"dangling_port.yaml", {}, 4, "valve", "", {"port 'b'", "not connected"}},
      {"duplicate_component.yaml", {}, 6, "tank", "", {"duplicate key 'tank'", "duplicate_component.yaml:5:"}},
      {"duplicate_key.yaml", {}, 9, "tank", "V", {"duplicate key 'V'", "duplicate_key.yaml:7:"}},
      {"duplicate_section.yaml", {}, 11, "", "", {"duplicate key 'outputs'"}},
      {"zero_volume.yaml", {}, 7, "tank", "V", {"out of range", "[1e-12, 100]"}},
      {"merge_key.yaml", {}, 6, "tank", "", {"merge keys (<<) are not supported"}},
      {"parameter_reference.yaml", {}, 5, "", "p_supply", {"cannot refer to another parameter"}},
      {"implausible_pressure.yaml", {}, 7, "source", "p", {"out of range", "'p_supply'", "[1, 1e+08]"}},
      {"implausible_pressure.yaml", {"p_supply=1e-320 Pa"}, 7, "source", "p", {"out of range", "1e-320 Pa"}},
      // A bare number is SI, refused where that cannot be meant: 6 Pa for a supply.
      {"implausible_pressure.yaml", {"p_supply=6"}, 5, "", "p_supply", {"--set p_supply=6", "6 Pa", "p_supply=6 bar"}},
      {"table_negative_conductance.yaml", {}, 38, "cylinder", "cushion_C_of_z", {"row 3, column 2", "[0, 0.001]"}},
      {"negative_volume.yaml", {}, 9, "tank", "V", {"out of range", "'V_tank'", "negative_volume.yaml:4:"}},
      {"yaml_syntax.yaml", {}, 5, "", "", {"YAML syntax error", "never closed"}},
      {"unknown_port.yaml", {}, 8, "valve", "", {"no port 'c'", "valid: a, b, opening"}},
      {"unknown_component_in_connection.yaml", {}, 9, "tnak", "", {"no component named 'tnak'", "did you mean 'tank'"}},
      {"pneumatic_to_thermal.yaml", {}, 10, "tank", "", {"valve.b (pneumatic)", "tank.heat (thermal)"}},
      {"unknown_output.yaml", {}, 11, "tank", "", {"output 'p'", "no variable 'pressure'"}},
      {"unknown_section.yaml", {}, 11, "", "", {"unknown section 'simulaton'", "did you mean 'simulation'"}},
      {"empty.yaml", {}, 1, "", "", {"empty"}},
      {"bad_simulation.yaml", {}, 13, "", "simulation.t_end", {"must be > t_start"}},
      {"component_rejects_parameters.yaml", {}, 6, "valve", "laminar_ratio", {"larger than b"}},
      // --set: errors point at the declaration (or at 'parameters:' on line 3).
      {"set_target.yaml", {"V_tnk=2"}, 3, "", "V_tnk", {"--set V_tnk=2", "did you mean 'V_tank'"}},
      {"set_target.yaml", {"V_tank=2 bar"}, 5, "", "V_tank", {"--set V_tank=2 bar", "dimension"}},
      {"set_target.yaml", {"V_tank=abc"}, 5, "", "V_tank", {"--set V_tank=abc", "cannot read 'abc'"}},
      {"set_target.yaml", {"V_tank"}, 3, "", "", {"expected NAME=VALUE"}},
      // A well-formed override whose value the component rejects: reported
      // where the parameter is used (line 9), naming the declaration.
      {"set_target.yaml", {"V_tank=-1 L"}, 9, "tank", "V", {"out of range", "'V_tank'"}},
  };
  return cases;
}

// Everything the CLI does before integrating: load, override, elaborate,
// assemble. Returns the InputError, or fails the test if none is thrown.
std::optional<InputError> input_error(const std::string& path, const std::vector<std::string>& sets) {
  try {
    Netlist nl = load_netlist(path);
    for (const auto& s : sets) apply_override(nl, s);
    System system(elaborate(nl, builtin_registry()));
  } catch (const InputError& e) {
    return e;
  }
  return std::nullopt;
}

std::string first_line(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  return line;
}

std::string shell_quote(const std::string& s) {
  std::string q(1, '\'');
  for (char c : s) {
    if (c == '\'') {
      q.append("'\\''");
    } else {
      q.push_back(c);
    }
  }
  q.push_back('\'');
  return q;
}

struct CliResult {
  bool exited = false;  // false: killed by a signal (a crash)
  int status = -1;
  std::string out, err;
};

CliResult run_cli(const std::vector<std::string>& args, const fs::path& dir) {
  std::string cmd = shell_quote(PNEUMO_BINARY);
  for (const auto& a : args) cmd.append(1, ' ').append(shell_quote(a));
  const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  cmd.append(" >").append(shell_quote(out.string())).append(" 2>").append(shell_quote(err.string()));
  const int rc = std::system(cmd.c_str());
  CliResult r;
  // The shell reports a child killed by signal N as exit status 128 + N.
  r.exited = rc != -1 && WIFEXITED(rc) && WEXITSTATUS(rc) < 128;
  r.status = rc != -1 && WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  r.out = read_file(out);
  r.err = read_file(err);
  return r;
}

std::vector<std::string> simulate_args(const std::string& netlist, const std::vector<std::string>& sets,
                                       const fs::path& output) {
  std::vector<std::string> args{"simulate", netlist};
  for (const auto& s : sets) args.insert(args.end(), {"--set", s});
  args.insert(args.end(), {"-o", output.string(), "--quiet"});
  return args;
}

class BadNetlist : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadNetlist, ApiThrowsInputErrorAtTheMistake) {
  const BadCase& c = GetParam();
  const std::string path = kBadDir + c.file;
  ASSERT_TRUE(fs::exists(path)) << path;
  const auto e = input_error(path, c.sets);
  ASSERT_TRUE(e.has_value()) << c << ": no InputError";
  EXPECT_EQ(e->where().file, path) << e->what();
  EXPECT_EQ(e->where().line, c.line) << e->what();
  EXPECT_GT(e->where().column, 0) << e->what();
  EXPECT_EQ(e->component(), c.component) << e->what();
  EXPECT_EQ(e->parameter(), c.parameter) << e->what();
  const std::string what = e->what();
  EXPECT_NE(what.find(path + ":" + std::to_string(c.line) + ":"), std::string::npos) << what;
  for (const auto& word : c.contains) EXPECT_NE(what.find(word), std::string::npos) << "'" << word << "' in: " << what;
}

TEST_P(BadNetlist, CliExitsWithStatus2AndNamesFileLineComponentParameter) {
  const BadCase& c = GetParam();
  TempDir dir;
  const fs::path output = dir.path() / "out.csv";
  const std::string path = kBadDir + c.file;
  const CliResult r = run_cli(simulate_args(path, c.sets, output), dir.path());
  ASSERT_TRUE(r.exited) << c << ": the CLI crashed; stderr: " << r.err;
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find(path + ":" + std::to_string(c.line) + ":"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("error"), std::string::npos) << r.err;
  if (!c.component.empty()) {
    EXPECT_NE(r.err.find("component '" + c.component + "'"), std::string::npos) << r.err;
  }
  if (!c.parameter.empty()) {
    EXPECT_NE(r.err.find("parameter '" + c.parameter + "'"), std::string::npos) << r.err;
  }
  for (const auto& word : c.contains) EXPECT_NE(r.err.find(word), std::string::npos) << "'" << word << "' in: " << r.err;
  EXPECT_FALSE(fs::exists(output)) << "bad input must not produce a results file";
  EXPECT_FALSE(fs::exists(partial_csv_path(output.string()))) << "bad input is not a failed run";
}

std::string case_name(const ::testing::TestParamInfo<BadCase>& info) {
  std::string name = info.param.file.substr(0, info.param.file.find('.'));
  for (const auto& s : info.param.sets) name += "_set_" + s;
  for (auto& ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return name + "_" + std::to_string(info.index);
}

INSTANTIATE_TEST_SUITE_P(Files, BadNetlist, ::testing::ValuesIn(bad_cases()), case_name);

// Every file in the directory is either a case above or used below, and
// each starts with a comment saying what is wrong.
TEST(BadNetlists, EveryFileIsCoveredAndDocumented) {
  std::set<std::string> used{"solver_failure.yaml"};
  for (const auto& c : bad_cases()) used.insert(c.file);
  for (const auto& entry : fs::directory_iterator(kBadDir)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(used.count(name)) << name << " is not used by any test";
    EXPECT_EQ(first_line(entry.path()).rfind("# ", 0), 0u) << name << " must start with a comment";
  }
}

// The one valid file in the directory really is valid: the --set errors
// above come from the override, not from the netlist.
TEST(BadNetlists, SetTargetIsValidAndAcceptsAGoodOverride) {
  TempDir dir;
  const fs::path output = dir.path() / "out.csv";
  const CliResult r = run_cli(simulate_args(kBadDir + "set_target.yaml", {"V_tank=2 L", "p_supply=3 bar"}, output),
                              dir.path());
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(output));
}

TEST(BadNetlists, ZeroByteFileIsEmpty) {
  TempDir dir;
  const fs::path path = dir.path() / "zero.yaml";
  std::ofstream(path).close();
  const auto e = input_error(path.string(), {});
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->where().file, path.string());
  EXPECT_EQ(e->where().line, 1);
  EXPECT_NE(std::string(e->what()).find("empty"), std::string::npos) << e->what();

  const CliResult r = run_cli(simulate_args(path.string(), {}, dir.path() / "out.csv"), dir.path());
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(path.string() + ":1:"), std::string::npos) << r.err;
}

// A missing file has no line to point at: the message names the file.
TEST(BadNetlists, MissingFile) {
  TempDir dir;
  const std::string path = (dir.path() / "no_such_netlist.yaml").string();
  const auto e = input_error(path, {});
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->where().file, path);
  EXPECT_EQ(e->where().line, 0);
  EXPECT_NE(std::string(e->what()).find("no such file"), std::string::npos) << e->what();

  const CliResult r = run_cli(simulate_args(path, {}, dir.path() / "out.csv"), dir.path());
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(path + ": error: cannot open the netlist file"), std::string::npos) << r.err;
}

TEST(BadNetlists, DirectoryInsteadOfFile) {
  TempDir dir;
  const auto e = input_error(dir.path().string(), {});
  ASSERT_TRUE(e.has_value());
  EXPECT_NE(std::string(e->what()).find("directory"), std::string::npos) << e->what();
  const CliResult r = run_cli(simulate_args(dir.path().string(), {}, dir.path() / "out.csv"), dir.path());
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.status, 2) << r.err;
}

// YAML syntax errors the parser notices on the line of the mistake, and
// unclosed brackets or quotes, which it notices later: the error points at
// the opening bracket or quote.
TEST(BadNetlists, YamlSyntaxErrorsPointAtTheMistake) {
  struct Case {
    std::string text;
    int line;
    std::string contains;
  };
  const std::vector<Case> cases = {
      {"components:\n  tank: {type: volume, V: 1 L}\n bad: 1\n", 3, "YAML syntax error"},
      {"components:\n  tank: {type: volume, V: 1 L}}\n", 2, "YAML syntax error"},
      {"components:\n  tank:\n    type: volume\n    V: [1 L\n    p0: 1 bar\noutputs:\n  p: tank.p\n", 4,
       "list '[' opened here is never closed"},
      {"# it's a comment {\ncomponents: {x: 'a''bc}\noutputs: {}\n", 2, "quoted value"},
      {"title: see [1\ncomponents: {x: [1, {a: 2}, 3}\n", 2, "list '['"},
      {"components:\n\ttank: {type: volume}\n", 2, "tab"},
  };
  for (const auto& c : cases) {
    try {
      parse_netlist(c.text, "inline.yaml");
      ADD_FAILURE() << "no error for:\n" << c.text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().line, c.line) << e.what() << "\nfor:\n" << c.text;
      EXPECT_NE(std::string(e.what()).find(c.contains), std::string::npos) << e.what();
    }
  }
}

// Odd shapes that must be rejected cleanly rather than crash.
TEST(BadNetlists, OddShapesAreInputErrors) {
  const std::vector<std::pair<std::string, int>> cases = {
      {"just a string\n", 1},
      {"- a\n- b\n", 1},
      {"components: [a, b]\n", 1},
      {"components:\n  tank:\n", 2},
      {"components:\n  tank: 5\n", 2},
      {"components:\n  tank: {type: [volume]}\n", 2},
      {"components:\n  tank: {type: volume, V: [1, 2]}\n", 2},
      {"components:\n  9tank: {type: volume, V: 1 L}\n", 2},
      {"components:\n  tank: {type: volume, V: 1 L}\nconnections: [tank.port]\n", 3},
      {"components:\n  tank: {type: volume, V: 1 L}\nconnections:\n  - [tank]\n", 4},
      {"components:\n  tank: {type: volume, V: 1 L}\noutputs: {p: tankp}\n", 3},
      {"components:\n  tank: {type: volume, V: 1 L}\nsimulation: {t_end: 1 bar}\n", 3},
      {"components:\n  tank: {type: volume, V: 1 L}\nsimulation: {dt: 1 s}\n", 3},
      {"components:\n  tank: {type: volume, V: 1 L}\nsimulation:\n  rtol: 2\n", 4},
      {"components:\n  tank: {type: volume, V: 1 L}\nsimulation:\n  jacobian_reuse: maybe\n", 4},
      {"components:\n  tank: {type: volume, V: 1 L}\ngas:\n  kappa: 0.9\n", 4},
      {"components:\n  tank: {type: volume, V: 1 L}\nambient:\n  T: -300 degC\n", 4},
      {"parameters: {p: 5 blorp}\ncomponents:\n  tank: {type: volume, V: 1 L}\n", 1},
      {"title: no components\n", 1},
  };
  for (const auto& [text, line] : cases) {
    try {
      const Netlist nl = parse_netlist(text, "inline.yaml");
      System system(elaborate(nl, builtin_registry()));
      ADD_FAILURE() << "no error for:\n" << text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().file, "inline.yaml");
      EXPECT_EQ(e.where().line, line) << e.what() << "\nfor:\n" << text;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not an InputError: " << e.what() << "\nfor:\n" << text;
    }
  }
}

// ---- failed runs and results files --------------------------------------

const std::string kSolverFailure = kBadDir + "solver_failure.yaml";

TEST(FailedRun, ApiReportsFailureWithRowsSoFar) {
  const RunResult run = run_simulation(load_netlist(kSolverFailure), builtin_registry());
  EXPECT_FALSE(run.solver.ok);
  EXPECT_FALSE(run.solver.message.empty());
  EXPECT_LT(run.solver.t_reached, 1.0);
  ASSERT_GE(run.table.rows.size(), 1u);
  EXPECT_EQ(run.table.rows.front().front(), 0.0);
}

TEST(FailedRun, CliLeavesAnIncompletePartialFileAndTheNamedFileAsItWas) {
  TempDir dir;
  const fs::path output = dir.path() / "out.csv";
  const fs::path partial = dir.path() / "out.partial.csv";
  std::ofstream(output) << "t [s],T [K]\n0,1\n";  // stale results of an earlier run
  const CliResult r = run_cli(simulate_args(kSolverFailure, {}, output), dir.path());
  ASSERT_TRUE(r.exited) << r.err;
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_EQ(first_line(output), "t [s],T [K]") << "a failed run must not delete or change the file -o names";
  ASSERT_TRUE(fs::exists(partial));
  EXPECT_EQ(first_line(partial).rfind("# INCOMPLETE", 0), 0u) << first_line(partial);
  EXPECT_NE(r.err.find("failed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(partial.string()), std::string::npos) << r.err;
  for (const auto& entry : fs::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().rfind(".out", 0), std::string::npos) << "no temporary left: " << entry.path();
  // The partial file is still readable data (the comment line is skipped).
  const ResultsTable t = read_csv(partial.string());
  ASSERT_EQ(t.names.size(), 2u);
  EXPECT_EQ(t.names[1], "T");
  ASSERT_GE(t.rows.size(), 1u);
  EXPECT_DOUBLE_EQ(t.rows[0][1], 350.0);
}

ResultsTable small_table() {
  ResultsTable t;
  t.names = {"t", "p"};
  t.units = {"s", "Pa"};
  t.add_row({0.0, 1e5});
  t.add_row({0.5, 1.5e5});
  return t;
}

TEST(ResultsFiles, PartialLeavesTheTargetAsItWasAndIsMarkedIncomplete) {
  TempDir dir;
  const fs::path output = dir.path() / "run.csv";
  std::ofstream(output) << "earlier\n";
  const std::string partial = write_partial_csv(output.string(), small_table(), "solver gave up\nat t = 0.5 s");
  EXPECT_EQ(partial, (dir.path() / "run.partial.csv").string());
  EXPECT_EQ(partial, partial_csv_path(output.string()));
  EXPECT_EQ(first_line(output), "earlier") << "a failed run must not delete or change the file -o names";
  const std::string first = first_line(partial);
  EXPECT_EQ(first.rfind("# INCOMPLETE", 0), 0u) << first;
  EXPECT_NE(first.find("solver gave up at t = 0.5 s"), std::string::npos) << "the reason is one line: " << first;
  const ResultsTable t = read_csv(partial);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[1][1], 1.5e5);
  EXPECT_EQ(t.units[1], "Pa");
}

TEST(ResultsFiles, PartialPathWithoutExtension) {
  EXPECT_EQ(partial_csv_path("dir/results"), "dir/results.partial.csv");
  EXPECT_EQ(partial_csv_path("dir/results.csv"), "dir/results.partial.csv");
}

TEST(ResultsFiles, AtomicWriteReplacesAndRemovesStalePartial) {
  TempDir dir;
  const fs::path output = dir.path() / "run.csv";
  std::ofstream(output) << "old\n";
  std::ofstream(dir.path() / "run.partial.csv") << "# INCOMPLETE: old failure\n";
  write_csv_atomic(output.string(), small_table());
  EXPECT_EQ(first_line(output), "t [s],p [Pa]");
  EXPECT_FALSE(fs::exists(dir.path() / "run.partial.csv")) << "a success must not leave an older failure's data";
  EXPECT_FALSE(fs::exists(dir.path() / "run.csv.writing"));
  EXPECT_EQ(read_csv(output.string()).rows.size(), 2u);
}

TEST(ResultsFiles, AtomicWriteBelowAFileThrowsAndWritesNothing) {
  TempDir dir;
  std::ofstream(dir.path() / "plain") << "x\n";
  const fs::path output = dir.path() / "plain" / "run.csv";
  EXPECT_THROW(write_csv_atomic(output.string(), small_table()), std::runtime_error);
  EXPECT_FALSE(fs::exists(output));
  EXPECT_EQ(first_line(dir.path() / "plain"), "x");
}

TEST(ResultsFiles, CliSuccessRemovesStalePartial) {
  TempDir dir;
  const fs::path output = dir.path() / "out.csv";
  std::ofstream(dir.path() / "out.partial.csv") << "# INCOMPLETE: old failure\n";
  const CliResult r = run_cli(simulate_args(kBadDir + "set_target.yaml", {}, output), dir.path());
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(output));
  EXPECT_FALSE(fs::exists(dir.path() / "out.partial.csv"));
}

}  // namespace
}  // namespace pneumo
