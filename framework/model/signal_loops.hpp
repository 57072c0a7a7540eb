// Loops of memoryless signal blocks (logic gates): refused before assembly.
#pragma once

#include "framework/model/circuit.hpp"

namespace pneumo {

// A component whose ports are all signals and which has no internal
// variables, modes, roots or input-following: its outputs are functions of
// its inputs at the same instant (a logic gate).
bool is_memoryless_signal_block(const ComponentInfo& info);

// Throws InputError at a connection of the loop, naming its components, if
// outputs of memoryless signal blocks feed back to their own inputs through
// other such blocks. Such a loop has no 0/1 solution: a NOT gate fed by its
// own output "settles" at y = 1 - y = 0.5, an even loop has any value. A
// real gate's delay would make it oscillate at a rate the model cannot
// know; memory and rhythm belong to components with modes (flip-flops,
// timers).
void check_signal_loops(const Circuit& circuit);

}  // namespace pneumo
