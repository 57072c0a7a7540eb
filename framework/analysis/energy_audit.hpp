// Cushioning energy audit: the kinetic energy a cylinder brings into its
// cap-end cushioning zone, and where it - together with the driving work
// done while cushioning - went.
//
// For every cushioned_cylinder of a netlist, prepare_energy_audit() adds
// integral outputs of the cylinder's power observables (integrated by the
// solver as IDAS quadratures, so the accounts are as accurate as the
// trajectory) and the samples it needs. After the run, energy_audit() takes
// the accounts from the cushion entry event to the piston's first standstill
// or reversal after it (the end of the run if it never stops):
//
//   in:  kinetic energy at entry   1/2 M v_entry^2   (M: the translational
//                                   masses on the cylinder's flange node)
//        driving work              rod-side gas and ambient on the piston
//   out: cushion gas compression   internal energy gained by the cushion gas
//                                   (including the gas that has left it:
//                                   dU_EC + H_out / kappa)
//        throttle dissipation      flow work pushing that gas out through the
//                                   needle throttle, bore opening, check valve
//                                   and tap: H_out (kappa - 1) / kappa
//        heat to the walls         from the cushion gas
//        channel work              work on the plug column / channel gas,
//                                   expelled through port B
//        friction                  dissipated by the piston friction
//        end stop                  absorbed by the elastic stop (damping +
//                                   spring energy left)
//        kinetic energy at the end
//
// The cushion gas's energy balance and the piston's equation of motion make
// in - out vanish exactly; the audit's residual is the solver's error.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "framework/netlist/netlist.hpp"
#include "framework/run/run.hpp"

namespace pneumo {

struct AuditTerm {
  std::string name;         // machine name (YAML key)
  std::string description;  // for the printed table
  double joules = 0.0;
};

struct CushionAudit {
  std::string cylinder;
  bool entered = false;      // false: the piston never reached the cushioning zone
  double t_entry = 0.0;      // s
  double t_end = 0.0;        // s: first standstill or reversal after entry, else end of the run
  std::string end_reason;
  double v_entry = 0.0;      // m/s
  double moving_mass = 0.0;  // kg
  std::vector<AuditTerm> in, out;
  double total_in = 0.0, total_out = 0.0;
  double residual() const { return total_in - total_out; }
};

// Adds the audit's outputs (named "audit.<cylinder>.<account>") to the
// netlist; returns the names of the cylinders audited (may be empty).
std::vector<std::string> prepare_energy_audit(Netlist& netlist);

// The audits of a finished run of a netlist prepared as above.
std::vector<CushionAudit> energy_audit(const Netlist& netlist, const RunResult& run);

// Removes the audit's columns from a results table (the user's -o file
// holds only the netlist's own outputs).
void drop_audit_columns(ResultsTable& table);

void print_audit(const CushionAudit& a, std::ostream& out);
// YAML, one document with a list of audits.
void write_audit_yaml(const std::vector<CushionAudit>& audits, std::ostream& out);

}  // namespace pneumo
