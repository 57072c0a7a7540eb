#include "framework/diagnose/yaml_file.hpp"

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "framework/core/error.hpp"
#include "framework/netlist/yaml_location.hpp"

namespace pneumo::diagnose {

namespace {

std::string key_text(const YAML::Node& key) {
  if (key.IsNull()) return "null";
  return key.IsScalar() ? key.Scalar() : "";
}

// Every map below `node` checked for a key written twice. A node reached
// again through an alias (same position in the file) is not walked again:
// a "billion laughs" document stays linear.
void check_unique_keys(const std::string& path, const YAML::Node& node, std::set<int>& walked) {
  if (!node.IsMap() && !node.IsSequence()) return;
  if (const auto m = node.Mark(); !m.is_null() && !walked.insert(m.pos).second) return;
  if (node.IsSequence()) {
    for (const auto& item : node) check_unique_keys(path, item, walked);
    return;
  }
  std::map<std::string, int> first_line;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string k = key_text(it->first);
    if (!k.empty() || it->first.IsScalar()) {
      const auto [seen, fresh] = first_line.emplace(k, location_of(path, it->first).line);
      if (!fresh)
        throw InputError(location_of(path, it->first), "", quoted_cell(k),
                         "key '" + quoted_cell(k) + "' appears twice in one map (first at line " +
                             std::to_string(seen->second) + "); keep one of them");
    }
    check_unique_keys(path, it->first, walked);
    check_unique_keys(path, it->second, walked);
  }
}

// The line of the second document's start: its first node's mark, else
// the second '---' line (an empty document has no node to point at).
int second_document_line(const std::string& text, const YAML::Node& second) {
  if (const auto m = second.Mark(); !m.is_null()) return m.line + 1;
  std::istringstream in(text);
  std::string line;
  int n = 0, markers = 0, last = 0;
  bool content = false;
  while (std::getline(in, line)) {
    ++n;
    if (line.rfind("---", 0) == 0) {
      if (content || markers > 0) return n;
      ++markers;
      last = n;
    } else if (!line.empty() && line[0] != '#' && line.find_first_not_of(" \t\r") != std::string::npos) {
      content = true;
    }
  }
  return last > 0 ? last : 1;
}

}  // namespace

std::string quoted_cell(const std::string& text, std::size_t max_chars) {
  std::string out;
  for (char c : text.substr(0, max_chars)) out += (static_cast<unsigned char>(c) < 0x20) ? '?' : c;
  return text.size() > max_chars ? out + "..." : out;
}

YAML::Node load_yaml_document(const std::string& path, const std::string& what) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st))
    throw InputError(SourceLocation{path, 0, 0}, "", "", "cannot open the " + what);
  if (!std::filesystem::is_regular_file(st))
    throw InputError(SourceLocation{path, 0, 0}, "", "",
                     "the " + what + " is not a regular file (a directory, device or FIFO); name a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(SourceLocation{path, 0, 0}, "", "", "cannot open the " + what);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  check_no_nul(path, text);
  FirstDocument doc;
  try {
    doc = load_first_document(text);
  } catch (const YAML::ParserException& ex) {
    throw InputError(SourceLocation{path, ex.mark.line + 1, ex.mark.column + 1}, "", "", ex.msg);
  }
  if (doc.second_line > 0)
    throw InputError(SourceLocation{path, doc.second_line, 1}, "", "",
                     "a second YAML document ('---') in the " + what +
                         ": only one is read; merge it into the first or remove it");
  if (!doc.root.IsDefined() || doc.root.IsNull()) return YAML::Node();
  check_expanded_size(path, doc.root);
  std::set<int> walked;
  check_unique_keys(path, doc.root, walked);
  return doc.root;
}

}  // namespace pneumo::diagnose
