// Comma-separated option values ("x,v,p_A"), shared by the subcommands.
#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace pneumo::cli {

// The items of a comma-separated list; empty items (",,", a trailing comma) are dropped.
inline std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

}  // namespace pneumo::cli
