// The component reference under docs/reference is what the registry says
// today: a fresh `pneumo components --reference` equals the committed pages
// (regenerate with the build target reference_docs).
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using pneumo::test_support::read_file;
using pneumo::test_support::run_cli;
using pneumo::test_support::TempDir;

std::set<std::string> files_under(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out.insert(fs::relative(e.path(), dir).generic_string());
  return out;
}

TEST(ReferenceDocs, TheCommittedComponentReferenceEqualsOneGeneratedFromTheRegistry) {
  TempDir dir;
  const auto [status, out] = run_cli("components --reference '" + dir.path().string() + "'");
  ASSERT_EQ(status, 0) << out;
  const fs::path committed = fs::path(PNEUMO_SOURCE_DIR) / "docs" / "reference";
  const auto fresh = files_under(dir.path());
  auto old = files_under(committed);
  std::erase_if(old, [](const std::string& f) { return f != "components.md" && f.rfind("symbols/", 0) != 0; });
  EXPECT_EQ(fresh, old) << "run: cmake --build build --target reference_docs";
  for (const auto& f : fresh)
    EXPECT_EQ(read_file(dir.path() / f), read_file(committed / f))
        << "docs/reference/" << f << " is stale; run: cmake --build build --target reference_docs";
  // every built-in type has its section and its symbol
  const std::string md = read_file(dir.path() / "components.md");
  for (const char* t : {"cylinder", "directional_valve_52", "one_way_flow_control", "limit_switch", "sequencer"}) {
    EXPECT_NE(md.find("\n## " + std::string(t) + "\n"), std::string::npos) << t;
    EXPECT_TRUE(fresh.count("symbols/" + std::string(t) + ".svg")) << t;
  }
}

TEST(ReferenceDocs, RefusesToReplaceAFileItDidNotWrite) {
  TempDir dir;
  const std::string mine = dir.write("components.md", "my notes\n");
  const auto [status, out] = run_cli("components --reference '" + dir.path().string() + "'");
  EXPECT_EQ(status, 2) << out;
  EXPECT_EQ(read_file(mine), "my notes\n");
  EXPECT_FALSE(fs::exists(dir.path() / "symbols"));
}

}  // namespace
