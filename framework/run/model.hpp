// A netlist file loaded for running: its text, the parsed netlist and the
// registry its `plugins:` make. Every command, study, diagnosis and the
// Python module load a netlist through load_model, so that a component a
// plugin adds works in all of them, and the plugins are resolved once per
// file, not once per run.
#pragma once

#include <string>
#include <vector>

#include "framework/model/registry.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo {

struct Model {
  std::string path;   // as given
  // The file's text: a study's journal identifies the netlist by it, and
  // threads parse copies of their own (YAML nodes are not shared safely).
  std::string text;
  Netlist netlist;    // with the command line's --set applied
  Registry registry;  // the base registry plus the netlist's plugins
  std::vector<std::string> sets;  // the --set assignments, in order

  // What a journal resumes only for the same model: the text and the sets.
  std::string identity() const;
};

// Reads and parses `path`, loads its plugins into a copy of `base` (usually
// builtin_registry()) and applies `sets` (apply_override). Throws
// InputError naming the file, or the netlist line of a plugin that cannot
// be loaded, or the --set that is wrong.
Model load_model(const std::string& path, const Registry& base, const std::vector<std::string>& sets = {});

}  // namespace pneumo
