// The framework's folders depend one way (docs/ARCHITECTURE.md): a file
// includes only its own folder and folders on lower floors. A folder that
// includes one on its own floor or above would let a lower room depend on
// a higher one. And the framework does not know the component library:
// only the faces (cli, testkit, the FMU's fmi) include components/.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// The floors of docs/ARCHITECTURE.md, ground first.
const std::map<std::string, int> kFloor{
    {"framework/core", 0},     {"framework/io", 1},       {"framework/model", 1},     {"framework/netlist", 2},
    {"framework/assembly", 2}, {"components", 2},         {"framework/solver", 3},    {"framework/plugin", 3},
    {"framework/fit", 3},      {"framework/draw", 3},     {"components/fit", 4},     {"framework/run", 4},      {"framework/analysis", 5},  {"framework/testkit", 5},
    {"framework/fmi", 5},
    {"framework/diagnose", 6}, {"framework/study", 6},    {"framework/cli", 7},
};

std::string folder_of(const std::string& path) { return path.substr(0, path.rfind('/')); }

// The faces: the command line, the component authors' checks and the FMU
// (an entry point from another program) choose the library; every other
// framework room works on the Component interface.
bool is_face(const std::string& folder) {
  return folder == "framework/cli" || folder == "framework/testkit" || folder == "framework/fmi";
}

TEST(Layers, EveryFrameworkIncludeGoesToItsOwnFolderOrALowerFloor) {
  const fs::path root = PNEUMO_SOURCE_DIR;
  const std::regex include(R"(^\s*#include\s+"((framework/[a-z_]+|components/fit|components)/[^"]+)\")");
  int files = 0, checked = 0;
  std::vector<fs::directory_entry> entries;
  for (const char* top : {"framework", "components"})
    for (const auto& entry : fs::recursive_directory_iterator(root / top)) entries.push_back(entry);
  for (const auto& entry : entries) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".cpp" && ext != ".hpp") continue;
    const std::string rel = fs::relative(entry.path(), root).generic_string();
    const auto from = kFloor.find(folder_of(rel));
    ASSERT_NE(from, kFloor.end()) << rel << ": a folder without a floor; add it to docs/ARCHITECTURE.md and here";
    ++files;
    std::ifstream in(entry.path());
    int line_no = 0;
    for (std::string line; std::getline(in, line);) {
      ++line_no;
      std::smatch m;
      if (!std::regex_search(line, m, include)) continue;
      const std::string to_folder = m[2];
      if (to_folder == from->first) continue;
      if (to_folder.starts_with("components") && from->first.starts_with("framework/"))
        EXPECT_TRUE(is_face(from->first)) << rel << ":" << line_no << " includes " << m[1]
                                          << ": below the faces the framework does not know the component library";
      const auto to = kFloor.find(to_folder);
      ASSERT_NE(to, kFloor.end()) << rel << ":" << line_no << " includes " << m[1];
      EXPECT_LT(to->second, from->second) << rel << ":" << line_no << " includes " << m[1] << " (floor "
                                          << to->second << ") from floor " << from->second;
      ++checked;
    }
  }
  EXPECT_GT(files, 50);
  EXPECT_GT(checked, 50);  // the cross-folder includes (73 when written)
}

}  // namespace
