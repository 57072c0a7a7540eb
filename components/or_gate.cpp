// Logic OR of 0/1 signals, y = 1 - (1 - in1)(1 - in2)(1 - in3)(1 - in4): an
// algebraic equation (no modes), so the output jumps with its inputs.
#include "components/builtin.hpp"
#include "components/logic_gates.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class OrGate final : public ComponentT<OrGate> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "or";
    i.description =
        "Logic OR of 0/1 signals: y = 1 - (1 - in1)(1 - in2)(1 - in3)(1 - in4) (in3, in4 optional, 0 when "
        "unconnected).";
    i.symbol = symbols::function_block("\u22651");
    i.ports = gate_ports(0.0);
    i.equations = {"y = in1 or in2 or in3 or in4"};
    return i;
  }
  using ComponentT::ComponentT;

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.signal(4) - (1.0 - (1.0 - e.signal(0)) * (1.0 - e.signal(1)) * (1.0 - e.signal(2)) * (1.0 - e.signal(3)));
  }
};

void register_or_gate(Registry& r) { r.add<OrGate>(); }

}  // namespace pneumo::components
