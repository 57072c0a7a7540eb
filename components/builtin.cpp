#include "components/builtin.hpp"

namespace pneumo {

namespace components {
// Replaying measured inputs (data_signal.cpp, position_source.cpp).
void register_position_source(Registry& r);
void register_data_signal(Registry& r);
}  // namespace components

void register_builtin_components(Registry& r) {
  using namespace components;
  register_volume(r);
  register_iso6358_throttle(r);
  register_pressure_source(r);
  register_atmosphere(r);
  register_heat_convection(r);
  register_thermal_mass(r);
  register_fixed_temperature(r);
  register_translational_mass(r);
  register_fixed_position(r);
  register_force_source(r);
  register_signal_source(r);
  register_external_input(r);
  register_cushioned_cylinder(r);
  register_friction_element(r);
  register_spring_damper(r);
  register_velocity_source(r);
  register_position_source(r);
  register_data_signal(r);
  register_nozzle(r);
  register_hose(r);
  register_check_valve(r);
  register_one_way_flow_control(r);
  register_directional_valve_32(r);
  register_directional_valve_52(r);
  register_pressure_sensor(r);
  register_temperature_sensor(r);
  register_position_sensor(r);
  register_limit_switch(r);
  register_pressure_switch(r);
  register_and_gate(r);
  register_or_gate(r);
  register_not_gate(r);
  register_timer(r);
  register_flip_flop(r);
  register_sequencer(r);
  register_cylinder(r);
  register_single_acting_cylinder(r);
  register_two_pressure_valve(r);
  register_shuttle_valve(r);
  register_quick_exhaust_valve(r);
  register_directional_valve_53(r);
  register_pressure_regulator(r);
  register_relief_valve(r);
}

const Registry& builtin_registry() {
  static const Registry registry = [] {
    Registry r;
    register_builtin_components(r);
    return r;
  }();
  return registry;
}

}  // namespace pneumo
