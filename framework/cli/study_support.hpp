// What the study commands (sweep, sensitivity) share: their error
// handling under MPI, their summary line and default output names.
#pragma once

#include <string>

#include "framework/study/sweep.hpp"

namespace pneumo::cli {

// NETLIST_STEM + suffix, in the working directory.
std::string default_output(const std::string& netlist, const char* suffix);

// After bad input: under mpirun an error on one rank must stop the others,
// which would otherwise wait for it in a collective call.
void stop_ranks();

// The sweep's summary line on stdout (nothing when quiet).
void report(const study::SweepSummary& s, const std::string& output, bool quiet);

}  // namespace pneumo::cli
