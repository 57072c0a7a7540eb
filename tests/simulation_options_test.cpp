// The solver settings are declared once (framework/model/simulation_options.cpp):
// the netlist reader, `pneumo simulate --help` and the table in docs/reference/netlist.md must say
// what the table says - every key, its unit, default and range.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "framework/model/simulation_options.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "test_support.hpp"

namespace pneumo {
namespace {

using test_support::num;

// A netlist whose `simulation:` holds one key, on line 4.
std::string netlist_with(const std::string& key, const std::string& value) {
  return "components:\n  tank: {type: volume, V: 1 L}\nsimulation:\n  " + key + ": " + value + "\n";
}

std::string text_of(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// The values just outside a spec's range (none when it is unbounded).
std::vector<double> outside(const ParameterSpec& s) {
  std::vector<double> out;
  if (std::isfinite(s.min)) out.push_back(s.min_exclusive ? s.min : s.min - 1.0);
  if (std::isfinite(s.max)) out.push_back(s.max_exclusive ? s.max : s.max + 1.0);
  return out;
}

TEST(SimulationOptions, ReaderTakesEveryKeyInItsUnitIntoSettingsAndSolverOptions) {
  const SimulationSettings defaults;
  for (const auto& o : simulation_options()) {
    SCOPED_TRACE(o.spec.name);
    if (o.flag) {
      EXPECT_EQ(*o.spec.default_text, defaults.*(o.flag) ? "true" : "false");
      const std::string other = defaults.*(o.flag) ? "false" : "true";
      const Netlist nl = parse_netlist(netlist_with(o.spec.name, other), "inline.yaml");
      EXPECT_EQ(nl.simulation.*(o.flag), other == "true");
      EXPECT_EQ(solver_options(nl.simulation).*(o.flag), other == "true");
      continue;
    }
    ASSERT_TRUE(o.number);
    EXPECT_EQ(*o.spec.default_value, defaults.*(o.number));
    EXPECT_TRUE(o.spec.in_range(*o.spec.default_value));
    // A value other than the default, inside the range; seconds written in ms.
    const double v = defaults.*(o.number) != 0.0 ? 0.5 * defaults.*(o.number) : 0.5;
    ASSERT_TRUE(o.spec.in_range(v));
    const std::string text = o.spec.unit == "s" ? num(v * 1e3) + " ms" : num(v);
    const Netlist nl = parse_netlist(netlist_with(o.spec.name, text), "inline.yaml");
    EXPECT_NEAR(nl.simulation.*(o.number), v, 1e-15 * v);
    EXPECT_EQ(solver_options(nl.simulation).*(o.number), nl.simulation.*(o.number));
  }
}

TEST(SimulationOptions, ReaderRejectsValuesOutsideTheRangeAtTheirLine) {
  int bounded = 0;
  for (const auto& o : simulation_options()) {
    std::vector<std::string> bad;
    if (o.flag) bad.push_back("maybe");
    for (double v : outside(o.spec)) bad.push_back(num(v) + (o.spec.unit == "1" ? "" : " " + o.spec.unit));
    bounded += !outside(o.spec).empty();
    for (const auto& value : bad) {
      SCOPED_TRACE(o.spec.name + ": " + value);
      try {
        (void)parse_netlist(netlist_with(o.spec.name, value), "inline.yaml");
        ADD_FAILURE() << "accepted";
      } catch (const InputError& e) {
        EXPECT_EQ(e.where().file, "inline.yaml");
        EXPECT_EQ(e.where().line, 4);
        EXPECT_EQ(e.parameter(), "simulation." + o.spec.name);
        if (o.number) {
          EXPECT_NE(e.message().find(o.spec.range_text()), std::string::npos) << e.message();
        }
      }
    }
  }
  EXPECT_GE(bounded, 4);  // rtol, atol, output_interval, max_step
}

TEST(SimulationOptions, UnknownKeyIsAnErrorListingEveryKey) {
  try {
    (void)parse_netlist(netlist_with("dt", "1 ms"), "inline.yaml");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 4);
    for (const auto& o : simulation_options()) EXPECT_NE(e.message().find(o.spec.name), std::string::npos);
  }
}

TEST(SimulationOptions, CliHelpListsEveryKeyWithUnitDefaultAndRange) {
  const auto [status, out] = test_support::run_cli("simulate --help");
  ASSERT_EQ(status, 0) << out;
  for (const auto& o : simulation_options()) {
    SCOPED_TRACE(o.spec.name);
    const auto at = out.find("\n  " + o.spec.name + " [");
    ASSERT_NE(at, std::string::npos) << out;
    const std::string line = out.substr(at + 1, out.find('\n', at + 1) - at - 1);
    if (o.number) {
      EXPECT_NE(line.find("[" + o.spec.unit + "]"), std::string::npos) << line;
      EXPECT_NE(line.find("default " + text_of(*o.spec.default_value)), std::string::npos) << line;
      EXPECT_NE(line.find(o.spec.range_text()), std::string::npos) << line;
    } else {
      EXPECT_NE(line.find("default " + *o.spec.default_text), std::string::npos) << line;
    }
  }
}

TEST(SimulationOptions, CliRejectsABadValueWithFileLineAndStatus2) {
  test_support::TempDir dir;
  const std::string path = dir.write("bad.yaml", netlist_with("rtol", "2"));
  const auto [status, out] = test_support::run_cli("simulate " + path + " -o " + dir.path().string() + "/x.csv");
  EXPECT_EQ(status, 2) << out;
  EXPECT_NE(out.find("bad.yaml:4"), std::string::npos) << out;
  EXPECT_NE(out.find("simulation.rtol"), std::string::npos) << out;
}

// docs/reference/netlist.md's table of `simulation:` keys: | `key` | unit | default | valid | meaning |
TEST(SimulationOptions, ReferenceTableAgreesWithTheDeclaration) {
  const std::string readme = test_support::read_file(std::string(PNEUMO_SOURCE_DIR) + "/docs/reference/netlist.md");
  for (const auto& o : simulation_options()) {
    SCOPED_TRACE(o.spec.name);
    const std::string head = "| `" + o.spec.name + "` |";
    const auto at = readme.find(head);
    ASSERT_NE(at, std::string::npos);
    EXPECT_EQ(readme.find(head, at + 1), std::string::npos) << "listed twice";
    std::vector<std::string> cells;
    std::istringstream row(readme.substr(at, readme.find('\n', at) - at));
    for (std::string cell; std::getline(row, cell, '|');) {
      const auto b = cell.find_first_not_of(' '), e = cell.find_last_not_of(' ');
      cells.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
    }
    ASSERT_GE(cells.size(), 6u);  // "" before the first '|', key, unit, default, valid, meaning
    if (o.number) {
      EXPECT_EQ(cells[2], o.spec.unit);
      EXPECT_EQ(cells[3], text_of(*o.spec.default_value));
      EXPECT_EQ(cells[4], o.spec.range_text());
    } else {
      EXPECT_EQ(cells[2], "true/false");
      EXPECT_EQ(cells[3], *o.spec.default_text);
    }
  }
}

// `--set simulation.KEY=VALUE` goes through the same table: every key takes
// a value in its unit, and the reader's ranges hold there too.
TEST(SimulationOptions, SetOverridesEveryKeyWithinItsRange) {
  const SourceLocation where{"cli.yaml", 1, 1};
  for (const auto& o : simulation_options()) {
    SCOPED_TRACE(o.spec.name);
    SimulationSettings s;
    if (o.flag) {
      ASSERT_TRUE(apply_simulation_override(s, "simulation." + o.spec.name + "=false", where));
      EXPECT_FALSE(s.*(o.flag));
      EXPECT_THROW(apply_simulation_override(s, "simulation." + o.spec.name + "=maybe", where), InputError);
      continue;
    }
    const double v = SimulationSettings{}.*(o.number) != 0.0 ? 0.5 * SimulationSettings{}.*(o.number) : 0.5;
    const std::string text = o.spec.unit == "s" ? num(v * 1e3) + " ms" : num(v);
    ASSERT_TRUE(apply_simulation_override(s, "simulation." + o.spec.name + "=" + text, where));
    EXPECT_NEAR(s.*(o.number), v, 1e-15 * v);
    for (double bad : outside(o.spec)) {
      try {
        apply_simulation_override(s, "simulation." + o.spec.name + "=" + num(bad), where);
        ADD_FAILURE() << "accepted " << bad;
      } catch (const InputError& e) {
        EXPECT_EQ(e.parameter(), "simulation." + o.spec.name);
        EXPECT_NE(e.message().find(o.spec.range_text()), std::string::npos) << e.message();
      }
    }
  }
  SimulationSettings s;
  EXPECT_FALSE(apply_simulation_override(s, "p_supply=7 bar", where));  // a top-level parameter
  EXPECT_THROW(apply_simulation_override(s, "simulation.dt=1 ms", where), InputError);
  EXPECT_THROW(apply_simulation_override(s, "simulation.t_end=5 kg", where), InputError);
  EXPECT_THROW(apply_simulation_override(s, "simulation.t_end=-1 s", where), InputError);  // before t_start
}

// Through the CLI: the tank filling (outputs every 10 ms) stopped at 0.1 s
// writes the rows t = 0, 0.01, ..., 0.1.
TEST(SimulationOptions, CliSetShortensTheRun) {
  test_support::TempDir dir;
  const std::string csv = (dir.path() / "tank.csv").string();
  const auto [status, out] = test_support::run_cli("simulate " + std::string(PNEUMO_SOURCE_DIR) +
                                                   "/netlists/tank_filling.yaml -q -o " + csv +
                                                   " --set 'simulation.t_end=100 ms'");
  ASSERT_EQ(status, 0) << out;
  const std::string text = test_support::read_file(csv);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1 + 11) << text;  // header and 11 rows
  EXPECT_NE(text.find("\n0.1"), std::string::npos) << text;
}

}  // namespace
}  // namespace pneumo
