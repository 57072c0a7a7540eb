// Signal sources: constant, step, ramp, or a table over time. Steps are
// discrete modes switched by time events, so the integrator never steps
// across the jump; ramp and table corners are time events too.
#include <algorithm>

#include "components/builtin.hpp"
#include "components/symbols.hpp"
#include "framework/core/smooth.hpp"

namespace pneumo::components {

class SignalSource final : public ComponentT<SignalSource> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "signal_source";
    i.description =
        "Signal over time. kind constant: value; step: value, jumping by height at t_start; ramp: value rising by "
        "height linearly from t_start over duration; table: linear interpolation in [[t, value], ...].";
    i.symbol = symbols::function_block("source");
    i.parameters = {
        ParameterSpec::text("kind", {"constant", "step", "ramp", "table"}, "shape of the signal", "constant"),
        ParameterSpec::scalar("value", "1", "value (at t < t_start for step and ramp); SI units", 0.0),
        ParameterSpec::scalar("height", "1", "height of the step or ramp; SI units", 1.0),
        ParameterSpec::scalar("t_start", "s", "time of the step or start of the ramp", 0.0),
        ParameterSpec::scalar("duration", "s", "duration of the ramp", 1.0).positive(),
        ParameterSpec::table("table", {"s", "1"}, "[[t, value], ...] with increasing t (kind table)", false),
    };
    i.ports = {{"y", Domain::signal, Causality::output, "the signal"}};
    i.modes = 1;  // step: 0 before, 1 after t_start
    i.events = {{"step", "the step at t_start (kind step)"}};
    i.equations = {"signal value"};
    return i;
  }

  explicit SignalSource(const Construction& c)
      : ComponentT(c),
        kind_(c.params.text("kind")),
        value_(c.params["value"]),
        height_(c.params["height"]),
        t_start_(c.params["t_start"]),
        duration_(c.params["duration"]) {
    if (c.params.has("table")) table_ = c.params.table("table");
    if (kind_ == "table") {
      if (table_.empty()) throw ParameterError("table", "kind 'table' needs a 'table' of [t, value] rows");
      require_increasing(table_, "table", "times");
    }
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.signal(0) - at(e.t(), e.mode(0));
  }

  double at(double t, double mode) const {
    if (kind_ == "step") return value_ + (mode > 0.5 ? height_ : 0.0);
    if (kind_ == "ramp") return value_ + height_ * std::clamp((t - t_start_) / duration_, 0.0, 1.0);
    if (kind_ == "table") return interpolate(table_, t);
    return value_;
  }

  void initial_modes(double* modes) const override { modes[0] = 0.0; }
  std::vector<double> time_events() const override {
    if (kind_ == "step") return {t_start_};
    if (kind_ == "ramp") return {t_start_, t_start_ + duration_};
    std::vector<double> out;
    if (kind_ == "table")
      for (const auto& row : table_) out.push_back(row[0]);
    return out;
  }
  EventResult on_event(const Eval<double>& e, double* modes, EventKind, int, int) const override {
    if (kind_ == "step" && modes[0] < 0.5 && e.t() >= t_start_) {
      modes[0] = 1.0;
      return {true, "step to " + std::to_string(value_ + height_), "step"};
    }
    return {};
  }

 private:
  std::string kind_;
  double value_, height_, t_start_, duration_;
  Table table_;
};

void register_signal_source(Registry& r) { r.add<SignalSource>(); }

}  // namespace pneumo::components
