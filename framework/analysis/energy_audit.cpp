#include "framework/analysis/energy_audit.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

namespace pneumo {

namespace {

const char* kCylinderType = "cushioned_cylinder";
const std::string kPrefix = "audit.";

bool has_parameter(const ComponentDecl& c, const std::string& name) {
  for (const auto& [k, v] : c.parameters)
    if (k == name) return true;
  return false;
}

std::string text_parameter(const ComponentDecl& c, const std::string& name) {
  for (const auto& [k, v] : c.parameters)
    if (k == name && v.IsScalar()) return v.as<std::string>();
  return "";
}

double scalar_parameter(const Netlist& nl, const ComponentDecl& c, const std::string& name, const std::string& unit,
                        double fallback) {
  for (const auto& [k, v] : c.parameters)
    if (k == name) return parameter_value(nl, c, ParameterSpec::scalar(name, unit, ""), v);
  return fallback;
}

// Sum of the masses of the translational_mass components sharing a node with
// `component`.`port` (union of the connection sets that contain it).
double moving_mass(const Netlist& nl, const std::string& component, const std::string& port) {
  std::map<std::string, std::string> parent;
  auto find = [&](std::string k) {
    if (!parent.count(k)) parent[k] = k;
    while (parent[k] != k) k = parent[k] = parent[parent[k]];
    return k;
  };
  for (const auto& c : nl.connections)
    for (std::size_t i = 1; i < c.ports.size(); ++i)
      parent[find(c.ports[i].component + "." + c.ports[i].port)] = find(c.ports[0].component + "." + c.ports[0].port);
  const std::string node = find(component + "." + port);
  // Each mass appears once per connection that names it; count it once.
  double unique = 0.0;
  std::map<std::string, bool> seen;
  for (const auto& c : nl.connections)
    for (const auto& p : c.ports)
      if (find(p.component + "." + p.port) == node && !seen[p.component])
        for (const auto& d : nl.components)
          if (d.name == p.component && d.type == "translational_mass") {
            seen[p.component] = true;
            unique += scalar_parameter(nl, d, "m", "kg", 0.0);
          }
  return unique;
}

struct Accounts {
  bool rod_cushion = false, taps = false;
};

Accounts accounts_of(const ComponentDecl& c) {
  return {has_parameter(c, "rod_plug_diameter"), text_parameter(c, "cushion_taps") == "yes"};
}

}  // namespace

std::vector<std::string> prepare_energy_audit(Netlist& nl) {
  std::vector<std::string> cylinders;
  for (const auto& c : nl.components) {
    if (c.type != kCylinderType) continue;
    cylinders.push_back(c.name);
    const Accounts a = accounts_of(c);
    auto add = [&](const std::string& account, const std::string& quantity, bool integral) {
      nl.outputs.push_back({kPrefix + c.name + "." + account, c.name, quantity, c.where, integral});
    };
    add("x", "x", false);
    add("v", "v", false);
    add("U_EC", "U_EC", false);
    add("W_A", "P_pdV_A", true);
    if (a.rod_cushion) add("W_EC_rod", "P_pdV_EC_rod", true);
    add("W_EC", "P_pdV_EC", true);
    add("W_ch", "P_pdV_ch", true);
    add("H_cushion", "H_cushion", true);
    add("Q_cap", "Q_cap", true);
    if (a.taps) add("H_tap", "H_EC", true);
    add("E_friction", "P_friction", true);
    add("E_stop", "P_stop", true);
  }
  return cylinders;
}

void drop_audit_columns(ResultsTable& table) {
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < table.names.size(); ++i)
    if (table.names[i].rfind(kPrefix, 0) != 0) keep.push_back(i);
  auto filter = [&](auto& v) {
    std::remove_reference_t<decltype(v)> out;
    for (std::size_t i : keep) out.push_back(v[i]);
    v = std::move(out);
  };
  filter(table.names);
  filter(table.units);
  for (auto& row : table.rows) filter(row);
}

std::vector<CushionAudit> energy_audit(const Netlist& nl, const RunResult& run) {
  std::vector<CushionAudit> audits;
  const ResultsTable& tab = run.table;
  for (const auto& c : nl.components) {
    if (c.type != kCylinderType) continue;
    const Accounts acc = accounts_of(c);
    CushionAudit a;
    a.cylinder = c.name;
    a.moving_mass = moving_mass(nl, c.name, "flange");
    for (const auto& e : run.solver.events)
      if (e.component == c.name && e.message.rfind("enters the cushioning zone", 0) == 0) {
        a.entered = true;
        a.t_entry = e.t;
        break;
      }
    if (tab.rows.empty()) {
      audits.push_back(a);
      continue;
    }
    a.t_end = tab.rows.back()[0];
    if (!a.entered) {
      audits.push_back(a);
      continue;
    }
    // The row written right after the entry event (its time is the event's).
    std::size_t ke = 0;
    while (ke + 1 < tab.rows.size() && tab.rows[ke][0] < a.t_entry - 1e-12) ++ke;
    auto col = [&](const std::string& account) {
      const int i = tab.column(kPrefix + c.name + "." + account);
      if (i < 0) throw std::runtime_error("energy audit: no column for " + c.name + "." + account);
      return i;
    };
    auto at = [&](const std::string& account, std::size_t k) { return tab.rows[k][col(account)]; };
    // The window ends when the piston first stops (or turns back: a
    // rebound from the cushion or from the stop), else at the end of the run.
    std::size_t kend = tab.rows.size() - 1;
    a.end_reason = "end of the run";
    for (std::size_t k = ke + 1; k < tab.rows.size(); ++k)
      if (at("v", k) <= 0.0) {
        kend = k;
        a.end_reason = "first standstill or reversal";
        break;
      }
    a.t_end = tab.rows[kend][0];
    auto delta = [&](const std::string& account) { return at(account, kend) - at(account, ke); };
    const double M = a.moving_mass;
    a.v_entry = at("v", ke);
    const double v_end = at("v", kend);
    const double A_R = M_PI / 4 * std::pow(scalar_parameter(nl, c, "rod", "m", 0.0), 2);
    const double W_ambient = nl.gas.p_ambient * A_R * (at("x", kend) - at("x", ke));
    double W_drive = delta("W_A") + W_ambient;
    if (acc.rod_cushion) W_drive += delta("W_EC_rod");
    a.in = {{"kinetic_energy_at_entry", "kinetic energy at cushion entry", 0.5 * M * a.v_entry * a.v_entry},
            {"driving_work", "work of the rod-side gas and ambient on the piston", W_drive}};
    // The gas leaving the cushion volume carries its internal energy u = h / kappa
    // and was pushed out with the flow work p/rho = h (kappa - 1) / kappa. The
    // compression of the cushion gas (all of it, including what has left) is
    // the change of its internal energy, dU_EC + H/kappa; the flow work is
    // what the throttle (and bore opening) dissipates in its jet.
    const double kappa = nl.gas.kappa;
    const double H_out = delta("H_cushion") - (acc.taps ? delta("H_tap") : 0.0);
    a.out = {{"cushion_gas_compression", "compression of the cushion gas (its internal energy)",
              delta("U_EC") + H_out / kappa},
             {"cushion_throttle_dissipation", "flow work through the cushion throttle / bore opening",
              H_out * (kappa - 1.0) / kappa},
             {"heat_to_walls", "heat from the cushion gas to the walls", -delta("Q_cap")},
             {"channel_work", "work on the plug column / channel gas (expelled at port B)", -delta("W_ch")},
             {"friction", "dissipated by friction", -delta("E_friction")},
             {"end_stop", "absorbed by the end stop (damping + spring)", -delta("E_stop")},
             {"kinetic_energy_at_end", "kinetic energy left at the end", 0.5 * M * v_end * v_end}};
    for (auto& t : a.out) t.joules += 0.0;  // no "-0"
    for (const auto& t : a.in) a.total_in += t.joules;
    for (const auto& t : a.out) a.total_out += t.joules;
    audits.push_back(a);
  }
  return audits;
}

void print_audit(const CushionAudit& a, std::ostream& out) {
  out << "energy audit of " << a.cylinder << " (moving mass " << a.moving_mass << " kg)";
  if (!a.entered) {
    out << ": the piston did not reach the cap-end cushioning zone by t = " << a.t_end << " s\n";
    return;
  }
  out << ", from cushion entry at t = " << a.t_entry << " s (" << a.v_entry << " m/s) to t = " << a.t_end
      << " s (" << a.end_reason << ")\n";
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
  out << "  balance: in " << a.total_in << " J, out " << a.total_out << " J, residual " << a.residual() << " J ("
      << std::setprecision(3) << 100.0 * a.residual() / base << " % of the input)\n"
      << std::defaultfloat;
}

void write_audit_yaml(const std::vector<CushionAudit>& audits, std::ostream& out) {
  out << std::setprecision(10);
  out << "# pneumo energy audit: energy into and out of each cylinder's cap-end cushioning zone,\n"
         "# from the cushion entry event to the end of the run; J.\n";
  out << "audits:\n";
  for (const auto& a : audits) {
    out << "  - cylinder: " << a.cylinder << "\n";
    out << "    entered_cushion: " << (a.entered ? "true" : "false") << "\n";
    out << "    moving_mass: " << a.moving_mass << "\n";
    if (!a.entered) continue;
    out << "    t_entry: " << a.t_entry << "\n    t_end: " << a.t_end << "\n    window_end: " << a.end_reason
        << "\n    v_entry: " << a.v_entry << "\n";
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
