// The gas model belongs to the network: every component sees the same R and
// kappa through its evaluation context and keeps no gas constants of its own.
#pragma once

namespace pneumo {

struct GasModel {
  double R = 287.05;     // specific gas constant, J/(kg K) (dry air)
  double kappa = 1.4;    // ratio of specific heats c_p / c_v
  // ISO 6358 reference (normal, ANR) conditions used by sonic conductances.
  double rho_ref = 1.185;  // kg/m^3
  double T_ref = 293.15;   // K
  // Ambient conditions: the atmosphere component's defaults and the datum of
  // gauge pressures in netlists.
  double p_ambient = 101325.0;  // Pa absolute
  double T_ambient = 293.15;    // K
  // Mass flow below which the upwinding of stream temperatures is smoothed,
  // kg/s. Keeps the energy equations differentiable at zero flow.
  double m_flow_small = 1e-7;

  double cp() const { return kappa * R / (kappa - 1.0); }
  double cv() const { return R / (kappa - 1.0); }
};

}  // namespace pneumo
