// Phases of the measured runs for the gap report, from the unpatched
// model's own run at each operating point: the catalogue's list (each phase
// starting at an event COMPONENT.TAG, a time-valued metric of the model, or
// "start"), or else one phase per tagged event of the model, from its first
// occurrence, ordered by the median of those times over the runs.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "framework/diagnose/catalogue.hpp"

namespace pneumo::diagnose {

// What one model run tells the phases: the first time of each event
// COMPONENT.TAG and the value of each metric (by name).
using PhaseStarts = std::map<std::string, double>;

struct Phases {
  std::vector<std::string> names;
  std::vector<std::vector<int>> of_sample;  // per run, per sample: the phase index
  std::vector<std::vector<double>> times;   // per run: each phase's start, then the run's end
};

// `starts[k]`: what the model's run at measured run k gave (empty if it failed).
Phases assign_phases(const std::vector<PhaseDecl>& declared, const std::vector<std::vector<double>>& run_times,
                     const std::vector<PhaseStarts>& starts);

}  // namespace pneumo::diagnose
