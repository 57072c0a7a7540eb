// Event tags: a component declares every tag its events carry, and a netlist
// metric that names COMPONENT.TAG is refused at load unless that component
// raises it (a misspelt tag used to give a metric of nan in a run that
// exited 0).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "components/builtin.hpp"
#include "framework/core/error.hpp"
#include "framework/diagnose/catalogue.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"
#include "test_support.hpp"

namespace pneumo {
namespace {

using test_support::read_file;
using test_support::replace_once;
using test_support::run_cli;
using test_support::TempDir;

const std::string kSequence = std::string(PNEUMO_SOURCE_DIR) + "/netlists/sequence_ab.yaml";
const std::string kCycleTime = "seq.cycle_end - seq.cycle_start";

// The line of `needle` in `text`, counted from 1.
int line_of(const std::string& text, const std::string& needle) {
  const auto at = text.find(needle);
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

TEST(EventTags, AMisspeltTagOfAnExistingComponentIsRefusedWithTheTagsItRaises) {
  const TempDir dir;
  const std::string text = replace_once(read_file(kSequence), kCycleTime, "seq.cycle_endd - seq.cycle_start");
  const std::string path = dir.write("misspelt.yaml", text);
  const auto [status, out] = run_cli("simulate '" + path + "' -o '" + (dir.path() / "out.csv").string() + "'");
  EXPECT_EQ(status, 2) << out;
  EXPECT_NE(out.find("misspelt.yaml:" + std::to_string(line_of(text, "cycle_endd"))), std::string::npos) << out;
  EXPECT_NE(out.find("raises no event 'cycle_endd'"), std::string::npos) << out;
  EXPECT_NE(out.find("cycle_start, step_K, cycle_end"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "out.csv"));
}

TEST(EventTags, AWindowBoundedByAnUnknownTagIsRefused) {
  const std::string text = replace_once(read_file(kSequence), "metrics:\n",
                                    "metrics:\n  p_peak: {max: p_rod_A, from: cyl_A.extendd}\n");
  try {
    (void)elaborate(parse_netlist(text, "window.yaml"), builtin_registry());
    ADD_FAILURE() << "a window opened by an event cyl_A never raises was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("raises no event 'extendd'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("retracted, left_retracted, extended, left_extended"), std::string::npos)
        << e.what();
  }
}

TEST(EventTags, ANumberedStepIsAcceptedAndAnUnnumberedOneIsNot) {
  const std::string base = read_file(kSequence);
  const auto with = [&](const std::string& tag) {
    return parse_netlist(replace_once(base, kCycleTime, tag + " - seq.cycle_start"), "steps.yaml");
  };
  EXPECT_NO_THROW((void)elaborate(with("seq.step_2"), builtin_registry()));
  EXPECT_THROW((void)elaborate(with("seq.step_x"), builtin_registry()), InputError);
  EXPECT_THROW((void)elaborate(with("seq.step_"), builtin_registry()), InputError);
}

// A diagnosis catalogue's phase starting at a tag the component never
// raises would never start: refused at its line, with the tags there are.
TEST(EventTags, ACataloguePhaseAtAnUndeclaredTagIsRefusedAtItsLine) {
  const Netlist model = load_netlist(std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml");
  TempDir dir;
  const auto load = [&](const std::string& from) {
    std::ofstream(dir.path() / "c.yaml") << "effects: {}\nphases:\n  - {name: rest, from: start}\n"
                                       << "  - {name: cushion, from: " << from << "}\n";
    try {
      (void)diagnose::load_catalogue((dir.path() / "c.yaml").string(), model, builtin_registry());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string e = load("cylinder.cushion_entryy");
  EXPECT_NE(e.find("c.yaml:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("raises no event 'cushion_entryy'"), std::string::npos) << e;
  EXPECT_NE(e.find("cushion_entry, cushion_exit"), std::string::npos) << e;
  EXPECT_EQ(load("cylinder.cushion_entry"), "");
}

// Every tag the shipped circuits raise is one their components declare: the
// declarations are what the check above holds a netlist to.
TEST(EventTags, EveryTagRaisedByAShippedCircuitIsDeclaredByItsComponent) {
  int tagged = 0;
  std::set<std::string> seen;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(PNEUMO_SOURCE_DIR) + "/netlists")) {
    if (entry.path().extension() != ".yaml") continue;
    const Netlist nl = load_netlist(entry.path().string());
    const Circuit circuit = elaborate(nl, builtin_registry());
    const RunResult r = run_simulation(nl, builtin_registry());
    for (const auto& e : r.solver.events) {
      if (e.tag.empty()) continue;
      const auto c = std::find_if(circuit.components.begin(), circuit.components.end(),
                                  [&](const auto& comp) { return comp->name() == e.component; });
      ASSERT_NE(c, circuit.components.end()) << e.component;
      EXPECT_TRUE((*c)->info().raises(e.tag))
          << entry.path().filename() << ": " << e.component << " (" << (*c)->info().type << ") raised '" << e.tag
          << "', which its type does not declare (" << (*c)->info().event_list() << ")";
      ++tagged;
      seen.insert((*c)->info().type + "." + e.tag);
    }
  }
  EXPECT_GT(tagged, 20);
  EXPECT_GT(seen.size(), 10u);  // cylinders, valves, the sequencer, switches
}

}  // namespace
}  // namespace pneumo
