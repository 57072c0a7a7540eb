// Enthalpy carried by a flow into a gas volume, upwinded: inflow (m > 0)
// brings c_p T_in, outflow takes c_p T_own. smooth_pos(x) - smooth_pos(-x)
// == x, so this is exactly m c_p T_upstream away from zero flow and
// conservative between neighbours at any flow, while staying differentiable
// at m = 0 (scale gas.m_flow_small).
#pragma once

#include "framework/core/smooth.hpp"
#include "framework/model/gas.hpp"

namespace pneumo::components {

template <class T>
T enthalpy_inflow(const T& m_flow, const T& T_in, const T& T_own, const GasModel& gas) {
  const double eps = gas.m_flow_small;
  T in, out;
  smooth_pos_pair(m_flow, eps, in, out);
  return gas.cp() * (in * T_in - out * T_own);
}

}  // namespace pneumo::components
