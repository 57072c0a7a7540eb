// Component plugins (framework/plugin): a shared library named in a
// netlist's `plugins:` registers its types before elaboration; a plugin
// built for another pneumo, with another plugin API or other type layouts,
// one whose type clashes with a built-in or another plugin's, a missing file
// and a library without the entry point are refused with an error at the
// netlist line that names the plugin. The plugins are built in the tree
// (tests/plugins/plugins.cmake); the out-of-tree build against an installed
// pneumo is tests/plugins/example_test.cpp.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/plugin/plugin.hpp"
#include "framework/plugin/plugin_api.hpp"
#include "framework/testkit/testkit.hpp"
#include "tests/test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;

const fs::path kPlugins = PNEUMO_TEST_PLUGIN_DIR;

using test_support::TempDir;

// A tank draining through the seal of the example plugin; `plugins` are
// written one a line from line 2 on.
std::string netlist_text(const std::vector<std::string>& plugins) {
  std::string s = "plugins:\n";
  for (const auto& p : plugins) s += "  - " + p + "\n";
  s += "components:\n"
       "  tank: {type: volume, V: 0.1 L, p0: 6 bar}\n"
       "  seal: {type: seal_leakage, d: 20 mm, h: 15 um, L: 5 mm}\n"
       "  air:  {type: atmosphere}\n"
       "connections:\n"
       "  - [tank.port, seal.a]\n"
       "  - [seal.b, air.port]\n"
       "outputs: {p: tank.p}\n";
  return s;
}

fs::path write(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

// The InputError that loading the netlist's plugins throws ("" if none).
struct LoadOutcome {
  bool failed = false;
  SourceLocation where;
  std::string message;
};
LoadOutcome load(const fs::path& netlist_path) {
  LoadOutcome out;
  try {
    registry_with_plugins(builtin_registry(), load_netlist(netlist_path.string()));
  } catch (const InputError& e) {
    out.failed = true;
    out.where = e.where();
    out.message = e.what();
  }
  return out;
}

TEST(Plugin, LoadsFromAPathRelativeToTheNetlistAndItsComponentsConserveMass) {
  TempDir dir;
  fs::create_directories(dir.path() / "lib");
  fs::copy_file(kPlugins / "seal_leakage.so", dir.path() / "lib" / "seal.so");
  const fs::path net = write(dir.path() / "net.yaml", netlist_text({"lib/seal.so"}));
  // Loaded from another working directory: the path is the netlist's.
  const fs::path cwd = fs::current_path();
  fs::current_path(fs::temp_directory_path());
  const Registry registry = registry_with_plugins(builtin_registry(), load_netlist(net.string()));
  fs::current_path(cwd);
  ASSERT_NE(registry.find("seal_leakage"), nullptr);
  EXPECT_NE(registry.find("volume"), nullptr) << "the built-in types must stay";
  EXPECT_EQ(builtin_registry().find("seal_leakage"), nullptr) << "plugins must not change the built-in registry";

  // The plugin's component in a closed circuit: two insulated tanks joined
  // by the seal keep their total mass and energy (to rounding, 1e-12).
  const char* closed = R"(
components:
  a:    {type: volume, V: 0.1 L, p0: 6 bar, T0: 320 K}
  seal: {type: seal_leakage, d: 20 mm, h: 30 um, L: 4 mm}
  b:    {type: volume, V: 0.3 L, p0: 1 bar, T0: 280 K}
connections:
  - [a.port, seal.a]
  - [seal.b, b.port]
simulation: {t_end: 5 s, rtol: 1e-8, atol: 1e-8, output_interval: 0.1 s}
)";
  for (const auto& c : testkit::check_conservation(closed, registry, {testkit::mass_of({"a", "b"}),
                                                                      testkit::energy_of({"a", "b"})}))
    EXPECT_TRUE(c.passed(1e-12)) << c.report();
}

struct Refusal {
  const char* name;
  const char* plugin;    // file in the test plugin directory
  const char* expected;  // in the message
};
void PrintTo(const Refusal& r, std::ostream* os) { *os << r.plugin; }
class RefusedPlugin : public ::testing::TestWithParam<Refusal> {};

TEST_P(RefusedPlugin, IsAnErrorAtItsNetlistLineNamingThePlugin) {
  TempDir dir;
  const std::string path = (kPlugins / GetParam().plugin).string();
  const fs::path net = write(dir.path() / "net.yaml", netlist_text({path}));
  const LoadOutcome r = load(net);
  ASSERT_TRUE(r.failed) << GetParam().plugin << " was loaded";
  EXPECT_EQ(r.where.file, net.string());
  EXPECT_EQ(r.where.line, 2);
  EXPECT_EQ(r.where.column, 5);
  EXPECT_NE(r.message.find("plugin '" + path + "'"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find(GetParam().expected), std::string::npos) << r.message;
}

INSTANTIATE_TEST_SUITE_P(
    Plugin, RefusedPlugin,
    ::testing::Values(
        Refusal{"OtherPneumoVersion", "defective_1.so", "refused, it was built for pneumo 0.0.1 (" PNEUMO_PLUGIN_STDLIB},
        Refusal{"OtherPneumoVersionNamesOurs", "defective_1.so", "but this is pneumo " PNEUMO_VERSION_STRING " (" PNEUMO_PLUGIN_STDLIB},
        Refusal{"OtherPluginApi", "defective_2.so", "plugin API version 42, but this pneumo (" PNEUMO_VERSION_STRING ") loads version 1"},
        Refusal{"OtherTypeLayout", "defective_3.so", "sizeof(Dual) is"},
        Refusal{"TypeClashesWithBuiltin", "defective_4.so", "its component type 'volume' clashes with the built-in type 'volume'"},
        Refusal{"RegisterFunctionThrows", "defective_5.so", "registering its components failed: the sink's license file is missing"},
        Refusal{"NullAbiStrings", "defective_6.so", "its plugin information names no pneumo version (a null string"},
        Refusal{"RegisterThrowsNonStd", "defective_7.so", "registering its components failed: it threw something that is not a std::exception"},
        Refusal{"EntryPointThrowsNonStd", "defective_8.so", "pneumo_plugin_info() threw something that is not a std::exception"},
        Refusal{"NoEntryPoint", "not_a_plugin.so", "not a pneumo plugin: it exports no pneumo_plugin_info()"},
        Refusal{"MissingFile", "no_such_plugin.so", "no such file"}),
    [](const ::testing::TestParamInfo<Refusal>& info) { return std::string(info.param.name); });

// A FIFO named as a plugin made dlopen block forever (issue #23): now it is
// refused before it is opened.
TEST(Plugin, AFifoIsRefusedNotOpened) {
  TempDir dir;
  const fs::path fifo = dir.path() / "plugin.so";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const fs::path net = write(dir.path() / "net.yaml", netlist_text({fifo.string()}));
  const LoadOutcome r = load(net);
  ASSERT_TRUE(r.failed);
  EXPECT_EQ(r.where.line, 2);
  EXPECT_NE(r.message.find("not a regular file"), std::string::npos) << r.message;
}

TEST(Plugin, ATypeRegisteredByAnotherPluginIsAClashNamingBoth) {
  TempDir dir;
  fs::copy_file(kPlugins / "seal_leakage.so", dir.path() / "first.so");
  fs::copy_file(kPlugins / "seal_leakage.so", dir.path() / "second.so");
  const fs::path net = write(dir.path() / "net.yaml", netlist_text({"first.so", "second.so"}));
  const LoadOutcome r = load(net);
  ASSERT_TRUE(r.failed);
  EXPECT_EQ(r.where.line, 3);
  const std::string first = (dir.path() / "first.so").string(), second = (dir.path() / "second.so").string();
  EXPECT_NE(r.message.find("plugin '" + second + "': its component type 'seal_leakage' clashes with type "
                           "'seal_leakage' of plugin '" + first + "' (" + net.string() + ":2:5)"),
            std::string::npos)
      << r.message;
}

TEST(Plugin, TheSamePluginListedTwiceIsAnError) {
  TempDir dir;
  fs::copy_file(kPlugins / "seal_leakage.so", dir.path() / "seal.so");
  const fs::path net = write(dir.path() / "net.yaml", netlist_text({"seal.so", "./seal.so"}));
  const LoadOutcome r = load(net);
  ASSERT_TRUE(r.failed);
  EXPECT_EQ(r.where.line, 3);
  EXPECT_NE(r.message.find("listed twice (first at " + net.string() + ":2:5)"), std::string::npos) << r.message;
}

TEST(Plugin, AFileThatIsNoSharedLibraryCannotBeLoaded) {
  TempDir dir;
  write(dir.path() / "notes.so", "this is text\n");
  const fs::path net = write(dir.path() / "net.yaml", netlist_text({"notes.so"}));
  const LoadOutcome r = load(net);
  ASSERT_TRUE(r.failed);
  EXPECT_EQ(r.where.line, 2);
  EXPECT_NE(r.message.find("plugin '" + (dir.path() / "notes.so").string() + "': cannot load it: "),
            std::string::npos)
      << r.message;
}

TEST(Plugin, PluginsMustBeAListOfPaths) {
  try {
    parse_netlist("plugins: {seal: seal.so}\ncomponents:\n  air: {type: atmosphere}\n", "net.yaml");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 1);
    EXPECT_NE(std::string(e.what()).find("plugins must be a list"), std::string::npos) << e.what();
  }
}

TEST(Plugin, WithoutItsPluginTheTypeIsUnknown) {
  // A netlist using a plugin's type is elaborated against the registry the
  // caller passes; the built-in one does not know it.
  TempDir dir;
  const Netlist nl = parse_netlist(netlist_text({}), (dir.path() / "net.yaml").string());
  try {
    elaborate(nl, builtin_registry());
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.component(), "seal");
    EXPECT_NE(e.message().find("unknown component type 'seal_leakage'"), std::string::npos) << e.what();
  }
}

// The command line: exit status 2 (bad input), the error on stderr.
TEST(Plugin, SimulateRefusesABadPluginWithExitStatus2) {
  TempDir dir;
  const std::string bad = (kPlugins / "defective_1.so").string();
  const fs::path net = write(dir.path() / "net.yaml", netlist_text({bad}));
  const fs::path err = dir.path() / "err.txt";
  const std::string cmd = std::string("'") + PNEUMO_BINARY + "' simulate '" + net.string() + "' -o '" +
                          (dir.path() / "out.csv").string() + "' > /dev/null 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::stringstream text;
  text << std::ifstream(err).rdbuf();
  EXPECT_NE(text.str().find(net.string() + ":2:5: error: plugin '" + bad + "': refused, it was built for pneumo 0.0.1"),
            std::string::npos)
      << text.str();
  EXPECT_FALSE(fs::exists(dir.path() / "out.csv"));
}

// `pneumo components --plugin` describes the plugin's types.
TEST(Plugin, ComponentsCommandListsAPluginsTypes) {
  TempDir dir;
  const fs::path out = dir.path() / "out.txt";
  const std::string cmd = std::string("'") + PNEUMO_BINARY + "' components --plugin '" +
                          (kPlugins / "seal_leakage.so").string() + "' seal_leakage > '" + out.string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  std::stringstream text;
  text << std::ifstream(out).rdbuf();
  for (const char* s : {"seal_leakage", "h [m] required", "mu [Pa*s] default 1.81e-05"})
    EXPECT_NE(text.str().find(s), std::string::npos) << s << " not in:\n" << text.str();
}

}  // namespace
}  // namespace pneumo
