// Shuttle valve (OR gate): the outlet carries the higher of the two inlet
// pressures (components/selector_valve.hpp).
#include "components/builtin.hpp"
#include "components/selector_valve.hpp"

namespace pneumo::components {

struct ShuttleValveKind {
  static constexpr const char* type = "shuttle_valve";
  static constexpr const char* description =
      "Shuttle valve (OR): the outlet joined to the higher of the two inlets (a ball changing sides over 'ramp'); "
      "ISO 6358 paths.";
  static constexpr bool higher_wins = true;
};

void register_shuttle_valve(Registry& r) { r.add<SelectorValveComponent<ShuttleValveKind>>(); }

}  // namespace pneumo::components
