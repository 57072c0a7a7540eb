// The one double-acting cylinder: a piston between two CylinderSides
// (components/cylinder_parts.hpp), either of them optionally cushioned, with
// elastic end stops, friction, optional wall heat and the chambers' faults.
// The registered types `cylinder` and `cushioned_cylinder` are presets of it
// (cylinder.cpp, cushioned_cylinder.cpp): a CylinderLayout fixes which end
// is at x = 0, how an end's cushioning is read from the parameters, whether
// the cushion annuli may be tapped, whether the friction has a separate set
// in the cushioning zones, and the names of the ports, states, rows,
// observables and events.
//
// The side at x = 0 ("near") is at travel d = x from its end, the other
// ("far") at d = stroke - x. The force on the piston pushes +x, away from
// x = 0:
//   F = F_near_gas - F_far_gas +- p_amb A_rod + F_friction + F_stops
// Internal variables, per side (near first): the cushion annulus' (m, U)
// when that end is cushioned, then the gas behind the port; LuGre's z last.
// Rows: per side (near first) the annulus' two and the chamber's four; the
// force balance; the walls (near, far); the taps (cap, rod); LuGre's.
// Roots: the far end's bore-opening ramp start and cushion entry (if
// cushioned), the stops at x = 0 and x = stroke, the near end's ramp start
// and cushion entry (if cushioned).
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "components/cylinder_parts.hpp"
#include "framework/model/per_thread.hpp"
#include "framework/model/registry.hpp"

namespace pneumo::components {

enum class CylinderEnd { cap, rod };

// What an observable reports, of which end where it depends on one.
struct CylinderQuantity {
  enum Kind {
    x, v, v_negative, p_port, p_piston, T_port, T_piston, bore_open, m_cushion, H_cushion, U_cushion, H_port, H_tap,
    Q_heat, pdV_side, pdV_port, pdV_annulus, pdV_channel, pdV_total, F_pressure, F_friction, F_stop, z, P_friction,
    P_stop, E_stop, U_gas
  };
  Kind kind;
  CylinderEnd end = CylinderEnd::cap;
};
struct CylinderObservable {
  ObservableSpec spec;
  CylinderQuantity quantity;
};

// One end's names and events.
struct CylinderEndLayout {
  std::vector<VariableSpec> chamber_variables, annulus_variables;  // (m, U) of each
  std::vector<std::string> chamber_rows, annulus_rows;             // CylinderSide's names
  std::string wall_row;
  std::vector<CylinderObservable> cushion_observables;  // only a cushioned end has
  std::optional<PortSpec> tap;                          // a port into the annulus (taps on)
  std::vector<std::string> tap_rows;
  // Entering and leaving the cushioning zone; the bore opening starting to
  // close and fully open.
  CylinderEvent entry, exit, closing, open;
};

// Which ends are cushioned, whether tapped: what an energy audit depends on.
struct CylinderShape {
  bool cap_cushioned, rod_cushioned, taps;
  double A_rod;
};

struct CylinderLayout {
  CylinderEnd at_zero;
  // Ports in the order: near port, far port, flange, near heat, far heat.
  std::vector<PortSpec> ports;
  std::vector<CylinderObservable> observables;  // every instance's
  CylinderEndLayout cap, rod;
  StopEvents stops;
  std::string dead_volume_cap, dead_volume_rod, p0_cap, p0_rod;  // parameter names
  bool cushion_friction;  // friction_cushion blended in by the bore openings
  bool (*cushioned)(const ParameterValues&, CylinderEnd);
  bool (*taps)(const ParameterValues&);
  // The end's cushioning; its side has face area A, the rod A_rod inside
  // the annulus (0 at the cap end).
  std::optional<CylinderSide::Cushioning> (*cushioning)(const ParameterValues&, CylinderEnd, double A,
                                                         double A_rod, double stroke);
  std::optional<EnergyAuditSpec> (*audit)(const CylinderShape&, const GasModel&);

  const CylinderEndLayout& end(CylinderEnd e) const { return e == CylinderEnd::cap ? cap : rod; }
  CylinderEnd far() const { return at_zero == CylinderEnd::cap ? CylinderEnd::rod : CylinderEnd::cap; }
};

class DoubleActingCylinder final : public ComponentT<DoubleActingCylinder> {
 public:
  enum Port { kNear, kFar, kFlange, kHeatNear, kHeatFar, kFirstTap };
  using End = CylinderEnd;

  // An instance's ports, variables, observables, rows and roots (the order
  // of the header); describe() passes everything on.
  static void add_parts(const CylinderLayout& l, ComponentInfo& i, bool cap_cushion, bool rod_cushion, bool taps,
                        FrictionState friction_state) {
    clear_parts(i);
    const auto cushioned = [&](End e) { return e == End::cap ? cap_cushion : rod_cushion; };
    InfoPart all{.ports = l.ports, .roots = 2};
    for (const auto& o : l.observables) all.observables.push_back(o.spec);
    for (End e : {End::cap, End::rod})
      if (cushioned(e))
        for (const auto& o : l.end(e).cushion_observables) all.observables.push_back(o.spec);
    add_part(i, all);
    for (End e : {l.at_zero, l.far()}) {
      const CylinderEndLayout& n = l.end(e);
      if (cushioned(e)) add_part(i, {.variables = n.annulus_variables, .equations = n.annulus_rows, .roots = 2});
      add_part(i, {.variables = n.chamber_variables, .equations = n.chamber_rows});
    }
    add_part(i, {.equations = {"force balance", l.end(l.at_zero).wall_row, l.end(l.far()).wall_row}});
    for (End e : {End::cap, End::rod})
      if (taps && cushioned(e) && l.end(e).tap) add_part(i, {.ports = {*l.end(e).tap}, .equations = l.end(e).tap_rows});
    add_friction_state(i, friction_state);
  }
  static ComponentInfo instance_info(const CylinderLayout& l, ComponentInfo i, const ParameterValues& p) {
    add_parts(l, i, l.cushioned(p, End::cap), l.cushioned(p, End::rod), l.taps(p), friction_state_of(p));
    return i;
  }
  // Registers the preset `describe` (which calls add_parts with all true).
  static void add_preset(Registry& r, const CylinderLayout& l, ComponentInfo describe) {
    r.add(std::move(describe),
          [&l](const Construction& c) { return std::make_unique<DoubleActingCylinder>(c, l); },
          [&l](ComponentInfo i, const ParameterValues& p) { return instance_info(l, std::move(i), p); });
  }

  DoubleActingCylinder(const Construction& c, const CylinderLayout& layout)
      : ComponentT(c),
        l_(layout),
        near_(layout.at_zero),
        A_(circle_area(c.params["bore"])),
        A_rod_(circle_area(c.params["rod"])),
        stroke_(c.params["stroke"]),
        cap_(A_, c.params[layout.dead_volume_cap], kCylinderPi * c.params["bore"]),
        rod_(A_ - A_rod_, c.params[layout.dead_volume_rod], kCylinderPi * (c.params["bore"] + c.params["rod"])),
        stops_{c.params["stop_stiffness"], c.params["stop_damping"]},
        wall_alpha_(c.params["wall_alpha"]),
        friction_(FrictionLaw::from(c.params)),
        friction_faults_(c.params),
        presliding_(c.params),
        chamber_faults_(c.params),
        x0_(c.params["x0"]),
        p0_cap_(c.params[layout.p0_cap]),
        p0_rod_(c.params[layout.p0_rod]),
        T0_(c.params["T0"]) {
    const auto& p = c.params;
    if (p["rod"] >= p["bore"]) throw ParameterError("rod", "rod diameter must be smaller than the bore");
    if (auto k = l_.cushioning(p, End::cap, A_, 0.0, stroke_)) cap_.cushion(*k);
    if (auto k = l_.cushioning(p, End::rod, A_ - A_rod_, A_rod_, stroke_)) rod_.cushion(*k);
    if (cap_.cushioned() && rod_.cushioned() &&
        cap_.cushion_length() + cap_.ramp() + rod_.cushion_length() + rod_.ramp() >= stroke_)
      throw ParameterError("rod_cushion_length",
                           "the cushioning zones (with their bore-opening ramps) at both ends overlap");
    stops_.hold_before_empty(side(near_).travel_to_empty(), side(l_.far()).travel_to_empty());
    place(l_.taps(p));
    quantities_ = instance_quantities();
    if (2 + static_cast<int>(info().variables.size()) > kMemoKey)
      throw std::logic_error(c.name + ": the state memo's key is too short for its variables");
  }

  // Everything derived from the local variables, for equations and outputs.
  template <class T>
  struct State {
    T x, v, z;
    CylinderSide::Gas<T> cap, rod;
    T F_pressure, F_fric, F_stop;
  };

  // It reads only the position, the velocity and the chambers' masses and
  // energies (not the port pressures: the gas-law rows make them U's), so
  // the framework can solve the ports' pressures and the flange force from
  // it in one pass. For double it is memoised on those inputs (the
  // contract's memoisation, framework/model/component.hpp): one residual
  // call evaluates the cylinder twice at the same state, and outputs
  // observe it at a point just evaluated.
  template <class T>
  std::conditional_t<std::is_same_v<T, double>, const State<double>&, State<T>> state(const Eval<T>& e) const {
    if constexpr (std::is_same_v<T, double>) {
      const int n = static_cast<int>(info().variables.size());
      double key[kMemoKey];
      key[0] = e.flange(kFlange).s;
      key[1] = e.flange(kFlange).v;
      for (int k = 0; k < n; ++k) key[2 + k] = e.var(k);
      Memo& m = memo_.get();
      if (m.valid && std::equal(key, key + 2 + n, m.key)) return m.state;
      m.state = compute_state(e);
      std::copy_n(key, 2 + n, m.key);
      m.valid = true;
      return m.state;
    } else {
      return compute_state(e);
    }
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto& s = state(e);
    const bool faulty = chamber_faults_.any();
    const auto ff = faulty ? chamber_faults_.flows(s.cap, &s.rod, e.gas(), side(End::cap).wall_area(travel(End::cap, s.x)),
                                                   side(End::rod).wall_area(travel(End::rod, s.x)))
                           : ChamberFaults::Flows<T>{};
    for (End end : {End::cap, End::rod})
      side(end).equations(e, e.gas_port(port(end)), e.heat_port(heat(end)), gas(s, end), travel(end, s.x),
                          rate(end, s.v), wall_alpha_, r, faulty ? &(end == End::cap ? ff.cap : ff.rod) : nullptr,
                          rows_[index(end)]);
    // The flange pulls on the cylinder with f = -F.
    const T F = s.F_pressure + s.F_fric + s.F_stop;
    r[force_row_] = e.flange(kFlange).f + F;
    if (friction_.has_state()) r[friction_row_] = e.der(z_var_) - friction_.lugre_zdot(s.v, e.var(z_var_));
    if (presliding_.on()) presliding_.rows(e, z_var_, s.v, friction_.v_eps, r + friction_row_);
  }

  double observe(int k, const Eval<double>& e) const override { return observe(k, state(e), e); }
  void observe_all(const int* ks, int n, const Eval<double>& e, double* out) const override {
    // Result files usually ask for positions, pressures and temperatures
    // only: those skip the flows and forces (most of state()'s work).
    State<double> s{};
    if (std::all_of(ks, ks + n, [&](int k) { return gas_observable(quantities_[k].kind); }))
      gas_state(e, s);
    else
      s = state(e);
    for (int i = 0; i < n; ++i) out[i] = observe(ks[i], s, e);
  }

  void roots(const Eval<double>& e, double* g) const override {
    const double x = e.flange(kFlange).s;
    for (std::size_t k = 0; k < roots_.size(); ++k) g[k] = x - root_position(roots_[k]);
  }

  // The ends of a bore-opening ramp are kinks of a flow area only
  // (continuous flows): they are logged at their exact times and IDA's
  // error control steps over them, as over any steep part of a flow law
  // (re-initialising there cost 6 % more work for the same trajectory).
  EventResult on_event(const Eval<double>& e, double*, EventKind, int root, int dir) const override {
    const std::string at = " at v = " + std::to_string(e.flange(kFlange).v) + " m/s";
    const Root& k = roots_[root];
    if (k.kind == Root::stop_zero || k.kind == Root::stop_stroke)
      return l_.stops.event(k.kind == Root::stop_zero, dir, at);
    const CylinderEndLayout& n = l_.end(k.end);
    const bool toward_end = k.end == near_ ? dir < 0 : dir > 0;
    const CylinderEvent& ev = k.kind == Root::ramp ? (toward_end ? n.closing : n.open)
                                                   : (toward_end ? n.entry : n.exit);
    return {false, ev.text + at, ev.tag};
  }

  // Walls that exchange heat (wall_alpha > 0) with nothing connected are at
  // the ambient temperature.
  bool unconnected_heat_port_at_ambient(int port) const override {
    return wall_alpha_ > 0 && (port == kHeatNear || port == kHeatFar);
  }

  std::optional<EnergyAuditSpec> energy_audit(const GasModel& gas) const override {
    return l_.audit({cap_.cushioned(), rod_.cushioned(), tap_port_[0] >= 0, A_rod_}, gas);
  }

  void start(StartValues& sv, const GasModel& gas) const override {
    double x = x0_;
    if (std::isnan(x)) {
      // At rest against the stop at x = 0: the stop carries the net pressure
      // force (friction is zero at rest).
      const double F = toward_far(0.0, p0_cap_ * A_, p0_rod_ * (A_ - A_rod_), gas.p_ambient * A_rod_);
      x = F < 0 ? -stops_.rest_penetration_low(-F) : 0.0;
    }
    sv.fix_position(kFlange, x);
    for (End end : {near_, l_.far()})
      side(end).start(sv, gas, port(end), heat(end), end == End::cap ? p0_cap_ : p0_rod_, T0_, travel(end, x));
    if (friction_.has_state()) sv.fix_var(z_var_, 0.0);
    if (presliding_.on()) presliding_.start(sv, z_var_);
  }

 private:
  struct Root {
    enum Kind { ramp, entry, stop_zero, stop_stroke } kind;
    End end;
  };

  static int index(End e) { return e == End::cap ? 0 : 1; }
  const CylinderSide& side(End e) const { return e == End::cap ? cap_ : rod_; }
  CylinderSide& side(End e) { return e == End::cap ? cap_ : rod_; }
  int port(End e) const { return e == near_ ? kNear : kFar; }
  int heat(End e) const { return e == near_ ? kHeatNear : kHeatFar; }
  template <class T>
  static const CylinderSide::Gas<T>& gas(const State<T>& s, End e) {
    return e == End::cap ? s.cap : s.rod;
  }
  // The side's travel from its end and its rate.
  template <class T>
  T travel(End e, const T& x) const {
    return e == near_ ? x : T(stroke_ - x);
  }
  template <class T>
  T rate(End e, const T& v) const {
    return e == near_ ? v : T(-v);
  }
  // Where the root crosses zero, in x.
  double root_position(const Root& k) const {
    if (k.kind == Root::stop_zero) return 0.0;
    if (k.kind == Root::stop_stroke) return stroke_;
    const CylinderSide& c = side(k.end);
    const double ramp = k.kind == Root::ramp ? c.ramp() : 0.0;
    return k.end == near_ ? c.cushion_length() + ramp : stroke_ - c.cushion_length() - ramp;
  }

  // Variables, rows, taps and roots in the order add_parts() names them.
  void place(bool taps) {
    int row = place_sides();
    force_row_ = row++;
    rows_[index(near_)].wall = row++;
    rows_[index(l_.far())].wall = row++;
    friction_row_ = place_taps(taps, row);
    place_roots();
  }
  // Each side's variables and rows, near side first: the annulus' (when
  // cushioned), then the chamber's; returns the next row.
  int place_sides() {
    int var = 0, row = 0;
    for (End end : {near_, l_.far()}) {
      CylinderSide& c = side(end);
      CylinderSide::Rows& at = rows_[index(end)];
      const int annulus = var;
      if (c.cushioned()) {
        var += 2;
        at.annulus = row;
        row += 2;
      }
      c.set_variables(var, annulus);
      var += 2;
      at.chamber = row;
      row += 4;
    }
    z_var_ = var;
    return row;
  }
  // The taps' ports and rows (cap, rod) from `row` on; returns the next row.
  int place_taps(bool taps, int row) {
    int tap_port = kFirstTap;
    for (End end : {End::cap, End::rod}) {
      if (!(taps && side(end).cushioned() && l_.end(end).tap)) continue;
      tap_port_[index(end)] = tap_port;
      side(end).tap(tap_port++);
      rows_[index(end)].tap = row;
      row += 2;
    }
    return row;
  }
  void place_roots() {
    const End far = l_.far();
    if (side(far).cushioned()) roots_.insert(roots_.end(), {{Root::ramp, far}, {Root::entry, far}});
    roots_.insert(roots_.end(), {{Root::stop_zero, near_}, {Root::stop_stroke, far}});
    if (side(near_).cushioned()) roots_.insert(roots_.end(), {{Root::ramp, near_}, {Root::entry, near_}});
  }

  // The pressure force pushing +x from the cap side's annulus and port
  // parts, the rod side's and the ambient's on the rod; the terms in the
  // order each preset's figures were measured with (their rounding).
  template <class T>
  T toward_far(const T& cap_annulus, const T& cap_port, const T& rod, double ambient_on_rod) const {
    if (near_ == End::rod) return rod + ambient_on_rod - cap_annulus - cap_port;
    return cap_annulus + cap_port - rod - ambient_on_rod;
  }

  static bool gas_observable(CylinderQuantity::Kind k) {
    using Q = CylinderQuantity;
    return k == Q::x || k == Q::v || k == Q::p_port || k == Q::p_piston || k == Q::T_port || k == Q::T_piston ||
           k == Q::U_gas;
  }
  // The position, velocity and the chambers' pressures and temperatures:
  // all that the gas observables need.
  template <class T>
  void gas_state(const Eval<T>& e, State<T>& s) const {
    const auto fl = e.flange(kFlange);
    s.x = fl.s;
    s.v = fl.v;
    s.cap = cap_.chambers(e, travel(End::cap, s.x));
    s.rod = rod_.chambers(e, travel(End::rod, s.x));
  }
  // A side's gas; the far side's gap to its plug, (stroke - L) - x, is
  // exactly the cushion-entry root's negative, so the bore closes at the root.
  template <class T>
  CylinderSide::Gas<T> side_gas(const Eval<T>& e, End end, const T& x) const {
    const CylinderSide& c = side(end);
    if (end == near_) return c.gas(e, x);
    return c.gas(e, T(stroke_ - x), T(stroke_ - c.cushion_length() - x));
  }
  template <class T>
  State<T> compute_state(const Eval<T>& e) const {
    const GasModel& gas = e.gas();
    const auto fl = e.flange(kFlange);
    State<T> s;
    s.x = fl.s;
    s.v = fl.v;
    s.cap = side_gas(e, End::cap, s.x);
    s.rod = side_gas(e, End::rod, s.x);
    s.z = presliding_.on()        ? presliding_.engagement(e, z_var_)
          : friction_.has_state() ? e.var(z_var_)
                                  : T(0.0 * s.x);
    s.F_fric = presliding_.on()
                   ? presliding_.engaged([&](const T& v) { return all_friction(s, v, gas.p_ambient); }, s.v, s.z,
                                         friction_)
                   : all_friction(s, s.v, gas.p_ambient);
    s.F_stop = stops_.force(s.x, s.v, stroke_);
    s.F_pressure = toward_far(cap_.annulus_force(s.cap), cap_.port_force(s.cap), rod_.force(s.rod),
                              gas.p_ambient * A_rod_);
    return s;
  }

  // The law's friction and the faults' at the velocity v (the state's own,
  // or with presliding the speed the magnitude is taken at).
  template <class T>
  T all_friction(const State<T>& s, const T& v, double p_ambient) const {
    T F = friction(s, v, p_ambient);
    if (friction_faults_.per_chamber_pressure > 0)
      F *= friction_faults_.law_factor(s.cap.p_piston, s.rod.p_piston, p_ambient);
    if (friction_faults_.any()) F += friction_faults_.force(v, s.cap.p_piston, s.rod.p_piston, friction_.v_reg);
    if (cap_.has_seal_drag() || rod_.has_seal_drag())
      F += cap_.cushion_seal_drag(s.cap, v, friction_.v_reg) + rod_.cushion_seal_drag(s.rod, v, friction_.v_reg);
    return F;
  }

  // The law's friction on the piston (+x) at the velocity v. With a
  // cushioning-zone set, the presets blend the main-stroke set and the
  // cushioning set (at each cushioned end) by the bore openings; a set whose
  // weight is 0 (the opening clamped at 0 or 1, so its derivative is 0 too)
  // is not evaluated, except for the structural pattern.
  template <class T>
  T friction(const State<T>& s, const T& v, double p_ambient) const {
    const T& p_rod = s.rod.p_piston;
    const T& p_cap = s.cap.p_piston;
    if (!l_.cushion_friction) return piston_friction(friction_, v, s.z, p_rod, p_cap, p_cap, p_ambient);
    const T zero = 0.0 * s.x;
    if (friction_.model != FrictionModel::preset) return friction_.force(friction_.main, v, s.z, zero);
    auto set = [&](const FrictionCoefficients& c, const T& p_cushion) {
      return friction_force(c, v, p_rod, p_cap, p_cushion, p_ambient, friction_.v_reg, friction_.v_eps);
    };
    constexpr bool structural = std::is_same_v<T, Pattern>;
    const double open = value(s.cap.open), open_r = value(s.rod.open);
    const T F_main = structural || (open > 0.0 && open_r > 0.0) ? set(friction_.main, p_cap) : zero;
    const T F_cush = structural || open < 1.0 ? set(friction_.cushion, p_cap) : zero;
    if (!rod_.cushioned()) return friction_.scale * (s.cap.open * F_main + (1.0 - s.cap.open) * F_cush);
    const T F_cush_r = structural || open_r < 1.0 ? set(friction_.cushion, p_rod) : zero;
    return friction_.scale *
           (s.cap.open * s.rod.open * F_main + (1.0 - s.cap.open) * F_cush + (1.0 - s.rod.open) * F_cush_r);
  }

  double observe(int k, const State<double>& s, const Eval<double>& e) const {
    using Q = CylinderQuantity;
    const Q q = quantities_[k];
    const CylinderSide& c = side(q.end);
    const CylinderSide::Gas<double>& g = gas(s, q.end);
    const double d_dot = rate(q.end, s.v);
    auto inflow = [&](int port) {
      const auto f = e.gas_port(port);
      return enthalpy_inflow(f.m_flow, f.T_in, f.T_out, e.gas());
    };
    switch (q.kind) {
      case Q::x: return s.x;
      case Q::v: return s.v;
      case Q::v_negative: return -s.v;
      case Q::p_port: return g.p;
      case Q::p_piston: return g.p_piston;
      case Q::T_port: return g.T_gas;
      case Q::T_piston: return g.T_piston;
      case Q::bore_open: return g.open;
      case Q::m_cushion: return g.m_x;
      case Q::H_cushion: return g.H_x;
      case Q::U_cushion: return c.cushion_internal_energy(e);
      case Q::H_port: return inflow(port(q.end));
      case Q::H_tap: return tap_port_[index(q.end)] >= 0 ? inflow(tap_port_[index(q.end)]) : 0.0;
      case Q::Q_heat: return e.heat_port(heat(q.end)).Q;
      case Q::pdV_side: return c.p_dV(g, d_dot);
      case Q::pdV_port: return c.port_p_dV(g, d_dot);
      case Q::pdV_annulus: return c.annulus_p_dV(g, d_dot);
      case Q::pdV_channel: return c.channel_p_dV(g, d_dot);
      case Q::pdV_total: return total_p_dV(s);
      case Q::F_pressure: return s.F_pressure;
      case Q::F_friction: return s.F_fric;
      case Q::F_stop: return s.F_stop;
      case Q::z: return s.z;
      case Q::P_friction: return s.F_fric * s.v;
      case Q::P_stop: return s.F_stop * s.v;
      case Q::E_stop: return stops_.energy(s.x, stroke_);
      case Q::U_gas: return side(near_).internal_energy(e) + side(l_.far()).internal_energy(e);
    }
    return 0.0;
  }
  // p dV/dt summed over all chambers: the power from the gas to the piston.
  double total_p_dV(const State<double>& s) const {
    const End near = near_, far = l_.far();
    const CylinderSide &n = side(near), &f = side(far);
    const double v_near = rate(near, s.v), v_far = rate(far, s.v);
    return n.port_p_dV(gas(s, near), v_near) + f.annulus_p_dV(gas(s, far), v_far) + f.port_p_dV(gas(s, far), v_far) +
           n.annulus_p_dV(gas(s, near), v_near);
  }

  // The observables' quantities in the order of the instance's info.
  std::vector<CylinderQuantity> instance_quantities() const {
    std::vector<CylinderQuantity> q;
    for (const auto& o : l_.observables) q.push_back(o.quantity);
    for (End e : {End::cap, End::rod})
      if (side(e).cushioned())
        for (const auto& o : l_.end(e).cushion_observables) q.push_back(o.quantity);
    return q;
  }

  const CylinderLayout& l_;
  End near_;
  double A_, A_rod_, stroke_;
  CylinderSide cap_, rod_;
  EndStops stops_;
  double wall_alpha_;
  FrictionLaw friction_;
  FrictionFaults friction_faults_;
  SealPresliding presliding_;
  ChamberFaults chamber_faults_;
  double x0_, p0_cap_, p0_rod_, T0_;
  CylinderSide::Rows rows_[2];
  int tap_port_[2] = {-1, -1};
  std::vector<Root> roots_;
  int z_var_ = 0, force_row_ = 0, friction_row_ = -1;
  std::vector<CylinderQuantity> quantities_;
  // state<double>() memo: its inputs (s, v, internal variables) and result,
  // one per thread (threads may integrate one System at once).
  static constexpr int kMemoKey = 2 + 9;
  struct Memo {
    bool valid = false;
    double key[kMemoKey] = {};
    State<double> state{};
  };
  PerThread<Memo> memo_;
};

}  // namespace pneumo::components
