// Where a YAML node is written: for the readers of YAML files (netlist,
// metrics, effect catalogue), which are the only framework files that see
// yaml-cpp; everything past them works on typed values.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

#include "framework/core/error.hpp"

namespace pneumo {

SourceLocation location_of(const std::string& file, const YAML::Node& node);

}  // namespace pneumo
