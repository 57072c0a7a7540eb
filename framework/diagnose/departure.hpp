// Where a patched model first departs from a run of the unpatched one. A
// fault that acts only once its part works - a throttle's needle once gas
// flows through it, a valve's delay once it is switched, a piston's
// friction once it moves - leaves everything before that as the unpatched
// run has it, so the patched model's run resumes from the unpatched run's
// checkpoint there (run/run.hpp: Resumption) instead of integrating it
// again. On a line of drives that switch one after another, the faults of
// the later drives skip most of the run.
#pragma once

#include "framework/assembly/system.hpp"
#include "framework/run/run.hpp"

namespace pneumo::diagnose {

// The index of the last checkpoint of `kept` (a run of `unpatched` with
// `options`, one part) up to which `patched` is the same model there: the
// same unknowns, pattern, start values and modes, no other time event
// before it, and at each checkpoint up to it the same outputs (integrands
// for integrals), the same root functions and a
// residual whose difference moves no unknown by more than a hundredth of
// the solver's tolerance over one output interval (the unpatched model's
// Newton matrix solved for it). -1: the models differ from the start (or
// are not alike enough to tell). Checkpoints are instants: a fault that
// acts and stops again between two of them is not seen, so they are kept
// at every output time a run is compared at.
long last_checkpoint_before_departure(const System& unpatched, const System& patched, const RunResult& kept,
                                      const SolverOptions& options);

}  // namespace pneumo::diagnose
