// Reads the netlist's `metrics:` section (see MetricDecl in netlist.hpp).
// Checks what can be checked before a run: the outputs named exist, the
// components of event references exist, expressions parse and name only
// declared metrics or events, and no metric depends on itself.
#pragma once

#include <yaml-cpp/yaml.h>

#include <vector>

#include "framework/netlist/netlist.hpp"
#include "framework/netlist/yaml_location.hpp"

namespace pneumo {

std::vector<MetricDecl> read_metrics(const YAML::Node& section, const Netlist& netlist);

}  // namespace pneumo
