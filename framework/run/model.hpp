// A netlist file loaded for running: its text, the parsed netlist and the
// registry its `plugins:` make. Every command, study, diagnosis and the
// Python module load a netlist through load_model, so that a component a
// plugin adds works in all of them, and the plugins are resolved once per
// file, not once per run.
#pragma once

#include <string>

#include "framework/model/registry.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo {

struct Model {
  std::string path;   // as given
  // The file's text: a study's journal identifies the netlist by it, and
  // threads parse copies of their own (YAML nodes are not shared safely).
  std::string text;
  Netlist netlist;
  Registry registry;  // the base registry plus the netlist's plugins
};

// Reads and parses `path` and loads its plugins into a copy of `base`
// (usually builtin_registry()). Throws InputError naming the file, or the
// netlist line of a plugin that cannot be loaded.
Model load_model(const std::string& path, const Registry& base);

}  // namespace pneumo
