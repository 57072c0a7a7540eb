#include "framework/diagnose/sensors.hpp"

#include <algorithm>
#include <cmath>

#include "framework/core/parallel.hpp"
#include "framework/core/text.hpp"
#include "framework/diagnose/statistics.hpp"
#include "framework/model/circuit.hpp"
#include "framework/run/run.hpp"

namespace pneumo::diagnose {

namespace {

struct SensorKind {
  const char* unit;
  double sigma;  // typical industrial sensor noise, SI
  const char* words;
};

// Typical noise of a sensor for each unit, used when no measured signal has
// that unit: a 0-10 bar transducer at 0.1 % of span, a thin thermocouple, a
// linear encoder, a velocity from an encoder's differences, a load cell, a
// thermal mass-flow meter at 1 % of 1 kg/min.
constexpr SensorKind kSensorNoise[] = {
    {"Pa", 1e3, "a pressure sensor"},  {"K", 0.3, "a temperature sensor"}, {"m", 2e-5, "a position sensor"},
    {"m/s", 1e-3, "a velocity sensor"}, {"N", 1.0, "a force sensor"},      {"kg/s", 2e-4, "a mass-flow sensor"},
};

const SensorKind* kind_of(const std::string& unit) {
  for (const auto& k : kSensorNoise)
    if (unit == k.unit) return &k;
  return nullptr;
}

// The model with every sensor quantity as an output (metrics dropped: they
// may name outputs this run does not need).
Netlist with_all_outputs(Netlist nl, const std::vector<SensorQuantity>& qs) {
  nl.metrics.clear();
  for (const auto& q : qs) {
    OutputDecl o;
    o.name = q.name();
    o.component = q.component;
    o.quantity = q.quantity;
    o.where = nl.parameters_where;
    nl.outputs.push_back(std::move(o));
  }
  return nl;
}

}  // namespace

std::vector<SensorQuantity> sensor_quantities(const Netlist& model, const Registry& registry) {
  const Circuit c = elaborate(model, registry);
  std::vector<SensorQuantity> out;
  for (const auto& comp : c.components) {
    const auto names = local_variable_names(*comp), units = local_variable_units(*comp);
    for (std::size_t i = 0; i < names.size(); ++i)
      if (kind_of(units[i]) && !is_entering_stream_temperature(names[i])) out.push_back({comp->name(), names[i], units[i]});
    for (const auto& o : comp->info().observables)
      if (kind_of(o.unit)) out.push_back({comp->name(), o.name, o.unit});
  }
  return out;
}

std::map<std::string, double> sensor_noise(const std::map<std::string, double>& measured_by_unit) {
  std::map<std::string, double> out;
  for (const auto& k : kSensorNoise) out[k.unit] = k.sigma;
  for (const auto& [unit, sigma] : measured_by_unit)
    if (sigma > 0) out[unit] = sigma;
  return out;
}

SensorChoice choose_sensor(const std::string& effect_a, const std::string& effect_b,
                           const std::vector<Netlist>& runs_a, const std::vector<Netlist>& runs_b,
                           const Registry& registry, const std::map<std::string, double>& noise_by_unit,
                           const std::map<std::string, std::string>& measured, int threads) {
  SensorChoice choice{effect_a, effect_b, {}, 0, {}, {}};
  if (runs_a.empty() || runs_a.size() != runs_b.size()) return choice;
  const auto qs = sensor_quantities(runs_a.front(), registry);
  const long nr = static_cast<long>(runs_a.size());
  std::vector<RunResult> res(2 * nr);
  parallel_for(2 * nr, threads, [&](int, long j) {
    try {
      res[j] = run_simulation(with_all_outputs(j < nr ? runs_a[j] : runs_b[j - nr], qs), registry);
    } catch (const std::exception& ex) {
      res[j].solver.ok = false;  // a model that does not run here separates nothing
      res[j].solver.message = ex.what();
    }
  });
  std::vector<double> ssr(qs.size(), 0.0);
  long n = 0;
  for (long k = 0; k < nr; ++k) {
    const RunResult &a = res[k], &b = res[nr + k];
    if (!a.solver.ok || !b.solver.ok || a.table.rows.size() < 2 || b.table.rows.size() < 2) {
      for (const auto& [effect, r] : {std::pair{&effect_a, &a}, {&effect_b, &b}})
        if (!r->solver.ok || r->table.rows.size() < 2)
          choice.run_failures.push_back("run " + std::to_string(k + 1) + " of " + *effect + ": " +
                                        (r->solver.ok ? "fewer than two output rows" : r->solver.message));
      continue;
    }
    std::vector<double> tb;
    for (const auto& row : b.table.rows) tb.push_back(row[0]);
    for (std::size_t q = 0; q < qs.size(); ++q) {
      const int ca = a.table.column(qs[q].name()), cb = b.table.column(qs[q].name());
      std::vector<double> yb;
      for (const auto& row : b.table.rows) yb.push_back(row[cb]);
      const double sigma = noise_by_unit.at(qs[q].unit);
      for (const auto& row : a.table.rows) {
        const double d = (row[ca] - interp(tb, yb, row[0])) / sigma;
        ssr[q] += d * d;
      }
    }
    n += static_cast<long>(a.table.rows.size());
  }
  if (n == 0) return choice;
  std::vector<SensorSeparation> all;
  for (std::size_t q = 0; q < qs.size(); ++q)
    all.push_back({qs[q].name(), qs[q].unit, noise_by_unit.at(qs[q].unit), std::sqrt(ssr[q] / n),
                   measured.count(qs[q].name()) > 0});
  // Quantities of one node (a port's pressure on each component it joins)
  // give the same trace: one of them stands for all, a measured one first.
  auto same = [](const SensorSeparation& x, const SensorSeparation& y) {
    return x.unit == y.unit && std::abs(x.separation - y.separation) <= 1e-9 * std::max(1.0, x.separation);
  };
  std::stable_sort(all.begin(), all.end(), [](const auto& x, const auto& y) { return x.measured > y.measured; });
  std::vector<SensorSeparation> distinct;
  for (const auto& s : all)
    if (std::none_of(distinct.begin(), distinct.end(), [&](const auto& d) { return same(d, s); }))
      distinct.push_back(s);
  for (const auto& s : distinct)
    if (s.measured && s.separation >= choice.measured_separation) {
      choice.measured_separation = s.separation;
      choice.measured_signal = measured.at(s.quantity);
    }
  for (const auto& s : distinct)
    if (!s.measured) choice.best.push_back(s);
  std::stable_sort(choice.best.begin(), choice.best.end(),
                   [](const auto& x, const auto& y) { return x.separation > y.separation; });
  if (choice.best.size() > 3) choice.best.resize(3);
  return choice;
}

std::string sensor_sentence(const SensorChoice& c) {
  if (c.best.empty()) return {};
  const auto& s = c.best.front();
  return std::string(kind_of(s.unit)->words) + " at " + s.quantity + " would separate " + c.effect_a + " from " +
         c.effect_b + " by " + rounded(s.separation, 2) + " noise sd (the measured signals: " +
         rounded(c.measured_separation, 2) + " at best)";
}

std::string sensor_clause(const SensorChoice& c) {
  if (c.best.empty() || c.best.front().separation < 1) return {};  // a sensor that sees less than its noise decides nothing
  const auto& s = c.best.front();
  return "measure " + s.quantity + " (" + kind_of(s.unit)->words + ": " + rounded(s.separation, 2) +
         " noise sd over the measured runs)";
}

}  // namespace pneumo::diagnose
