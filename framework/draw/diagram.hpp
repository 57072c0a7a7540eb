// ISO 1219 circuit diagrams of a netlist (`pneumo draw`).
//
// Layout after ISO 1219-2 habits, by a layered placement of our own rather
// than graphviz: graphviz's dot ranks by edge direction and knows neither
// the energy flow (supply bottom, actuators top), nor that a valve belongs
// under its cylinder, nor where on a symbol a port is; its orthogonal
// splines also ignore port anchors. Here each actuator heads a column, the
// components that feed it stand beneath in rows by their distance along the
// air lines, supply and exhaust form the bottom row, sensors sit at their
// actuator and signal logic in a column to the left. Lines are routed on a
// 10 px grid (a maze router: Dijkstra with bend and crossing costs) that
// never enters a symbol and never runs along another net's line; crossings
// are allowed straight across, junctions get dots.
//
// Symbols come from each instance's ComponentInfo::symbol; a type without
// one (a plugin's, say) gets a box with its ports named.
#pragma once

#include <array>
#include <set>
#include <string>
#include <vector>

#include "framework/model/circuit.hpp"
#include "framework/model/symbol.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo::draw {

struct PlacedSymbol {
  std::string name, type;
  Symbol symbol;  // completed: every port has an anchor
  double x = 0.0, y = 0.0;
  std::vector<std::string> label;  // lines: the name, then key parameters
  double label_x = 0.0, label_y = 0.0;
  std::set<std::string> connected;  // its ports that have a line
};

struct WireEnd {
  int symbol = 0;
  std::string port;
};

struct Wire {
  std::string domain;  // "pneumatic", "signal", ...
  std::vector<WireEnd> ends;
  std::vector<std::array<double, 4>> segments;  // x0 y0 x1 y1, horizontal or vertical
  std::vector<std::array<double, 2>> junctions;
  bool routed = true;  // false: no free path was found; drawn straight (dashed red)
  // A signal that would cross the sheet is drawn as a short stub at each of
  // its ports carrying its name (`reference`, the driving port's
  // COMPONENT.PORT), as electro-pneumatic diagrams refer to a switch's
  // signal by its tag instead of a line across every column.
  std::string reference;
  std::vector<std::array<double, 3>> reference_labels;  // x, y, side of the text ('r', 'l', 't', 'b')
};

struct Diagram {
  std::string title;
  std::vector<PlacedSymbol> symbols;
  std::vector<Wire> wires;
  double width = 0.0, height = 0.0;
};

// The symbol to draw for an instance: its type's, with an anchor for every
// port (missing ones along the top edge), or a box with the ports named.
Symbol complete_symbol(const ComponentInfo& info);

// Lays out and routes the elaborated circuit of `netlist`. A signal line
// longer than kReferenceLength (its ports' bounding box, half perimeter, px)
// becomes a reference (Wire::reference).
inline constexpr double kReferenceLength = 500.0;
Diagram layout(const Netlist& netlist, const Circuit& circuit);

// Ids and attributes the results view animates: each symbol is a <g
// class="symbol" data-name=...> with data-x/-y/-w/-h, its moving parts <g
// class="part PART" data-part=...>, anchors <circle class="anchor"
// data-port=...>; each wire a <g class="net" data-net=K data-ports="a.p b.q">
// of <line class="wire"> and <circle class="junction">.
std::string to_svg(const Diagram& d);

// One type's symbol alone (complete_symbol), with its ports named beside
// their anchors: for the component reference.
std::string symbol_svg(const ComponentInfo& info);

}  // namespace pneumo::draw
