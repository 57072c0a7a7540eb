// A request to stop the work under way, process-wide: the Python binding
// sets it when Ctrl-C arrives while C++ runs (Python only sees its signals
// between bytecodes, so without it a sweep would finish first). The solver
// looks at it before every step and throws Interrupted.
//
// Interrupted is deliberately not a std::exception: the places that turn a
// failed run into a record ("catch (const std::exception&)" in sweeps,
// fits and optimisers) must not swallow it as one more failure.
#pragma once

namespace pneumo {

struct Interrupted {};

void request_interrupt();
void clear_interrupt();
bool interrupt_requested();

inline void throw_if_interrupted() {
  if (interrupt_requested()) throw Interrupted{};
}

}  // namespace pneumo
