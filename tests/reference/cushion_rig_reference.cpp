// Independent reference implementation of the basic end-cushioning rig.
// See cushion_rig_reference.hpp for the model summary. No pneumo framework
// code is used here on purpose.
#include "cushion_rig_reference.hpp"

// IDAS, the library pneumo links: one process must not load both IDA and
// IDAS (they export the same IDA* symbols).
#include <idas/idas.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_types.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace pneumo_reference {
namespace {

constexpr int NX = 10;
enum Idx : int { IX = 0, IV, IPA, ITA, IPE, ITE, IPC, ITC, IPB, ITB };

// Fixed structural pattern of df/dy (the IDA Jacobian is cj*I - df/dy, so the
// diagonal is always structural). pattern[row][col].
constexpr bool kPattern[NX][NX] = {
    //  x  v  pA TA pE TE pC TC pB TB
    {1, 1, 0, 0, 0, 0, 0, 0, 0, 0},  // x'  = v
    {1, 1, 1, 0, 1, 0, 1, 0, 0, 0},  // v'  = F / m
    {1, 1, 1, 1, 0, 0, 0, 0, 0, 0},  // pA'
    {1, 1, 1, 1, 0, 0, 0, 0, 0, 0},  // TA'
    {1, 1, 0, 0, 1, 1, 1, 1, 0, 0},  // pEC'
    {1, 1, 0, 0, 1, 1, 1, 1, 0, 0},  // TEC'
    {1, 1, 0, 0, 1, 1, 1, 1, 1, 1},  // pch'
    {1, 1, 0, 0, 1, 1, 1, 1, 1, 1},  // Tch'
    {0, 0, 0, 0, 0, 0, 1, 1, 1, 1},  // pLB'
    {0, 0, 0, 0, 0, 0, 1, 1, 1, 1},  // TLB'
};

constexpr int pattern_nnz() {
    int n = 0;
    for (int i = 0; i < NX; ++i)
        for (int j = 0; j < NX; ++j) n += kPattern[i][j] ? 1 : 0;
    return n;
}
constexpr int kNnz = pattern_nnz();

constexpr double kCUnit = 1e-8;  // dm^3/(s bar) -> m^3/(s Pa)

// ---------------------------------------------------------------------------
// ISO 6358 flow element between node 1 and node 2; m > 0 means 1 -> 2.
struct Flow {
    double m = 0, dm_dp1 = 0, dm_dT1 = 0, dm_dp2 = 0, dm_dT2 = 0;
    double H = 0, dH_dp1 = 0, dH_dT1 = 0, dH_dp2 = 0, dH_dT2 = 0;
};

struct Model {
    // gas
    double R, kappa, km1, cp;
    // ISO reference
    double T_ref, r_lam;
    // boundaries
    double p_sup, T_sup, p_amb, T_amb;
    // geometry
    double A_A, A_R, A_ann, A_CP;
    double L, x_plug, ramp;
    double V0A, V0E, V0C, VLB;
    // flow elements: K = C * 1e-8 * rho_ref
    double K_valve, b_valve, K_bore, b_bore, K_cush, b_cush, K_mo, b_mo;
    // mechanics
    double m, k_stop, d_stop;
    double vr, eps, fb, fdS, vS, kv, a;
    // switching
    bool valves_open = false;

    // flow function phi(r) and dphi/dr
    inline void phi(double r, double b, double& ph, double& dph) const {
        if (r <= b) {
            ph = 1.0;
            dph = 0.0;
        } else if (r <= r_lam) {
            const double s = (r - b) / (1.0 - b);
            ph = std::sqrt(1.0 - s * s);
            dph = -s / ((1.0 - b) * ph);
        } else {
            const double sl = (r_lam - b) / (1.0 - b);
            const double phl = sl > 0.0 ? std::sqrt(1.0 - sl * sl) : 1.0;
            ph = phl * (1.0 - r) / (1.0 - r_lam);
            dph = -phl / (1.0 - r_lam);
        }
    }

    inline Flow flow(double K, double b, double p1, double T1, double p2, double T2) const {
        Flow f;
        if (K <= 0.0) return f;
        const bool fwd = p1 >= p2;
        const double pu = fwd ? p1 : p2, Tu = fwd ? T1 : T2, pd = fwd ? p2 : p1;
        const double r = pd / pu;
        double ph, dph;
        phi(r, b, ph, dph);
        const double g = K * std::sqrt(T_ref / Tu);
        const double m = g * pu * ph;
        const double dm_dpu = g * (ph - r * dph);
        const double dm_dpd = g * dph;
        const double dm_dTu = -0.5 * m / Tu;
        const double cT = cp * Tu;
        if (fwd) {
            f.m = m;
            f.dm_dp1 = dm_dpu;
            f.dm_dp2 = dm_dpd;
            f.dm_dT1 = dm_dTu;
            f.H = cT * m;
            f.dH_dp1 = cT * dm_dpu;
            f.dH_dp2 = cT * dm_dpd;
            f.dH_dT1 = 0.5 * cp * m;
        } else {
            f.m = -m;
            f.dm_dp2 = -dm_dpu;
            f.dm_dp1 = -dm_dpd;
            f.dm_dT2 = -dm_dTu;
            f.H = -cT * m;
            f.dH_dp2 = -cT * dm_dpu;
            f.dH_dp1 = -cT * dm_dpd;
            f.dH_dT2 = -0.5 * cp * m;
        }
        return f;
    }

    // Net pressure force on the piston (positive towards the cap) at rest.
    double pressure_force(double pA, double pE, double pC) const {
        return pA * A_A + p_amb * A_R - pE * A_ann - pC * A_CP;
    }

    // f(y) and optionally the dense Jacobian df/dy (J[row][col]).
    // Returns false for a non-physical state (p or T <= 0).
    template <bool WithJac>
    bool eval(const double* y, double* f, double (*J)[NX]) const {
        const double x = y[IX], v = y[IV];
        for (int i = IPA; i < NX; ++i)
            if (!(y[i] > 0.0)) return false;
        const double pA = y[IPA], TA = y[ITA], pE = y[IPE], TE = y[ITE], pC = y[IPC],
                     TC = y[ITC], pB = y[IPB], TB = y[ITB];

        // net mass / enthalpy inflow into the four volumes and their gradients
        double M[4] = {0, 0, 0, 0}, H[4] = {0, 0, 0, 0};
        double dM[4][NX] = {}, dH[4][NX] = {};
        enum { VA = 0, VE = 1, VC = 2, VB = 3 };
        const int pIdx[4] = {IPA, IPE, IPC, IPB};
        const int TIdx[4] = {ITA, ITE, ITC, ITB};

        // flow from volume a to volume b (a or b = -1: fixed boundary node);
        // fx: opening factor, dfx: d(opening)/dx
        auto connect = [&](int a, int b, const Flow& fl, double fx, double dfx) {
            if (a >= 0) {
                M[a] -= fx * fl.m;
                H[a] -= fx * fl.H;
            }
            if (b >= 0) {
                M[b] += fx * fl.m;
                H[b] += fx * fl.H;
            }
            if constexpr (WithJac) {
                for (int s = 0; s < 2; ++s) {
                    const int vol = s == 0 ? a : b;
                    if (vol < 0) continue;
                    const double sg = s == 0 ? -fx : fx;
                    if (a >= 0) {
                        dM[vol][pIdx[a]] += sg * fl.dm_dp1;
                        dM[vol][TIdx[a]] += sg * fl.dm_dT1;
                        dH[vol][pIdx[a]] += sg * fl.dH_dp1;
                        dH[vol][TIdx[a]] += sg * fl.dH_dT1;
                    }
                    if (b >= 0) {
                        dM[vol][pIdx[b]] += sg * fl.dm_dp2;
                        dM[vol][TIdx[b]] += sg * fl.dm_dT2;
                        dH[vol][pIdx[b]] += sg * fl.dH_dp2;
                        dH[vol][TIdx[b]] += sg * fl.dH_dT2;
                    }
                    if (dfx != 0.0) {
                        const double sx = s == 0 ? -dfx : dfx;
                        dM[vol][IX] += sx * fl.m;
                        dH[vol][IX] += sx * fl.H;
                    }
                }
            }
        };

        if (valves_open) {
            connect(-1, VA, flow(K_valve, b_valve, p_sup, T_sup, pA, TA), 1.0, 0.0);
            connect(VB, -1, flow(K_valve, b_valve, pB, TB, p_amb, T_amb), 1.0, 0.0);
        }
        // bore opening EC <-> ch, closes linearly over `ramp` before the plug engages
        {
            const double u = (x_plug - x) / ramp;
            double fx, dfx;
            if (u <= 0.0) {
                fx = 0.0;
                dfx = 0.0;
            } else if (u >= 1.0) {
                fx = 1.0;
                dfx = 0.0;
            } else {
                fx = u;
                dfx = -1.0 / ramp;
            }
            if (fx > 0.0 || dfx != 0.0)
                connect(VE, VC, flow(K_bore, b_bore, pE, TE, pC, TC), fx, dfx);
        }
        connect(VE, VC, flow(K_cush, b_cush, pE, TE, pC, TC), 1.0, 0.0);
        connect(VC, VB, flow(K_mo, b_mo, pC, TC, pB, TB), 1.0, 0.0);

        // volumes: V, dV/dx (dV/dt = dV/dx * v)
        const double dVdx[4] = {A_A, -A_ann, -A_CP, 0.0};
        const double V[4] = {V0A + A_A * x, V0E + A_ann * (L - x), V0C + A_CP * (L - x), VLB};
        for (int i = 0; i < 4; ++i) {
            if (!(V[i] > 0.0)) return false;
            const int ip = pIdx[i], iT = TIdx[i];
            const double p = y[ip], T = y[iT], Vi = V[i];
            const double Vd = dVdx[i] * v;
            const double gp = (km1 * H[i] - kappa * p * Vd) / Vi;
            const double Q = km1 * H[i] - km1 * p * Vd - R * T * M[i];
            const double c = T / (p * Vi);
            const double gT = c * Q;
            f[ip] = gp;
            f[iT] = gT;
            if constexpr (WithJac) {
                for (int z = 0; z < NX; ++z) {
                    const double dp = z == ip ? 1.0 : 0.0;
                    const double dT = z == iT ? 1.0 : 0.0;
                    const double dVd = z == IV ? dVdx[i] : 0.0;
                    const double dV = z == IX ? dVdx[i] : 0.0;
                    J[ip][z] = (km1 * dH[i][z] - kappa * (dp * Vd + p * dVd)) / Vi - gp * dV / Vi;
                    const double dQ = km1 * dH[i][z] - km1 * (dp * Vd + p * dVd) -
                                      R * (dT * M[i] + T * dM[i][z]);
                    J[iT][z] = (dT * Q + T * dQ) / (p * Vi) - gT * (dp / p + dV / Vi);
                }
            }
        }

        // mechanics
        double F = pressure_force(pA, pE, pC);
        double dF_dx = 0.0, dF_dv = 0.0;
        {
            const double th = std::tanh(v / vr);
            const double s = std::sqrt(v * v + eps * eps);
            const double e = std::exp(-s / vS);
            const double sa = std::pow(s, a);
            const double G = fb + fdS * e + kv * sa;
            F -= th * G;
            if constexpr (WithJac) {
                const double Gp = -fdS / vS * e + a * kv * sa / s;
                dF_dv -= (1.0 - th * th) / vr * G + th * Gp * (v / s);
            }
        }
        if (x < 0.0) {
            const double q = k_stop * (-x) + d_stop * (-v);
            if (q > 0.0) {
                F += q;
                dF_dx -= k_stop;
                dF_dv -= d_stop;
            }
        } else if (x > L) {
            const double q = k_stop * (x - L) + d_stop * v;
            if (q > 0.0) {
                F -= q;
                dF_dx -= k_stop;
                dF_dv -= d_stop;
            }
        }
        f[IX] = v;
        f[IV] = F / m;
        if constexpr (WithJac) {
            for (int z = 0; z < NX; ++z) J[IX][z] = J[IV][z] = 0.0;
            J[IX][IV] = 1.0;
            J[IV][IX] = dF_dx / m;
            J[IV][IV] = dF_dv / m;
            J[IV][IPA] = A_A / m;
            J[IV][IPE] = -A_ann / m;
            J[IV][IPC] = -A_CP / m;
        }
        return true;
    }
};

double table_C(const RigParams& P, double z) {
    const auto& t = P.C_of_z;
    if (t.empty()) return 0.0;
    if (z <= t.front().first) return t.front().second;
    if (z >= t.back().first) return t.back().second;
    for (std::size_t i = 1; i < t.size(); ++i) {
        if (z <= t[i].first) {
            const double w = (z - t[i - 1].first) / (t[i].first - t[i - 1].first);
            return t[i - 1].second + w * (t[i].second - t[i - 1].second);
        }
    }
    return t.back().second;
}

Model make_model(const RigParams& P) {
    constexpr double pi = 3.14159265358979323846;
    Model M;
    M.R = P.R;
    M.kappa = P.kappa;
    M.km1 = P.kappa - 1.0;
    M.cp = P.kappa * P.R / (P.kappa - 1.0);
    M.T_ref = P.T_ref;
    M.r_lam = P.laminar_ratio;
    M.p_sup = P.p_supply;
    M.T_sup = P.T_amb;
    M.p_amb = P.p_amb;
    M.T_amb = P.T_amb;
    const double A_B = pi * P.bore * P.bore / 4.0;
    M.A_R = pi * P.rod * P.rod / 4.0;
    M.A_A = A_B - M.A_R;
    M.A_CP = pi * P.plug_diameter * P.plug_diameter / 4.0;
    M.A_ann = A_B - M.A_CP;
    M.L = P.stroke;
    M.x_plug = P.stroke - P.cushion_length;
    M.ramp = P.bore_opening_ramp;
    M.V0A = P.dead_volume_rod_side;
    M.V0E = P.dead_volume_cushion;
    M.V0C = P.dead_volume_channel;
    M.VLB = P.line_B_volume;
    const double k = kCUnit * P.rho_ref;
    M.K_valve = P.valve_C * k;
    M.b_valve = P.valve_b;
    M.K_bore = P.bore_opening_C * k;
    M.b_bore = P.bore_opening_b;
    const double Ccush = table_C(P, P.z_EC);
    M.K_cush = Ccush * k;
    M.b_cush = P.cushion_b0 + P.cushion_b_slope * Ccush / P.cushion_C_max;
    M.K_mo = P.meter_out_C * k;
    M.b_mo = P.meter_out_b;
    M.m = P.m_load;
    M.k_stop = P.stop_stiffness;
    M.d_stop = P.stop_damping;
    M.vr = P.friction_v_reg;
    M.eps = P.friction_abs_eps;
    M.fb = P.fr_b;
    M.fdS = P.fr_FS - P.fr_FC;
    M.vS = P.fr_vS;
    M.kv = P.fr_kv;
    M.a = P.fr_a;
    return M;
}

std::array<double, NX> initial_state(const RigParams& P, const Model& M) {
    std::array<double, NX> y{};
    const double Fp = M.pressure_force(P.p_amb, P.p_supply, P.p_supply);
    y[IX] = std::min(0.0, Fp / P.stop_stiffness);  // stop force k*(-x) balances Fp
    y[IV] = 0.0;
    y[IPA] = P.p_amb;
    y[ITA] = P.T_amb;
    y[IPE] = P.p_supply;
    y[ITE] = P.T_amb;
    y[IPC] = P.p_supply;
    y[ITC] = P.T_amb;
    y[IPB] = P.p_supply;
    y[ITB] = P.T_amb;
    return y;
}

// ---------------------------------------------------------------------------
// SUNDIALS callbacks

// What the callbacks share: the model and, when the Newton matrix is reused
// the way pneumo reuses it (SolverOptions::jacobian_reuse), the df/dy of its
// last evaluation. Here F = y' - f(y), so the matrix is cj I - df/dy and a
// request that only follows a change of cj needs no evaluation.
struct Session {
    Model model;
    void* ida = nullptr;
    bool jacobian_reuse = false;
    bool jac_valid = false;
    long steps_at = 0, conv_failures_at = 0, recombined = 0;
    double J[NX][NX];
};
constexpr long kMaxJacobianAgeSteps = 50;  // as pneumo's NewtonMatrixParts

int residual(sunrealtype /*t*/, N_Vector yy, N_Vector yp, N_Vector rr, void* user) {
    const Model& M = static_cast<const Session*>(user)->model;
    const double* y = N_VGetArrayPointer(yy);
    const double* ydot = N_VGetArrayPointer(yp);
    double* r = N_VGetArrayPointer(rr);
    double f[NX];
    if (!M.eval<false>(y, f, nullptr)) return 1;  // recoverable: IDA cuts the step
    for (int i = 0; i < NX; ++i) r[i] = ydot[i] - f[i];
    return 0;
}

int jacobian(sunrealtype /*t*/, sunrealtype cj, N_Vector yy, N_Vector /*yp*/, N_Vector /*rr*/,
             SUNMatrix Jm, void* user, N_Vector, N_Vector, N_Vector) {
    Session& S = *static_cast<Session*>(user);
    const double* y = N_VGetArrayPointer(yy);
    double f[NX];
    auto& J = S.J;
    long steps = 0, conv_failures = 0;
    if (S.jacobian_reuse) {  // the floor as written asks IDA nothing here
        IDAGetNumSteps(S.ida, &steps);
        IDAGetNumNonlinSolvConvFails(S.ida, &conv_failures);
    }
    if (S.jacobian_reuse && S.jac_valid && conv_failures == S.conv_failures_at && steps >= S.steps_at &&
        steps - S.steps_at < kMaxJacobianAgeSteps) {
        ++S.recombined;
    } else {
        S.jac_valid = false;
        if (!S.model.eval<true>(y, f, J)) return 1;
        S.jac_valid = true;
        S.steps_at = steps;
        S.conv_failures_at = conv_failures;
    }
    // IDA zeroes the sparse matrix (including its pattern) before each call,
    // so the (constant) CSC pattern is rewritten every time.
    sunindextype* colptr = SUNSparseMatrix_IndexPointers(Jm);
    sunindextype* rowval = SUNSparseMatrix_IndexValues(Jm);
    double* data = SUNSparseMatrix_Data(Jm);
    sunindextype nz = 0;
    for (int j = 0; j < NX; ++j) {
        colptr[j] = nz;
        for (int i = 0; i < NX; ++i) {
            if (!kPattern[i][j]) continue;
            rowval[nz] = i;
            data[nz] = (i == j ? cj : 0.0) - J[i][j];
            ++nz;
        }
    }
    colptr[NX] = nz;
    return 0;
}

// ---------------------------------------------------------------------------
// RAII wrappers
struct CtxDel {
    void operator()(SUNContext c) const { SUNContext_Free(&c); }
};
struct NVecDel {
    void operator()(_generic_N_Vector* v) const { N_VDestroy(v); }
};
struct MatDel {
    void operator()(_generic_SUNMatrix* m) const { SUNMatDestroy(m); }
};
struct LSDel {
    void operator()(_generic_SUNLinearSolver* s) const { SUNLinSolFree(s); }
};
struct IdaDel {
    void operator()(void* mem) const { IDAFree(&mem); }
};
using CtxPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, CtxDel>;
using NVecPtr = std::unique_ptr<_generic_N_Vector, NVecDel>;
using MatPtr = std::unique_ptr<_generic_SUNMatrix, MatDel>;
using LSPtr = std::unique_ptr<_generic_SUNLinearSolver, LSDel>;
using IdaPtr = std::unique_ptr<void, IdaDel>;

void check(int flag, const char* what) {
    if (flag < 0) {
        const char* name = IDAGetReturnFlagName(flag);
        std::string msg = std::string("pneumo_reference: ") + what + " failed with flag " +
                          std::to_string(flag) + " (" + (name ? name : "?") + ")";
        // IDAGetReturnFlagName returns malloc'd memory
        free(const_cast<char*>(name));
        throw std::runtime_error(msg);
    }
}

void check_ptr(const void* p, const char* what) {
    if (!p) throw std::runtime_error(std::string("pneumo_reference: ") + what + " returned NULL");
}

void add_stats(void* mem, RigStats& s) {
    long v = 0;
    IDAGetNumSteps(mem, &v);
    s.steps += v;
    IDAGetNumResEvals(mem, &v);
    s.residual_evals += v;
    IDAGetNumJacEvals(mem, &v);
    s.jacobian_evals += v;
    IDAGetNumErrTestFails(mem, &v);
    s.error_test_failures += v;
    IDAGetNumNonlinSolvConvFails(mem, &v);
    s.nonlinear_conv_failures += v;
}

}  // namespace

double cushion_throttle_C(const RigParams& params, double z_EC) { return table_C(params, z_EC); }

double initial_position(const RigParams& params) {
    const Model M = make_model(params);
    return initial_state(params, M)[IX];
}

RigResult simulate(const RigParams& P, double t_end, double rtol, double output_interval,
                   void (*prepare_vector)(_generic_N_Vector*), bool jacobian_reuse) {
    if (!(t_end > 0.0) || !(output_interval > 0.0) || !(rtol > 0.0))
        throw std::runtime_error("pneumo_reference::simulate: invalid t_end/rtol/output_interval");

    Session session;
    session.model = make_model(P);
    session.jacobian_reuse = jacobian_reuse;
    Model& model = session.model;
    model.valves_open = P.t_switch <= 0.0;

    SUNContext raw_ctx = nullptr;
    if (SUNContext_Create(nullptr, &raw_ctx) != 0 || !raw_ctx)
        throw std::runtime_error("pneumo_reference: SUNContext_Create failed");
    CtxPtr ctx(raw_ctx);

    NVecPtr y(N_VNew_Serial(NX, ctx.get()));
    NVecPtr yp(N_VNew_Serial(NX, ctx.get()));
    NVecPtr atol(N_VNew_Serial(NX, ctx.get()));
    check_ptr(y.get(), "N_VNew_Serial");
    check_ptr(yp.get(), "N_VNew_Serial");
    check_ptr(atol.get(), "N_VNew_Serial");
    if (prepare_vector)
        for (N_Vector v : {y.get(), yp.get(), atol.get()}) prepare_vector(v);
    double* yd = N_VGetArrayPointer(y.get());
    double* ypd = N_VGetArrayPointer(yp.get());
    double* ad = N_VGetArrayPointer(atol.get());

    const auto y0 = initial_state(P, model);
    std::copy(y0.begin(), y0.end(), yd);
    auto consistent_yp = [&]() {
        if (!model.eval<false>(yd, ypd, nullptr))
            throw std::runtime_error("pneumo_reference: non-physical state at (re)start");
    };
    consistent_yp();

    const double scale[NX] = {0.01, 0.1, 1e5, 300.0, 1e5, 300.0, 1e5, 300.0, 1e5, 300.0};
    for (int i = 0; i < NX; ++i) ad[i] = rtol * scale[i];

    MatPtr A(SUNSparseMatrix(NX, NX, kNnz, CSC_MAT, ctx.get()));
    check_ptr(A.get(), "SUNSparseMatrix");
    LSPtr LS(SUNLinSol_KLU(y.get(), A.get(), ctx.get()));
    check_ptr(LS.get(), "SUNLinSol_KLU");

    IdaPtr mem(IDACreate(ctx.get()));
    check_ptr(mem.get(), "IDACreate");
    void* ida = mem.get();
    check(IDAInit(ida, residual, 0.0, y.get(), yp.get()), "IDAInit");
    check(IDASVtolerances(ida, rtol, atol.get()), "IDASVtolerances");
    session.ida = ida;
    check(IDASetUserData(ida, &session), "IDASetUserData");
    check(IDASetLinearSolver(ida, LS.get(), A.get()), "IDASetLinearSolver");
    check(IDASetJacFn(ida, jacobian), "IDASetJacFn");
    check(IDASetMaxNumSteps(ida, 200000), "IDASetMaxNumSteps");

    bool switched = model.valves_open || P.t_switch >= t_end;
    check(IDASetStopTime(ida, switched ? t_end : P.t_switch), "IDASetStopTime");

    RigResult res;
    const long n_out = static_cast<long>(std::ceil(t_end / output_interval - 1e-9));
    res.samples.reserve(static_cast<std::size_t>(n_out) + 2);
    auto record = [&](double t) {
        res.samples.push_back({t, yd[IX], yd[IV], yd[IPA], yd[IPE], yd[ITE], yd[IPC]});
    };
    record(0.0);

    double t = 0.0;
    for (long k = 1; k <= n_out; ++k) {
        const double tout = std::min(static_cast<double>(k) * output_interval, t_end);
        if (!switched && tout >= P.t_switch * (1.0 - 1e-12)) {
            check(IDASolve(ida, P.t_switch, &t, y.get(), yp.get(), IDA_NORMAL), "IDASolve");
            add_stats(ida, res.stats);
            model.valves_open = true;
            session.jac_valid = false;
            consistent_yp();
            t = P.t_switch;
            check(IDAReInit(ida, t, y.get(), yp.get()), "IDAReInit");
            check(IDASetStopTime(ida, t_end), "IDASetStopTime");
            switched = true;
        }
        if (tout > t) check(IDASolve(ida, tout, &t, y.get(), yp.get(), IDA_NORMAL), "IDASolve");
        record(tout);
    }
    add_stats(ida, res.stats);
    res.stats.jacobian_evals -= session.recombined;
    res.stats.jacobian_recombinations = session.recombined;
    return res;
}

double jacobian_self_check(const RigParams& P) {
    Model M = make_model(P);
    const auto y0 = initial_state(P, M);
    // a handful of states covering the different flow branches and regions
    const double states[][NX] = {
        {0.03, 0.3, 3.9e5, 290.0, 2.1e5, 280.0, 2.0e5, 281.0, 1.6e5, 275.0},
        {0.0799, 0.35, 4.2e5, 300.0, 2.5e5, 300.0, 2.2e5, 290.0, 1.5e5, 270.0},
        {0.0802, 0.2, 4.5e5, 300.0, 6.0e5, 380.0, 1.4e5, 270.0, 1.2e5, 260.0},
        {0.0999, -0.05, 4.9e5, 295.0, 1.0e5 * 1.0005, 300.0, 1.0e5, 301.0, 1.0e5 * 0.9995, 296.0},
        {0.10002, 0.01, 5.0e5, 293.0, 2.0e5, 310.0, 1.2e5, 295.0, 1.05e5, 290.0},
        {-2e-5, -1e-3, 1.5e5, 280.0, 4.0e5, 260.0, 3.9e5, 262.0, 3.0e5, 255.0},
        {0.05, 3e-5, 4.0e5, 300.0, 1.2e5, 290.0, 1.2e5 * 0.99995, 289.0, 1.1e5, 285.0},
        {y0[0], y0[1], y0[2], y0[3], y0[4], y0[5], y0[6], y0[7], y0[8], y0[9]},
    };
    const double scale[NX] = {0.1, 0.1, 1e5, 300.0, 1e5, 300.0, 1e5, 300.0, 1e5, 300.0};
    double worst = 0.0;
    for (int open = 0; open < 2; ++open) {
        M.valves_open = open != 0;
        for (const auto& s : states) {
            double y[NX], f[NX], fp[NX], fm[NX], J[NX][NX];
            std::copy(s, s + NX, y);
            if (!M.eval<true>(y, f, J)) continue;
            // row scaling: typical magnitude of each row of J
            for (int j = 0; j < NX; ++j) {
                const double h = 1e-7 * scale[j];
                double yy[NX];
                std::copy(y, y + NX, yy);
                yy[j] = y[j] + h;
                M.eval<false>(yy, fp, nullptr);
                yy[j] = y[j] - h;
                M.eval<false>(yy, fm, nullptr);
                for (int i = 0; i < NX; ++i) {
                    const double fd = (fp[i] - fm[i]) / (2 * h);
                    if (!kPattern[i][j] && J[i][j] != 0.0) worst = std::max(worst, 1e300);
                    const double err = std::abs(J[i][j] - fd) / (std::abs(fd) + 1e-6 * std::abs(J[i][j]) + 1e-3);
                    worst = std::max(worst, err);
                }
            }
        }
    }
    return worst;
}

}  // namespace pneumo_reference
