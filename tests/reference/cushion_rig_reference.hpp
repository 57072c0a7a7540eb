// Independent, hand-written reference implementation of the BASIC end-cushioning
// rig (/work/shared/rigs/cushion-rig.yaml, seed paper 000: Festo DSBF 32/100,
// pull-in stroke towards the cap end, meter-out speed control).
//
// It uses SUNDIALS IDA + SUNLinSol_KLU directly and deliberately shares no
// code with the pneumo framework. Purposes:
//   1. cross-check reference for the framework's rig model (tests),
//   2. speed floor for benchmarks: no allocation in the residual, hand-coded
//      analytic Jacobian, fixed sparsity pattern, KLU refactorisation.
//
// Model (all SI, Pa absolute; x = 0 extended, x = stroke at the cap):
//   state y = [x, v, p_A, T_A, p_EC, T_EC, p_ch, T_ch, p_LB, T_LB]
//   residual F = y' - f(y) (an ODE posed as a DAE with identity mass matrix).
//   Every volume: ideal gas, adiabatic, mass and energy balance
//     dm/dt = sum mdot_in,  dU/dt = sum H_in - p dV/dt,  U = m c_v T,
//   rewritten exactly in (p, T):
//     dp/dt = ((kappa-1) H - kappa p dV/dt) / V
//     dT/dt = T/(p V) * ((kappa-1) H - (kappa-1) p dV/dt - R T M)
//   with M = net mass inflow, H = net enthalpy inflow (inflow carries
//   c_p T_upstream, outflow c_p T_own).
//   Flows: ISO 6358 (seed eq. 15-16) with a linear laminar branch above
//   r = laminar_ratio (continuous there, zero at r = 1), direction by the
//   sign of the pressure difference.
//   Friction (seed eq. 7, Annex B row 5.14 bar_rel):
//     F_fr = tanh(v/v_reg) * (b + (FS-FC) exp(-|v|_e/vS) + kv |v|_e^a),
//   REGULARISATION OF |v|: |v| is replaced by |v|_e = sqrt(v^2 + eps^2),
//   eps = friction_abs_eps (default 1e-6 m/s = 1 % of v_reg), because
//   d|v|^a/dv is unbounded at v = 0 for a < 1. Like the tanh(v/v_reg) that
//   replaces sign(v), it is a smooth substitute acting only in a tiny
//   velocity band (the friction changes by < 0.01 N at v = 0 and by a
//   relative 1e-10 at 0.1 m/s).
//   End stops at x = 0 and x = stroke: max(0, k pen + d pen_rate), pushing back.
//   Valve paths P->A and B->R are closed for t < t_switch and fully open from
//   t_switch on; the integrator is stopped exactly at t_switch (IDASetStopTime)
//   and restarted with IDAReInit (consistent y' recomputed).
#pragma once

#include <array>
#include <utility>
#include <vector>

struct _generic_N_Vector;  // SUNDIALS' N_Vector

namespace pneumo_reference {

struct RigParams {
    // gas (dry air, ideal)
    double R = 287.05;              // J/(kg K)
    double kappa = 1.4;
    // ISO 6358 reference conditions
    double rho_ref = 1.185;         // kg/m^3
    double T_ref = 293.15;          // K
    double laminar_ratio = 0.999;   // above this p2/p1 the flow function is linear in (1 - r)
    // ambient
    double p_amb = 101325.0;        // Pa abs
    double T_amb = 293.15;          // K
    // operating point
    double p_supply = 5.0e5;        // Pa abs
    double m_load = 3.7;            // kg
    double z_EC = 1.5;              // cushion throttle opening, revolutions
    // 5/2 valve, paths P->A and B->R
    double valve_C = 1.0;           // dm^3/(s bar)
    double valve_b = 0.30;
    double t_switch = 0.01;         // s
    // cylinder
    double bore = 0.032;            // m
    double rod = 0.012;             // m
    double stroke = 0.100;          // m
    double plug_diameter = 0.016;   // m
    double cushion_length = 0.020;  // m
    double dead_volume_rod_side = 3.0e-6;  // m^3
    double dead_volume_cushion = 2.0e-6;   // m^3
    double dead_volume_channel = 1.0e-6;   // m^3
    double bore_opening_C = 5.0;    // dm^3/(s bar)
    double bore_opening_b = 0.5;
    double bore_opening_ramp = 0.0005;     // m
    // cushion throttle C(z), piecewise linear [rev, dm^3/(s bar)]; constant beyond the ends
    std::vector<std::pair<double, double>> C_of_z = {
        {0.0, 0.0}, {0.1, 0.015}, {1.5, 0.12}, {3.5, 0.30}, {6.0, 0.40}};
    double cushion_b0 = 0.30;       // b = b0 + slope * C / C_max
    double cushion_b_slope = 0.45;
    double cushion_C_max = 0.40;    // dm^3/(s bar)
    // meter-out throttle (channel -> line B)
    double meter_out_C = 0.35;      // dm^3/(s bar)
    double meter_out_b = 0.45;
    // line B volume (fixed)
    double line_B_volume = 1.0e-6;  // m^3
    // end stops
    double stop_stiffness = 1.0e7;  // N/m
    double stop_damping = 3000.0;   // N s/m
    // friction, seed eq. (7), Annex B row p0 = 5.14 bar_rel
    double friction_v_reg = 1.0e-4; // m/s, sign(v) -> tanh(v / v_reg)
    double friction_abs_eps = 1.0e-6;  // m/s, |v| -> sqrt(v^2 + eps^2) (see header comment)
    double fr_b = 2.776;            // N
    double fr_FS = 25.05;           // N
    double fr_FC = 4.31;            // N
    double fr_vS = 0.004033;        // m/s
    double fr_kv = 128.7;           // kg/s (N per (m/s)^a)
    double fr_a = 0.6843;
};

struct RigSample {
    double t, x, v, p_A, p_EC, T_EC, p_ch;
};

struct RigStats {
    long steps = 0, residual_evals = 0, jacobian_evals = 0, error_test_failures = 0,
         nonlinear_conv_failures = 0, jacobian_recombinations = 0;
};

struct RigResult {
    std::vector<RigSample> samples;
    RigStats stats;
};

// Samples at t = 0, output_interval, 2*output_interval, ... <= t_end (plus t_end
// itself if it is not on the grid). Absolute tolerances are rtol times a
// nominal scale per variable (x: 0.01 m, v: 0.1 m/s, p: 1e5 Pa, T: 300 K).
// Throws std::runtime_error (with the IDA flag name) on failure.
// `prepare_vector`, if given, is called on each vector before IDA sees it
// (IDA's own vectors are clones of y): the benchmark passes pneumo's
// compiled vector kernels through it to time the floor like for like; the
// reference itself shares no code with pneumo. `jacobian_reuse` answers
// IDA's requests for a Newton matrix that only follow a change of cj from
// the last df/dy, with pneumo's rule (SolverOptions::jacobian_reuse).
RigResult simulate(const RigParams& params, double t_end = 1.2, double rtol = 1e-6,
                   double output_interval = 1e-3, void (*prepare_vector)(_generic_N_Vector*) = nullptr,
                   bool jacobian_reuse = false);

// Cushion throttle conductance C(z_EC) in dm^3/(s bar) (piecewise-linear table).
double cushion_throttle_C(const RigParams& params, double z_EC);

// Initial piston position: static balance against the stop at x = 0 (x0 < 0).
double initial_position(const RigParams& params);

// Development aid: max relative deviation between the analytic Jacobian df/dy
// and central finite differences over a set of perturbed states (returns the
// worst |J_an - J_fd| / (|J_fd| + scale) found).
double jacobian_self_check(const RigParams& params);

}  // namespace pneumo_reference
