// How values are written: a gauge unit gives only absolute pressures (a
// cracking pressure of 0.2 barg would be read as 1.21 bar), and a bare number
// is SI, refused where that is implausible for the parameter's dimension
// (`bore: 40` would be a 40 m bore, `--set p_supply=6` a 6 Pa supply).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "components/builtin.hpp"
#include "framework/core/error.hpp"
#include "framework/netlist/netlist.hpp"
#include "test_support.hpp"

namespace pneumo {
namespace {

using test_support::run_cli;
using test_support::TempDir;

// A meter-out drive: supply, flow control, cylinder; the arguments add to their entries.
std::string drive(const std::string& flow_control, const std::string& cylinder, const std::string& parameters = "") {
  return "parameters: {p_supply: 6 bar" + parameters +
         "}\n"
         "components:\n"
         "  supply: {type: pressure_source, p: p_supply}\n"
         "  speed: {type: one_way_flow_control, C: 0.1 dm3/(s*bar)" +
         flow_control +
         "}\n"
         "  cyl: {type: cylinder, stroke: 100 mm, rod: 12 mm" +
         cylinder +
         "}\n"
         "  load: {type: translational_mass, m: 2}\n"
         "connections:\n"
         "  - [supply.port, speed.a]\n"
         "  - [speed.b, cyl.cap]\n"
         "  - [cyl.flange, load.flange]\n"
         "outputs: {x: {var: cyl.x, unit: mm}}\n"
         "simulation: {t_end: 0.1 s}\n";
}

std::string refusal(const std::string& text) {
  try {
    (void)elaborate(parse_netlist(text, "drive.yaml"), builtin_registry());
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return "";
}

// The SI value of parameter `name` of component `component` as the netlist `text` writes it.
double written(const std::string& text, const std::string& component, const std::string& name) {
  const Netlist nl = parse_netlist(text, "drive.yaml");
  for (const auto& c : nl.components) {
    if (c.name != component) continue;
    const ParameterSpec* spec = builtin_registry().find(c.type)->info->parameter(name);
    for (const auto& [key, value] : c.parameters)
      if (key == name) return parameter_value(nl, c, *spec, value);
  }
  ADD_FAILURE() << component << "." << name << " not written";
  return -1;
}

TEST(WrittenUnits, AGaugeUnitOnAPressureDifferenceIsRefused) {
  const std::string e = refusal(drive(", check_cracking: 0.2 barg", ", bore: 32 mm"));
  EXPECT_NE(e.find("drive.yaml:4"), std::string::npos) << e;
  EXPECT_NE(e.find("check_cracking"), std::string::npos) << e;
  EXPECT_NE(e.find("pressure difference"), std::string::npos) << e;
  EXPECT_NE(e.find("0.2 bar"), std::string::npos) << e;
  // The same difference in bar is 0.2e5 Pa (not 1.21e5).
  EXPECT_DOUBLE_EQ(written(drive(", check_cracking: 0.2 bar", ", bore: 32 mm"), "speed", "check_cracking"), 0.2e5);
}

TEST(WrittenUnits, AGaugeTopLevelParameterOnAPressureDifferenceIsRefused) {
  const std::string e = refusal(drive(", check_cracking: dp", ", bore: 32 mm", ", dp: 0.2 barg"));
  EXPECT_NE(e.find("top-level parameter 'dp'"), std::string::npos) << e;
  EXPECT_NE(e.find("pressure difference"), std::string::npos) << e;
}

TEST(WrittenUnits, AGaugeUnitOnAnAbsolutePressureIsTheAmbientPlusIt) {
  EXPECT_DOUBLE_EQ(written(drive("", ", bore: 32 mm, p0_rod: 6 barg"), "cyl", "p0_rod"), 6e5 + 101325.0);
}

TEST(WrittenUnits, ABareBoreOfFortyIsRefusedWithTheUnitToWrite) {
  const std::string e = refusal(drive("", ", bore: 40"));
  EXPECT_NE(e.find("'bore'"), std::string::npos) << e;
  EXPECT_NE(e.find("40 m"), std::string::npos) << e;
  EXPECT_NE(e.find("'40 mm'"), std::string::npos) << e;
  // Plausible SI stays SI: a 40 mm bore written in metres.
  EXPECT_NO_THROW((void)elaborate(parse_netlist(drive("", ", bore: 0.04"), "drive.yaml"), builtin_registry()));
}

// What is plausible depends on the parameter: a 20 m hose is, a 40 m bore is not.
TEST(WrittenUnits, ABareHoseLengthIsPlausibleInMetresUpToAKilometre) {
  const auto line = [](const std::string& length) {
    return "components:\n"
           "  supply: {type: pressure_source, p: 6 bar}\n"
           "  line: {type: hose, D: 4 mm, L: " + length + "}\n"
           "  tank: {type: volume, V: 1 L}\n"
           "connections:\n"
           "  - [supply.port, line.a]\n"
           "  - [line.b, tank.port]\n";
  };
  EXPECT_NO_THROW((void)elaborate(parse_netlist(line("20"), "line.yaml"), builtin_registry()));
  EXPECT_NE(refusal(line("5000")).find("'5000 mm'"), std::string::npos);
}

TEST(WrittenUnits, BareTemperatureAndConductanceInTheirHabitualUnitsAreRefused) {
  EXPECT_NE(refusal(drive("", ", bore: 32 mm, T0: 20")).find("degC"), std::string::npos);
  EXPECT_NE(refusal(drive(", check_C: 0.4", ", bore: 32 mm")).find("dm3/(s*bar)"), std::string::npos);
  // Mass has no habit but kilograms: a bare 2 is 2 kg (the load above).
}

TEST(WrittenUnits, ABareSetOfAPressureIsRefusedOnTheCommandLine) {
  const TempDir dir;
  const std::string nl = dir.write("drive.yaml", drive("", ", bore: 32 mm"));
  const std::string out = (dir.path() / "out.csv").string();
  const auto [status, text] = run_cli("simulate '" + nl + "' --set p_supply=6 -o '" + out + "'");
  EXPECT_EQ(status, 2) << text;
  EXPECT_NE(text.find("6 Pa"), std::string::npos) << text;
  EXPECT_NE(text.find("--set 'p_supply=6 bar'"), std::string::npos) << text;
  EXPECT_FALSE(std::filesystem::exists(out));
  const auto [ok, text2] = run_cli("simulate '" + nl + "' --set p_supply=6e5 -o '" + out + "'");
  EXPECT_EQ(ok, 0) << text2;
}

}  // namespace
}  // namespace pneumo
