// A signal set from outside the circuit while it runs: an FMU's input
// (pneumo export-fmu), named after the component. Until set it holds
// `start`; `pneumo simulate` runs it at that value. Its value is a discrete
// mode the framework writes (Component::external_inputs), so a change
// between two communication points is handled as an event: the integrator
// restarts from consistent values and never steps across the jump.
#include "components/builtin.hpp"
#include "components/symbols.hpp"
#include "framework/core/units.hpp"

namespace pneumo::components {

class ExternalInput final : public ComponentT<ExternalInput> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "external_input";
    i.description =
        "Signal set from outside while the circuit runs (an exported FMU's input, named after the component): a valve "
        "command, a set point, a force. Holds 'start' until set; 'pneumo simulate' runs it at 'start'.";
    i.symbol = symbols::function_block("input");
    i.parameters = {
        ParameterSpec::scalar("start", "1", "value until set from outside; SI units", 0.0),
        ParameterSpec::text("unit", {}, "SI unit of the value, for the FMU's description (\"1\", \"Pa\", \"N\")",
                            "1"),
    };
    i.ports = {{"y", Domain::signal, Causality::output, "the signal"}};
    i.modes = 1;  // the value set from outside
    i.equations = {"signal value"};
    return i;
  }

  explicit ExternalInput(const Construction& c)
      : ComponentT(c), start_(c.params["start"]), unit_(c.params.text("unit")) {
    try {
      units::dimension_of(unit_);
    } catch (const std::exception& e) {
      throw ParameterError("unit", "'" + unit_ + "' is not a unit: " + e.what());
    }
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.signal(0) - e.mode(0);
  }

  void initial_modes(double* modes) const override { modes[0] = start_; }
  std::vector<ExternalInputSpec> external_inputs() const override {
    return {{0, start_, unit_, "external input " + name()}};
  }

 private:
  double start_;
  std::string unit_;
};

void register_external_input(Registry& r) { r.add<ExternalInput>(); }

}  // namespace pneumo::components
