// Loading component plugins (shared libraries exporting PNEUMO_PLUGIN, see
// plugin_api.hpp) into a registry, before a netlist is elaborated.
//
// A plugin is opened with dlopen(RTLD_NOW | RTLD_LOCAL), its PluginInfo is
// checked (API version, then pneumo version, standard library and type
// sizes) before any of its code but the entry point runs, and its types are
// registered into a staging registry first, so that a type name taken by a
// built-in or by an earlier plugin is refused naming both. A loaded plugin
// is never unloaded: the components it makes hold its vtables and code.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "framework/core/error.hpp"
#include "framework/model/registry.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo {

struct LoadedPlugin {
  std::string path;                // as opened
  std::string name;                // the plugin's own name
  std::vector<std::string> types;  // the component types it registered
  SourceLocation where;            // what named it (netlist entry, command line)
};

// Where each type of a registry came from, for clash messages: types absent
// from the map are built-in.
using TypeOrigins = std::map<std::string, LoadedPlugin>;

// Loads one plugin into `registry`. Every error is an InputError at `where`
// that names the plugin file. `origins` is updated with the new types.
LoadedPlugin load_plugin(const std::string& path, const SourceLocation& where, Registry& registry,
                         TypeOrigins& origins);

// `base` (usually builtin_registry()) plus the netlist's plugins.
Registry registry_with_plugins(const Registry& base, const Netlist& netlist);

}  // namespace pneumo
