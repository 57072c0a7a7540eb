// One FMU instance: the netlist from the FMU's resources, integrated by
// pneumo's own solver from one communication point to the next. Everything
// an instance uses is its own (model, System, integration), so several run
// side by side in one process. Errors are thrown as FmuError; the C
// functions (fmi2_functions.cpp) turn them into fmi2Error with the message
// logged.
#pragma once

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "framework/fmi/description.hpp"
#include "framework/run/model.hpp"
#include "framework/solver/integration.hpp"

namespace pneumo::fmi {

struct FmuError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// (category, message): what the instance tells the importer's logger.
using LogFn = std::function<void(const char* category, const std::string& message)>;

class Instance {
 public:
  // resources: the FMU's resources folder (netlist.yaml, interface.txt).
  Instance(const std::string& resources, const std::string& guid, LogFn log);
  ~Instance();

  void setup_experiment(double t_start, bool stop_defined, double t_stop);
  void enter_initialization();
  void exit_initialization();
  void do_step(double t, double h);
  void terminate();
  void reset();

  double get(unsigned vr);
  void set(unsigned vr, double value);
  double time() const { return t_; }

 private:
  enum class Phase { instantiated, initialising, stepping, terminated };
  void build();
  void apply_inputs();
  void read_outputs();
  const Variable& variable(unsigned vr) const;

  Model model_;
  Description description_;
  LogFn log_;
  Phase phase_ = Phase::instantiated;
  double t_start_ = 0, t_end_ = 0, t_ = 0;
  std::vector<double> values_;  // by value reference: parameters, inputs as set, outputs as computed
  std::vector<char> input_changed_;
  struct Run;
  std::unique_ptr<Run> run_;  // from initialisation on
};

}  // namespace pneumo::fmi
