// Enthalpy carried by a flow into a gas volume, upwinded: inflow (m > 0)
// brings c_p T_in, outflow takes c_p T_own.
//
// Written as H = c_p (m (T_in + T_own) / 2 + a(m) (T_in - T_own) / 2) with
// a(m) a smooth |m| that is 0 at m = 0: a(m) = m^2 / sqrt(m^2 + eps^2). So
//  * at zero flow no energy moves, whatever the temperatures: a regularised
//    |m| that stayed eps at zero (sqrt(m^2 + eps^2)) acted as a heat
//    conductance c_p eps / 2 between a closed volume and its neighbour,
//    which pulled a 1e-8 m3 volume from 385 K to the supply's 293 K within
//    a second of the filling's end;
//  * for |m| >> eps it is m c_p T_upstream (the departure falls as eps^2/m^2);
//  * in between the carried temperature is a blend of T_upstream (weight
//    between 1/2 and 1) and T_downstream, never outside the two;
//  * in(m) = out(-m), so the energy leaving one volume is the energy
//    entering its neighbour at any flow (the flow's two ends see the same
//    m with opposite signs);
//  * it is differentiable at m = 0 (scale gas.m_flow_small).
#pragma once

#include "framework/core/smooth.hpp"
#include "framework/model/gas.hpp"

namespace pneumo::components {

// The weights of the two temperatures: in (of T_in) and out (of T_own),
// in - out == m, both 0 at m = 0.
template <class T>
void upwind_weights(const T& m_flow, double eps, T& in, T& out) {
  const T a = m_flow * m_flow / smooth_abs(m_flow, eps);
  in = 0.5 * (a + m_flow);
  out = 0.5 * (a - m_flow);
}

template <class T>
T enthalpy_inflow(const T& m_flow, const T& T_in, const T& T_own, const GasModel& gas) {
  T in, out;
  upwind_weights(m_flow, gas.m_flow_small, in, out);
  return gas.cp() * (in * T_in - out * T_own);
}

}  // namespace pneumo::components
