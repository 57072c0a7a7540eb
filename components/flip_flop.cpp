// SR flip-flop (a pneumatic memory valve's logic): S = 1 sets Q, R = 1
// resets it; with both high the dominant input wins. Q holds between
// (a mode). Inputs are read at roots of S - 0.5, R - 0.5 and by the event
// iteration (an input that jumps at another component's event).
#include "components/builtin.hpp"
#include "components/switching.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class FlipFlop final : public ComponentT<FlipFlop> {
 public:
  enum Port { kS, kR, kQ, kQn };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "flip_flop";
    i.description =
        "SR flip-flop: S = 1 sets Q = 1, R = 1 resets Q = 0, both high: the dominant input wins; Qn = 1 - Q. "
                    "Events: set, reset.";
    i.symbol = symbols::function_block("SR");
    i.parameters = {
        ParameterSpec::text("dominant", {"reset", "set"}, "which input wins when both are high", "reset"),
        ParameterSpec::scalar("initial", "1", "Q before any input: 0 or 1", 0.0).range(0.0, 1.0),
    };
    i.ports = {{"S", Domain::signal, Causality::input, "set 0/1", true, 0.0},
               {"R", Domain::signal, Causality::input, "reset 0/1", true, 0.0},
               {"Q", Domain::signal, Causality::output, "stored state 0/1", true},
               {"Qn", Domain::signal, Causality::output, "1 - Q", true}};
    i.observables = {{"Q", "1", "stored state 0/1"}};
    i.equations = {"output Q", "output Qn"};
    i.modes = 1;
    i.roots = 2;
    i.events = {{"set", "Q goes to 1"}, {"reset", "Q goes to 0"}};
    i.follows_inputs = true;
    return i;
  }

  explicit FlipFlop(const Construction& c)
      : ComponentT(c), set_dominant_(c.params.text("dominant") == "set"), initial_(c.params["initial"]) {
    if (initial_ != 0.0 && initial_ != 1.0) throw ParameterError("initial", "initial must be 0 or 1");
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.signal(kQ) - e.mode(0);
    r[1] = e.signal(kQn) - (1.0 - e.mode(0));
  }
  double observe(int, const Eval<double>& e) const override { return e.mode(0); }
  void initial_modes(double* modes) const override { modes[0] = initial_; }

  void roots(const Eval<double>& e, double* g) const override {
    g[0] = e.signal(kS) - 0.5;
    g[1] = e.signal(kR) - 0.5;
  }
  EventResult on_event(const Eval<double>& e, double* modes, EventKind, int root, int direction) const override {
    return follow(high(e.signal(kS), root == 0 ? direction : 0), high(e.signal(kR), root == 1 ? direction : 0), modes);
  }
  EventResult on_inputs_changed(const Eval<double>& e, double* modes) const override {
    return follow(high(e.signal(kS)), high(e.signal(kR)), modes);
  }

 private:
  EventResult follow(bool s, bool r, double* modes) const {
    if (s && r) (set_dominant_ ? r : s) = false;
    const double q = s ? 1.0 : r ? 0.0 : modes[0];
    if (q == modes[0]) return {};
    modes[0] = q;
    return {true, q == 1.0 ? "set" : "reset", q == 1.0 ? "set" : "reset"};
  }

  bool set_dominant_;
  double initial_;
};

void register_flip_flop(Registry& r) { r.add<FlipFlop>(); }

}  // namespace pneumo::components
