// Two-pressure valve (AND gate): the outlet carries the lower of the two
// inlet pressures, so it is pressurised only when both inlets are
// (components/selector_valve.hpp).
#include "components/builtin.hpp"
#include "components/selector_valve.hpp"

namespace pneumo::components {

struct TwoPressureValveKind {
  static constexpr const char* type = "two_pressure_valve";
  static constexpr const char* description =
      "Two-pressure valve (AND): the outlet joined to the lower of the two inlets, so it carries pressure only when "
      "both do; ISO 6358 paths.";
  static constexpr bool higher_wins = false;
};

void register_two_pressure_valve(Registry& r) { r.add<SelectorValveComponent<TwoPressureValveKind>>(); }

}  // namespace pneumo::components
