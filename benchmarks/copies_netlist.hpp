// Netlists of N copies of one rig (the scale benchmark's and the tests'):
// copy k's components, top-level parameters and outputs are the rig's,
// renamed "cK_NAME", so that nothing is shared unless asked for.
#pragma once

#include <yaml-cpp/yaml.h>

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace pneumo_scale {

inline std::string copy_name(int k, const std::string& name) { return "c" + std::to_string(k) + "_" + name; }

// "comp.port" of copy k; the shared component keeps its name.
inline std::string copy_ref(int k, const std::string& ref, const std::string& shared) {
  const std::string comp = ref.substr(0, ref.find('.'));
  return comp == shared ? ref : copy_name(k, ref);
}

// N copies of the netlist `rig` (YAML text); metrics are left out (they
// name one copy's events). `edit(k, parameters)` may change copy k's
// top-level parameters (the rig's names) before they are renamed. With
// `shared` naming a component (a supply), it is kept once and every copy's
// ports connected to one of its ports join that port's node: the copies
// are then one coupled circuit.
inline std::string copies_netlist(const std::string& rig, int n,
                                  const std::function<void(int, YAML::Node)>& edit = {},
                                  const std::string& shared = "") {
  const YAML::Node in = YAML::Load(rig);
  YAML::Node out;
  for (const char* key : {"gas", "ambient", "simulation"})
    if (in[key]) out[key] = YAML::Clone(in[key]);
  std::map<std::string, std::vector<std::string>> at_shared;  // shared port -> copies' ports
  std::vector<std::string> shared_ports;
  for (int k = 0; k < n; ++k) {
    YAML::Node params = YAML::Clone(in["parameters"]);
    if (edit) edit(k, params);
    for (const auto& p : params) out["parameters"][copy_name(k, p.first.as<std::string>())] = p.second;
    for (const auto& c : in["components"]) {
      const std::string name = c.first.as<std::string>();
      if (name == shared && k > 0) continue;
      YAML::Node decl = YAML::Clone(c.second);
      for (auto v : decl)
        if (v.second.IsScalar() && in["parameters"][v.second.as<std::string>()])
          v.second = copy_name(k, v.second.as<std::string>());
      out["components"][name == shared ? name : copy_name(k, name)] = decl;
    }
    for (const auto& c : in["connections"]) {
      YAML::Node line;
      std::string shared_port;
      for (const auto& port : c) {
        const std::string ref = port.as<std::string>();
        if (ref.substr(0, ref.find('.')) == shared)
          shared_port = ref;
        else
          line.push_back(copy_ref(k, ref, shared));
      }
      if (shared_port.empty()) {
        out["connections"].push_back(line);
        continue;
      }
      if (!at_shared.count(shared_port)) shared_ports.push_back(shared_port);
      for (const auto& port : line) at_shared[shared_port].push_back(port.as<std::string>());
    }
    for (const auto& o : in["outputs"]) {
      YAML::Node ref = YAML::Clone(o.second);
      if (ref.IsScalar())
        ref = copy_ref(k, ref.as<std::string>(), shared);
      else
        ref["var"] = copy_ref(k, ref["var"].as<std::string>(), shared);
      out["outputs"][copy_name(k, o.first.as<std::string>())] = ref;
    }
  }
  for (const auto& port : shared_ports) {
    YAML::Node line;
    line.push_back(port);
    for (const auto& other : at_shared[port]) line.push_back(other);
    out["connections"].push_back(line);
  }
  YAML::Emitter e;
  e << out;
  return e.c_str();
}

}  // namespace pneumo_scale
