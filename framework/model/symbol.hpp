// A component type's circuit symbol (ISO 1219-1), declared through the
// component interface so that `pneumo draw` draws any type - a plugin's too -
// without knowing it by name.
//
// Symbol coordinates: pixels, x right, y down, the symbol's box from (0, 0)
// to (width, height). The diagram routes lines on a 10 px grid, so width,
// height and every port anchor are multiples of 10 and each anchor lies on
// the box's edge (`side` says which: the line leaves the symbol that way).
//
// Shapes may belong to a moving `part` that the results view animates:
// "piston" (moved by `motion`), "spool" (the valve's switching squares,
// moved by `motion`), "lamp" (lit while `lamp_quantity` > 0.5).
#pragma once

#include <string>
#include <vector>

namespace pneumo {

struct SymbolShape {
  // line: x0 y0 x1 y1; polyline / polygon: x0 y0 x1 y1 ...; circle: cx cy r;
  // arc: cx cy r from_deg to_deg (counter-clockwise, y up as on paper);
  // rect: x y w h [corner radius]; arrow: x0 y0 x1 y1 (head at x1 y1); text: x y;
  // spring: x0 y0 x1 y1 half_width (a zig-zag between the two points).
  enum class Kind { line, polyline, polygon, circle, arc, rect, arrow, text, spring };
  Kind kind = Kind::line;
  std::vector<double> v;
  std::string text;  // Kind::text
  bool filled = false;
  bool dashed = false;
  std::string part;  // "" static, or "piston", "spool", "lamp"
};

struct SymbolAnchor {
  std::string port;
  double x = 0.0, y = 0.0;
  char side = 'b';  // 'l', 'r', 't', 'b': the edge the anchor is on
};

// How a part moves in the results view: offset = value / full_scale *
// (dx, dy), where value is the instance's `quantity` (an observable or
// variable) and full_scale the SI value of parameter `full_scale_parameter`
// (or `full_scale` when that is empty).
struct SymbolMotion {
  std::string part;
  std::string quantity;
  std::string full_scale_parameter;
  double full_scale = 1.0;
  double dx = 0.0, dy = 0.0;
};

struct Symbol {
  // Where the layout puts the symbol (ISO 1219-2 habits: actuators on top,
  // their valves and flow controls beneath, supply at the bottom, signal
  // logic to the side, sensors at their actuator).
  enum class Tier { other, actuator, valve, line, supply, signal, sensor, mechanical };
  Tier tier = Tier::other;
  double width = 0.0, height = 0.0;
  std::vector<SymbolShape> shapes;
  std::vector<SymbolAnchor> anchors;
  std::vector<SymbolMotion> motions;
  // The quantity holding the pressure at a port, for colouring its line
  // (ports not listed: "PORT.p").
  std::vector<std::pair<std::string, std::string>> port_pressure;
  std::string lamp_quantity;
  // Parameters shown under the name (as written in the netlist).
  std::vector<std::string> label_parameters;
  // Empty shapes: a box with the ports named and this title (function
  // blocks of signal logic; the type's name if empty).
  std::string title;

  bool empty() const { return shapes.empty(); }
  const SymbolAnchor* anchor(const std::string& port) const {
    for (const auto& a : anchors)
      if (a.port == port) return &a;
    return nullptr;
  }
};

}  // namespace pneumo
