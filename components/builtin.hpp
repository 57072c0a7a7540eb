// The built-in component library. Each component lives in its own file and
// registers itself by type name through one function listed in builtin.cpp.
#pragma once

#include "framework/model/registry.hpp"

namespace pneumo::components {

void register_volume(Registry& r);
void register_iso6358_throttle(Registry& r);
void register_pressure_source(Registry& r);
void register_atmosphere(Registry& r);
void register_heat_convection(Registry& r);
void register_thermal_mass(Registry& r);
void register_fixed_temperature(Registry& r);
void register_translational_mass(Registry& r);
void register_fixed_position(Registry& r);
void register_force_source(Registry& r);
void register_signal_source(Registry& r);
void register_external_input(Registry& r);
void register_cushioned_cylinder(Registry& r);
void register_friction_element(Registry& r);
void register_spring_damper(Registry& r);
void register_velocity_source(Registry& r);
void register_nozzle(Registry& r);
void register_hose(Registry& r);
void register_check_valve(Registry& r);
void register_one_way_flow_control(Registry& r);
void register_directional_valve_32(Registry& r);
void register_directional_valve_52(Registry& r);
void register_pressure_sensor(Registry& r);
void register_temperature_sensor(Registry& r);
void register_position_sensor(Registry& r);
void register_limit_switch(Registry& r);
void register_pressure_switch(Registry& r);
void register_and_gate(Registry& r);
void register_or_gate(Registry& r);
void register_not_gate(Registry& r);
void register_timer(Registry& r);
void register_flip_flop(Registry& r);
void register_sequencer(Registry& r);
void register_cylinder(Registry& r);
void register_single_acting_cylinder(Registry& r);
void register_two_pressure_valve(Registry& r);
void register_shuttle_valve(Registry& r);
void register_quick_exhaust_valve(Registry& r);
void register_directional_valve_53(Registry& r);
void register_pressure_regulator(Registry& r);
void register_relief_valve(Registry& r);

}  // namespace pneumo::components

namespace pneumo {
// All built-in component types.
void register_builtin_components(Registry& r);
// A registry holding the built-in types (built once).
const Registry& builtin_registry();
}  // namespace pneumo
