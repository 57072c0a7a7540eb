// Logic AND of 0/1 signals, y = in1 in2 in3 in4: an algebraic equation (no
// modes), so the output jumps at the event where an input jumps.
#include "components/builtin.hpp"
#include "components/logic_gates.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class AndGate final : public ComponentT<AndGate> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "and";
    i.description = "Logic AND of 0/1 signals: y = in1 in2 in3 in4 (in3, in4 optional, 1 when unconnected).";
    i.symbol = symbols::function_block("&");
    i.ports = gate_ports(1.0);
    i.equations = {"y = in1 in2 in3 in4"};
    return i;
  }
  using ComponentT::ComponentT;

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.signal(4) - e.signal(0) * e.signal(1) * e.signal(2) * e.signal(3);
  }
};

void register_and_gate(Registry& r) { r.add<AndGate>(); }

}  // namespace pneumo::components
