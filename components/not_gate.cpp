// Logic NOT of a 0/1 signal, y = 1 - in: an algebraic equation (no modes).
#include "components/builtin.hpp"
#include "components/symbols.hpp"

namespace pneumo::components {

class NotGate final : public ComponentT<NotGate> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
    i.type = "not";
    i.description = "Logic NOT of a 0/1 signal: y = 1 - in.";
    i.symbol = symbols::function_block("1");
    i.ports = {{"in", Domain::signal, Causality::input, "input 0/1"},
               {"y", Domain::signal, Causality::output, "output 0/1", true}};
    i.equations = {"y = 1 - in"};
    return i;
  }
  using ComponentT::ComponentT;

  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    r[0] = e.signal(1) - (1.0 - e.signal(0));
  }
};

void register_not_gate(Registry& r) { r.add<NotGate>(); }

}  // namespace pneumo::components
