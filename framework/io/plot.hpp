// Plots of results files through gnuplot (Debian package gnuplot-nox): one
// panel per chosen column (or group of columns) over time, or a
// displacement-step diagram, written as PNG and SVG.
#pragma once

#include <string>
#include <vector>

namespace pneumo {

// Writes PREFIX.png and PREFIX.svg. Each entry of `columns` is a panel;
// names joined by '+' share it ("p_cap+p_rod") with a legend. Empty
// `columns` = every column but t, one panel each. Throws std::runtime_error
// (unknown column, gnuplot missing or failing).
void plot_results(const std::string& csv_path, const std::string& prefix, const std::vector<std::string>& columns,
                  const std::string& title = "");

// The same panels with the curves of several results files overlaid (runs
// to compare), each curve's legend naming its file. The panels are those of
// the first file; every file must have their columns. A file that shows a
// column in another unit of the same quantity is converted to the first
// file's unit; a gauge pressure beside an absolute one is refused, because
// the files do not say their ambient pressure.
void plot_overlay(const std::vector<std::string>& csv_paths, const std::string& prefix,
                  const std::vector<std::string>& columns, const std::string& title = "");

// The displacement-step diagram of a sequence (VDI 3260): one lane per
// column of `columns` (an actuator's travel, normalised to 0 .. 1 over the
// run), over a step axis on which each step - the time between two changes
// of the column `step_column` (the sequencer's active step) - takes one
// unit; the transitions' times are marked on the top axis.
void plot_step_diagram(const std::string& csv_path, const std::string& prefix, const std::vector<std::string>& columns,
                       const std::string& step_column, const std::string& title = "");

// A two-objective plot: every design evaluated (grey points) and the Pareto
// front (a red line), to PREFIX.png and PREFIX.svg.
void plot_pareto_front(const std::string& prefix, const std::string& x_label, const std::string& y_label,
                       const std::vector<std::vector<double>>& designs, const std::vector<std::vector<double>>& front);

}  // namespace pneumo
