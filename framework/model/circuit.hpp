// A circuit: component instances and the connections between their ports.
// Built by the netlist layer (or by code), consumed by assembly.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "framework/core/error.hpp"
#include "framework/core/units.hpp"
#include "framework/model/component.hpp"
#include "framework/model/gas.hpp"

namespace pneumo {

struct PortId {
  int component = -1;
  int port = -1;
  bool operator==(const PortId&) const = default;
};

// All ports in one connection share one node: equal across variables, flows
// summing to zero, stream variables mixed.
struct Connection {
  std::vector<PortId> ports;
  SourceLocation where;
};

// A named signal written to the results: a component's local variable (a
// port or internal variable) or one of its observables.
struct Probe {
  enum class Kind { local, observable };
  std::string name;
  int component = -1;
  Kind kind = Kind::local;
  int index = -1;
  std::string unit;
  bool integral = false;  // the output is the time integral of this quantity
  units::DisplayUnit display;    // how result files show it (SI inside)
};

// The local variable names of a component, in layout order ("port.p",
// "port.m_flow", ..., then internal variables).
std::vector<std::string> local_variable_names(const Component& c);
std::vector<std::string> local_variable_units(const Component& c);
// Whether a local variable is a port's T_in: the temperature of the gas that
// would enter through it, upwinded - held at the last stream's when nothing
// enters, so it is no gas's state and no thermometer in the line reads it.
bool is_entering_stream_temperature(const std::string& local_variable);

struct Circuit;
// The probe of a component's quantity as outputs name it: an observable, a
// local variable, or a signal port by its name alone (source.y for the
// value of port y); index -1 when the component has none such.
Probe find_probe(const Circuit& circuit, int component, const std::string& quantity);

struct Circuit {
  GasModel gas;
  std::vector<std::unique_ptr<Component>> components;
  std::vector<SourceLocation> component_where;  // parallel to components
  std::vector<Connection> connections;
  std::vector<Probe> probes;

  int find(const std::string& name) const {
    for (std::size_t i = 0; i < components.size(); ++i)
      if (components[i]->name() == name) return static_cast<int>(i);
    return -1;
  }
  std::string port_name(PortId id) const {
    return components[id.component]->name() + "." +
           components[id.component]->info().ports[id.port].name;
  }
};

}  // namespace pneumo
