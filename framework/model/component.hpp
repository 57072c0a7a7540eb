// The component interface.
//
// A component is immutable after construction: a description (parameters
// with unit, default and range; ports; internal variables), and equations
// written once as a template over the scalar type. The framework owns all
// state (y, y', discrete modes) and hands the component a read-only view of
// its local variables through Eval<T>. No Jacobian code, no solver code.
//
// Local variable layout (what Eval indexes into): the ports in declared
// order, each with its domain's variables, then the internal variables.
//   pneumatic:     p (across, Pa abs), m_flow (through, kg/s, positive INTO
//                  the component), T_out (stream: the temperature the gas
//                  leaving the component through this port has), T_in (the
//                  stream temperature of gas entering through the port, i.e.
//                  Modelica's inStream(T_out); supplied by the framework)
//   thermal:       T (across, K), Q (through, W, positive into the component)
//   translational: s (across, position, m), f (through, force on the
//                  component at this flange, N), v (across, velocity, m/s;
//                  the framework adds ds/dt = v once per node, so that
//                  components use v as a variable and not s' - which would
//                  put stiff damping and friction slopes on the 1/h diagonal)
//   signal:        value (across)
// A component provides one equation per through variable, one per stream
// variable T_out, one per signal output and one per internal variable.
//
// Memoisation, the one mutable state allowed: a component may cache, for
// T = double only, a pure function of its local variables (and parameters),
// keyed on the exact values it reads, because the framework evaluates one
// component several times at the same point within one residual call (the
// explicitly solved unknowns, then IDA's rows, then outputs). The cache must
// be invisible: bit-identical results to recomputing. It is kept per thread
// (PerThread, framework/model/per_thread.hpp): threads may integrate one
// assembled System at the same time, each with an Evaluator of its own, and
// nothing in a component instance may change while they do.
#pragma once

#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "framework/core/scalar.hpp"
#include "framework/model/gas.hpp"
#include "framework/model/symbol.hpp"

namespace pneumo {

enum class Domain { pneumatic, thermal, translational, signal };
enum class Causality { acausal, input, output };

const char* domain_name(Domain d);
// Number of local variables of a port of this domain.
int port_width(Domain d);
// Number of equations the component owes per port of this kind.
int port_equations(Domain d, Causality c);

struct PortSpec {
  std::string name;
  Domain domain = Domain::pneumatic;
  Causality causality = Causality::acausal;
  std::string description;
  // An optional port may stay unconnected: a pneumatic or thermal port is
  // then closed (no flow), a mechanical flange free (no force), a signal
  // input holds `default_value`.
  bool optional = false;
  double default_value = 0.0;
};

enum class ParameterKind { scalar, table, text };

using Table = std::vector<std::vector<double>>;

struct ParameterSpec {
  std::string name;
  std::string unit;  // SI unit expression, e.g. "Pa", "m3", "m3/(s*Pa)", "1"
  std::string description;
  ParameterKind kind = ParameterKind::scalar;
  std::optional<double> default_value;  // scalars; none = required
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  bool max_exclusive = false;
  // tables: units of the columns (rows are read as SI numbers or quantities)
  std::vector<std::string> columns;
  bool required_table = true;
  bool is_optional = false;
  // An absolute pressure (a start pressure, a supply, a set point): the only
  // pressures a gauge unit (barg, psig) may give. Every other pressure is a
  // difference (a cracking pressure, a band, a droop, a hysteresis), which
  // the ambient pressure a gauge unit adds would falsify: 0.2 barg is 1.21 bar.
  bool is_absolute = false;
  // The largest SI value a bare number (no unit) may give, where it differs
  // from its dimension's (units::habitual_unit_if_implausible): a hose of
  // 20 m is plausible where a bore of 40 m is not. 0: the dimension's.
  double bare_max = 0.0;
  // A start value or gas temperature that, left out, is the netlist's
  // ambient pressure or temperature (`ambient:`): a chamber written without
  // p0 is at rest with its surroundings whatever they are. default_value
  // holds the standard ambient for where no netlist is at hand.
  enum class Ambient { none, pressure, temperature };
  Ambient ambient_default = Ambient::none;
  // text parameters: allowed values (empty = any), default
  std::vector<std::string> choices;
  std::optional<std::string> default_text;
  // A text parameter naming a file: a relative name is read from the
  // netlist's folder (so a netlist runs from any working directory).
  bool is_path = false;

  // Builders so that a component's parameter list reads like a table.
  static ParameterSpec scalar(std::string name, std::string unit, std::string description,
                              std::optional<double> default_value = std::nullopt) {
    ParameterSpec s;
    s.name = std::move(name);
    s.unit = std::move(unit);
    s.description = std::move(description);
    s.default_value = default_value;
    return s;
  }
  static ParameterSpec table(std::string name, std::vector<std::string> columns,
                             std::string description, bool required = true) {
    ParameterSpec s;
    s.name = std::move(name);
    s.kind = ParameterKind::table;
    s.columns = std::move(columns);
    s.description = std::move(description);
    s.required_table = required;
    return s;
  }
  static ParameterSpec text(std::string name, std::vector<std::string> choices,
                            std::string description, std::optional<std::string> def) {
    ParameterSpec s;
    s.name = std::move(name);
    s.kind = ParameterKind::text;
    s.choices = std::move(choices);
    s.description = std::move(description);
    s.default_text = std::move(def);
    return s;
  }
  // May be left out (the component checks ParameterValues::has()).
  ParameterSpec optional() && { required_table = false; is_optional = true; return std::move(*this); }
  ParameterSpec absolute() && { is_absolute = true; return std::move(*this); }
  ParameterSpec ambient_pressure_by_default() && {
    ambient_default = Ambient::pressure;
    default_value = 101325.0;
    return std::move(*this);
  }
  ParameterSpec ambient_temperature_by_default() && {
    ambient_default = Ambient::temperature;
    default_value = 293.15;
    return std::move(*this);
  }
  // The value a left-out scalar takes in a netlist of this ambient.
  std::optional<double> default_at(double p_ambient, double T_ambient) const {
    if (ambient_default == Ambient::pressure) return p_ambient;
    if (ambient_default == Ambient::temperature) return T_ambient;
    return default_value;
  }
  // The default as the reference shows it.
  std::string default_text_of_scalar() const;
  ParameterSpec path() && { is_path = true; return std::move(*this); }
  ParameterSpec bare_up_to(double si) && { bare_max = si; return std::move(*this); }
  ParameterSpec positive() && { min = 0.0; min_exclusive = true; return std::move(*this); }
  ParameterSpec non_negative() && { min = 0.0; return std::move(*this); }
  ParameterSpec range(double lo, double hi) && { min = lo; max = hi; return std::move(*this); }
  ParameterSpec open_range(double lo, double hi) && {
    min = lo; max = hi; min_exclusive = max_exclusive = true; return std::move(*this);
  }
  std::string range_text() const;
  bool in_range(double v) const;
};

struct VariableSpec {
  std::string name;
  std::string unit;
  std::string description;
  // Typical magnitude used to scale absolute tolerances; 0 = from the unit.
  double nominal = 0.0;
  // For a gas mass: the variable holding the same gas's internal energy U.
  // Gas that enters or leaves unseen (a disturbance of the mass balance,
  // SolverOptions::disturbances) carries its enthalpy kappa U / m with it.
  std::string internal_energy = {};
};

struct ObservableSpec {
  std::string name;
  std::string unit;
  std::string description;
  // What the framework may use the observable for without knowing the
  // component: "kinetic_energy" (J) marks the energy a mass stores, which an
  // energy audit counts for every mass on the audited flange's node.
  std::string role = {};
};

// A fault mode an FMEA of the component would list (a leaking seal, a slow
// valve, a clogged throttle), for diagnosis without a hand-written
// catalogue. Each fault parameter sets one of the component's own
// parameters, which its equations read; at the null the fault vanishes and
// the model is the fault-free one, bit for bit (a fault-only parameter
// defaults to its null; a factor fault at 1 multiplies by 1).
struct FaultParameterSpec {
  std::string name;       // the fault's name for it ("C", "k")
  std::string parameter;  // the component parameter it sets
  std::string unit;       // of the fault's value (a factor: "1")
  // The value is a factor on the instance's own value of `parameter`
  // (misadjusted, clogged, mass off), else the parameter's SI value.
  bool factor = false;
  double null_value = 0, lower = 0, upper = 0, initial = 0;  // plausible range, SI (or factors)
  bool log_scale = false;
};
struct FaultSpec {
  std::string name;         // e.g. "piston_seal_leak"; diagnosis names it COMPONENT.FAULT
  std::string description;  // what fails, in the words of a maintenance list
  std::vector<FaultParameterSpec> parameters;
  // A fault of an optional part exists only where the part does: where the
  // instance is given this parameter (rod-end cushioning's plug), or where
  // this port of it is connected (a valve path's opening signal); naming
  // both, where either is (a valve's command: a schedule or a signal).
  // Empty: always.
  std::string needs_parameter = {};
  std::string needs_port = {};
  // A value someone sets by hand (a needle, a knob, a dial, a set screw, a
  // switch's place on its rail) turned off its setting. Settings are turned
  // far more often than parts fail, so where the runs cannot tell such a
  // fault from the failure of a part of the same component, the diagnosis
  // names the setting first.
  bool setting = false;
};

// A tagged event a component raises (EventResult::tag), which metrics,
// energy audits and diagnosis phases name as COMPONENT.TAG. A tag ending in
// "_K" stands for a numbered family: step_K covers step_2, step_3, ...
struct EventSpec {
  std::string tag;
  std::string description;  // when it happens, in the user's words
  bool matches(const std::string& t) const;
};

struct ComponentInfo {
  std::string type;
  std::string description;
  std::vector<ParameterSpec> parameters;
  std::vector<PortSpec> ports;
  std::vector<VariableSpec> variables;      // internal variables
  std::vector<ObservableSpec> observables;  // derived outputs
  std::vector<std::string> equations;       // optional names, for diagnostics
  int modes = 0;                            // discrete state values
  int roots = 0;                            // state event functions
  // The modes follow the inputs: on_inputs_changed is called after every
  // re-initialisation (event iteration).
  bool follows_inputs = false;
  std::vector<FaultSpec> faults;  // what can fail in this component (none: nothing declared)
  // Every tag its events carry; a netlist naming another is refused at load
  // (none: it raises no event a metric can name).
  std::vector<EventSpec> events;
  // Its ISO 1219-1 symbol (framework/model/symbol.hpp); empty: `pneumo
  // draw` draws a box with the ports named.
  Symbol symbol;

  int port_index(const std::string& name) const;
  const ParameterSpec* parameter(const std::string& name) const;
  bool raises(const std::string& tag) const;
  std::string event_list() const;  // "cycle_start, step_K, cycle_end" or "none"
};

// Parameter values after unit conversion and range checks, SI.
class ParameterValues {
 public:
  double operator[](const std::string& name) const { return scalar(name); }
  double scalar(const std::string& name) const;
  const Table& table(const std::string& name) const;
  const std::string& text(const std::string& name) const;
  bool has(const std::string& name) const;

  void set_scalar(const std::string& name, double v) { scalars_[name] = v; }
  void set_table(const std::string& name, Table t) { tables_[name] = std::move(t); }
  void set_text(const std::string& name, std::string t) { texts_[name] = std::move(t); }
  // Every value the same, bit for bit (a NaN "not given" equals itself).
  bool same_bits(const ParameterValues& other) const;

 private:
  std::map<std::string, double> scalars_;
  std::map<std::string, Table> tables_;
  std::map<std::string, std::string> texts_;
};

// Thrown by a component constructor when a combination of parameter values is
// invalid; the netlist layer adds file, line and component name.
class ParameterError : public std::runtime_error {
 public:
  ParameterError(std::string parameter, const std::string& message)
      : std::runtime_error(message), parameter_(std::move(parameter)) {}
  const std::string& parameter() const { return parameter_; }

 private:
  std::string parameter_;
};

// Throws ParameterError unless the first column of `table` strictly
// increases (interpolation tables, schedules); `what` names that column.
void require_increasing(const Table& table, const std::string& parameter, const std::string& what);

template <class T>
struct GasPortView {
  const T& p;
  const T& m_flow;
  const T& T_out;
  const T& T_in;
};
template <class S>
struct HeatPortView {
  const S& T;  // temperature
  const S& Q;  // heat flow into the component
};
template <class T>
struct FlangeView {
  const T& s;
  const T& f;
  const T& v;  // velocity (= ds/dt, an algebraic link kept by the framework)
  const T& a;  // dv/dt
};

class Component;

// Read-only view of one component's local variables during an evaluation.
template <class T>
class Eval {
 public:
  Eval(const Component& c, double t, const T* y, const T* yp, const double* modes,
       const bool* connected, const GasModel& gas, bool* invalid)
      : c_(c), t_(t), y_(y), yp_(yp), modes_(modes), connected_(connected), gas_(gas),
        invalid_(invalid) {}

  double t() const { return t_; }
  const GasModel& gas() const { return gas_; }
  const T& y(int local) const { return y_[local]; }
  const T& yp(int local) const { return yp_[local]; }

  inline GasPortView<T> gas_port(int port) const;
  inline HeatPortView<T> heat_port(int port) const;
  inline FlangeView<T> flange(int port) const;
  inline const T& signal(int port) const;
  inline const T& var(int k) const;  // internal variable k
  inline const T& der(int k) const;  // its time derivative
  inline int port_offset(int port) const;
  double mode(int k) const { return modes_[k]; }
  bool connected(int port) const { return connected_[port]; }

  // Flag the evaluation as invalid (e.g. a pressure <= 0 during a Newton
  // iterate): IDA then retries with a smaller step instead of failing.
  void reject_unless_positive(const T& x) const {
    if (!(value(x) > 0.0)) *invalid_ = true;
  }

 private:
  const Component& c_;
  double t_;
  const T* y_;
  const T* yp_;
  const double* modes_;
  const bool* connected_;
  const GasModel& gas_;
  bool* invalid_;
};

// Start values for one component's local variables. `fix` marks a
// differential state whose initial value is given (IDACalcIC keeps it);
// `guess` is only a starting point for the consistent-initialisation Newton.
class StartValues {
 public:
  enum class Kind : unsigned char { none, guess, fixed };
  StartValues(const Component& c, double* values, Kind* kinds) : c_(c), v_(values), k_(kinds) {}
  void fix_var(int k, double v);
  void guess_var(int k, double v);
  void fix_local(int local, double v) { set(local, v, Kind::fixed); }
  void guess_local(int local, double v) { set(local, v, Kind::guess); }
  void guess_pressure(int port, double p);
  void guess_temperature(int port, double T);  // T_out of a gas port / T of a heat port
  void fix_position(int port, double s);
  void guess_position(int port, double s);
  void fix_velocity(int port, double v);

 private:
  void set(int local, double v, Kind k) {
    if (k_[local] == Kind::fixed && k != Kind::fixed) return;
    v_[local] = v;
    k_[local] = k;
  }
  const Component& c_;
  double* v_;
  Kind* k_;
};

enum class EventKind { time, root };

struct EventResult {
  bool changed = false;  // discrete modes changed: the solver re-initialises
  std::string message;   // for the event log ("" = not worth logging)
  // What happened, as a name netlist metrics, energy audits and diagnosis
  // phases refer to ("cushion_entry", "cap_impact"; written COMPONENT.TAG).
  // Empty: the event is only told to people.
  std::string tag = {};
};

// An energy balance a component declares over a window of its motion, so
// that `--energy-audit` and the audit metrics work on any component that
// has one. Each term is a sum of its observables' changes over the window
// and of their time integrals (IDAS quadratures), scaled by coefficients:
//   term = sum c_i (q_i(t_close) - q_i(t_open)) + sum d_j int q_j dt
// plus, where `kinetic` says so, the kinetic energy of the masses on the
// node of `kinetic_port` (observables of role "kinetic_energy") at the
// window's start or end. In a correct model the terms in and out balance;
// the residual is the solver's error.
struct EnergyTerm {
  enum class Kinetic { none, at_open, at_close };
  std::string name;         // machine name (YAML key, metric lookup)
  std::string description;  // for the printed table
  bool in = false;          // energy brought in (else where it went)
  std::vector<std::pair<std::string, double>> changes;
  std::vector<std::pair<std::string, double>> integrals;
  Kinetic kinetic = Kinetic::none;
};
struct EnergyAuditSpec {
  std::string title;             // "cap-end cushioning"
  std::string opens_at;          // tag of this component's event; "" = the run's start
  std::string open_description;  // "cushion entry"
  // The window closes when this observable first falls to 0 or below after
  // opening (a velocity: first standstill or reversal); "" = the run's end.
  std::string closes_when_not_positive;
  std::string kinetic_port;      // translational port whose node's masses count
  std::vector<EnergyTerm> terms;
};

// A value a program outside the circuit sets while it runs (an FMU's
// input, fmi2SetReal between steps). The component holds it in one of its
// discrete modes, which the framework writes; a change is a discontinuity,
// handled as an event's.
struct ExternalInputSpec {
  int mode = 0;      // the component's mode that holds the value
  double start = 0;  // its value until set (SI)
  std::string unit;  // SI unit of the value
  std::string description;
};

struct Construction {
  std::string name;
  std::shared_ptr<const ComponentInfo> info;
  ParameterValues params;
};

class Component {
 public:
  explicit Component(const Construction& c);
  virtual ~Component() = default;
  Component(const Component&) = delete;
  Component& operator=(const Component&) = delete;

  const std::string& name() const { return name_; }
  const ComponentInfo& info() const { return *info_; }
  int n_local() const { return n_local_; }
  int n_equations() const { return n_equations_; }
  int port_offset(int port) const { return port_offset_[port]; }
  int internal_offset() const { return internal_offset_; }

  virtual void residual(const Eval<double>& e, double* r) const = 0;
  virtual void residual(const Eval<Dual>& e, Dual* r) const = 0;
  virtual void residual(const Eval<Pattern>& e, Pattern* r) const = 0;

  // Initial values (fixed differential states) and guesses, in SI.
  virtual void start(StartValues& s, const GasModel& gas) const { (void)s; (void)gas; }
  virtual double observe(int k, const Eval<double>& e) const { (void)k; (void)e; return 0.0; }
  // out[i] = observe(ks[i], e) for i < n. Outputs ask for several
  // observables of one component at the same point: a component whose
  // observables share an expensive computation (flows, friction) overrides
  // this to do it once.
  virtual void observe_all(const int* ks, int n, const Eval<double>& e, double* out) const {
    for (int i = 0; i < n; ++i) out[i] = observe(ks[i], e);
  }

  // The energy balance this instance offers for auditing (none by default).
  virtual std::optional<EnergyAuditSpec> energy_audit(const GasModel& gas) const {
    (void)gas;
    return std::nullopt;
  }

  // Discrete modes and events. Time events are known in advance (the solver
  // stops there); roots are state events g(t, y, y') = 0 located by IDA.
  virtual void initial_modes(double* modes) const { (void)modes; }
  virtual std::vector<double> time_events() const { return {}; }
  virtual void roots(const Eval<double>& e, double* g) const { (void)e; (void)g; }
  // Update the discrete modes at an event (a time event of this component, or
  // its root function `root` crossing zero in direction `direction`).
  virtual EventResult on_event(const Eval<double>& e, double* modes, EventKind kind, int root,
                               int direction) const {
    (void)e; (void)modes; (void)kind; (void)root; (void)direction;
    return {};
  }

  // Whether optional heat port `port`, left unconnected, is held at the
  // ambient temperature (a wall at ambient temperature) instead of being
  // insulated (no heat flows, the default): a cylinder given a gas-to-wall
  // heat transfer coefficient means walls that exchange heat, and with
  // nothing connected to them those are walls at the ambient temperature.
  virtual bool unconnected_heat_port_at_ambient(int port) const {
    (void)port;
    return false;
  }

  // The values a program outside the circuit may set while it runs, named
  // after the component (none by default).
  virtual std::vector<ExternalInputSpec> external_inputs() const { return {}; }

  // What a run that ended here leaves unfinished and a user should hear -
  // a step chain still waiting for a switch that never closed - as one
  // sentence, or "" (the default). Asked once, after a run that succeeded.
  virtual std::string at_end(const Eval<double>& e, const double* modes) const {
    (void)e; (void)modes;
    return "";
  }

  // Event iteration (for types whose info says follows_inputs). After an
  // event changed some modes, the signals they drive jump at the
  // re-initialisation, where no root function can see the jump; the
  // framework then calls this at the new consistent values, again and again
  // (a bounded number of passes) until no component changes its modes. A
  // component switched by such signals re-reads its inputs here and updates
  // its modes as at an event (one discrete step per call).
  virtual EventResult on_inputs_changed(const Eval<double>& e, double* modes) const {
    (void)e; (void)modes;
    return {};
  }

 private:
  std::string name_;
  std::shared_ptr<const ComponentInfo> info_;
  std::vector<int> port_offset_;
  int internal_offset_ = 0;
  int n_local_ = 0;
  int n_equations_ = 0;
};

// CRTP glue: the derived class defines
//   template <class T> void equations(const Eval<T>& e, T* r) const;
template <class Derived>
class ComponentT : public Component {
 public:
  using Component::Component;
  void residual(const Eval<double>& e, double* r) const final { self().equations(e, r); }
  void residual(const Eval<Dual>& e, Dual* r) const final { self().equations(e, r); }
  void residual(const Eval<Pattern>& e, Pattern* r) const final { self().equations(e, r); }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

// ---------------------------------------------------------------------------
template <class T>
int Eval<T>::port_offset(int port) const {
  return c_.port_offset(port);
}
template <class T>
GasPortView<T> Eval<T>::gas_port(int port) const {
  const int o = c_.port_offset(port);
  return {y_[o], y_[o + 1], y_[o + 2], y_[o + 3]};
}
template <class T>
HeatPortView<T> Eval<T>::heat_port(int port) const {
  const int o = c_.port_offset(port);
  return {y_[o], y_[o + 1]};
}
template <class T>
FlangeView<T> Eval<T>::flange(int port) const {
  const int o = c_.port_offset(port);
  return {y_[o], y_[o + 1], y_[o + 2], yp_[o + 2]};
}
template <class T>
const T& Eval<T>::signal(int port) const {
  return y_[c_.port_offset(port)];
}
template <class T>
const T& Eval<T>::var(int k) const {
  return y_[c_.internal_offset() + k];
}
template <class T>
const T& Eval<T>::der(int k) const {
  return yp_[c_.internal_offset() + k];
}

}  // namespace pneumo
