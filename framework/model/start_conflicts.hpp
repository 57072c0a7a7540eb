// Start values that two components fix differently on one node.
#pragma once

#include "framework/model/circuit.hpp"

namespace pneumo {

// Throws InputError at a connection if two components on one mechanical
// node fix its start position (or velocity) to values farther apart than
// 1 um (1 um/s): assembly would keep one of them and silently ignore the
// other (a frame at 50 mm holding the flange of a cylinder that starts
// retracted held the rod at 0).
void check_start_conflicts(const Circuit& circuit);

}  // namespace pneumo
