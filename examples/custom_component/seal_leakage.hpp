// A component outside pneumo's tree: laminar gas leakage through a seal gap.
// seal_leakage.cpp holds the component and the plugin entry point; this
// header lets tests register the type without loading the plugin file.
#pragma once

#include "framework/model/registry.hpp"

namespace seal_example {
void register_seal_leakage(pneumo::Registry& registry);
}
