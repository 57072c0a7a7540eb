// The animated results view (results_view.hpp).
#include "framework/draw/results_view.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "framework/core/units.hpp"

namespace pneumo::draw {

namespace {

// The results column of output `component`.`quantity`, or -1.
int column_of(const Netlist& nl, const ResultsTable& r, const std::string& component, const std::string& quantity) {
  for (const auto& o : nl.outputs)
    if (o.component == component && o.quantity == quantity && !o.integral) {
      const int c = r.column(o.name);
      if (c >= 0) return c;
    }
  return -1;
}

// A column in SI (result files may show a display unit such as barg, mm).
std::vector<double> si_column(const ResultsTable& r, int c, double p_ambient) {
  std::vector<double> v;
  v.reserve(r.rows.size());
  const std::string& unit = r.units[static_cast<std::size_t>(c)];
  const bool convert = !unit.empty();
  const units::Unit u = convert ? units::parse_unit(unit) : units::Unit{};
  for (const auto& row : r.rows) v.push_back(convert ? units::to_si(u, row[c], p_ambient) : row[c]);
  return v;
}

// The SI value of parameter `name` of instance `i` (its default if not given).
double parameter_si(const Netlist& nl, const Circuit& circuit, int i, const std::string& name) {
  const auto& info = circuit.components[i]->info();
  const ParameterSpec* spec = info.parameter(name);
  if (!spec) return 1.0;
  if (const ComponentDecl* c = nl.component(circuit.components[i]->name()))
    if (const ValueDecl* v = c->written(name)) return parameter_value(nl, *c, *spec, *v);
  return spec->default_value.value_or(1.0);
}

void json_array(std::ostringstream& o, const std::vector<double>& v) {
  o << "[";
  for (std::size_t k = 0; k < v.size(); ++k) o << (k ? "," : "") << v[k];
  o << "]";
}

}  // namespace

std::string results_view_html(const Diagram& d, const Netlist& nl, const Circuit& circuit, const ResultsTable& r,
                              const std::string& results_name) {
  const double p_amb = circuit.gas.p_ambient;
  std::vector<int> used;  // results columns the view needs
  auto use = [&](int c) {
    auto it = std::find(used.begin(), used.end(), c);
    if (it != used.end()) return static_cast<int>(it - used.begin());
    used.push_back(c);
    return static_cast<int>(used.size() - 1);
  };
  std::vector<int> pressure_columns;
  std::ostringstream bind;
  bind << "{\"nets\":[";
  bool first = true;
  for (std::size_t k = 0; k < d.wires.size(); ++k) {
    const Wire& w = d.wires[k];
    if (w.domain != "pneumatic") continue;
    for (const auto& e : w.ends) {
      const auto& s = d.symbols[e.symbol];
      std::string q = e.port + ".p";
      for (const auto& [port, quantity] : s.symbol.port_pressure)
        if (port == e.port) q = quantity;
      const int c = column_of(nl, r, s.name, q);
      if (c < 0) continue;
      pressure_columns.push_back(c);
      bind << (first ? "" : ",") << "{\"id\":\"net" << k << "\",\"col\":" << use(c) << "}";
      first = false;
      break;
    }
  }
  bind << "],\"parts\":[";
  first = true;
  for (std::size_t i = 0; i < d.symbols.size(); ++i) {
    const auto& s = d.symbols[i];
    for (const auto& m : s.symbol.motions) {
      const int c = column_of(nl, r, s.name, m.quantity);
      if (c < 0) continue;
      const double full = m.full_scale_parameter.empty()
                              ? m.full_scale
                              : parameter_si(nl, circuit, static_cast<int>(i), m.full_scale_parameter);
      bind << (first ? "" : ",") << "{\"sym\":\"sym" << i << "\",\"part\":\"" << m.part << "\",\"col\":" << use(c)
           << ",\"full\":" << full << ",\"dx\":" << m.dx << ",\"dy\":" << m.dy << "}";
      first = false;
    }
  }
  bind << "],\"lamps\":[";
  first = true;
  for (std::size_t i = 0; i < d.symbols.size(); ++i) {
    const auto& s = d.symbols[i];
    if (s.symbol.lamp_quantity.empty()) continue;
    const int c = column_of(nl, r, s.name, s.symbol.lamp_quantity);
    if (c < 0) continue;
    bind << (first ? "" : ",") << "{\"sym\":\"sym" << i << "\",\"col\":" << use(c) << "}";
    first = false;
  }
  bind << "]}";
  if (used.empty())
    throw std::invalid_argument(
        "the results '" + results_name +
        "' hold no output this view can show (a pressure at a port, a piston position, a spool, a switch state); "
        "are they the results of this netlist? Add outputs such as CYL.x, CYL.p_cap, VALVE.x, SWITCH.state");

  std::ostringstream data;
  data << "{\"t\":";
  std::vector<double> t;
  for (const auto& row : r.rows) t.push_back(row[0]);
  json_array(data, t);
  data << ",\"cols\":[";
  double p_max = 1e5;
  for (std::size_t k = 0; k < used.size(); ++k) {
    const auto v = si_column(r, used[k], p_amb);
    data << (k ? "," : "");
    json_array(data, v);
  }
  data << "]}";
  // the pressure scale: up to the highest pressure shown, in whole bar
  for (int c : pressure_columns)
    for (double v : si_column(r, c, p_amb)) p_max = std::max(p_max, v - p_amb);
  const double bar_max = std::ceil(p_max / 1e5);

  std::ostringstream o;
  o << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" << "pneumo results view" << "</title>\n"
    << "<style>body{font-family:DejaVu Sans,sans-serif;margin:12px}#controls{display:flex;gap:12px;align-items:center;"
       "margin-bottom:8px}#slider{width:480px}#legend{display:flex;align-items:center;gap:6px;font-size:12px}"
       "#bar{width:200px;height:12px;background:linear-gradient(to right,hsl(240,80%,45%),hsl(180,80%,40%),"
       "hsl(120,80%,40%),hsl(60,90%,45%),hsl(0,85%,50%))}.net.p line{stroke-width:3}</style></head><body>\n"
    << "<div id=\"controls\"><button id=\"play\">play</button><input id=\"slider\" type=\"range\" min=\"0\" max=\""
    << (r.rows.empty() ? 0 : r.rows.size() - 1) << "\" value=\"0\"><span id=\"time\">t = 0 s</span>"
    << "<div id=\"legend\">0 bar g<div id=\"bar\"></div><span id=\"pmax\">" << bar_max << "</span> bar g</div></div>\n"
    << to_svg(d) << "<script>\nconst data = " << data.str() << ";\nconst bind = " << bind.str()
    << ";\nconst pAmb = " << p_amb << ", pScale = " << bar_max * 1e5 << ";\n"
    << R"JS(
function colour(pg) {
  const f = Math.max(0, Math.min(1, pg / pScale));
  return 'hsl(' + (240 * (1 - f)).toFixed(0) + ',80%,' + (45 - 5 * Math.sin(Math.PI * f)).toFixed(0) + '%)';
}
function show(k) {
  const t = data.t[k];
  document.getElementById('time').textContent = 't = ' + t.toFixed(3) + ' s';
  for (const n of bind.nets) {
    const g = document.getElementById(n.id);
    const pg = data.cols[n.col][k] - pAmb;
    g.classList.add('p');
    g.setAttribute('data-p-barg', (pg / 1e5).toFixed(3));
    for (const l of g.querySelectorAll('line')) l.style.stroke = colour(pg);
    for (const c of g.querySelectorAll('circle')) c.style.fill = colour(pg);
  }
  for (const m of bind.parts) {
    const f = data.cols[m.col][k] / m.full;
    const g = document.querySelector('#' + m.sym + ' > g.part.' + m.part);
    if (!g) continue;
    g.setAttribute('transform', 'translate(' + (f * m.dx).toFixed(2) + ',' + (f * m.dy).toFixed(2) + ')');
    g.setAttribute('data-fraction', f.toFixed(4));
  }
  for (const l of bind.lamps) {
    const g = document.querySelector('#' + l.sym + ' > g.part.lamp');
    if (g) g.classList.toggle('lit', data.cols[l.col][k] > 0.5);
  }
}
function index_at(t) {
  let k = 0;
  while (k + 1 < data.t.length && data.t[k + 1] <= t) ++k;
  return k;
}
const slider = document.getElementById('slider');
slider.addEventListener('input', () => show(+slider.value));
let timer = null;
document.getElementById('play').addEventListener('click', () => {
  if (timer) { clearInterval(timer); timer = null; return; }
  const t0 = performance.now(), start = data.t[+slider.value] || 0;
  timer = setInterval(() => {
    const t = start + (performance.now() - t0) / 1000 * 0.25;  // quarter speed
    const k = index_at(t);
    slider.value = k;
    show(k);
    if (k + 1 >= data.t.length) { clearInterval(timer); timer = null; }
  }, 40);
});
const m = /t=([0-9.eE+-]+)/.exec(location.hash);
const k0 = m ? index_at(parseFloat(m[1])) : 0;
slider.value = k0;
show(k0);
)JS"
    << "</script>\n</body></html>\n";
  return o.str();
}

}  // namespace pneumo::draw
