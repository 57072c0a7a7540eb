// pneumo plot results.csv [more.csv ...] [-o PREFIX] [--columns a,b] [--steps x_A,x_B [--step-column step]]
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/cli/command.hpp"
#include "framework/cli/split_list.hpp"
#include "framework/io/plot.hpp"

namespace pneumo::cli {

namespace {

struct PlotArgs {
  std::vector<std::string> csvs;
  std::string out, columns, steps, step_column = "step";
};

int plot_command(const PlotArgs& a) {
  const std::string& first = a.csvs.front();
  std::string out = a.out;
  if (out.empty() && a.csvs.size() > 1)
    throw std::invalid_argument("plot: several results files are overlaid into one plot: name it with -o PREFIX");
  if (out.empty()) out = (std::filesystem::path(first).parent_path() / std::filesystem::path(first).stem()).string();
  if (!a.steps.empty() && a.csvs.size() > 1)
    throw std::invalid_argument("plot --steps: a displacement-step diagram is of one results file");
  std::string title;
  for (const auto& csv : a.csvs) title += (title.empty() ? "" : " vs ") + csv;
  if (a.steps.empty())
    plot_overlay(a.csvs, out, split_list(a.columns), title);
  else
    plot_step_diagram(first, out, split_list(a.steps), a.step_column, first);
  std::cout << "plotted " << out << ".png and " << out << ".svg\n";
  return 0;
}

}  // namespace

Command add_plot_command(CLI::App& app) {
  auto a = std::make_shared<PlotArgs>();
  auto* plot = app.add_subcommand("plot", "plot a results CSV to PNG and SVG through gnuplot");
  plot->add_option("results", a->csvs, "results CSV; several are overlaid, each curve's legend naming its file")
      ->required();
  plot->add_option("-o,--output", a->out, "output prefix (default: the CSV path without .csv; required for several)");
  auto* columns = plot->add_option("--columns", a->columns, "columns to plot, comma separated (default: all)");
  plot->add_option("--steps", a->steps,
                   "draw the displacement-step diagram of these travel columns (comma separated) instead")
      ->excludes(columns);
  plot->add_option("--step-column", a->step_column, "with --steps: the column of the active step (default: step)");
  return {.app = plot, .run = [a] { return plot_command(*a); }};
}

}  // namespace pneumo::cli
