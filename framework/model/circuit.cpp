#include "framework/model/circuit.hpp"

namespace pneumo {

namespace {
struct Named {
  const char* name;
  const char* unit;
};
// Variable names and units per domain, in the local layout order.
const std::vector<Named>& domain_variables(Domain d) {
  static const std::vector<Named> pneumatic{{"p", "Pa"}, {"m_flow", "kg/s"}, {"T_out", "K"}, {"T_in", "K"}};
  static const std::vector<Named> thermal{{"T", "K"}, {"Q", "W"}};
  static const std::vector<Named> translational{{"s", "m"}, {"f", "N"}, {"v", "m/s"}};
  static const std::vector<Named> signal{{"value", "1"}};
  switch (d) {
    case Domain::pneumatic: return pneumatic;
    case Domain::thermal: return thermal;
    case Domain::translational: return translational;
    case Domain::signal: return signal;
  }
  return signal;
}
}  // namespace

std::vector<std::string> local_variable_names(const Component& c) {
  std::vector<std::string> out;
  for (const auto& p : c.info().ports)
    for (const auto& v : domain_variables(p.domain)) out.push_back(p.name + "." + v.name);
  for (const auto& v : c.info().variables) out.push_back(v.name);
  return out;
}

std::vector<std::string> local_variable_units(const Component& c) {
  std::vector<std::string> out;
  for (const auto& p : c.info().ports)
    for (const auto& v : domain_variables(p.domain)) out.push_back(v.unit);
  for (const auto& v : c.info().variables) out.push_back(v.unit);
  return out;
}

}  // namespace pneumo
