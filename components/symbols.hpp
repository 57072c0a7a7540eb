// ISO 1219-1 symbols of the built-in components, in a few lines each
// (framework/model/symbol.hpp: pixels, y down, anchors on the 10 px grid and
// on the box's edge). A component's describe() sets i.symbol from here.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "framework/model/symbol.hpp"

namespace pneumo::components::symbols {

using K = SymbolShape::Kind;

inline SymbolShape shape(K k, std::vector<double> v, std::string part = {}) {
  SymbolShape s;
  s.kind = k;
  s.v = std::move(v);
  s.part = std::move(part);
  return s;
}
inline SymbolShape line(double x0, double y0, double x1, double y1, std::string part = {}) {
  return shape(K::line, {x0, y0, x1, y1}, std::move(part));
}
inline SymbolShape dashed(double x0, double y0, double x1, double y1) {
  auto s = line(x0, y0, x1, y1);
  s.dashed = true;
  return s;
}
inline SymbolShape rect(double x, double y, double w, double h, std::string part = {}) {
  return shape(K::rect, {x, y, w, h}, std::move(part));
}
inline SymbolShape filled(SymbolShape s) {
  s.filled = true;
  return s;
}
inline SymbolShape circle(double cx, double cy, double r, std::string part = {}) {
  return shape(K::circle, {cx, cy, r}, std::move(part));
}
inline SymbolShape arc(double cx, double cy, double r, double from_deg, double to_deg) {
  return shape(K::arc, {cx, cy, r, from_deg, to_deg});
}
inline SymbolShape arrow(double x0, double y0, double x1, double y1, std::string part = {}) {
  return shape(K::arrow, {x0, y0, x1, y1}, std::move(part));
}
inline SymbolShape poly(std::vector<double> v, bool closed = false, std::string part = {}) {
  return shape(closed ? K::polygon : K::polyline, std::move(v), std::move(part));
}
inline SymbolShape spring(double x0, double y0, double x1, double y1, double half_width = 5) {
  return shape(K::spring, {x0, y0, x1, y1, half_width});
}
inline SymbolShape text(double x, double y, std::string t) {
  SymbolShape s = shape(K::text, {x, y});
  s.text = std::move(t);
  return s;
}
// A port that is blocked inside a valve square: a short T.
inline std::vector<SymbolShape> blocked(double x, double y, bool from_top, std::string part) {
  const double d = from_top ? 8 : -8;
  return {line(x, y, x, y + d, part), line(x - 4, y + d, x + 4, y + d, part)};
}

inline void add(Symbol& s, std::vector<SymbolShape> more) {
  for (auto& m : more) s.shapes.push_back(std::move(m));
}

// Line elements stand vertically in an actuator's column: port `top` above,
// `bottom` below, an optional signal on the left.
inline Symbol vertical(double w, double h, const std::string& top, const std::string& bottom,
                       Symbol::Tier tier = Symbol::Tier::line) {
  Symbol s;
  s.tier = tier;
  s.width = w;
  s.height = h;
  s.anchors = {{top, w / 2, 0, 't'}, {bottom, w / 2, h, 'b'}};
  return s;
}

// The throttle's two curves at (x, y) (centre), with the adjusting arrow.
inline std::vector<SymbolShape> throttle_at(double x, double y, bool adjustable) {
  std::vector<SymbolShape> v{arc(x - 14, y, 12, -35, 35), arc(x + 14, y, 12, 145, 215)};
  if (adjustable) v.push_back(arrow(x - 12, y + 12, x + 12, y - 12));
  return v;
}

// ISO 6358 throttle (adjustable), ports a (top) and b (bottom).
inline Symbol throttle(bool adjustable = true) {
  Symbol s = vertical(40, 60, "a", "b");
  s.anchors.push_back({"opening", 0, 30, 'l'});
  add(s, {line(20, 0, 20, 60)});
  add(s, throttle_at(20, 30, adjustable));
  s.label_parameters = {"C"};
  return s;
}

// Ball and seat of a check valve at (x, y), passing flow upward.
inline std::vector<SymbolShape> check_at(double x, double y) {
  return {poly({x - 7, y + 2, x, y + 9, x + 7, y + 2}), circle(x, y - 2, 5)};
}

inline Symbol check_valve() {
  Symbol s = vertical(40, 60, "out", "in");
  add(s, {line(20, 0, 20, 21), line(20, 41, 20, 60)});
  add(s, check_at(20, 30));
  s.label_parameters = {"C", "cracking"};
  return s;
}

// Throttle with a check valve in parallel: free flow b -> a (up).
inline Symbol one_way_flow_control() {
  Symbol s = vertical(60, 60, "a", "b");
  s.anchors = {{"a", 20, 0, 't'}, {"b", 20, 60, 'b'}, {"opening", 0, 30, 'l'}};
  add(s, {line(20, 0, 20, 60), poly({20, 10, 48, 10, 48, 19}), poly({48, 41, 48, 50, 20, 50})});
  add(s, throttle_at(20, 30, true));
  add(s, check_at(48, 30));
  add(s, {rect(4, 4, 52, 52)});
  s.shapes.back().dashed = true;
  s.label_parameters = {"C"};
  return s;
}

inline Symbol nozzle() {
  Symbol s = vertical(40, 60, "a", "b");
  s.anchors.push_back({"opening", 0, 30, 'l'});
  add(s, {line(20, 0, 20, 60), line(8, 26, 32, 26), line(8, 34, 32, 34)});
  s.label_parameters = {"d", "A"};
  return s;
}

inline Symbol hose() {
  Symbol s = vertical(40, 60, "a", "b");
  add(s, {line(20, 0, 20, 10), line(20, 50, 20, 60)});
  add(s, {shape(K::polyline, {20, 10, 28, 18, 30, 26, 26, 34, 14, 40, 12, 46, 20, 50})});
  s.label_parameters = {"length", "d"};
  return s;
}

// Reservoir: a rounded box; ports top and (optional second) bottom.
inline Symbol volume() {
  Symbol s;
  s.tier = Symbol::Tier::line;
  s.width = 60;
  s.height = 40;
  s.anchors = {{"port", 30, 0, 't'}, {"port_b", 30, 40, 'b'}, {"heat", 60, 20, 'r'}};
  add(s, {shape(K::rect, {8, 6, 44, 28, 8}), line(30, 0, 30, 6), line(30, 34, 30, 40)});
  s.port_pressure = {{"port", "p"}, {"port_b", "p"}};
  s.label_parameters = {"V"};
  return s;
}

// Compressed air source: circle with a filled triangle.
inline Symbol pressure_source() {
  Symbol s;
  s.tier = Symbol::Tier::supply;
  s.width = 40;
  s.height = 40;
  s.anchors = {{"port", 20, 0, 't'}, {"p_in", 0, 30, 'l'}};
  add(s, {line(20, 0, 20, 8), circle(20, 22, 14), filled(poly({20, 12, 13, 26, 27, 26}, true))});
  s.label_parameters = {"p"};
  return s;
}

// Exhaust to atmosphere: an open triangle under the port.
inline Symbol atmosphere() {
  Symbol s;
  s.tier = Symbol::Tier::supply;
  s.width = 40;
  s.height = 30;
  s.anchors = {{"port", 20, 0, 't'}};
  add(s, {line(20, 0, 20, 14), poly({10, 14, 30, 14, 20, 26}, true)});
  return s;
}

// Double-acting cylinder: barrel, piston and rod (part "piston", moved by
// x over the stroke), ports on the barrel's underside, the rod end right.
// `cap_at_zero`: x = 0 is retracted (else x = 0 is extended).
inline Symbol cylinder(const std::string& cap, const std::string& rod, bool cap_at_zero = true) {
  Symbol s;
  s.tier = Symbol::Tier::actuator;
  s.width = 210;
  s.height = 40;
  s.anchors = {{cap, 10, 40, 'b'}, {rod, 90, 40, 'b'}, {"flange", 210, 20, 'r'}};
  const double x0 = cap_at_zero ? 0 : 86;
  add(s, {rect(0, 0, 100, 40), filled(rect(4 + x0, 2, 6, 36, "piston")), rect(10 + x0, 16, 110, 8, "piston")});
  s.motions = {{"piston", "x", "stroke", 1.0, cap_at_zero ? 86.0 : -86.0, 0.0}};
  s.port_pressure = {{cap, "p_cap"}, {rod, "p_rod"}};
  s.label_parameters = {"bore", "rod", "stroke"};
  return s;
}

// Adjustable end cushioning at both ends (cushion plugs and arrows).
inline void add_cushioning(Symbol& s) {
  add(s, {rect(10, 12, 8, 16), rect(82, 12, 8, 16), arrow(20, 34, 34, 6), arrow(66, 34, 80, 6)});
}

inline Symbol single_acting_cylinder() {
  Symbol s = cylinder("cap", "rod");
  s.anchors = {{"cap", 10, 40, 'b'}, {"rod", 90, 40, 'b'}, {"flange", 210, 20, 'r'}};
  add(s, {spring(34, 8, 98, 8, 4)});
  s.label_parameters = {"bore", "stroke"};
  return s;
}

// Directional valve of `squares` positions (40 px each for 3/2, 60 px for
// 5/2 and 5/3) drawn by `draw(square_left, part)` per position, the ports on
// the rest square; actuation left (solenoid) and right (spring, or a second
// solenoid). The squares are the "spool" part: x shifts them by a square.
struct ValveLayout {
  double size = 60;      // square width
  int squares = 2;
  int rest = 1;          // index of the rest square (from the left)
  bool right_solenoid = false;
};

inline Symbol directional_valve(const ValveLayout& v, const std::vector<SymbolAnchor>& ports_at_rest,
                                const std::vector<std::vector<SymbolShape>>& square_contents,
                                const std::string& quantity) {
  Symbol s;
  s.tier = Symbol::Tier::valve;
  const double left = 20;
  s.width = left + v.squares * v.size + 30;
  s.height = 40;
  for (int k = 0; k < v.squares; ++k) {
    const double x = left + k * v.size;
    s.shapes.push_back(rect(x, 0, v.size, 40, "spool"));
    for (auto sh : square_contents[static_cast<std::size_t>(k)]) {
      if (sh.kind == K::line || sh.kind == K::arrow)
        sh.v = {sh.v[0] + x, sh.v[1], sh.v[2] + x, sh.v[3]};
      sh.part = "spool";
      s.shapes.push_back(std::move(sh));
    }
  }
  const double rest_x = left + v.rest * v.size;
  for (auto a : ports_at_rest) {
    if (a.side == 't' || a.side == 'b') a.x += rest_x;
    s.anchors.push_back(a);
  }
  // solenoid left; spring (and solenoid) right
  add(s, {rect(0, 10, 14, 20), line(4, 10, 10, 30), line(14, 20, left, 20)});
  const double r = left + v.squares * v.size;
  add(s, {spring(r, 20, r + 24, 20, 7)});
  if (v.right_solenoid) add(s, {rect(r + 16, 10, 14, 20), line(r + 20, 10, r + 26, 30)});
  s.motions = {{"spool", quantity, "", 1.0, v.size, 0.0}};
  s.label_parameters = {"C"};
  return s;
}

// Square contents are in square coordinates (0 .. size, 0 .. 40).
inline Symbol valve_32() {
  ValveLayout v{40, 2, 1, false};
  // actuated: P (10) -> A (20); rest: A (20) -> R (30), P blocked
  std::vector<SymbolShape> act{arrow(10, 40, 20, 0)};
  std::vector<SymbolShape> rest{arrow(20, 0, 30, 40), line(10, 40, 10, 32), line(6, 32, 14, 32)};
  auto s = directional_valve(v, {{"A", 20, 0, 't'}, {"P", 10, 40, 'b'}, {"R", 30, 40, 'b'}, {"command", 0, 20, 'l'}},
                             {act, rest}, "x");
  return s;
}

inline Symbol valve_52() {
  ValveLayout v{60, 2, 1, false};
  // ports in a square: A 10, B 50 (top); R 10, P 30, S 50 (bottom)
  std::vector<SymbolShape> act{arrow(30, 40, 10, 0), arrow(50, 0, 50, 40), line(6, 32, 14, 32), line(10, 40, 10, 32)};
  std::vector<SymbolShape> rest{arrow(30, 40, 50, 0), arrow(10, 0, 10, 40), line(46, 32, 54, 32), line(50, 40, 50, 32)};
  return directional_valve(v, {{"A", 10, 0, 't'}, {"B", 50, 0, 't'}, {"R", 10, 40, 'b'}, {"P", 30, 40, 'b'},
                               {"command", 0, 20, 'l'}},
                           {act, rest}, "x");
}

inline Symbol valve_53() {
  ValveLayout v{60, 3, 1, true};
  std::vector<SymbolShape> s14{arrow(30, 40, 10, 0), arrow(50, 0, 50, 40)};
  std::vector<SymbolShape> centre{line(10, 0, 10, 8), line(6, 8, 14, 8), line(50, 0, 50, 8), line(46, 8, 54, 8),
                                  line(30, 40, 30, 32), line(26, 32, 34, 32)};
  std::vector<SymbolShape> s12{arrow(30, 40, 50, 0), arrow(10, 0, 10, 40)};
  auto s = directional_valve(v, {{"A", 10, 0, 't'}, {"B", 50, 0, 't'}, {"R", 10, 40, 'b'}, {"P", 30, 40, 'b'},
                                 {"command_14", 0, 20, 'l'}},
                             {s14, centre, s12}, "y");
  s.anchors.push_back({"command_12", s.width, 20, 'r'});
  return s;
}

// Shuttle (OR) and two-pressure (AND) valves: a horizontal body, inputs at
// its ends, the output on top.
inline Symbol logic_valve(bool two_pressure) {
  Symbol s;
  s.tier = Symbol::Tier::line;
  s.width = 60;
  s.height = 40;
  s.anchors = {{"out", 30, 0, 't'}, {"in_1", 0, 30, 'l'}, {"in_2", 60, 30, 'r'}};
  add(s, {rect(6, 20, 48, 20), line(30, 0, 30, 20), line(0, 30, 6, 30), line(54, 30, 60, 30)});
  if (two_pressure)
    add(s, {rect(20, 23, 20, 14), line(6, 30, 20, 30), line(40, 30, 54, 30)});
  else
    add(s, {circle(30, 30, 6), poly({12, 22, 18, 30, 12, 38}), poly({48, 22, 42, 30, 48, 38})});
  return s;
}

inline Symbol quick_exhaust_valve() {
  Symbol s;
  s.tier = Symbol::Tier::line;
  s.width = 60;
  s.height = 60;
  s.anchors = {{"A", 30, 0, 't'}, {"P", 30, 60, 'b'}, {"R", 60, 30, 'r'}};
  add(s, {rect(14, 16, 32, 28), line(30, 0, 30, 16), line(30, 44, 30, 60), line(46, 30, 60, 30),
          circle(30, 30, 5), poly({50, 36, 56, 44, 44, 44}, true)});
  return s;
}

// Pressure valves: a square with the flow arrow, an adjustable spring on
// the right and the dashed pilot line from the controlled pressure.
inline Symbol relief_valve() {
  Symbol s = vertical(60, 60, "out", "in");
  add(s, {rect(10, 10, 40, 40), line(30, 0, 30, 10), line(30, 50, 30, 60), arrow(36, 46, 36, 14),
          spring(50, 30, 60, 30, 5), arrow(50, 40, 60, 20), dashed(10, 44, 4, 44), dashed(4, 44, 4, 20),
          dashed(4, 20, 10, 20)});
  s.label_parameters = {"p_crack", "cracking"};
  return s;
}

inline Symbol pressure_regulator() {
  Symbol s = vertical(60, 60, "out", "in");
  s.anchors.push_back({"exhaust", 60, 40, 'r'});
  add(s, {rect(10, 10, 40, 40), line(30, 0, 30, 10), line(30, 50, 30, 60), arrow(24, 46, 24, 14), line(50, 40, 60, 40),
          arrow(36, 14, 46, 40), dashed(4, 16, 10, 16), dashed(4, 4, 4, 16), dashed(4, 4, 30, 4)});
  s.label_parameters = {"p_set"};
  return s;
}

// Measuring instruments and switches: a circle (or the switch's lever)
// with the signal leaving right.
inline Symbol gauge(const std::string& port, const std::string& signal, const std::string& letter) {
  Symbol s;
  s.tier = Symbol::Tier::line;
  s.width = 40;
  s.height = 40;
  s.anchors = {{port, 20, 40, 'b'}, {signal, 40, 20, 'r'}};
  add(s, {circle(20, 20, 13), text(20, 25, letter), line(20, 33, 20, 40), line(33, 20, 40, 20)});
  return s;
}

// Roller-lever limit switch at its actuator: the lever (lit while closed).
inline Symbol limit_switch() {
  Symbol s;
  s.tier = Symbol::Tier::sensor;
  s.width = 40;
  s.height = 40;
  s.anchors = {{"flange", 20, 40, 'b'}, {"y", 40, 20, 'r'}};
  add(s, {filled(rect(6, 8, 24, 20, "lamp")), circle(18, 34, 5), line(18, 28, 18, 29), line(30, 20, 40, 20)});
  s.lamp_quantity = "state";
  s.label_parameters = {"position"};
  return s;
}

// A box on the mechanical side (mass, stops, force and velocity sources).
inline Symbol mechanical(const std::string& title, std::vector<SymbolAnchor> anchors, double w = 40, double h = 40) {
  Symbol s;
  s.tier = Symbol::Tier::mechanical;
  s.width = w;
  s.height = h;
  s.anchors = std::move(anchors);
  add(s, {rect(0, 0, w, h), text(w / 2, h / 2 + 5, title)});
  return s;
}

// Signal elements: a function block; empty shapes = the framework's box with
// the ports named, titled `title`.
inline Symbol function_block(const std::string& title) {
  Symbol s;
  s.tier = Symbol::Tier::signal;
  s.title = title;
  return s;
}


// Cylinder with adjustable end cushioning (cushioned_cylinder: x = 0
// extended; port B the cap side, A the rod side, EC and EC_rod the cushion
// tappings).
inline Symbol cushioned_cylinder() {
  Symbol s = cylinder("B", "A", false);
  s.anchors.push_back({"EC", 30, 40, 'b'});
  s.anchors.push_back({"EC_rod", 70, 40, 'b'});
  add_cushioning(s);
  return s;
}

// Position sensor at the rod: flange below, signals right.
inline Symbol position_sensor() {
  Symbol s;
  s.tier = Symbol::Tier::sensor;
  s.width = 40;
  s.height = 40;
  s.anchors = {{"flange", 20, 40, 'b'}, {"s", 40, 10, 'r'}, {"v", 40, 30, 'r'}};
  add(s, {rect(4, 4, 32, 30), text(20, 24, "s")});
  return s;
}

// Thermal elements: a box with the ports named (framework's), titled.
inline Symbol thermal_box(const std::string& title) {
  Symbol s;
  s.title = title;
  return s;
}

}  // namespace pneumo::components::symbols
