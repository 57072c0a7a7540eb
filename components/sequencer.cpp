// Sequencer: a step chain (GRAFCET / Modelica StateGraph) written in the
// netlist in the pneumatic notation, e.g. steps: "A+ B+ B- A-".
//  * Each step holds actions "X+" / "X-": stored actions that set / reset
//    the output signal X (a valve command, 1 = extend). Actions in
//    parentheses run in one step: "A+ (B+ C+) (B- C-) A-".
//  * The transition that ends a step waits for the limit switches of its
//    actions, the inputs X1 (X extended) for X+ and X0 (X retracted) for
//    X-, all high; `transitions: "A1 B1&C1 t_done A0"` names other inputs
//    instead (one entry per step, inputs joined by &).
//  * The chain starts when the input `start` is high, runs `cycles` times
//    (0: for ever, restarting while start is high) and waits in step 0.
// Inputs and outputs are ports declared per instance from these parameters.
// The active step and the outputs are modes: they change only at events -
// roots of the inputs crossing 0.5 or, for inputs that jump at another
// component's event (a limit switch), the event iteration - one transition
// per pass. Events: cycle_start, step_K (step K entered), cycle_end.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "components/switching.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

namespace {

struct Chain {
  struct Action {
    int output;    // index into outputs
    double level;  // 1 for X+, 0 for X-
  };
  std::vector<std::vector<Action>> steps;
  std::vector<std::string> step_text;
  std::vector<std::vector<int>> transitions;  // per step: the inputs (indices) that must all be high
  std::vector<std::string> transition_text;
  std::vector<std::string> inputs, outputs;

  static bool is_name(const std::string& s) {
    return !s.empty() && (std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_') &&
           std::all_of(s.begin(), s.end(),
                       [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
  }
  static int index_of(std::vector<std::string>& names, const std::string& n) {
    const auto it = std::find(names.begin(), names.end(), n);
    if (it != names.end()) return static_cast<int>(it - names.begin());
    names.push_back(n);
    return static_cast<int>(names.size()) - 1;
  }
  // Whitespace-separated words; '(' and ')' are words of their own.
  static std::vector<std::string> words(std::string text) {
    std::string spaced;
    for (char c : text) spaced += (c == '(' || c == ')') ? std::string(" ") + c + " " : std::string(1, c);
    std::istringstream in(spaced);
    std::vector<std::string> out;
    for (std::string w; in >> w;) out.push_back(w);
    return out;
  }

  static Chain parse(const ParameterValues& p) {
    Chain c;
    const auto ws = words(p.text("steps"));
    bool open = false;
    for (const auto& w : ws) {
      if (w == "(" || w == ")") {
        if ((w == "(") == open) throw ParameterError("steps", "unbalanced parentheses in the steps");
        open = w == "(";
        if (open) c.steps.emplace_back(), c.step_text.emplace_back();
        continue;
      }
      const std::string name = w.substr(0, w.size() - 1);
      if (w.size() < 2 || (w.back() != '+' && w.back() != '-') || !is_name(name))
        throw ParameterError("steps", "'" + w + "' is not an action; write the actuator's name and + (extend) or - "
                                      "(retract), e.g. \"A+ B+ B- A-\", with ( ) around actions of one step");
      if (name == "start") throw ParameterError("steps", "'start' names the start input, not an actuator");
      if (!open) c.steps.emplace_back(), c.step_text.emplace_back();
      const int output = index_of(c.outputs, name);
      for (const auto& a : c.steps.back())
        if (a.output == output)
          // Both would wait for X1 and X0 together: the chain stalls.
          throw ParameterError("steps", "step " + std::to_string(c.steps.size()) + " (" + c.step_text.back() + " " +
                                            w + ") acts twice on actuator '" + name +
                                            "'; one step extends or retracts an actuator once - put " + w +
                                            " in a step of its own or remove it");
      c.steps.back().push_back({output, w.back() == '+' ? 1.0 : 0.0});
      c.step_text.back() += (c.step_text.back().empty() ? "" : " ") + w;
    }
    if (open) throw ParameterError("steps", "unbalanced parentheses in the steps");
    if (c.steps.empty()) throw ParameterError("steps", "the chain has no steps");
    for (const auto& s : c.steps)
      if (s.empty()) throw ParameterError("steps", "an empty step '()'");

    std::vector<std::string> given;
    if (p.has("transitions")) {
      given = words(p.text("transitions"));
      if (given.size() != c.steps.size())
        throw ParameterError("transitions", "one transition per step is needed: " + std::to_string(c.steps.size()) +
                                                " steps, " + std::to_string(given.size()) + " transitions");
    }
    for (std::size_t k = 0; k < c.steps.size(); ++k) {
      std::vector<std::string> names;
      if (given.empty()) {
        for (const auto& a : c.steps[k]) names.push_back(c.outputs[a.output] + (a.level > 0.5 ? "1" : "0"));
      } else {
        std::istringstream in(given[k]);
        for (std::string n; std::getline(in, n, '&');) names.push_back(n);
      }
      std::vector<int> ids;
      std::string text;
      for (const auto& n : names) {
        if (!is_name(n) || n == "start")
          throw ParameterError(given.empty() ? "steps" : "transitions",
                               "'" + n + "' cannot name an input (a name, not 'start'; inputs joined by &)");
        if (std::find(c.outputs.begin(), c.outputs.end(), n) != c.outputs.end())
          throw ParameterError(given.empty() ? "steps" : "transitions",
                               "'" + n + "' names both an output (an actuator) and an input");
        ids.push_back(index_of(c.inputs, n));
        text += (text.empty() ? "" : "&") + n;
      }
      c.transitions.push_back(std::move(ids));
      c.transition_text.push_back(std::move(text));
    }
    return c;
  }
};

}  // namespace

class Sequencer final : public ComponentT<Sequencer> {
 public:
  enum Mode { kStep, kCycles, kCycleStart, kStepEntered, kOutputs };

  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "sequencer";
    i.description =
        "Step chain in pneumatic notation, e.g. steps: \"A+ B+ B- A-\" (parentheses: one step, \"A+ (B+ C+)\"). Ports "
        "per instance: input start; inputs X1 / X0 (X's extended / retracted limit switch) ending each step, or as "
        "named in transitions; outputs X (1 from X+ to X-, the valve command). Events: cycle_start, step_K, cycle_end.";
    i.symbol = symbols::function_block("SEQ");
    i.parameters = {
        ParameterSpec::text("steps", {}, "the chain, e.g. \"A+ B+ B- A-\"", std::nullopt),
        ParameterSpec::text("transitions", {}, "per step the input(s) that end it, e.g. \"A1 B1 B0 A0\"; joined by & "
                                               "for all of several (default: the steps' limit switches)",
                            std::nullopt)
            .optional(),
        ParameterSpec::scalar("cycles", "1", "number of cycles to run (0: endless while start is high)", 1.0)
            .non_negative(),
    };
    i.ports = {{"start", Domain::signal, Causality::input, "starts a cycle when 1"}};
    i.observables = {{"step", "1", "active step (0: waiting for start)"}};
    i.modes = kOutputs;
    i.roots = 1;
    i.events = {{"cycle_start", "start: step 1 entered"},
                {"step_K", "step K entered (K = 2, 3, ...)"},
                {"cycle_end", "the last transition fired: the cycle is done"}};
    i.follows_inputs = true;
    return i;
  }

  static ComponentInfo instance_info(ComponentInfo i, const ParameterValues& p) {
    const Chain c = Chain::parse(p);
    for (const auto& n : c.inputs)
      i.ports.push_back({n, Domain::signal, Causality::input, "transition input 0/1"});
    for (const auto& n : c.outputs) {
      i.ports.push_back(
          {n, Domain::signal, Causality::output, "command of " + n + ": 1 from " + n + "+ to " + n + "-", true});
      i.equations.push_back("output " + n);
    }
    i.modes = kOutputs + static_cast<int>(c.outputs.size());
    i.roots = 1 + static_cast<int>(c.inputs.size());
    return i;
  }

  explicit Sequencer(const Construction& c)
      : ComponentT(c), chain_(Chain::parse(c.params)), cycles_(c.params["cycles"]) {
    if (cycles_ != std::floor(cycles_)) throw ParameterError("cycles", "cycles must be a whole number");
  }

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    for (std::size_t k = 0; k < chain_.outputs.size(); ++k)
      r[k] = e.signal(output_port(k)) - e.mode(kOutputs + static_cast<int>(k));
  }
  double observe(int, const Eval<double>& e) const override { return e.mode(kStep); }

  void roots(const Eval<double>& e, double* g) const override {
    for (int k = 0; k <= static_cast<int>(chain_.inputs.size()); ++k) g[k] = e.signal(k) - 0.5;
  }
  EventResult on_event(const Eval<double>& e, double* modes, EventKind, int root, int direction) const override {
    return advance(e, modes, root, direction);
  }
  EventResult on_inputs_changed(const Eval<double>& e, double* modes) const override {
    return advance(e, modes, -1, 0);
  }

  // A chain that ends mid-cycle names its step and the inputs it still waits
  // for, and since when: a switch that never closes (outside the stroke, not
  // connected) otherwise only shows as a metric of nan.
  std::string at_end(const Eval<double>& e, const double* modes) const override {
    const int step = static_cast<int>(modes[kStep]);
    if (step == 0) return "";
    std::string waiting;
    for (int input : chain_.transitions[step - 1])
      if (!high(e.signal(1 + input), 0)) waiting += (waiting.empty() ? "" : " and ") + chain_.inputs[input];
    if (waiting.empty()) waiting = chain_.transition_text[step - 1];
    return "the cycle did not end: step " + std::to_string(step) + " (" + chain_.step_text[step - 1] +
           ") was entered at " + format_number(modes[kStepEntered]) + " s and was still waiting for " + waiting +
           " at the end of the run";
  }

 private:
  int output_port(std::size_t k) const { return 1 + static_cast<int>(chain_.inputs.size() + k); }

  // One transition, if the active one can fire. Port `root` has just crossed
  // 0.5 in `direction` (its level is that direction, whatever rounding left).
  EventResult advance(const Eval<double>& e, double* modes, int root, int direction) const {
    auto level = [&](int port) { return high(e.signal(port), port == root ? direction : 0); };
    const auto n = static_cast<int>(chain_.steps.size());
    const int step = static_cast<int>(modes[kStep]);
    if (step == 0) {
      if (!level(0) || (cycles_ > 0 && modes[kCycles] >= cycles_)) return {};
      enter(1, e.t(), modes);
      modes[kCycleStart] = e.t();
      return {true, "start: step 1 " + chain_.step_text[0], "cycle_start"};
    }
    for (int input : chain_.transitions[step - 1])
      if (!level(1 + input)) return {};
    const std::string after = chain_.transition_text[step - 1];
    if (step < n) {
      enter(step + 1, e.t(), modes);
      return {true, after + ": step " + std::to_string(step + 1) + " " + chain_.step_text[step],
              "step_" + std::to_string(step + 1)};
    }
    modes[kStep] = 0.0;
    modes[kCycles] += 1.0;
    return {true,
            after + ": cycle " + format_number(modes[kCycles]) + " done, cycle time " +
                format_number(e.t() - modes[kCycleStart]) + " s",
            "cycle_end"};
  }
  void enter(int step, double t, double* modes) const {
    modes[kStep] = step;
    modes[kStepEntered] = t;
    for (const auto& a : chain_.steps[step - 1]) modes[kOutputs + a.output] = a.level;
  }

  Chain chain_;
  double cycles_;
};

void register_sequencer(Registry& r) { r.add<Sequencer>(); }

}  // namespace pneumo::components
