// Ports of the combinational gates (and, or): inputs in1 .. in4 (in3, in4
// optional, holding the gate's neutral value when unconnected) and output y.
// The gates are algebraic equations of 0/1 inputs, without modes: their
// output jumps exactly when an input does, at the same event.
#pragma once

#include <string>
#include <vector>

#include "framework/model/component.hpp"

namespace pneumo::components {

inline std::vector<PortSpec> gate_ports(double neutral) {
  std::vector<PortSpec> ports;
  for (int k = 1; k <= 4; ++k)
    ports.push_back({"in" + std::to_string(k), Domain::signal, Causality::input,
                     "input 0/1" + std::string(k > 2 ? " (optional)" : ""), k > 2, neutral});
  ports.push_back({"y", Domain::signal, Causality::output, "output 0/1", true});
  return ports;
}

}  // namespace pneumo::components
