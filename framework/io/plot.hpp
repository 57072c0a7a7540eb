// Plots of results files through gnuplot (Debian package gnuplot-nox): one
// panel per chosen column over time, written as PNG and SVG.
#pragma once

#include <string>
#include <vector>

namespace pneumo {

// Writes PREFIX.png and PREFIX.svg. Empty `columns` = every column but t.
// Throws std::runtime_error (unknown column, gnuplot missing or failing).
void plot_results(const std::string& csv_path, const std::string& prefix, const std::vector<std::string>& columns,
                  const std::string& title = "");

}  // namespace pneumo
