// Which sensor would decide between candidate explanations that the measured
// signals cannot tell apart (docs/how-to/diagnose.md).
//
// Both fitted models are run at every run's operating point with every
// quantity of the model as an output (each component's observables and
// local variables: port pressures, temperatures, flows, positions, forces,
// internal states), and each quantity is scored by how far the two models'
// traces lie apart in noise units of a sensor for it: RMS over all samples of
// (a - b) / sigma. Sigma is the noise the measurements show for that unit
// (median over measured signals of the same unit), else a typical industrial
// sensor's (kSensorNoise in sensors.cpp). In the spirit of sensor placement
// for fault isolability: the best quantity is the one whose measurement
// separates the two hypotheses most.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "framework/model/registry.hpp"
#include "framework/netlist/netlist.hpp"

namespace pneumo::diagnose {

struct SensorSeparation {
  std::string quantity;  // COMPONENT.QUANTITY, e.g. "cyl.A.p"
  std::string unit;      // SI unit of the quantity
  double sigma = 0;      // the sensor noise assumed for it (SI)
  double separation = 0; // RMS of (a - b) / sigma over all runs' samples
  bool measured = false; // already one of the measured signals
};

struct SensorChoice {
  std::string effect_a, effect_b;
  std::vector<SensorSeparation> best;  // unmeasured quantities, best first (at most a few)
  double measured_separation = 0;      // the best of the measured signals, same measure
  std::string measured_signal;
  std::vector<std::string> run_failures;  // runs skipped because a model failed there, and why
};

// The quantities a sensor could measure: observables and local variables of
// every component whose unit has a sensor noise (pressure, temperature,
// position, velocity, force, mass flow).
struct SensorQuantity {
  std::string component, quantity, unit;
  std::string name() const { return component + "." + quantity; }
};
std::vector<SensorQuantity> sensor_quantities(const Netlist& model, const Registry& registry);

// Sensor noise per SI unit: the measured one (median over signals of that
// unit) where a measured signal has the unit, else the typical one.
std::map<std::string, double> sensor_noise(const std::map<std::string, double>& measured_by_unit);

// Separates model a from model b: runs_a[k] and runs_b[k] are the two models
// at run k's operating point and span; `measured` maps quantity names
// (COMPONENT.QUANTITY) that are already measured to their signal name.
// Runs that fail in either model are skipped, their reasons kept.
SensorChoice choose_sensor(const std::string& effect_a, const std::string& effect_b,
                           const std::vector<Netlist>& runs_a, const std::vector<Netlist>& runs_b,
                           const Registry& registry, const std::map<std::string, double>& noise_by_unit,
                           const std::map<std::string, std::string>& measured, int threads);

// One sentence for the report, e.g. "a pressure sensor at cyl.A.p would
// separate line_volume from supply_droop by 12 noise sd (the measured
// signals: 0.8 at best)".
std::string sensor_sentence(const SensorChoice& c);

// The same advice as a clause to follow another ("measure cyl.A.p (a
// pressure sensor: 12 noise sd over the measured runs)"); empty without one
// that separates them by at least its noise.
std::string sensor_clause(const SensorChoice& c);

}  // namespace pneumo::diagnose
