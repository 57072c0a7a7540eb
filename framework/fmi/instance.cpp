#include "framework/fmi/instance.hpp"

#include <cmath>

#include "components/builtin.hpp"
#include "framework/assembly/system.hpp"
#include "framework/io/files.hpp"
#include "framework/run/run.hpp"

namespace pneumo::fmi {

// What exists from initialisation on: the elaborated circuit's System, its
// integration and the outputs' probes.
struct Instance::Run {
  System system;
  Evaluator eval;
  Integration integration;
  ProbeSet outputs;
  Run(Circuit circuit, const SolverOptions& options)
      : system(std::move(circuit), AssemblyOptions{.rest_heat = options.steady_start}),
        eval(system),
        integration(eval, options, [](double, const double*, const double*) {}) {}
};

namespace {

std::string file_text(const std::string& path, const char* what) {
  try {
    return read_input_file(path, what);
  } catch (const std::exception& e) {
    throw FmuError(std::string("cannot read the FMU's ") + what + ": " + e.what());
  }
}

}  // namespace

Instance::Instance(const std::string& resources, const std::string& guid, LogFn log) : log_(std::move(log)) {
  const std::string netlist = resources + "/netlist.yaml";
  model_ = load_model(netlist, builtin_registry());
  description_ = describe(model_, parse_selection(file_text(resources + "/interface.txt", "interface")));
  if (!guid.empty() && guid != description_.guid)
    throw FmuError("fmuGUID " + guid + " is not this FMU's (" + description_.guid +
                   "): its modelDescription.xml and resources do not belong together");
  reset();
}

Instance::~Instance() = default;

void Instance::reset() {
  run_.reset();
  phase_ = Phase::instantiated;
  values_.clear();
  for (const auto& v : description_.variables) values_.push_back(v.start);
  input_changed_.assign(values_.size(), 0);
  t_start_ = t_ = description_.t_start;
  t_end_ = description_.t_end;
}

void Instance::setup_experiment(double t_start, bool stop_defined, double t_stop) {
  if (phase_ != Phase::instantiated) throw FmuError("fmi2SetupExperiment after initialisation");
  t_start_ = t_ = t_start;
  // Without a stop time the netlist's t_end is the run's end.
  t_end_ = stop_defined ? t_stop : std::max(description_.t_end, t_start);
  if (!(t_end_ > t_start_)) throw FmuError("stopTime must be after startTime");
}

void Instance::enter_initialization() {
  if (phase_ != Phase::instantiated) throw FmuError("fmi2EnterInitializationMode twice");
  phase_ = Phase::initialising;
}

void Instance::exit_initialization() {
  if (phase_ != Phase::initialising) throw FmuError("fmi2ExitInitializationMode outside initialisation mode");
  if (!run_) build();
  phase_ = Phase::stepping;
}

// The parameters as set, the circuit elaborated with them, integrated to
// consistent values at t_start with the inputs as set.
void Instance::build() {
  Netlist netlist = model_.netlist;
  for (std::size_t i = 0; i < values_.size(); ++i)
    if (description_.variables[i].causality == Variable::Causality::parameter)
      set_si_value(netlist, ParameterPath::parse(description_.variables[i].name), values_[i]);
  SolverOptions options = solver_options(netlist.simulation);
  options.t_start = t_start_;
  options.t_end = t_end_;
  options.threads = 1;
  run_ = std::make_unique<Run>(elaborate(netlist, model_.registry), options);
  std::vector<Probe> probes;
  for (const auto& v : description_.variables)
    if (v.causality == Variable::Causality::output) probes.push_back(run_->system.circuit().probes[v.index]);
  run_->outputs = run_->system.probe_set(probes);
  // The integration's constructor set the modes to their initial values.
  for (std::size_t i = 0; i < values_.size(); ++i)
    if (description_.variables[i].causality == Variable::Causality::input)
      run_->eval.set_external_input(description_.variables[i].index, values_[i]);
  input_changed_.assign(values_.size(), 0);
  if (!run_->integration.start())
    throw FmuError("initialisation failed: " + run_->integration.result().message);
  t_ = run_->integration.time();
  read_outputs();
}

void Instance::read_outputs() {
  std::vector<double> out(values_.size());  // at most one per variable
  run_->eval.probe_all(run_->outputs, t_, run_->integration.y(), run_->integration.yp(), out.data());
  std::size_t k = 0;
  for (std::size_t i = 0; i < values_.size(); ++i)
    if (description_.variables[i].causality == Variable::Causality::output) values_[i] = out[k++];
}

// Inputs set since the last step: written into the System, then one
// restart from consistent values (a discontinuity, as at an event).
void Instance::apply_inputs() {
  bool any = false;
  for (std::size_t i = 0; i < values_.size(); ++i)
    if (input_changed_[i]) {
      run_->eval.set_external_input(description_.variables[i].index, values_[i]);
      input_changed_[i] = 0;
      any = true;
    }
  if (any && !run_->integration.inputs_changed())
    throw FmuError("restart after an input changed at t = " + std::to_string(t_) +
                   " s failed: " + run_->integration.result().message);
}

void Instance::do_step(double t, double h) {
  if (phase_ != Phase::stepping) throw FmuError("fmi2DoStep before initialisation or after fmi2Terminate");
  if (!(h > 0)) throw FmuError("communicationStepSize must be > 0");
  const double eps = 1e-9 * std::max(1.0, std::abs(t));
  if (std::abs(t - t_) > eps)
    throw FmuError("currentCommunicationPoint " + std::to_string(t) + " s is not the FMU's time " +
                   std::to_string(t_) + " s");
  if (t + h > t_end_ + eps)
    throw FmuError("a step to " + std::to_string(t + h) + " s goes beyond the stop time " + std::to_string(t_end_) +
                   " s");
  apply_inputs();
  const std::size_t logged = run_->integration.result().events.size();
  const bool ok = run_->integration.advance_to(std::min(t + h, t_end_));
  const auto& events = run_->integration.result().events;
  for (std::size_t i = logged; i < events.size(); ++i)
    log_("logEvents", "t = " + std::to_string(events[i].t) + " s: " + events[i].component + ": " +
                          (events[i].message.empty() ? events[i].tag : events[i].message));
  if (!ok) throw FmuError(run_->integration.result().message);
  t_ = t + h;
  read_outputs();
}

void Instance::terminate() {
  if (run_ && phase_ == Phase::stepping) run_->integration.finish();
  phase_ = Phase::terminated;
}

const Variable& Instance::variable(unsigned vr) const {
  if (vr >= description_.variables.size())
    throw FmuError("no variable with value reference " + std::to_string(vr) + " (this FMU has " +
                   std::to_string(description_.variables.size()) + ")");
  return description_.variables[vr];
}

double Instance::get(unsigned vr) {
  const Variable& v = variable(vr);
  // An output asked for in initialisation mode: initialise now (the
  // parameters then stay as they are).
  if (v.causality == Variable::Causality::output && !run_) {
    if (phase_ != Phase::initialising) throw FmuError("output '" + v.name + "' is known from initialisation on");
    build();
  }
  return values_[vr];
}

void Instance::set(unsigned vr, double value) {
  const Variable& v = variable(vr);
  if (!std::isfinite(value)) throw FmuError("'" + v.name + "' set to a value that is not finite");
  switch (v.causality) {
    case Variable::Causality::output:
      throw FmuError("'" + v.name + "' is an output: it cannot be set");
    case Variable::Causality::parameter:
      if (run_ || phase_ == Phase::stepping || phase_ == Phase::terminated)
        throw FmuError("parameter '" + v.name + "' is fixed: set it before initialisation ends");
      break;
    case Variable::Causality::input:
      if (phase_ == Phase::terminated) throw FmuError("input '" + v.name + "' set after fmi2Terminate");
      if (value != values_[vr]) input_changed_[vr] = 1;
      break;
  }
  values_[vr] = value;
  if (run_ && phase_ == Phase::initialising && v.causality == Variable::Causality::input) apply_inputs();
}

}  // namespace pneumo::fmi
