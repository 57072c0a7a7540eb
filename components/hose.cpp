// Pneumatic hose (tube) from inner diameter D and length L, lumped into N
// segments on a staggered grid:
//
//   a --[L/2N]-- (V_1) --[L/N]-- (V_2) ... (V_N) --[L/2N]-- b
//
// Each segment volume V = A L/N (A = pi D^2/4) has the mass and energy balance
// of components/volume.cpp (states m, U; ideal gas; adiabatic wall), each of
// the N + 1 flow elements (length l) the friction law
//
//   dp_f = 32 mu l w / (rho A D^2) * max(1, (Re/Re_t)^(3/4)),  Re = |w| D/(A mu)
//
// i.e. the Darcy-Weisbach loss with friction factor max(64/Re, 0.3164 Re^-1/4)
// (Hagen-Poiseuille laminar, Blasius turbulent, continuous where they meet at
// Re_t = (64/0.3164)^(4/3) = 1187), rho = p_mean / (R T) with the element's
// mean pressure (p_l + p_r)/2 and the adjacent segment temperature(s). With
// the mean pressure the lumped line reproduces the isothermal compressible
// pipe law p_a^2 - p_b^2 = f(Re) (L/D) w^2 R T / A^2 exactly at steady flow,
// for any N.
//
// Without inertia each element is algebraic (dp = dp_f(w)); with
// `inertia: true` it carries the momentum balance
//   (l/A) dw/dt = p_l - p_r - dp_f(w),
// so that with the segments' adiabatic capacitance a pressure wave travels at
// sqrt(kappa R T) (choose enough segments for the wave you want to see:
// the line's cutoff frequency is about N c/(pi L)). Convective momentum and
// kinetic energy are neglected. Flow elements are isenthalpic; the energy
// flow between segments is upwinded (enthalpy_flow.hpp).
#include <cmath>
#include <memory>
#include <numbers>

#include "components/builtin.hpp"
#include "components/faults.hpp"
#include "components/enthalpy_flow.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class Hose final : public ComponentT<Hose> {
 public:
  enum Port { kA, kB };
  static constexpr int kMaxSegments = 16;

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "hose";
    i.description =
        "Hose/tube of inner diameter D and length L in N lumped segments: segment volumes with mass and energy "
        "balance, flow elements with laminar (Hagen-Poiseuille) / turbulent (Blasius) friction, optional inertia "
        "(pressure waves at the speed of sound). Adiabatic.";
    i.symbol = symbols::hose();
    i.parameters = {
        ParameterSpec::scalar("D", "m", "inner diameter, e.g. 4 mm").positive(),
        ParameterSpec::scalar("L", "m", "length, e.g. 2 m").positive().bare_up_to(1000.0),
        ParameterSpec::scalar("segments", "1", "number of lumped segments N (1 to 16)", 1.0).range(1.0, kMaxSegments),
        ParameterSpec::text("inertia", {"false", "true"}, "momentum balance of the gas in each flow element", "false"),
        ParameterSpec::scalar("mu", "Pa*s", "dynamic viscosity of the gas (air at 20 degC: 1.81e-5 Pa*s)", 1.81e-5)
            .positive(),
        ParameterSpec::scalar("p0", "Pa", "initial pressure, absolute; default: ambient")
            .positive()
            .absolute()
            .ambient_pressure_by_default(),
        ParameterSpec::scalar("T0", "K", "initial gas temperature; default: ambient")
            .positive()
            .ambient_temperature_by_default(),
    };
    i.ports = {{"a", Domain::pneumatic, Causality::acausal, "end a"},
               {"b", Domain::pneumatic, Causality::acausal, "end b"}};
    i.variables = variables(1);
    i.observables = {{"m_flow", "kg/s", "mass flow into end a"}, {"m_flow_b", "kg/s", "mass flow out of end b"}};
    i.faults = {fault("resistance", "flow resistance off (kinked, partly blocked or longer line), as a factor on the viscous resistance",
                      {fault_factor("mu", 0.25, 20.0, 2.0)})};
    return i;
  }

  explicit Hose(const Construction& c)
      : ComponentT(with_segments(c)),
        D_(c.params["D"]),
        L_(c.params["L"]),
        N_(segments(c.params)),
        inertia_(c.params.text("inertia") == "true"),
        mu_(c.params["mu"]),
        p0_(c.params["p0"]),
        T0_(c.params["T0"]) {
    A_ = std::numbers::pi / 4.0 * D_ * D_;
    V_ = A_ * L_ / N_;
  }

  // Index of the segment variables m_k, U_k (k = 0..N-1) and flows w_j (j = 0..N).
  int var_m(int k) const { return 2 * k; }
  int var_U(int k) const { return 2 * k + 1; }
  int var_w(int j) const { return 2 * N_ + j; }
  double element_length(int j) const { return (j == 0 || j == N_ ? 0.5 : 1.0) * L_ / N_; }

  // Friction pressure drop of an element of length l at mass flow w (a to b)
  // and density rho: laminar times max(1, (Re/Re_t)^(3/4)), the Blasius
  // factor beyond Re_t. The maximum is rounded, (a + b + sqrt((a - b)^2 +
  // delta^2)) / 2 with delta = kTransitionWidth: a sharp maximum put a kink
  // into an algebraic equation, and Newton cycled across it when a flow
  // settled near Re_t (the full cushion rig at 5 bar, 3 rev, t = 0.354 s).
  // The friction factor departs from the sharp law by at most delta/2 = 5 %
  // at Re_t, by 1.8 % at 0.84 Re_t and by < 1e-5 beyond 3 Re_t.
  static constexpr double kTransitionWidth = 0.1;
  template <class T>
  T friction(const T& w, const T& rho, double l) const {
    const double Re_t = std::pow(64.0 / 0.3164, 4.0 / 3.0);
    const double w_t = Re_t * A_ * mu_ / D_;
    const T laminar = 32.0 * mu_ * l * w / (rho * A_ * D_ * D_);
    const T turbulent_factor = pow(max(T(abs(w) / w_t), T(1e-12)), 0.75);
    const T factor = 0.5 * (1.0 + turbulent_factor + smooth_abs(T(turbulent_factor - 1.0), kTransitionWidth));
    return laminar * factor;
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto a = e.gas_port(kA);
    const auto b = e.gas_port(kB);
    const GasModel& gas = e.gas();
    T p[kMaxSegments], Tg[kMaxSegments];
    for (int k = 0; k < N_; ++k) {
      const T& m = e.var(var_m(k));
      e.reject_unless_positive(m);
      Tg[k] = e.var(var_U(k)) / (m * gas.cv());
      e.reject_unless_positive(Tg[k]);
      p[k] = m * gas.R * Tg[k] / V_;
    }
    // Energy flow through element j, positive toward b.
    auto H = [&](int j) {
      const T& w = e.var(var_w(j));
      const T& T_left = j == 0 ? a.T_in : Tg[j - 1];
      const T& T_right = j == N_ ? b.T_in : Tg[j];
      T right, left;
      upwind_weights(w, gas.m_flow_small, right, left);
      return T(gas.cp() * (right * T_left - left * T_right));
    };
    r[0] = a.m_flow - e.var(var_w(0));
    r[1] = b.m_flow + e.var(var_w(N_));
    r[2] = a.T_out - Tg[0];
    r[3] = b.T_out - Tg[N_ - 1];
    int row = 4;
    for (int k = 0; k < N_; ++k) {
      r[row++] = e.der(var_m(k)) - (e.var(var_w(k)) - e.var(var_w(k + 1)));
      r[row++] = e.der(var_U(k)) - (H(k) - H(k + 1));
    }
    for (int j = 0; j <= N_; ++j) {
      const T& p_l = j == 0 ? a.p : p[j - 1];
      const T& p_r = j == N_ ? b.p : p[j];
      const T T_el = j == 0 ? Tg[0] : (j == N_ ? Tg[N_ - 1] : T(0.5 * (Tg[j - 1] + Tg[j])));
      const T rho = 0.5 * (p_l + p_r) / (gas.R * T_el);
      const double l = element_length(j);
      const T balance = p_l - p_r - friction(e.var(var_w(j)), rho, l);
      r[row++] = inertia_ ? T(l / A_ * e.der(var_w(j)) - balance) : balance;
    }
  }

  double observe(int k, const Eval<double>& e) const override { return k == 0 ? e.var(var_w(0)) : e.var(var_w(N_)); }

  void start(StartValues& s, const GasModel& gas) const override {
    const double m0 = p0_ * V_ / (gas.R * T0_);
    for (int k = 0; k < N_; ++k) {
      s.fix_var(var_m(k), m0);
      s.fix_var(var_U(k), m0 * gas.cv() * T0_);
    }
    for (int j = 0; j <= N_; ++j) {
      if (inertia_)
        s.fix_var(var_w(j), 0.0);
      else
        s.guess_var(var_w(j), 0.0);
    }
    s.guess_pressure(kA, p0_);
    s.guess_pressure(kB, p0_);
    s.guess_temperature(kA, T0_);
    s.guess_temperature(kB, T0_);
  }

 private:
  static int segments(const ParameterValues& p) {
    const double n = p["segments"];
    if (n != std::floor(n)) throw ParameterError("segments", "segments must be a whole number");
    return static_cast<int>(n);
  }
  static std::vector<VariableSpec> variables(int n) {
    std::vector<VariableSpec> v;
    for (int k = 1; k <= n; ++k) {
      v.push_back({"m_" + std::to_string(k), "kg", "gas mass in segment " + std::to_string(k), 0.0, "U_" + std::to_string(k)});
      v.push_back({"U_" + std::to_string(k), "J", "internal energy in segment " + std::to_string(k)});
    }
    for (int j = 0; j <= n; ++j)
      v.push_back({"w_" + std::to_string(j), "kg/s",
                   "mass flow toward b through flow element " + std::to_string(j) + " (0: at a, N: at b)"});
    return v;
  }
  // The number of internal variables depends on `segments`: this component
  // gets its own copy of the type description with N segments' variables.
  static Construction with_segments(const Construction& c) {
    Construction k = c;
    auto info = std::make_shared<ComponentInfo>(*c.info);
    const int n = segments(c.params);
    info->variables = variables(n);
    info->equations.clear();
    k.info = std::move(info);
    return k;
  }

  double D_, L_;
  int N_;
  bool inertia_;
  double mu_, p0_, T0_;
  double A_ = 0.0, V_ = 0.0;
};

void register_hose(Registry& r) { r.add<Hose>(); }

}  // namespace pneumo::components
