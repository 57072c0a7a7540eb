// Energy audits of the components that declare one (Component::energy_audit,
// e.g. a cylinder's cushioning): where the energy that entered a window of
// the motion went.
//
// prepare_energy_audit() asks every component of the run's circuit (as
// elaborated for the run: no second elaboration) for its declaration and
// adds the outputs the audit reads to that circuit: the declared
// observables (integrals as IDAS quadratures, so the accounts are as
// accurate as the trajectory) and the kinetic energy of every mass on the
// declared flange's node (observables of role "kinetic_energy"). After the
// run, energy_audit() evaluates each term over the window - from the
// component's opening event to the first row where its closing observable
// is <= 0 (else the end of the run). The component's balances make
// in - out vanish exactly; the residual is the solver's error. The audit
// knows no component by name.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "framework/model/registry.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo {

struct AuditTerm {
  std::string name;         // machine name (YAML key)
  std::string description;  // for the printed table
  double joules = 0.0;
};

struct EnergyAudit {
  std::string component;
  std::string title;             // what is audited ("cap-end cushioning")
  std::string open_description;  // what opens the window ("cushion entry")
  bool opened = false;           // false: the opening event never happened
  double t_open = 0.0;           // s
  double t_close = 0.0;          // s
  std::string close_reason;
  double speed_at_open = 0.0;    // the closing observable at the opening (a velocity)
  std::vector<AuditTerm> in, out;
  double total_in = 0.0, total_out = 0.0;
  double residual() const { return total_in - total_out; }
};

// One component's declaration and the output columns that carry it.
struct AuditPlan {
  std::string component;
  EnergyAuditSpec spec;
  std::vector<std::string> kinetic_columns;  // one per mass on the flange's node
};

// Adds the audits' outputs (named "audit.<component>. ...") to `circuit`,
// elaborated from `netlist` and not yet assembled; returns one plan per
// component that declares an audit (may be empty).
std::vector<AuditPlan> prepare_energy_audit(const Netlist& netlist, Circuit& circuit);

// The audits of a finished run of a netlist prepared as above.
std::vector<EnergyAudit> energy_audit(const std::vector<AuditPlan>& plans, const RunResult& run);

// Removes the audit's columns from a results table (the user's -o file
// holds only the netlist's own outputs).
void drop_audit_columns(ResultsTable& table);

void print_audit(const EnergyAudit& a, std::ostream& out);
// YAML, one document with a list of audits.
void write_audit_yaml(const std::vector<EnergyAudit>& audits, std::ostream& out);

}  // namespace pneumo
