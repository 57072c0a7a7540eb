// The results view: a circuit diagram animated over a run's results, as one
// self-contained HTML file (inline SVG and script, nothing fetched): a time
// slider and play button; lines coloured by pressure (legend in bar g);
// pistons at their position; valve spools shifted; limit switches lit.
//
// What moves is what the results hold: a line is coloured when an output of
// the netlist gives the pressure at one of its ports (the symbol's
// port_pressure quantity, else PORT.p), a part moves when an output gives
// its motion's quantity, a lamp lights from its lamp quantity. Opening the
// file with #t=SECONDS shows that moment.
#pragma once

#include <string>

#include "framework/draw/diagram.hpp"
#include "framework/io/results.hpp"

namespace pneumo::draw {

// Throws std::invalid_argument when the results share no column with the
// netlist's outputs (another netlist's results).
std::string results_view_html(const Diagram& d, const Netlist& netlist, const Circuit& circuit,
                              const ResultsTable& results, const std::string& results_name);

}  // namespace pneumo::draw
