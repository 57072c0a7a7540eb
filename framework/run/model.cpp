#include "framework/run/model.hpp"

#include <stdexcept>

#include "framework/io/files.hpp"
#include "framework/plugin/plugin.hpp"

namespace pneumo {

Model load_model(const std::string& path, const Registry& base, const std::vector<std::string>& sets) {
  Model m;
  m.path = path;
  try {
    m.text = read_input_file(path, "netlist");
  } catch (const std::invalid_argument& e) {
    // There is no line to point at: the message names the file only.
    throw InputError(SourceLocation{path, 0, 0}, "", "", std::string("cannot open the netlist file (") + e.what() + ")");
  }
  m.netlist = parse_netlist(m.text, path);
  m.registry = registry_with_plugins(base, m.netlist);
  for (const auto& s : sets) apply_override(m.netlist, s);
  m.sets = sets;
  return m;
}

std::string Model::identity() const {
  std::string id = text;
  for (const auto& s : sets) id += "\n# --set " + s;
  return id;
}

}  // namespace pneumo
