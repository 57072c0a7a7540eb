// A flange held in place (the frame).
#include "components/builtin.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class FixedPosition final : public ComponentT<FixedPosition> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "fixed_position";
    i.description = "Flange fixed at position s0 (the machine frame).";
    i.symbol = symbols::mechanical("fixed", {{"flange", 0, 20, 'l'}});
    i.parameters = {ParameterSpec::scalar("s0", "m", "position", 0.0)};
    i.ports = {{"flange", Domain::translational, Causality::acausal, "flange"}};
    i.equations = {"fixed position"};
    return i;
  }
  explicit FixedPosition(const Construction& c) : ComponentT(c), s0_(c.params["s0"]) {}
  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    // Held still: v = 0. The position itself is the node's differential
    // state (ds/dt = v), fixed at s0 initially; writing s = s0 here would
    // make the system index 2.
    r[0] = e.flange(0).v;
  }
  void start(StartValues& s, const GasModel&) const override { s.fix_position(0, s0_); }

 private:
  double s0_;
};

void register_fixed_position(Registry& r) { r.add<FixedPosition>(); }

}  // namespace pneumo::components
