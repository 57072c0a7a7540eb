// The netlist's gas and ambient constants declared like component
// parameters: unit, default (GasModel's) and range, so that `gas:` and
// `ambient:` values are checked as component parameters are.
#pragma once

#include <string>
#include <vector>

#include "framework/model/component.hpp"
#include "framework/model/gas.hpp"

namespace pneumo {

struct GasParameter {
  ParameterSpec spec;
  double GasModel::*field;
};

// gas: R, kappa, rho_ref, T_ref, m_flow_small.
inline const std::vector<GasParameter>& gas_parameters() {
  static const std::vector<GasParameter> specs = [] {
    const GasModel d;
    using P = ParameterSpec;
    // An ideal gas has 1 < kappa <= 5/3 (monatomic); kappa = 1 divides by zero in c_v.
    P kappa = P::scalar("kappa", "1", "ratio of specific heats c_p / c_v", d.kappa);
    kappa.min = 1.0;
    kappa.min_exclusive = true;
    kappa.max = 1.67;
    return std::vector<GasParameter>{
        {P::scalar("R", "J/(kg*K)", "specific gas constant", d.R).positive(), &GasModel::R},
        {std::move(kappa), &GasModel::kappa},
        // 0 would make every ISO 6358 conductance pass no flow.
        {P::scalar("rho_ref", "kg/m3", "density at the ISO 6358 reference state", d.rho_ref).positive(),
         &GasModel::rho_ref},
        {P::scalar("T_ref", "K", "temperature of the ISO 6358 reference state", d.T_ref).positive(),
         &GasModel::T_ref},
        // 0 would make the regularised flows non-differentiable at zero flow.
        {P::scalar("m_flow_small", "kg/s",
                   "mass flow below which stream temperatures are smoothed; keep it well below the circuit's "
                   "flows (micro-throttles: lower it)",
                   d.m_flow_small)
             .positive(),
         &GasModel::m_flow_small},
    };
  }();
  return specs;
}

// ambient: p (absolute: it is the datum of gauge pressures), T.
inline const std::vector<GasParameter>& ambient_parameters() {
  static const std::vector<GasParameter> specs = [] {
    const GasModel d;
    using P = ParameterSpec;
    return std::vector<GasParameter>{
        {P::scalar("p", "Pa", "ambient pressure, absolute", d.p_ambient).positive(), &GasModel::p_ambient},
        {P::scalar("T", "K", "ambient temperature", d.T_ambient).positive(), &GasModel::T_ambient},
    };
  }();
  return specs;
}

}  // namespace pneumo
