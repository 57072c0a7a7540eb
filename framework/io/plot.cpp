#include "framework/io/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "framework/core/units.hpp"
#include "framework/io/files.hpp"
#include "framework/io/results.hpp"
#include "framework/io/spawn.hpp"

namespace pneumo {

namespace fs = std::filesystem;

namespace {

// A gnuplot string literal that is data, never script: single quotes (no
// escapes are interpreted inside them), a quote doubled, and line breaks and
// other control characters - which would end the command - made spaces.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') out += "''";
    else out += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? ' ' : c;
  }
  return out + "'";
}

int column_of(const ResultsTable& table, const std::string& name, const std::string& csv_path) {
  const int i = table.column(name);
  if (i >= 0) return i;
  std::string valid;
  for (std::size_t k = 1; k < table.names.size(); ++k) valid += (k > 1 ? ", " : "") + table.names[k];
  throw std::runtime_error("plot: no column '" + name + "' in " + csv_path + "; columns: " + valid);
}

// The panels: each a list of columns ("p_cap+p_rod" is one panel of two).
std::vector<std::vector<int>> panels_of(const ResultsTable& table, const std::vector<std::string>& specs,
                                        const std::string& csv_path) {
  std::vector<std::vector<int>> panels;
  if (specs.empty())
    for (std::size_t i = 1; i < table.names.size(); ++i) panels.push_back({static_cast<int>(i)});
  for (const auto& spec : specs) {
    std::vector<int> panel;
    std::stringstream ss(spec);
    for (std::string name; std::getline(ss, name, '+');)
      if (!name.empty()) panel.push_back(column_of(table, name, csv_path));
    if (!panel.empty()) panels.push_back(std::move(panel));
  }
  if (panels.empty()) throw std::runtime_error("plot: nothing to plot in " + csv_path);
  return panels;
}

std::string with_unit(const ResultsTable& table, int c) {
  return table.names[c] + (table.units[c].empty() ? "" : " [" + table.units[c] + "]");
}

// The y label of a panel: "p_cap, p_rod [barg]" when the columns share a
// unit; each curve's legend then names the column alone.
std::string panel_label(const ResultsTable& table, const std::vector<int>& panel) {
  const bool same =
      std::all_of(panel.begin(), panel.end(), [&](int c) { return table.units[c] == table.units[panel[0]]; });
  if (!same) return "";
  std::string names;
  for (int c : panel) names += (names.empty() ? "" : ", ") + table.names[c];
  return names + (table.units[panel[0]].empty() ? "" : " [" + table.units[panel[0]] + "]");
}

// Draws PREFIX.png and PREFIX.svg with gnuplot. Everything gnuplot reads or
// writes lives in a private folder (the plotted data copied there, the
// script, the images), so no user's name ever becomes script text; the images
// are then written to PREFIX.png/.svg as any output is. `body(gp, title)`
// writes the plot commands; it finds its data as `folder.data(name)`.
template <class Body>
void run_gnuplot(const std::string& prefix, int height, const std::string& title, const Body& body) {
  const std::string png = prefix + ".png", svg = prefix + ".svg";
  check_output_file(png, "plot");
  check_output_file(svg, "plot");
  const PrivateFolder folder;
  const std::string script_path = folder.path("plot.gnuplot");
  {
    std::ofstream gp(script_path);
    if (!gp) throw std::runtime_error("plot: cannot write its script in " + folder.path(""));
    gp << "set datafile separator ','\nset grid\n";
    for (const std::string term : {"pngcairo", "svg"}) {
      const std::string ext = term == "pngcairo" ? ".png" : ".svg";
      gp << "set terminal " << term << " size 900," << height << (term == "pngcairo" ? " font 'sans,10'" : "")
         << "\n"
         << "set termoption noenhanced\n"
         << "set output " << quoted(folder.path("plot" + ext)) << "\n";
      body(gp, title, folder);
      gp << "set output\n";
    }
  }
  run_program({"gnuplot", script_path}, folder.path("gnuplot.log"), "gnuplot-nox");
  write_text_atomic(png, read_input_file(folder.path("plot.png"), "plot"));
  write_text_atomic(svg, read_input_file(folder.path("plot.svg"), "plot"));
}

// Writes the rows of `table` (no header) as the CSV gnuplot reads.
void write_rows(const std::string& path, const std::vector<std::vector<double>>& rows) {
  std::ofstream out(path);
  out << std::setprecision(10);
  for (const auto& row : rows) {
    for (std::size_t i = 0; i < row.size(); ++i) out << (i ? "," : "") << row[i];
    out << "\n";
  }
  if (!out) throw std::runtime_error("plot: cannot write its data in " + path);
}

}  // namespace

namespace {

// Column `c` of `table` (read from `path`) in `unit`, the first file's unit
// for it: as is when the units agree, through SI (units::to_si) between two
// units of one quantity, refused otherwise. Both gauge or both absolute, the
// ambient pressure cancels, so the standard one serves.
std::vector<double> column_in(const ResultsTable& table, int c, const std::string& unit, const std::string& path) {
  const std::string& own = table.units[c];
  std::vector<double> out;
  if (own == unit) {
    for (const auto& row : table.rows) out.push_back(row[c]);
    return out;
  }
  units::Unit from, to;
  try {
    from = units::parse_unit(own), to = units::parse_unit(unit);
  } catch (const units::ParseError&) {
    from.dim = units::dims::none, to.dim = units::dims::length;  // unknown: not comparable
  }
  if (!(from.dim == to.dim) || from.gauge != to.gauge)
    throw std::runtime_error("plot: column '" + table.names[c] + "' of " + path + " is in '" + own +
                             "' but the first file shows it in '" + unit + "'" +
                             (from.gauge != to.gauge && from.dim == to.dim
                                  ? "; a gauge and an absolute pressure need the ambient pressure, which the files "
                                    "do not hold: write both runs with the same display unit"
                                  : ", another quantity"));
  const double zero = units::to_si(to, 0.0);  // SI value of 0 in `unit`
  for (const auto& row : table.rows) out.push_back((units::to_si(from, row[c]) - zero) / to.scale);
  return out;
}

std::string file_label(const std::string& path) { return fs::path(path).stem().string(); }

}  // namespace

void plot_results(const std::string& csv_path, const std::string& prefix, const std::vector<std::string>& columns,
                  const std::string& title) {
  plot_overlay({csv_path}, prefix, columns, title);
}

void plot_overlay(const std::vector<std::string>& csv_paths, const std::string& prefix,
                  const std::vector<std::string>& columns, const std::string& title) {
  if (csv_paths.empty()) throw std::runtime_error("plot: no results file");
  std::vector<ResultsTable> tables;
  for (const auto& path : csv_paths) tables.push_back(read_csv(path));
  const ResultsTable& table = tables.front();
  const auto panels = panels_of(table, columns, csv_paths.front());
  const bool overlay = tables.size() > 1;
  const int n = static_cast<int>(panels.size());
  run_gnuplot(prefix, 220 * n + 60, title, [&](std::ostream& gp, const std::string& t, const PrivateFolder& folder) {
    // Each file's time and panel columns, in the first file's units.
    for (std::size_t f = 0; f < tables.size(); ++f) {
      std::vector<std::vector<double>> rows(tables[f].rows.size());
      for (std::size_t r = 0; r < rows.size(); ++r) rows[r].push_back(tables[f].rows[r][0]);
      for (const auto& panel : panels)
        for (int c : panel) {
          const int own = column_of(tables[f], table.names[c], csv_paths[f]);
          const auto values = column_in(tables[f], own, table.units[c], csv_paths[f]);
          for (std::size_t r = 0; r < rows.size(); ++r) rows[r].push_back(values[r]);
        }
      write_rows(folder.path("data" + std::to_string(f) + ".csv"), rows);
    }
    gp << "set multiplot layout " << n << ",1 title " << quoted(t) << "\n"
       << "set lmargin 12\n";  // the panels' time axes aligned whatever their labels
    int field = 2;             // gnuplot's column of the panel's first curve in every data file
    for (int k = 0; k < n; ++k) {
      const auto& panel = panels[k];
      const std::string label = panel_label(table, panel);
      gp << (panel.size() > 1 || overlay ? "set key top right\n" : "set key off\n")
         << "set ylabel " << quoted(label.empty() ? "" : label) << "\n"
         << (k + 1 == n ? "set xlabel 't [s]'\n" : "unset xlabel\n") << "plot ";
      for (std::size_t j = 0; j < panel.size(); ++j) {
        const int c = panel[j];
        const std::string curve = label.empty() ? with_unit(table, c) : table.names[c];
        for (std::size_t f = 0; f < tables.size(); ++f) {
          const std::string name = !overlay ? curve : panel.size() > 1 ? curve + " (" + file_label(csv_paths[f]) + ")"
                                                                       : file_label(csv_paths[f]);
          gp << (j || f ? ", " : "") << quoted(folder.path("data" + std::to_string(f) + ".csv")) << " using 1:"
             << field + static_cast<int>(j) << " with lines lw 2" << (f ? " dt " + std::to_string(f + 1) : "")
             << " title " << quoted(name);
        }
      }
      field += static_cast<int>(panel.size());
      gp << "\n";
    }
    gp << "unset multiplot\n";
  });
}

void plot_step_diagram(const std::string& csv_path, const std::string& prefix, const std::vector<std::string>& columns,
                       const std::string& step_column, const std::string& title) {
  const ResultsTable table = read_csv(csv_path);
  const int sc = column_of(table, step_column, csv_path);
  std::vector<int> cols;
  for (const auto& c : columns) cols.push_back(column_of(table, c, csv_path));
  if (cols.empty()) throw std::runtime_error("plot --steps: name the displacement columns, e.g. --steps x_A,x_B");
  // Transitions: the rows where the active step changes (the solver writes
  // a row at every event, so these are the event times).
  std::vector<std::size_t> change;
  bool whole = true;
  for (std::size_t i = 0; i < table.rows.size(); ++i) {
    whole &= table.rows[i][sc] == std::floor(table.rows[i][sc]);
    if (i > 0 && table.rows[i][sc] != table.rows[i - 1][sc]) change.push_back(i);
  }
  if (!whole || change.size() < 2)
    throw std::runtime_error("plot --steps: column '" + step_column + "' of " + csv_path +
                             " is not a step index that changes at least twice (whole numbers); output the sequencer's "
                             "step (outputs: {step: SEQ.step})");
  // Each step's time span maps onto one unit of the step axis (VDI 3260):
  // transition k at abscissa k + 1, linear in time in between.
  std::vector<double> lo, hi;  // each column normalised: 0 at its least, 1 at its greatest value
  for (int c : cols) {
    lo.push_back(table.rows[0][c]), hi.push_back(table.rows[0][c]);
    for (const auto& r : table.rows) lo.back() = std::min(lo.back(), r[c]), hi.back() = std::max(hi.back(), r[c]);
  }
  std::vector<std::vector<double>> lanes;
  {
    for (std::size_t k = 0; k + 1 < change.size(); ++k) {
      const double t0 = table.rows[change[k]][0], t1 = table.rows[change[k + 1]][0];
      for (std::size_t i = change[k]; i <= change[k + 1]; ++i) {
        const auto& row = table.rows[i];
        lanes.push_back({(k + 1) + (t1 > t0 ? (row[0] - t0) / (t1 - t0) : 0.0)});
        for (std::size_t j = 0; j < cols.size(); ++j)
          lanes.back().push_back(hi[j] > lo[j] ? (row[cols[j]] - lo[j]) / (hi[j] - lo[j]) : 0.0);
      }
    }
  }
  const int n = static_cast<int>(cols.size());
  const int last = static_cast<int>(change.size());
  std::ostringstream times;
  times << std::setprecision(3);
  for (int k = 0; k < last; ++k) {
    std::ostringstream label;
    label << std::fixed << std::setprecision(3) << table.rows[change[k]][0];
    times << (k ? ", " : "") << quoted(label.str()) << " " << k + 1;
  }
  run_gnuplot(prefix, 150 * n + 120, title, [&](std::ostream& gp, const std::string& t, const PrivateFolder& folder) {
    const std::string data_path = folder.path("steps.csv");
    write_rows(data_path, lanes);
    gp << "set multiplot layout " << n << ",1 title "
       << quoted(t + ": displacement-step diagram (top axis: transition times in s)") << "\n"
       << "set key off\nset xrange [1:" << last << "]\nset yrange [-0.15:1.15]\nset ytics ('0' 0, '1' 1)\n"
       << "set xtics 1\nset grid xtics ytics\nset lmargin 12\nset rmargin 6\n";
    for (int k = 0; k < n; ++k) {
      gp << (k == 0 ? "set x2tics (" + times.str() + ")\nset tmargin 3\n" : "unset x2tics\nset tmargin 1\n")
         << (k + 1 == n ? "set xlabel 'step'\n" : "unset xlabel\n") << "set ylabel " << quoted(table.names[cols[k]])
         << "\nplot " << quoted(data_path) << " using 1:" << k + 2 << " with lines lw 3\n";
    }
    gp << "unset multiplot\n";
  });
}

void plot_pareto_front(const std::string& prefix, const std::string& x_label, const std::string& y_label,
                       const std::vector<std::vector<double>>& designs, const std::vector<std::vector<double>>& front) {
  run_gnuplot(prefix, 480, "", [&](std::ostream& gp, const std::string&, const PrivateFolder& folder) {
    write_rows(folder.path("designs.csv"), designs);
    write_rows(folder.path("front.csv"), front);
    gp << "set xlabel " << quoted(x_label) << "\nset ylabel " << quoted(y_label) << "\nset key top right\n"
       << "plot " << quoted(folder.path("designs.csv"))
       << " using 1:2 with points pt 7 ps 0.5 lc rgb '#aaaaaa' title 'designs evaluated', "
       << quoted(folder.path("front.csv")) << " using 1:2 with linespoints pt 7 lw 2 lc rgb '#d62728' title 'Pareto front'\n";
  });
}

}  // namespace pneumo
