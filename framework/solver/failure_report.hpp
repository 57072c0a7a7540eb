// Words for a failed integration: which unknowns and equations failed, and
// what happened just before, in the names of the netlist (components, nodes
// "p at cyl.rod + flow_rod.a"), so that a user knows where to look.
#pragma once

#include <nvector/nvector_serial.h>

#include <string>
#include <vector>

#include "framework/assembly/system.hpp"
#include "framework/solver/ida_callbacks.hpp"

namespace pneumo {

// IDA gave up on a step from t: the unknowns with the largest weighted
// local error of its last step, the equations a component rejected at the
// last state (a residual that is not finite), the last event before t.
std::string step_failure_report(void* ida, UserData& u, N_Vector y, N_Vector yp, double t,
                                const std::vector<EventLogEntry>& events);

// When the unknown with the largest weighted local error of IDA's last step
// is the pressure of a junction without volume: that it is, and the line to
// draw as a volume there; else empty. Reads IDA's memory only.
std::string junction_failure_hint(void* ida, const System& s, N_Vector y);

// No consistent values at t: the unknowns no equation determines there (a
// zero column of the Newton matrix: a node between closed ports or flat
// flow laws), equations that depend on no unknown there, and the equations
// furthest from holding at IDA's last iterate (y, yp).
std::string start_failure_report(UserData& u, N_Vector y, N_Vector yp, double t);

}  // namespace pneumo
