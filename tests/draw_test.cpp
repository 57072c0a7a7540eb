// pneumo draw: the ISO 1219 diagram of every shipped netlist read back from
// its SVG - every connection reaches the anchor of each port it names and
// is one connected line; no two symbols overlap; no line passes through a
// symbol - a plugin's type drawn as a box with its ports named, and the
// results view in headless Chromium drawing the piston half-way when the
// cylinder is half-extended.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "framework/io/results.hpp"
#include "framework/draw/diagram.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using pneumo::test_support::read_file;
using pneumo::test_support::run_cli;
using pneumo::test_support::TempDir;

struct Rect {
  std::string name, type;
  double x, y, w, h;
  std::map<std::string, std::pair<double, double>> anchors;  // absolute
};
struct Seg {
  double x0, y0, x1, y1;
};
struct Net {
  std::string cls, domain;
  std::vector<std::string> ports;
  std::vector<Seg> segs;
  std::string ref;                // a signal drawn as tagged stubs: its tag
  std::vector<std::string> tags;  // the texts at the stubs
};
struct Svg {
  std::vector<Rect> symbols;
  std::vector<Net> nets;
};

std::string attr(const std::string& tag, const std::string& name) {
  const std::regex r("\\s" + name + "=\"([^\"]*)\"");
  std::smatch m;
  if (!std::regex_search(tag, m, r)) return "";
  return m[1];
}
double num_attr(const std::string& tag, const std::string& name) { return std::stod(attr(tag, name)); }

// Reads the diagram back: symbols (<g class="symbol">, their anchors) and
// nets (<g class="net">, their <line>s) - one element a line as written.
Svg parse(const std::string& svg) {
  Svg out;
  std::size_t pos = 0;
  while ((pos = svg.find("<g class=\"", pos)) != std::string::npos) {
    const std::size_t end_tag = svg.find('>', pos);
    const std::string tag = svg.substr(pos, end_tag - pos + 1);
    const std::size_t close = svg.find("\n", end_tag);
    const std::string body = svg.substr(end_tag + 1, close - end_tag - 1);
    if (tag.find("class=\"symbol\"") != std::string::npos) {
      Rect r{attr(tag, "data-name"), attr(tag, "data-type"), num_attr(tag, "data-x"), num_attr(tag, "data-y"),
             num_attr(tag, "data-w"), num_attr(tag, "data-h"), {}};
      const std::regex anchor("<circle class=\"anchor\"[^>]*>");
      for (auto it = std::sregex_iterator(body.begin(), body.end(), anchor); it != std::sregex_iterator(); ++it) {
        const std::string a = it->str();
        r.anchors[attr(a, "data-port")] = {r.x + num_attr(a, "cx"), r.y + num_attr(a, "cy")};
      }
      out.symbols.push_back(r);
    } else if (tag.find("class=\"net") != std::string::npos) {
      Net n{attr(tag, "class"), attr(tag, "data-domain"), {}, {}, attr(tag, "data-ref"), {}};
      const std::regex text("<text class=\"ref\"[^>]*>([^<]*)</text>");
      for (auto it = std::sregex_iterator(body.begin(), body.end(), text); it != std::sregex_iterator(); ++it)
        n.tags.push_back((*it)[1]);
      std::stringstream ports(attr(tag, "data-ports"));
      for (std::string p; ports >> p;) n.ports.push_back(p);
      const std::regex line("<line class=\"wire\"[^>]*>");
      for (auto it = std::sregex_iterator(body.begin(), body.end(), line); it != std::sregex_iterator(); ++it) {
        const std::string l = it->str();
        n.segs.push_back({num_attr(l, "x1"), num_attr(l, "y1"), num_attr(l, "x2"), num_attr(l, "y2")});
      }
      out.nets.push_back(n);
    }
    pos = end_tag;
  }
  return out;
}

bool on_segment(double x, double y, const Seg& s) {
  const double e = 1e-6;
  return x >= std::min(s.x0, s.x1) - e && x <= std::max(s.x0, s.x1) + e && y >= std::min(s.y0, s.y1) - e &&
         y <= std::max(s.y0, s.y1) + e && (std::abs(s.x0 - s.x1) < e || std::abs(s.y0 - s.y1) < e);
}

bool touches(const Seg& a, const Seg& b) {
  return on_segment(a.x0, a.y0, b) || on_segment(a.x1, a.y1, b) || on_segment(b.x0, b.y0, a) ||
         on_segment(b.x1, b.y1, a);
}

// Whether segment s enters the open interior of rectangle r.
bool enters(const Seg& s, const Rect& r) {
  const double x0 = std::min(s.x0, s.x1), x1 = std::max(s.x0, s.x1), y0 = std::min(s.y0, s.y1),
               y1 = std::max(s.y0, s.y1);
  return x1 > r.x + 1e-6 && x0 < r.x + r.w - 1e-6 && y1 > r.y + 1e-6 && y0 < r.y + r.h - 1e-6;
}

std::vector<fs::path> shipped_netlists() {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(fs::path(PNEUMO_SOURCE_DIR) / "netlists"))
    if (e.path().extension() == ".yaml") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

Svg draw(const TempDir& dir, const fs::path& netlist) {
  const fs::path svg = dir.path() / (netlist.stem().string() + ".svg");
  const auto [status, out] = run_cli("draw '" + netlist.string() + "' -o '" + svg.string() + "'");
  EXPECT_EQ(status, 0) << out;
  EXPECT_EQ(out.find("drawn straight"), std::string::npos) << netlist << ": " << out;
  return parse(read_file(svg));
}

TEST(Draw, EveryConnectionOfEveryShippedNetlistEndsOnTheAnchorsOfItsPortsAsOneLine) {
  TempDir dir;
  const auto netlists = shipped_netlists();
  ASSERT_GE(netlists.size(), 8u);
  for (const auto& nl : netlists) {
    const Svg d = draw(dir, nl);
    ASSERT_FALSE(d.nets.empty()) << nl;
    std::map<std::string, const Rect*> by_name;
    for (const auto& s : d.symbols) by_name[s.name] = &s;
    for (const auto& n : d.nets) {
      if (!n.ref.empty()) {  // a signal drawn as tagged stubs: one at each port, each tagged
        EXPECT_EQ(n.cls, "net ref") << nl << ": " << n.ports.front();
        EXPECT_EQ(n.segs.size(), n.ports.size()) << nl << ": " << n.ref;
        EXPECT_EQ(n.tags, std::vector<std::string>(n.ports.size(), n.ref)) << nl << ": " << n.ref;
      } else {
        EXPECT_EQ(n.cls, "net") << nl << ": an unrouted connection " << n.ports.front();
      }
      ASSERT_GE(n.ports.size(), 2u);
      for (const auto& p : n.ports) {
        const auto dot = p.find('.');
        const Rect* s = by_name.at(p.substr(0, dot));
        const auto a = s->anchors.find(p.substr(dot + 1));
        ASSERT_NE(a, s->anchors.end()) << nl << ": " << p << " has no anchor";
        bool reached = false;
        for (const auto& seg : n.segs)
          reached |= (std::abs(seg.x0 - a->second.first) < 1e-6 && std::abs(seg.y0 - a->second.second) < 1e-6) ||
                     (std::abs(seg.x1 - a->second.first) < 1e-6 && std::abs(seg.y1 - a->second.second) < 1e-6);
        EXPECT_TRUE(reached) << nl << ": the line of " << n.ports.front() << " does not end on " << p;
      }
      if (!n.ref.empty()) continue;
      // one connected line: flood over touching segments
      std::vector<bool> seen(n.segs.size(), false);
      std::vector<std::size_t> stack{0};
      seen[0] = true;
      while (!stack.empty()) {
        const auto k = stack.back();
        stack.pop_back();
        for (std::size_t j = 0; j < n.segs.size(); ++j)
          if (!seen[j] && touches(n.segs[k], n.segs[j])) seen[j] = true, stack.push_back(j);
      }
      EXPECT_EQ(std::count(seen.begin(), seen.end(), true), static_cast<long>(n.segs.size()))
          << nl << ": the line of " << n.ports.front() << " falls apart";
    }
  }
}

TEST(Draw, NoTwoSymbolsOverlapAndNoLinePassesThroughASymbol) {
  TempDir dir;
  for (const auto& nl : shipped_netlists()) {
    const Svg d = draw(dir, nl);
    for (std::size_t i = 0; i < d.symbols.size(); ++i)
      for (std::size_t j = i + 1; j < d.symbols.size(); ++j) {
        const Rect &a = d.symbols[i], &b = d.symbols[j];
        const bool overlap = a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
        EXPECT_FALSE(overlap) << nl << ": " << a.name << " and " << b.name << " overlap";
      }
    int lines = 0;
    for (const auto& n : d.nets)
      for (const auto& s : n.segs) {
        ++lines;
        for (const auto& r : d.symbols)
          EXPECT_FALSE(enters(s, r)) << nl << ": a line of " << n.ports.front() << " (" << s.x0 << "," << s.y0
                                     << ")-(" << s.x1 << "," << s.y1 << ") passes through " << r.name;
      }
    EXPECT_GT(lines, 0) << nl;
  }
}

// A signal that would run across the sheet (a limit switch at one
// cylinder to the sequencer at the side) is drawn as a stub at each port
// tagged with the signal's source, as electro-pneumatic diagrams do; the
// lines left are short. Before, the six-cylinder line's switches looped
// their lines around every column.
TEST(Draw, SignalsThatWouldCrossTheSheetAreTaggedStubsAndTheLinesLeftAreShort) {
  TempDir dir;
  for (const char* name : {"assembly_line.yaml", "sequence_ab.yaml"}) {
    const Svg d = draw(dir, fs::path(PNEUMO_SOURCE_DIR) / "netlists" / name);
    int refs = 0;
    for (const auto& n : d.nets) {
      if (n.domain != "signal") continue;
      double length = 0;
      for (const auto& s : n.segs) length += std::abs(s.x1 - s.x0) + std::abs(s.y1 - s.y0);
      if (n.ref.empty()) {
        EXPECT_LE(length, 2 * pneumo::draw::kReferenceLength) << name << ": the line of " << n.ports.front();
        continue;
      }
      ++refs;
      EXPECT_NE(std::find(n.ports.begin(), n.ports.end(), n.ref), n.ports.end()) << name << ": tag " << n.ref;
      EXPECT_LE(length, 30.0 * static_cast<double>(n.ports.size())) << name << ": stubs of " << n.ref;
    }
    EXPECT_GE(refs, 4) << name << ": the limit switches' signals to the sequencer";
  }
}

TEST(Draw, TheCylinderHeadsItsColumnWithItsValveBeneathAndTheSupplyAtTheBottom) {
  // ISO 1219-2: energy flows bottom to top.
  TempDir dir;
  const Svg d = draw(dir, fs::path(PNEUMO_SOURCE_DIR) / "netlists" / "sequence_ab.yaml");
  std::map<std::string, Rect> s;
  for (const auto& r : d.symbols) s[r.name] = r;
  for (const char* ab : {"A", "B"}) {
    const std::string x = ab;
    EXPECT_LT(s["cyl_" + x].y, s["flow_" + x + "_cap"].y);
    EXPECT_LT(s["flow_" + x + "_cap"].y, s["valve_" + x].y);
    EXPECT_LT(s["valve_" + x].y, s["supply"].y);
    EXPECT_LT(s["seq"].x + s["seq"].w, s["valve_" + x].x);  // signal logic to the side
  }
  EXPECT_LT(s["cyl_A"].x + s["cyl_A"].w, s["cyl_B"].x);  // one column each
}

// However many elements one path holds between the cylinder and its valve
// (cushion_rig_full: meter-out, line volume and hose on one side, a hose on
// the other; the meter-out cylinder: flow controls and lines), the valve is
// beneath all of them, and what hangs on its exhaust (a silencer) beneath it.
TEST(Draw, TheValveIsBeneathEveryElementBetweenItAndItsCylinder) {
  TempDir dir;
  const fs::path nets = fs::path(PNEUMO_SOURCE_DIR) / "netlists";
  auto by_name = [](const Svg& d) {
    std::map<std::string, Rect> s;
    for (const auto& r : d.symbols) s[r.name] = r;
    return s;
  };
  auto full = by_name(draw(dir, nets / "cushion_rig_full.yaml"));
  for (const char* between : {"meter_out", "line_B", "hose_A", "hose_B"}) {
    EXPECT_LT(full["cylinder"].y, full[between].y) << between;
    EXPECT_LT(full[between].y + full[between].h, full["valve"].y) << between;
  }
  EXPECT_LT(full["valve"].y, full["supply"].y);
  auto meter_out = by_name(draw(dir, nets / "meter_out_cylinder.yaml"));
  for (const char* between : {"flow_cap", "flow_rod", "line_A", "line_B"})
    EXPECT_LT(meter_out[between].y + meter_out[between].h, meter_out["valve"].y) << between;
  EXPECT_LT(meter_out["valve"].y, meter_out["silencer"].y);
}

TEST(Draw, APluginTypeWithoutASymbolIsABoxWithItsPortsNamed) {
  TempDir dir;
  const std::string net = dir.write("seal.yaml", "plugins:\n  - " + std::string(PNEUMO_TEST_PLUGIN_DIR) +
                                                     "/seal_leakage.so\n"
                                                     "components:\n"
                                                     "  tank: {type: volume, V: 0.1 L, p0: 6 bar}\n"
                                                     "  seal: {type: seal_leakage, d: 20 mm, h: 15 um, L: 5 mm}\n"
                                                     "  air:  {type: atmosphere}\n"
                                                     "connections:\n"
                                                     "  - [tank.port, seal.a]\n"
                                                     "  - [seal.b, air.port]\n"
                                                     "outputs: {p: tank.p}\n");
  const Svg d = draw(dir, net);
  const std::string svg = read_file(dir.path() / "seal.svg");
  const Rect* seal = nullptr;
  for (const auto& r : d.symbols)
    if (r.name == "seal") seal = &r;
  ASSERT_NE(seal, nullptr);
  EXPECT_EQ(seal->type, "seal_leakage");
  ASSERT_EQ(seal->anchors.size(), 2u);
  // both gas ports on the box's lower edge, their names written in the box
  for (const char* p : {"a", "b"}) EXPECT_DOUBLE_EQ(seal->anchors.at(p).second, seal->y + seal->h);
  const std::size_t g = svg.find("data-name=\"seal\"");
  const std::string box = svg.substr(g, svg.find("</g>", g) - g);
  EXPECT_NE(box.find(">seal_leakage</text>"), std::string::npos);
  EXPECT_NE(box.find("class=\"port\">a</text>"), std::string::npos);
  EXPECT_NE(box.find("class=\"port\">b</text>"), std::string::npos);
}

TEST(Draw, PngIsAPngImage) {
  TempDir dir;
  const fs::path png = dir.path() / "c.png";
  const auto [status, out] = run_cli("draw '" + std::string(PNEUMO_SOURCE_DIR) + "/netlists/sequence_ab.yaml' -o '" +
                                     png.string() + "'");
  ASSERT_EQ(status, 0) << out << " (rsvg-convert, Debian package librsvg2-bin, must be installed)";
  EXPECT_EQ(read_file(png).substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
}

TEST(Draw, RefusesAnOutputItCannotWriteAndAViewWithoutResults) {
  TempDir dir;
  const std::string nl = std::string(PNEUMO_SOURCE_DIR) + "/netlists/sequence_ab.yaml";
  auto [s1, o1] = run_cli("draw '" + nl + "' -o '" + (dir.path() / "c.pdf").string() + "'");
  EXPECT_EQ(s1, 2);
  EXPECT_NE(o1.find("give a name ending in .svg or .png"), std::string::npos) << o1;
  auto [s2, o2] = run_cli("draw '" + nl + "' -o '" + (dir.path() / "v.html").string() + "'");
  EXPECT_EQ(s2, 2);
  EXPECT_NE(o2.find("needs --results"), std::string::npos) << o2;
  EXPECT_FALSE(fs::exists(dir.path() / "v.html"));
  // another netlist's results: nothing in them to show
  const std::string csv = dir.write("other.csv", "t [s],q [1]\n0,1\n1,2\n");
  auto [s3, o3] = run_cli("draw '" + nl + "' --results '" + csv + "' -o '" + (dir.path() / "v.html").string() + "'");
  EXPECT_EQ(s3, 2);
  EXPECT_NE(o3.find("hold no output this view can show"), std::string::npos) << o3;
  EXPECT_FALSE(fs::exists(dir.path() / "v.html"));
}

TEST(Draw, ResultsViewInHeadlessChromiumDrawsThePistonHalfWayWhenTheCylinderIsHalfExtended) {
  TempDir dir;
  const std::string nl = std::string(PNEUMO_SOURCE_DIR) + "/netlists/sequence_ab.yaml";
  const std::string csv = (dir.path() / "run.csv").string();
  auto [s1, o1] = run_cli("simulate '" + nl + "' -q -o '" + csv + "'");
  ASSERT_EQ(s1, 0) << o1;
  // the first time cylinder A passes half its 100 mm stroke
  const pneumo::ResultsTable r = pneumo::read_csv(csv);
  const int cx = r.column("x_A");
  ASSERT_GE(cx, 0);
  ASSERT_EQ(r.units[static_cast<std::size_t>(cx)], "mm");  // the netlist's display; the view converts
  double t_half = -1, x_half = 0;  // mm
  for (const auto& row : r.rows)
    if (row[static_cast<std::size_t>(cx)] >= 50.0) {
      t_half = row[0];
      x_half = row[static_cast<std::size_t>(cx)];
      break;
    }
  ASSERT_GT(t_half, 0);
  const std::string view = (dir.path() / "view.html").string();
  auto [s2, o2] = run_cli("draw '" + nl + "' --results '" + csv + "' -o '" + view + "'");
  ASSERT_EQ(s2, 0) << o2;
  const fs::path dom = dir.path() / "dom.html";
  const std::string chromium = "chromium --headless --no-sandbox --disable-gpu --dump-dom 'file://" + view +
                               "#t=" + std::to_string(t_half) + "' > '" + dom.string() + "' 2>/dev/null";
  ASSERT_EQ(std::system(chromium.c_str()), 0) << "chromium (Debian package) must be installed: " << chromium;
  const std::string d = read_file(dom);
  // The barrel of cyl_A and its piston group, moved by the script.
  const std::size_t g = d.find("data-name=\"cyl_A\"");
  ASSERT_NE(g, std::string::npos);
  const std::string sym = d.substr(g, d.find('\n', g) - g);
  const std::regex barrel("<rect x=\"([0-9.]+)\" y=\"0\" width=\"([0-9.]+)\" height=\"40\"");
  std::smatch mb;
  ASSERT_TRUE(std::regex_search(sym, mb, barrel)) << sym;
  const double barrel_x = std::stod(mb[1]), barrel_w = std::stod(mb[2]);
  const std::regex piston("<g class=\"part piston\"[^>]*transform=\"translate\\(([-0-9.]+),([-0-9.]+)\\)\"");
  std::smatch mp;
  ASSERT_TRUE(std::regex_search(sym, mp, piston)) << "the script did not move the piston: " << sym;
  const std::regex head("<rect x=\"([0-9.]+)\" y=\"2\" width=\"([0-9.]+)\" height=\"36\" class=\"fill\"");
  std::smatch mh;
  ASSERT_TRUE(std::regex_search(sym, mh, head)) << sym;
  // piston centre, as a fraction of its travel inside the barrel
  const double w = std::stod(mh[2]), x = std::stod(mh[1]) + std::stod(mp[1]) + w / 2;
  const double travel_from = barrel_x + std::stod(mh[1]) + w / 2 - barrel_x;  // at x = 0
  const double travel = barrel_w - 2 * travel_from;
  EXPECT_NEAR((x - travel_from) / travel, x_half / 100.0, 0.01) << "piston at " << x << " px";
  EXPECT_NEAR((x - travel_from) / travel, 0.5, 0.03);
  // The cylinder's cap line is coloured by its pressure.
  EXPECT_NE(d.find("data-p-barg="), std::string::npos);
}

}  // namespace
