// pneumo draw NETLIST -o circuit.svg|circuit.png [--results run.csv -o view.html]
//
// The ISO 1219 diagram of a netlist (framework/draw/diagram.hpp) as SVG, as
// PNG (the SVG converted by rsvg-convert, Debian package librsvg2-bin, run
// without a shell), or with --results as the animated results view (HTML).
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/cli/command.hpp"
#include "framework/draw/diagram.hpp"
#include "framework/draw/results_view.hpp"
#include "framework/io/files.hpp"
#include "framework/io/results.hpp"
#include "framework/io/spawn.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/model.hpp"

namespace pneumo::cli {

namespace {

struct DrawArgs {
  std::string netlist, output, results;
  std::vector<std::string> sets;
};

std::string extension_of(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (auto& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

std::string png_of(const std::string& svg) {
  PrivateFolder folder;
  const std::string in = folder.path("circuit.svg"), out = folder.path("circuit.png");
  write_text_atomic(in, svg);
  run_program({"rsvg-convert", "--background-color=white", "-o", out, in}, folder.path("log"), "librsvg2-bin");
  return read_input_file(out, "converted diagram");
}

int draw_command(const DrawArgs& a) {
  const std::string ext = extension_of(a.output);
  if (ext != ".svg" && ext != ".png" && ext != ".html")
    throw std::invalid_argument("-o " + a.output + ": give a name ending in .svg or .png (the diagram) or .html (with "
                                "--results: the results view)");
  if (ext == ".html" && a.results.empty())
    throw std::invalid_argument("-o " + a.output + ": the .html results view needs --results RUN.csv");
  if (ext != ".html" && !a.results.empty())
    throw std::invalid_argument("--results: the results view is HTML; give -o VIEW.html");
  std::vector<std::string> inputs{a.netlist};
  if (!a.results.empty()) inputs.push_back(a.results);
  check_output_file(a.output, "-o", inputs);
  const Model model = load_model(a.netlist, builtin_registry(), a.sets);
  const Netlist& nl = model.netlist;
  const Registry& registry = model.registry;
  const Circuit circuit = elaborate(nl, registry);
  const draw::Diagram d = draw::layout(nl, circuit);
  std::string text;
  if (ext == ".html")
    text = draw::results_view_html(d, nl, circuit, read_csv(a.results), a.results);
  else if (ext == ".png")
    text = png_of(draw::to_svg(d));
  else
    text = draw::to_svg(d);
  write_text_atomic(a.output, text);
  int unrouted = 0;
  for (const auto& w : d.wires) unrouted += w.routed ? 0 : 1;
  std::cout << "drew " << d.symbols.size() << " components and " << d.wires.size() << " connections to " << a.output
            << "\n";
  if (unrouted > 0)
    std::cerr << "pneumo draw: " << unrouted << " connection(s) found no free path and are drawn straight (red)\n";
  return 0;
}

}  // namespace

Command add_draw_command(CLI::App& app) {
  auto a = std::make_shared<DrawArgs>();
  auto* draw = app.add_subcommand("draw", "draw a netlist's ISO 1219 circuit diagram (SVG, PNG) or its animated "
                                          "results view (HTML with --results)");
  draw->add_option("netlist", a->netlist, "netlist file (YAML)")->required();
  draw->add_option("-o,--output", a->output, "circuit.svg, circuit.png, or view.html with --results")->required();
  draw->add_option("--results", a->results, "results CSV of this netlist (pneumo simulate -o): animate them");
  add_set_option(draw, a->sets);
  return {.app = draw, .run = [a] { return draw_command(*a); }, .input = [a] { return a->netlist; }};
}

}  // namespace pneumo::cli
