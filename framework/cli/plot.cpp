// pneumo plot results.csv [-o PREFIX] [--columns a,b] [--steps x_A,x_B [--step-column step]]
#include <filesystem>
#include <iostream>
#include <memory>

#include "framework/cli/command.hpp"
#include "framework/cli/split_list.hpp"
#include "framework/io/plot.hpp"

namespace pneumo::cli {

namespace {

struct PlotArgs {
  std::string csv, out, columns, steps, step_column = "step";
};

int plot_command(const PlotArgs& a) {
  std::string out = a.out;
  if (out.empty())
    out = (std::filesystem::path(a.csv).parent_path() / std::filesystem::path(a.csv).stem()).string();
  if (a.steps.empty())
    plot_results(a.csv, out, split_list(a.columns), a.csv);
  else
    plot_step_diagram(a.csv, out, split_list(a.steps), a.step_column, a.csv);
  std::cout << "plotted " << out << ".png and " << out << ".svg\n";
  return 0;
}

}  // namespace

Command add_plot_command(CLI::App& app) {
  auto a = std::make_shared<PlotArgs>();
  auto* plot = app.add_subcommand("plot", "plot a results CSV to PNG and SVG through gnuplot");
  plot->add_option("results", a->csv, "results CSV")->required();
  plot->add_option("-o,--output", a->out, "output prefix (default: the CSV path without .csv)");
  auto* columns = plot->add_option("--columns", a->columns, "columns to plot, comma separated (default: all)");
  plot->add_option("--steps", a->steps,
                   "draw the displacement-step diagram of these travel columns (comma separated) instead")
      ->excludes(columns);
  plot->add_option("--step-column", a->step_column, "with --steps: the column of the active step (default: step)");
  return {.app = plot, .run = [a] { return plot_command(*a); }};
}

}  // namespace pneumo::cli
