#include "framework/plugin/plugin.hpp"

#include <dlfcn.h>

#include <cctype>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>
#include <sstream>

#include "framework/plugin/plugin_api.hpp"

namespace pneumo {

namespace {

struct DlClose {
  void operator()(void* handle) const { dlclose(handle); }
};
using Handle = std::unique_ptr<void, DlClose>;

std::string describe_abi(const PluginAbi& abi) {
  return std::string(abi.pneumo_version) + " (" + abi.stdlib + "; " + abi.compiler + ")";
}

// Empty if the plugin's ABI is this pneumo's; otherwise why not.
std::string abi_mismatch(const PluginAbi& plugin) {
  constexpr PluginAbi own = plugin_abi();
  // The strings come from the plugin: a null one is a defect, not a crash.
  for (const auto& [text, what] : {std::pair{plugin.pneumo_version, "pneumo version"}, std::pair{plugin.stdlib, "C++ standard library"},
                                   std::pair{plugin.compiler, "compiler"}})
    if (!text)
      return std::string("its plugin information names no ") + what +
             " (a null string; declare the plugin with PNEUMO_PLUGIN from framework/plugin/plugin_api.hpp)";
  if (std::strcmp(plugin.pneumo_version, own.pneumo_version) != 0 || std::strcmp(plugin.stdlib, own.stdlib) != 0)
    return "it was built for pneumo " + describe_abi(plugin) + ", but this is pneumo " + describe_abi(own);
  for (int k = 0; k < PluginAbi::kSizes; ++k)
    if (plugin.sizes[k] != own.sizes[k])
      return std::string("its headers do not match this pneumo's: sizeof(") + kPluginAbiSizeNames[k] + ") is " +
             std::to_string(plugin.sizes[k]) + " in the plugin and " + std::to_string(own.sizes[k]) + " here";
  return "";
}

bool is_type_name(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

std::string origin_text(const TypeOrigins& origins, const std::string& type) {
  auto it = origins.find(type);
  if (it == origins.end()) return "the built-in type '" + type + "'";
  return "type '" + type + "' of plugin '" + it->second.path + "' (" + it->second.where.to_string() + ")";
}

// The entry with the plugin's factory and refinement wrapped, so that an
// exception that is not a std::exception thrown by the plugin's code becomes
// an error naming the plugin instead of ending pneumo.
Registry::Entry guarded(Registry::Entry entry, const std::string& who) {
  auto unknown = [who](const char* doing) {
    return std::runtime_error(who + ": " + doing + " threw something that is not a std::exception");
  };
  if (entry.make)
    entry.make = [make = std::move(entry.make), unknown](const Construction& c) {
      try {
        return make(c);
      } catch (const std::exception&) {
        throw;
      } catch (...) {
        throw unknown("making a component");
      }
    };
  if (entry.refine)
    entry.refine = [refine = std::move(entry.refine), unknown](ComponentInfo i, const ParameterValues& v) {
      try {
        return refine(std::move(i), v);
      } catch (const std::exception&) {
        throw;
      } catch (...) {
        throw unknown("describing an instance");
      }
    };
  return entry;
}

}  // namespace

LoadedPlugin load_plugin(const std::string& path, const SourceLocation& where, Registry& registry,
                         TypeOrigins& origins) {
  const std::string prefix = "plugin '" + path + "': ";
  auto fail = [&](const std::string& message) -> void { throw InputError(where, "", "", prefix + message); };

  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail("no such file");
  if (std::filesystem::is_directory(path, ec)) fail("this is a directory, not a shared library");
  if (!std::filesystem::is_regular_file(path, ec)) fail("not a regular file (a FIFO or device?), not a shared library");
  // dlopen searches the library path for names without a slash; a plugin is
  // always the file named.
  std::string open_path = path;
  if (open_path.find('/') == std::string::npos) open_path = "./" + open_path;

  dlerror();
  Handle handle(dlopen(open_path.c_str(), RTLD_NOW | RTLD_LOCAL));
  if (!handle) {
    const char* why = dlerror();
    fail(std::string("cannot load it: ") + (why ? why : "unknown reason"));
  }
  dlerror();
  void* symbol = dlsym(handle.get(), kPluginEntryPoint);
  if (!symbol || dlerror())
    fail(std::string("not a pneumo plugin: it exports no ") + kPluginEntryPoint +
         "() (define one with PNEUMO_PLUGIN from framework/plugin/plugin_api.hpp)");
  PluginEntryPoint entry = nullptr;
  std::memcpy(&entry, &symbol, sizeof entry);
  const PluginInfo* info = nullptr;
  try {
    info = entry();
  } catch (const std::exception& e) {
    fail(std::string(kPluginEntryPoint) + "() failed: " + e.what());
  } catch (...) {
    fail(std::string(kPluginEntryPoint) + "() threw something that is not a std::exception");
  }
  if (!info) fail(std::string(kPluginEntryPoint) + "() returned no plugin information");
  if (info->api_version != kPluginApiVersion)
    fail("plugin API version " + std::to_string(info->api_version) + ", but this pneumo (" PNEUMO_VERSION_STRING
         ") loads version " + std::to_string(kPluginApiVersion) +
         "; rebuild the plugin against this pneumo's installed package");
  if (const std::string why = abi_mismatch(info->abi); !why.empty())
    fail("refused, " + why + "; rebuild the plugin against this pneumo's installed package");
  if (!info->register_components) fail("its plugin information has no register function");

  LoadedPlugin loaded;
  loaded.path = path;
  loaded.name = info->name ? info->name : "";
  loaded.where = where;
  {
    // Staged, so that nothing of a plugin that fails is half registered.
    Registry staging;
    try {
      info->register_components(staging);
    } catch (const std::exception& e) {
      fail(std::string("registering its components failed: ") + e.what());
    } catch (...) {
      fail("registering its components failed: it threw something that is not a std::exception");
    }
    const auto types = staging.types();
    if (types.empty()) fail("it registers no component types");
    for (const auto& type : types) {
      if (!is_type_name(type))
        fail("component type name '" + type + "' is not an identifier (letters, digits, _)");
      if (registry.find(type))
        fail("its component type '" + type + "' clashes with " + origin_text(origins, type) +
             "; rename the plugin's type");
    }
    for (const auto& type : types) {
      registry.add_entry(guarded(*staging.find(type), prefix + "component type '" + type + "'"));
      loaded.types.push_back(type);
    }
  }
  for (const auto& type : loaded.types) origins[type] = loaded;
  // Never unloaded: registry entries and every component made from them run
  // the plugin's code.
  (void)handle.release();
  return loaded;
}

Registry registry_with_plugins(const Registry& base, const Netlist& netlist) {
  Registry registry = base;
  TypeOrigins origins;
  std::map<std::string, SourceLocation> seen;
  for (const auto& p : netlist.plugins) {
    std::error_code ec;
    auto canonical = std::filesystem::weakly_canonical(p.resolved, ec);
    const std::string key = ec ? p.resolved : canonical.string();
    if (auto it = seen.find(key); it != seen.end())
      throw InputError(p.where, "", "",
                       "plugin '" + p.resolved + "': listed twice (first at " + it->second.to_string() + ")");
    seen[key] = p.where;
    load_plugin(p.resolved, p.where, registry, origins);
  }
  return registry;
}

}  // namespace pneumo
