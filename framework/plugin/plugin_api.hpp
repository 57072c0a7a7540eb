// What a component plugin exports. A plugin is a shared library, named in a
// netlist's `plugins:` list, that registers component types the way
// components/builtin.cpp does:
//
//   #include "framework/plugin/plugin_api.hpp"
//   PNEUMO_PLUGIN("seal leakage", registry) { registry.add<SealLeakage>(); }
//
// PNEUMO_PLUGIN defines the one entry point the loader looks up,
// extern "C" pneumo_plugin_info(), returning the plugin's PluginInfo.
//
// Components cross the plugin boundary as C++ objects (vtables,
// std::string, std::function, the Dual scalar with kMaxLocal slots), so a
// plugin only works in the pneumo it was compiled against: the loader
// refuses a plugin whose pneumo version, C++ standard library or type
// layouts (PluginAbi) differ from its own, before calling anything in it.
#pragma once

#include <cstddef>

#include "framework/core/version.hpp"
#include "framework/model/registry.hpp"

namespace pneumo {

// Layout of PluginInfo. Read before anything else in PluginInfo, so that a
// future layout change is refused instead of misread.
inline constexpr int kPluginApiVersion = 1;

#define PNEUMO_PLUGIN_STR_(x) #x
#define PNEUMO_PLUGIN_STR(x) PNEUMO_PLUGIN_STR_(x)
#if defined(_GLIBCXX_RELEASE)
#define PNEUMO_PLUGIN_STDLIB \
  "libstdc++ " PNEUMO_PLUGIN_STR(_GLIBCXX_RELEASE) ", cxx11 ABI " PNEUMO_PLUGIN_STR(_GLIBCXX_USE_CXX11_ABI)
#elif defined(_LIBCPP_VERSION)
#define PNEUMO_PLUGIN_STDLIB "libc++ " PNEUMO_PLUGIN_STR(_LIBCPP_VERSION)
#else
#define PNEUMO_PLUGIN_STDLIB "unknown C++ standard library"
#endif
#if defined(__clang__)
#define PNEUMO_PLUGIN_COMPILER "clang " __clang_version__
#elif defined(__GNUC__)
#define PNEUMO_PLUGIN_COMPILER "GCC " __VERSION__
#else
#define PNEUMO_PLUGIN_COMPILER "unknown compiler"
#endif

// The binary interface a translation unit was compiled for. The loader
// compares the plugin's with its own: pneumo version, standard library and
// every size must be equal. (The compiler is reported, not compared: GCC and
// clang share the Itanium C++ ABI on the same standard library.)
struct PluginAbi {
  const char* pneumo_version;
  const char* stdlib;
  const char* compiler;
  // sizeof of the types that cross the boundary; a header edited or
  // configured differently (e.g. kMaxLocal) shows up here.
  static constexpr int kSizes = 8;
  std::size_t sizes[kSizes];
};

inline constexpr const char* kPluginAbiSizeNames[PluginAbi::kSizes] = {
    "Dual", "Pattern", "Eval<double>", "Component", "ComponentInfo", "ParameterSpec", "Registry::Entry", "GasModel"};

constexpr PluginAbi plugin_abi() {
  return {PNEUMO_VERSION_STRING,
          PNEUMO_PLUGIN_STDLIB,
          PNEUMO_PLUGIN_COMPILER,
          {sizeof(Dual), sizeof(Pattern), sizeof(Eval<double>), sizeof(Component), sizeof(ComponentInfo),
           sizeof(ParameterSpec), sizeof(Registry::Entry), sizeof(GasModel)}};
}

struct PluginInfo {
  int api_version;  // kPluginApiVersion; must stay the first member
  const char* name;  // for messages, e.g. "seal leakage"
  PluginAbi abi;
  void (*register_components)(Registry& registry);
};

// The entry point's name and type.
inline constexpr const char* kPluginEntryPoint = "pneumo_plugin_info";
using PluginEntryPoint = const PluginInfo* (*)();

}  // namespace pneumo

// Defines the plugin's entry point; the block that follows is the body of
// its register function, with `registry_name` the Registry& to add to.
#define PNEUMO_PLUGIN(plugin_name, registry_name)                                                            \
  static void pneumo_plugin_register_components_(::pneumo::Registry&);                                      \
  extern "C" __attribute__((visibility("default"))) const ::pneumo::PluginInfo* pneumo_plugin_info() {      \
    static const ::pneumo::PluginInfo info{::pneumo::kPluginApiVersion, plugin_name, ::pneumo::plugin_abi(), \
                                           &pneumo_plugin_register_components_};                            \
    return &info;                                                                                            \
  }                                                                                                          \
  static void pneumo_plugin_register_components_(::pneumo::Registry& registry_name)
