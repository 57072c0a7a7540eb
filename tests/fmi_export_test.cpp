// The FMU export as an importer sees it: `pneumo export-fmu` writes an
// archive whose modelDescription.xml is well-formed (xmllint) and
// consistent (value references, ModelStructure, units); its shared library
// is dlopened and driven through the FMI 2.0 functions alone, and the
// cylinder's position over the run agrees with `pneumo simulate` of the
// same circuit (the input's changes given to the simulation as a signal
// source) - within 0.1 mm at 1 ms communication steps, 0.5 mm at 10 ms.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "framework/fmi/fmi2.hpp"
#include "framework/run/model.hpp"
#include "framework/run/run.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

const fs::path kSource = PNEUMO_SOURCE_DIR;

int shell(const std::string& command) { return std::system(command.c_str()); }

struct XmlVariable {
  int vr = -1;
  std::string causality, unit, display_unit;
};

// The ScalarVariables of modelDescription.xml by name, in order.
std::vector<std::pair<std::string, XmlVariable>> variables_of(const std::string& xml) {
  std::vector<std::pair<std::string, XmlVariable>> out;
  const std::regex var(R"re(<ScalarVariable name="([^"]*)" valueReference="(\d+)" causality="(\w+)"[^>]*><Real([^>]*?)/>)re");
  const std::regex unit(R"re( unit="([^"]*)")re"), display(R"re( displayUnit="([^"]*)")re");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), var); it != std::sregex_iterator(); ++it) {
    XmlVariable v{std::stoi((*it)[2]), (*it)[3], "", ""};
    const std::string real = (*it)[4];
    std::smatch m;
    if (std::regex_search(real, m, unit)) v.unit = m[1];
    if (std::regex_search(real, m, display)) v.display_unit = m[1];
    out.emplace_back((*it)[1], v);
  }
  return out;
}

std::vector<int> unknowns_in(const std::string& xml, const std::string& element) {
  std::vector<int> out;
  const auto a = xml.find("<" + element + ">"), b = xml.find("</" + element + ">");
  if (a == std::string::npos || b == std::string::npos) return out;
  const std::string part = xml.substr(a, b - a);
  const std::regex unknown(R"re(<Unknown index="(\d+)"/>)re");
  for (auto it = std::sregex_iterator(part.begin(), part.end(), unknown); it != std::sregex_iterator(); ++it)
    out.push_back(std::stoi((*it)[1]));
  return out;
}

// An FMU exported and unpacked; its library opened like an importer does.
class Fmu {
 public:
  Fmu(const TempDir& dir, const fs::path& netlist, const std::string& id) : root_(dir.path() / id) {
    const std::string fmu = (dir.path() / (id + ".fmu")).string();
    const auto [status, out] = run_cli("export-fmu '" + netlist.string() + "' -o '" + fmu + "'");
    EXPECT_EQ(status, 0) << out;
    EXPECT_EQ(shell("unzip -q -o '" + fmu + "' -d '" + root_.string() + "'"), 0);
    xml_ = read_file(root_ / "modelDescription.xml");
    lib_ = dlopen((root_ / "binaries" / "linux64" / (id + ".so")).c_str(), RTLD_NOW | RTLD_LOCAL);
    EXPECT_NE(lib_, nullptr) << dlerror();
    for (const auto& [name, v] : variables_of(xml_)) vr_[name] = v.vr;
    guid_ = std::regex_replace(xml_.substr(xml_.find("guid=\"") + 6, 38), std::regex("\".*"), "");
  }
  ~Fmu() {
    if (lib_) dlclose(lib_);
  }
  template <class F>
  F* fn(const char* name) const {
    auto* f = reinterpret_cast<F*>(dlsym(lib_, name));
    EXPECT_NE(f, nullptr) << name;
    return f;
  }
  unsigned vr(const std::string& name) const { return vr_.at(name); }
  const std::string& xml() const { return xml_; }
  const std::string& guid() const { return guid_; }
  const fs::path& root() const { return root_; }

 private:
  fs::path root_;
  std::string xml_, guid_;
  void* lib_ = nullptr;
  std::map<std::string, int> vr_;
};

std::string g_last_log;
void logger(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String message, ...) {
  char buf[2048];
  va_list args;
  va_start(args, message);
  std::vsnprintf(buf, sizeof buf, message, args);
  va_end(args);
  g_last_log = buf;
}
const fmi2CallbackFunctions kCallbacks{logger, nullptr, nullptr, nullptr, nullptr};

// One instance driven by the FMI functions.
struct Instance {
  const Fmu& fmu;
  fmi2Component c = nullptr;
  Instance(const Fmu& f, const std::string& name) : fmu(f) {
    const std::string uri = "file://" + (f.root() / "resources").string();
    c = f.fn<decltype(fmi2Instantiate)>("fmi2Instantiate")(name.c_str(), fmi2CoSimulation, f.guid().c_str(),
                                                             uri.c_str(), &kCallbacks, fmi2False, fmi2False);
    EXPECT_NE(c, nullptr) << g_last_log;
  }
  ~Instance() { fmu.fn<decltype(fmi2FreeInstance)>("fmi2FreeInstance")(c); }
  fmi2Status set(const std::string& name, double v) const {
    const fmi2ValueReference vr = fmu.vr(name);
    return fmu.fn<decltype(fmi2SetReal)>("fmi2SetReal")(c, &vr, 1, &v);
  }
  double get(const std::string& name) const {
    const fmi2ValueReference vr = fmu.vr(name);
    double v = NAN;
    EXPECT_EQ(fmu.fn<decltype(fmi2GetReal)>("fmi2GetReal")(c, &vr, 1, &v), fmi2OK) << g_last_log;
    return v;
  }
  void initialise(double t_end) const {
    ASSERT_EQ(fmu.fn<decltype(fmi2SetupExperiment)>("fmi2SetupExperiment")(c, fmi2False, 0, 0, fmi2True, t_end), fmi2OK);
    ASSERT_EQ(fmu.fn<decltype(fmi2EnterInitializationMode)>("fmi2EnterInitializationMode")(c), fmi2OK);
    ASSERT_EQ(fmu.fn<decltype(fmi2ExitInitializationMode)>("fmi2ExitInitializationMode")(c), fmi2OK) << g_last_log;
  }
  fmi2Status step(double t, double h) const {
    return fmu.fn<decltype(fmi2DoStep)>("fmi2DoStep")(c, t, h, fmi2True);
  }
};

// The largest |x_fmu - x_simulate| (m) over the communication points.
struct Track {
  double worst = 0.0, at = 0.0;
  void add(double t, double fmu, double reference) {
    if (std::abs(fmu - reference) > worst) worst = std::abs(fmu - reference), at = t;
  }
};

// The meter-out cylinder's valve command through the input: 1 from 0.1 s,
// 0 from 2 s, set at the communication points.
Track run_meter_out(const Fmu& fmu, const ResultsTable& reference, double h) {
  Instance in(fmu, "meter_out");
  in.initialise(4.0);
  Track track;
  const int n = static_cast<int>(std::lround(4.0 / h));
  for (int k = 0; k < n; ++k) {
    const double t = k * h;
    in.set("command", t >= 0.1 - 1e-9 && t < 2.0 - 1e-9 ? 1.0 : 0.0);
    EXPECT_EQ(in.step(t, h), fmi2OK) << g_last_log;
    const double t1 = (k + 1) * h;
    track.add(t1, in.get("x"), at(reference, "x", t1));
  }
  return track;
}

std::string meter_out_reference_text() {
  std::string text = read_file(kSource / "examples/fmi/meter_out_cylinder.yaml");
  // The command's changes as a table (a microsecond's ramp: a table's
  // times increase), the rows every millisecond.
  text = replace_once(text, "command:  {type: external_input, start: 0}",
                      "command:  {type: signal_source, kind: table, table: [[0, 0], [0.1, 0], [0.100001, 1], "
                      "[2.0, 1], [2.000001, 0], [4, 0]]}");
  return replace_once(text, "output_interval: 5 ms", "output_interval: 1 ms");
}

TEST(FmiExport, ModelDescriptionIsWellFormedAndConsistent) {
  TempDir dir;
  const Fmu fmu(dir, kSource / "examples/fmi/sequence_ab.yaml", "sequence_ab");
  EXPECT_EQ(shell("xmllint --noout '" + (fmu.root() / "modelDescription.xml").string() + "'"), 0);
  const auto vars = variables_of(fmu.xml());
  ASSERT_FALSE(vars.empty());
  std::vector<int> outputs;
  for (std::size_t i = 0; i < vars.size(); ++i) {
    EXPECT_EQ(vars[i].second.vr, static_cast<int>(i)) << vars[i].first;
    if (vars[i].second.causality == "output") outputs.push_back(static_cast<int>(i) + 1);
    // Every unit and display unit is defined.
    if (!vars[i].second.unit.empty())
      EXPECT_NE(fmu.xml().find("<Unit name=\"" + vars[i].second.unit + "\">"), std::string::npos) << vars[i].first;
    if (!vars[i].second.display_unit.empty())
      EXPECT_NE(fmu.xml().find("<DisplayUnit name=\"" + vars[i].second.display_unit + "\""), std::string::npos);
  }
  EXPECT_EQ(unknowns_in(fmu.xml(), "Outputs"), outputs);
  EXPECT_EQ(unknowns_in(fmu.xml(), "InitialUnknowns"), outputs);
  // The netlist's outputs with their units, the start signal, the parameter.
  const std::map<std::string, XmlVariable> by_name(vars.begin(), vars.end());
  EXPECT_EQ(by_name.at("x_A").unit, "m");
  EXPECT_EQ(by_name.at("x_A").display_unit, "mm");
  EXPECT_EQ(by_name.at("p_cap_A").display_unit, "barg");
  EXPECT_EQ(by_name.at("start").causality, "input");
  EXPECT_EQ(by_name.at("p_supply").causality, "parameter");
  EXPECT_EQ(by_name.at("p_supply").unit, "Pa");
  EXPECT_NE(fmu.xml().find("canHandleVariableCommunicationStepSize=\"true\""), std::string::npos);
  // The FMU's library finds every library it needs from its own folder and
  // the system's.
  EXPECT_EQ(shell("env -i /usr/bin/ldd '" + (fmu.root() / "binaries/linux64/sequence_ab.so").string() +
                  "' | grep -q 'not found'"),
            256);
}

// --input and --output choose the interface; a name the netlist lacks, a
// name that is no C identifier and an -o that is the netlist are refused
// with status 2, the named file left as it was.
TEST(FmiExport, TheCommandLineChoosesTheInterfaceAndRefusesBadNames) {
  TempDir dir;
  const std::string netlist = (kSource / "examples/fmi/sequence_ab.yaml").string();
  const std::string fmu = (dir.path() / "chosen.fmu").string();
  const auto [status, out] = run_cli("export-fmu '" + netlist + "' -o '" + fmu + "' --input start --output x_A x_B");
  ASSERT_EQ(status, 0) << out;
  ASSERT_EQ(shell("unzip -q -o '" + fmu + "' -d '" + (dir.path() / "chosen").string() + "'"), 0);
  const auto vars = variables_of(read_file(dir.path() / "chosen" / "modelDescription.xml"));
  std::vector<std::string> names;
  for (const auto& [name, v] : vars) names.push_back(name + ":" + v.causality);
  EXPECT_EQ(names, (std::vector<std::string>{"x_A:output", "x_B:output", "start:input", "p_supply:parameter"}));
  const auto [s1, o1] = run_cli("export-fmu '" + netlist + "' -o '" + fmu + "' --input nosuch");
  EXPECT_EQ(s1, 2);
  EXPECT_NE(o1.find("no input 'nosuch'"), std::string::npos) << o1;
  EXPECT_NE(o1.find("start"), std::string::npos) << o1;  // the choices
  const auto [s2, o2] = run_cli("export-fmu '" + netlist + "' -o '" + (dir.path() / "1st.fmu").string() + "'");
  EXPECT_EQ(s2, 2) << o2;
  const auto [s3, o3] = run_cli("export-fmu '" + netlist + "' -o '" + netlist + "'");
  EXPECT_EQ(s3, 2) << o3;
  EXPECT_TRUE(fs::is_regular_file(fmu));
}

TEST(FmiExport, MeterOutCylinderFollowsSimulateAt1msAnd10ms) {
  TempDir dir;
  const Fmu fmu(dir, kSource / "examples/fmi/meter_out_cylinder.yaml", "meter_out");
  const RunResult reference = run_text(meter_out_reference_text(), "meter_out_reference.yaml");
  const Track fine = run_meter_out(fmu, reference.table, 1e-3);
  const Track coarse = run_meter_out(fmu, reference.table, 1e-2);
  std::printf("meter-out x: max |FMU - simulate| = %.3g mm (at %.3f s) at 1 ms steps, %.3g mm (at %.3f s) at 10 ms\n",
              fine.worst * 1e3, fine.at, coarse.worst * 1e3, coarse.at);
  EXPECT_LT(fine.worst, 0.1e-3);
  EXPECT_LT(coarse.worst, 0.5e-3);
  // The piston went out and came back (the input acted).
  const auto x = column(reference.table, "x");
  EXPECT_GT(*std::max_element(x.begin(), x.end()), 0.099);
}

// The start signal through the input at 0.1 s; two instances at once with
// different supply pressures, each following its own `pneumo simulate`.
TEST(FmiExport, SequenceTwoInstancesWithTheirOwnParameters) {
  TempDir dir;
  const Fmu fmu(dir, kSource / "examples/fmi/sequence_ab.yaml", "sequence_ab");
  const std::vector<double> p_supply{7e5, 5e5};
  std::vector<ResultsTable> reference;
  for (double p : p_supply) {
    const Model m = load_model((kSource / "netlists/sequence_ab.yaml").string(), builtin_registry(),
                               {"p_supply=" + std::to_string(p)});
    RunResult r = run_simulation(m.netlist, m.registry);
    ASSERT_TRUE(r.solver.ok) << r.solver.message;
    reference.push_back(std::move(r.table));
  }
  const Instance a(fmu, "a"), b(fmu, "b");
  ASSERT_EQ(a.set("p_supply", p_supply[0]), fmi2OK);
  ASSERT_EQ(b.set("p_supply", p_supply[1]), fmi2OK);
  a.initialise(1.5);
  b.initialise(1.5);
  // A parameter is fixed once initialised.
  EXPECT_EQ(a.set("p_supply", 6e5), fmi2Error);
  EXPECT_NE(g_last_log.find("p_supply"), std::string::npos) << g_last_log;
  const double h = 1e-3;
  Track track_a, track_b;
  double differ = 0.0;
  for (int k = 0; k < 1500; ++k) {
    const double t = k * h;
    const double start = t >= 0.1 - 1e-9 ? 1.0 : 0.0;
    ASSERT_EQ(a.set("start", start), fmi2OK);
    ASSERT_EQ(b.set("start", start), fmi2OK);
    ASSERT_EQ(a.step(t, h), fmi2OK) << g_last_log;
    ASSERT_EQ(b.step(t, h), fmi2OK) << g_last_log;
    const double t1 = (k + 1) * h;
    for (const char* x : {"x_A", "x_B"}) {
      track_a.add(t1, a.get(x), at(reference[0], x, t1));
      track_b.add(t1, b.get(x), at(reference[1], x, t1));
    }
    differ = std::max(differ, std::abs(a.get("x_A") - b.get("x_A")));
  }
  std::printf("sequence x_A, x_B: max |FMU - simulate| = %.3g mm (7 bar), %.3g mm (5 bar) at 1 ms steps\n",
              track_a.worst * 1e3, track_b.worst * 1e3);
  EXPECT_LT(track_a.worst, 0.1e-3);
  EXPECT_LT(track_b.worst, 0.1e-3);
  EXPECT_GT(differ, 5e-3);  // the two supplies move the pistons differently
}

// The sequence at 10 ms communication steps: the start at 0.1 s falls on a
// communication point, the switches' events inside steps.
TEST(FmiExport, SequenceAt10msSteps) {
  TempDir dir;
  const Fmu fmu(dir, kSource / "examples/fmi/sequence_ab.yaml", "sequence_ab");
  const Model m = load_model((kSource / "netlists/sequence_ab.yaml").string(), builtin_registry());
  const RunResult reference = run_simulation(m.netlist, m.registry);
  ASSERT_TRUE(reference.solver.ok) << reference.solver.message;
  const Instance in(fmu, "coarse");
  in.initialise(1.5);
  const double h = 1e-2;
  Track track;
  for (int k = 0; k < 150; ++k) {
    const double t = k * h;
    ASSERT_EQ(in.set("start", t >= 0.1 - 1e-9 ? 1.0 : 0.0), fmi2OK);
    ASSERT_EQ(in.step(t, h), fmi2OK) << g_last_log;
    for (const char* x : {"x_A", "x_B"}) track.add((k + 1) * h, in.get(x), at(reference.table, x, (k + 1) * h));
  }
  std::printf("sequence x_A, x_B: max |FMU - simulate| = %.3g mm (at %.3f s) at 10 ms steps\n", track.worst * 1e3,
              track.at);
  EXPECT_LT(track.worst, 0.5e-3);
  // The whole cycle ran: A back at its retracted end.
  EXPECT_LT(in.get("x_A"), 1e-3);
  const auto x_A = column(reference.table, "x_A");
  EXPECT_GT(*std::max_element(x_A.begin(), x_A.end()), 0.099);
}

TEST(FmiExport, ErrorsAreReportedAndResetStartsAgain) {
  TempDir dir;
  const Fmu fmu(dir, kSource / "examples/fmi/meter_out_cylinder.yaml", "meter_out");
  const Instance in(fmu, "errors");
  in.initialise(1.0);
  EXPECT_EQ(in.step(0.5, 1e-3), fmi2Error);  // not the FMU's time
  EXPECT_NE(g_last_log.find("currentCommunicationPoint"), std::string::npos) << g_last_log;
  ASSERT_EQ(in.set("command", 1.0), fmi2OK);
  for (int k = 0; k < 300; ++k) ASSERT_EQ(in.step(k * 1e-3, 1e-3), fmi2OK) << g_last_log;
  const double x_run = in.get("x");
  EXPECT_GT(x_run, 1e-3);
  EXPECT_EQ(in.set("x", 1.0), fmi2Error);  // an output
  ASSERT_EQ(fmu.fn<decltype(fmi2Reset)>("fmi2Reset")(in.c), fmi2OK);
  in.initialise(1.0);
  EXPECT_LT(in.get("x"), 1e-6);  // back at the start, retracted
  ASSERT_EQ(in.set("command", 1.0), fmi2OK);
  // The same run in 3 communication steps of different size.
  ASSERT_EQ(in.step(0.0, 0.05), fmi2OK) << g_last_log;
  ASSERT_EQ(in.step(0.05, 0.2), fmi2OK) << g_last_log;
  ASSERT_EQ(in.step(0.25, 0.05), fmi2OK) << g_last_log;
  EXPECT_NEAR(in.get("x"), x_run, 0.1e-3);
  fmi2FMUstate state = nullptr;
  EXPECT_EQ(fmu.fn<decltype(fmi2GetFMUstate)>("fmi2GetFMUstate")(in.c, &state), fmi2Error);
  EXPECT_EQ(fmu.fn<decltype(fmi2Terminate)>("fmi2Terminate")(in.c), fmi2OK);
  // A wrong GUID is refused at instantiation.
  const std::string uri = "file://" + (fmu.root() / "resources").string();
  EXPECT_EQ(fmu.fn<decltype(fmi2Instantiate)>("fmi2Instantiate")("bad", fmi2CoSimulation, "{0}", uri.c_str(),
                                                                   &kCallbacks, fmi2False, fmi2False),
            nullptr);
  EXPECT_NE(g_last_log.find("GUID"), std::string::npos) << g_last_log;
}

}  // namespace
}  // namespace pneumo
