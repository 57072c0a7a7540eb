// Every `pneumo` command shown in README.md, docs/ and examples/ (the lines
// of their fenced blocks that start with `pneumo` or `./build/pneumo`) is
// one the command line has: each option it shows is in its subcommand's
// --help, and each concrete simulate, plot, draw and components command runs
// with exit status 0. A documented option once silently disappeared
// (`plot --steps`, lost when the command line was split into files; issue #30).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace pneumo {
namespace {

namespace fs = std::filesystem;
using test_support::read_file;
using test_support::TempDir;

const fs::path kSource = PNEUMO_SOURCE_DIR;

struct Documented {
  std::string file;
  std::vector<std::string> words;  // after "pneumo"
};

// Words as a POSIX shell splits them (quotes, backslash-newline joined),
// up to a comment.
std::vector<std::string> split_words(const std::string& line) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;
  char quote = 0;
  for (const char c : line) {
    if (quote) {
      if (c == quote) quote = 0;
      else word += c;
    } else if (c == '\'' || c == '"') {
      quote = c;
      in_word = true;
    } else if (c == ' ' || c == '\t') {
      if (in_word) words.push_back(word);
      word.clear();
      in_word = false;
    } else if (c == '#' && !in_word) {
      break;
    } else {
      word += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(word);
  return words;
}

std::vector<Documented> documented_commands() {
  std::vector<fs::path> files{kSource / "README.md"};
  for (const char* dir : {"docs", "examples"})
    for (const auto& e : fs::recursive_directory_iterator(kSource / dir))
      if (e.path().extension() == ".md") files.push_back(e.path());
  std::vector<Documented> out;
  for (const auto& f : files) {
    std::stringstream text(read_file(f));
    std::string line, pending;
    bool fenced = false;
    while (std::getline(text, line)) {
      if (line.rfind("```", 0) == 0) {
        fenced = !fenced;
        continue;
      }
      if (!fenced) continue;
      if (!pending.empty() || line.find("pneumo ") != std::string::npos) pending += line;
      if (!pending.empty() && pending.back() == '\\') {
        pending.pop_back();
        continue;
      }
      std::vector<std::string> words = split_words(pending);
      pending.clear();
      if (words.empty() || (words[0] != "pneumo" && words[0] != "./build/pneumo")) continue;
      words.erase(words.begin());
      if (!words.empty()) out.push_back({fs::relative(f, kSource).string(), words});
    }
  }
  return out;
}

std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::pair<int, std::string> run_in(const fs::path& dir, const std::vector<std::string>& words) {
  std::string cmd = "cd " + shell_quoted(dir.string()) + " && " + shell_quoted(PNEUMO_BINARY);
  for (const auto& w : words) cmd += " " + shell_quoted(w);
  cmd += " 2>&1";
  FILE* f = popen(cmd.c_str(), "r");
  std::string out;
  char buf[512];
  while (f && fgets(buf, sizeof buf, f)) out += buf;
  const int st = f ? pclose(f) : -1;
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

// "fit friction" has its own help; every other command is one word.
std::vector<std::string> subcommand_of(const std::vector<std::string>& words) {
  if (words[0] == "fit" && words.size() > 1) return {words[0], words[1]};
  return {words[0]};
}

TEST(DocumentedCommands, EveryOptionShownIsOneTheCommandHas) {
  const auto commands = documented_commands();
  ASSERT_GT(commands.size(), 30u);  // README, tutorials, how-tos, reference, examples
  std::map<std::string, std::string> help;
  for (const auto& c : commands) {
    const auto sub = subcommand_of(c.words);
    std::string key;
    for (const auto& w : sub) key += w + " ";
    if (!help.count(key)) {
      auto args = sub;
      args.push_back("--help");
      const auto [status, text] = run_in(kSource, args);
      EXPECT_EQ(status, 0) << c.file << ": 'pneumo " << key << "' is not a command\n" << text;
      help[key] = text;
    }
    static const std::regex option(R"((^|[\[|(])(--?[A-Za-z][A-Za-z0-9-]*))");
    for (const auto& w : c.words) {
      std::smatch m;
      if (!std::regex_search(w, m, option)) continue;
      const std::string name = m[2];
      // In --help a long option is "--name" and a short one "-x," or "-x ".
      const bool listed = name.rfind("--", 0) == 0
                              ? std::regex_search(help[key], std::regex("(^|[ ,!])" + name + "([ ,=\\[{]|$)"))
                              : help[key].find(name + ",") != std::string::npos ||
                                    help[key].find(" " + name + " ") != std::string::npos;
      EXPECT_TRUE(listed) << c.file << ": 'pneumo " << key << "' has no option " << name;
    }
  }
}

// A concrete command (no placeholder in capitals, no [optional] part) of
// simulate, plot, draw or components runs, from the repository's folder as
// the docs say, in the order each file shows them (a plot reads the file a
// simulate before it wrote). Outputs go to a folder of the test's own.
TEST(DocumentedCommands, TheConcreteSimulatePlotDrawAndComponentsCommandsRun) {
  TempDir dir;
  int ran = 0;
  for (auto c : documented_commands()) {
    if (c.words[0] != "simulate" && c.words[0] != "plot" && c.words[0] != "draw" && c.words[0] != "components")
      continue;
    bool concrete = true;
    for (const auto& w : c.words)
      if (std::regex_search(w, std::regex("[\\[\\]|]|^[A-Z][A-Z_]+(\\.|$)"))) concrete = false;
    if (!concrete) continue;
    // Outputs named out/... or docs/... (plot prefixes) go to the test's folder.
    for (auto& w : c.words)
      for (const char* prefix : {"out/", "docs/"})
        if (w.rfind(prefix, 0) == 0) w = (dir.path() / w).string();
    for (const auto& w : c.words)
      if (w.rfind(dir.path().string(), 0) == 0) fs::create_directories(fs::path(w).parent_path());
    const auto [status, text] = run_in(kSource, c.words);
    std::string shown;
    for (const auto& w : c.words) shown += " " + w;
    EXPECT_EQ(status, 0) << c.file << ": pneumo" << shown << "\n" << text;
    ++ran;
  }
  EXPECT_GT(ran, 15);
}

// Every relative link and image of README.md, docs/ and examples/ names a
// file or folder that exists (a newcomer following "where to go next" never
// meets a dead end); anchors (#...) are cut, web addresses skipped.
TEST(DocumentedCommands, EveryRelativeLinkOfTheDocsLeadsToAFileThatExists) {
  std::vector<fs::path> files{kSource / "README.md"};
  for (const char* dir : {"docs", "examples"})
    for (const auto& e : fs::recursive_directory_iterator(kSource / dir))
      if (e.path().extension() == ".md") files.push_back(e.path());
  const std::regex link(R"(\]\(([^)\s]+)\))");
  int checked = 0;
  for (const auto& f : files) {
    const std::string text = read_file(f);
    for (auto it = std::sregex_iterator(text.begin(), text.end(), link); it != std::sregex_iterator(); ++it) {
      std::string target = (*it)[1];
      if (target.find("://") != std::string::npos || target.rfind("mailto:", 0) == 0 || target[0] == '#') continue;
      target = target.substr(0, target.find('#'));
      EXPECT_TRUE(fs::exists(f.parent_path() / target))
          << fs::relative(f, kSource).string() << " links to " << target << ", which does not exist";
      ++checked;
    }
  }
  EXPECT_GT(checked, 30);
}

}  // namespace
}  // namespace pneumo
