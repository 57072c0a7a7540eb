#include "framework/analysis/energy_audit.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <set>
#include <stdexcept>

namespace pneumo {

namespace {

const std::string kPrefix = "audit.";

std::string column_of(const std::string& component, const std::string& account) {
  return kPrefix + component + "." + account;
}

// The components with a port on the same node as `port` of component `c`
// (the union of the connections that share ports with it, transitively).
std::set<int> components_on_node(const Circuit& circuit, int c, int port) {
  std::set<std::pair<int, int>> node = {{c, port}};
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& conn : circuit.connections) {
      const bool touches = std::any_of(conn.ports.begin(), conn.ports.end(),
                                       [&](const PortId& p) { return node.count({p.component, p.port}) > 0; });
      if (!touches) continue;
      for (const auto& p : conn.ports) grew |= node.insert({p.component, p.port}).second;
    }
  }
  std::set<int> out;
  for (const auto& [comp, _] : node) out.insert(comp);
  return out;
}

int kinetic_observable(const Component& c) {
  const auto& obs = c.info().observables;
  for (std::size_t k = 0; k < obs.size(); ++k)
    if (obs[k].role == "kinetic_energy") return static_cast<int>(k);
  return -1;
}

}  // namespace

std::vector<AuditPlan> prepare_energy_audit(const Netlist& nl, Circuit& circuit) {
  const SourceLocation where{nl.file, 1, 1};
  std::vector<AuditPlan> plans;
  for (std::size_t i = 0; i < circuit.components.size(); ++i) {
    const Component& c = *circuit.components[i];
    auto spec = c.energy_audit(circuit.gas);
    if (!spec) continue;
    AuditPlan plan{c.name(), *spec, {}};
    std::set<std::string> added;
    auto add = [&](const std::string& quantity, bool integral) {
      const std::string account = (integral ? "int." : "") + quantity;
      if (!added.insert(account).second) return;
      add_output(nl, circuit, {column_of(c.name(), account), c.name(), quantity, where, integral, "", {}});
    };
    if (!spec->closes_when_not_positive.empty()) add(spec->closes_when_not_positive, false);
    for (const auto& t : spec->terms) {
      for (const auto& [q, _] : t.changes) add(q, false);
      for (const auto& [q, _] : t.integrals) add(q, true);
    }
    if (!spec->kinetic_port.empty()) {
      const int port = c.info().port_index(spec->kinetic_port);
      for (int m : components_on_node(circuit, static_cast<int>(i), port)) {
        const Component& mass = *circuit.components[m];
        const int k = kinetic_observable(mass);
        if (k < 0) continue;
        const std::string col = column_of(c.name(), "kinetic." + mass.name());
        add_output(nl, circuit, {col, mass.name(), mass.info().observables[k].name, where, false, "", {}});
        plan.kinetic_columns.push_back(col);
      }
    }
    plans.push_back(std::move(plan));
  }
  return plans;
}

void drop_audit_columns(ResultsTable& table) { table.drop_columns(kPrefix); }

namespace {

// The rows that bound the window: the row written at the opening event
// (event rows carry the event's time) and the first row after it where the
// closing observable is <= 0.
struct Window {
  std::size_t open = 0, close = 0;
};

class AuditTable {
 public:
  AuditTable(const ResultsTable& t, const std::string& component) : t_(t), component_(component) {}
  int column(const std::string& account) const {
    const int i = t_.column(column_of(component_, account));
    if (i < 0) throw std::runtime_error("energy audit: no column for " + component_ + "." + account);
    return i;
  }
  double at(const std::string& account, std::size_t row) const { return t_.rows[row][column(account)]; }
  double change(const std::string& account, const Window& w) const { return at(account, w.close) - at(account, w.open); }
  double kinetic(const std::vector<std::string>& columns, std::size_t row) const {
    double e = 0.0;
    for (const auto& c : columns) e += t_.rows[row][t_.column(c)];
    return e;
  }

 private:
  const ResultsTable& t_;
  const std::string& component_;
};

double term_value(const EnergyTerm& term, const AuditTable& tab, const Window& w,
                  const std::vector<std::string>& kinetic) {
  double sum = 0.0;
  for (const auto& [q, c] : term.changes) sum += c * tab.change(q, w);
  for (const auto& [q, c] : term.integrals) sum += c * tab.change("int." + q, w);
  if (term.kinetic == EnergyTerm::Kinetic::at_open) sum += tab.kinetic(kinetic, w.open);
  if (term.kinetic == EnergyTerm::Kinetic::at_close) sum += tab.kinetic(kinetic, w.close);
  return sum + 0.0;  // no "-0"
}

EnergyAudit audit_one(const AuditPlan& plan, const RunResult& run) {
  const EnergyAuditSpec& spec = plan.spec;
  const ResultsTable& rows = run.table;
  EnergyAudit a;
  a.component = plan.component;
  a.title = spec.title;
  a.open_description = spec.open_description.empty() ? "start of the run" : spec.open_description;
  if (rows.rows.empty()) return a;
  a.t_open = rows.rows.front()[0];
  a.t_close = rows.rows.back()[0];
  a.opened = spec.opens_at.empty();
  for (const auto& e : run.solver.events)
    if (!a.opened && e.component == plan.component && e.tag == spec.opens_at) {
      a.opened = true;
      a.t_open = e.t;
    }
  if (!a.opened) return a;
  const AuditTable tab(rows, plan.component);
  Window w;
  while (w.open + 1 < rows.rows.size() && rows.rows[w.open][0] < a.t_open - 1e-12) ++w.open;
  w.close = rows.rows.size() - 1;
  a.close_reason = "end of the run";
  const std::string& stop = spec.closes_when_not_positive;
  if (!stop.empty()) {
    const int c = tab.column(stop);  // looked up once: the scan reads it on every row
    a.speed_at_open = rows.rows[w.open][c];
    for (std::size_t k = w.open + 1; k < rows.rows.size(); ++k)
      if (rows.rows[k][c] <= 0.0) {
        w.close = k;
        a.close_reason = "first standstill or reversal";
        break;
      }
  }
  a.t_close = rows.rows[w.close][0];
  for (const auto& t : spec.terms)
    (t.in ? a.in : a.out).push_back({t.name, t.description, term_value(t, tab, w, plan.kinetic_columns)});
  for (const auto& t : a.in) a.total_in += t.joules;
  for (const auto& t : a.out) a.total_out += t.joules;
  return a;
}

}  // namespace

std::vector<EnergyAudit> energy_audit(const std::vector<AuditPlan>& plans, const RunResult& run) {
  std::vector<EnergyAudit> audits;
  for (const auto& p : plans) audits.push_back(audit_one(p, run));
  return audits;
}

void print_audit(const EnergyAudit& a, std::ostream& out) {
  const auto precision = out.precision();
  out << "energy audit of " << a.component << " (" << a.title << ")";
  if (!a.opened) {
    out << ": no " << a.open_description << " by t = " << a.t_close << " s\n";
    return;
  }
  out << ", from " << a.open_description << " at t = " << a.t_open << " s (" << a.speed_at_open << " m/s) to t = "
      << a.t_close << " s (" << a.close_reason << ")\n";
  const double base = std::abs(a.total_in) > 0 ? std::abs(a.total_in) : 1.0;
  auto line = [&](const AuditTerm& t) {
    out << "  " << std::left << std::setw(58) << t.description << std::right << std::setw(12) << std::setprecision(6)
        << t.joules << " J " << std::setw(7) << std::fixed << std::setprecision(2) << 100.0 * t.joules / base
        << " %\n"
        << std::defaultfloat;
  };
  out << "  in:\n";
  for (const auto& t : a.in) line(t);
  out << "  out:\n";
  for (const auto& t : a.out) line(t);
  out << std::setprecision(6) << "  balance: in " << a.total_in << " J, out " << a.total_out << " J, residual " << a.residual() << " J ("
      << std::setprecision(3) << 100.0 * a.residual() / base << " % of the input)\n"
      << std::defaultfloat << std::setprecision(precision);
}

void write_audit_yaml(const std::vector<EnergyAudit>& audits, std::ostream& out) {
  out << std::setprecision(10);
  out << "# pneumo energy audit: for each component that declares one, the energy into and out of\n"
         "# its audited window (from the opening event to the first standstill or the end of the run); J.\n";
  out << "audits:\n";
  for (const auto& a : audits) {
    out << "  - component: " << a.component << "\n";
    out << "    title: " << a.title << "\n";
    out << "    opened: " << (a.opened ? "true" : "false") << "\n";
    if (!a.opened) continue;
    out << "    t_open: " << a.t_open << "\n    t_close: " << a.t_close << "\n    window_end: " << a.close_reason
        << "\n    speed_at_open: " << a.speed_at_open << "\n";
    out << "    in:\n";
    for (const auto& t : a.in) out << "      " << t.name << ": " << t.joules << "\n";
    out << "    out:\n";
    for (const auto& t : a.out) out << "      " << t.name << ": " << t.joules << "\n";
    out << "    total_in: " << a.total_in << "\n    total_out: " << a.total_out << "\n";
    out << "    residual: " << a.residual() << "\n";
    out << "    residual_relative: " << (a.total_in != 0 ? a.residual() / a.total_in : 0.0) << "\n";
  }
}

}  // namespace pneumo
