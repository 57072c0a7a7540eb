#include "framework/io/plot.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "framework/io/results.hpp"

namespace pneumo {

namespace fs = std::filesystem;

namespace {

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

void plot_results(const std::string& csv_path, const std::string& prefix, const std::vector<std::string>& columns,
                  const std::string& title) {
  const ResultsTable table = read_csv(csv_path);
  std::vector<int> cols;
  if (columns.empty()) {
    for (std::size_t i = 1; i < table.names.size(); ++i) cols.push_back(static_cast<int>(i));
  } else {
    for (const auto& c : columns) {
      const int i = table.column(c);
      if (i < 0) {
        std::string valid;
        for (std::size_t k = 1; k < table.names.size(); ++k) valid += (k > 1 ? ", " : "") + table.names[k];
        throw std::runtime_error("plot: no column '" + c + "' in " + csv_path + "; columns: " + valid);
      }
      cols.push_back(i);
    }
  }
  if (cols.empty()) throw std::runtime_error("plot: nothing to plot in " + csv_path);
  if (const auto parent = fs::path(prefix).parent_path(); !parent.empty()) fs::create_directories(parent);

  const std::string script_path = prefix + ".gnuplot";
  {
    std::ofstream gp(script_path);
    if (!gp) throw std::runtime_error("plot: cannot write " + script_path);
    const int panels = static_cast<int>(cols.size());
    const int height = 220 * panels + 60;
    gp << "set datafile separator ','\n"
       << "set key off\nset grid\n";
    for (const std::string term : {"pngcairo", "svg"}) {
      const std::string ext = term == "pngcairo" ? ".png" : ".svg";
      gp << "set terminal " << term << " size 900," << height << (term == "pngcairo" ? " font 'sans,10'" : "")
         << "\n"
         << "set termoption noenhanced\n"
         << "set output " << quoted(prefix + ext) << "\n"
         << "set multiplot layout " << panels << ",1 title " << quoted(title) << "\n";
      for (int k = 0; k < panels; ++k) {
        const int c = cols[k];
        const std::string unit = table.units[c].empty() ? "" : " [" + table.units[c] + "]";
        gp << "set ylabel " << quoted(table.names[c] + unit) << "\n"
           << (k + 1 == panels ? "set xlabel 't [s]'\n" : "unset xlabel\n")
           << "plot " << quoted(csv_path) << " every ::1 using 1:" << (c + 1) << " with lines lw 2\n";
      }
      gp << "unset multiplot\nset output\n";
    }
  }
  const std::string cmd = "gnuplot " + quoted(script_path) + " 2>" + quoted(prefix + ".gnuplot.log");
  const int rc = std::system(cmd.c_str());
  if (rc != 0)
    throw std::runtime_error("plot: gnuplot failed (is the Debian package gnuplot-nox installed?); see " + prefix +
                             ".gnuplot.log");
  std::error_code ec;
  fs::remove(prefix + ".gnuplot.log", ec);
  fs::remove(script_path, ec);
}

}  // namespace pneumo
