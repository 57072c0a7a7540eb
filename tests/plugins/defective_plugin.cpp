// Plugins that must be refused, one per PNEUMO_TEST_DEFECT (tests/plugin_test.cpp):
//   1 built against another pneumo version     2 an unknown plugin API version
//   3 a type layout that differs from the host  4 a type named like a built-in
//   5 a register function that throws
//   6 null strings in its ABI description      7 a register function that throws
//     (strcmp(NULL) crashed the loader)           something not a std::exception
//   8 an entry point that throws something not a std::exception
#include <stdexcept>

#include "framework/model/component.hpp"
#include "framework/plugin/plugin_api.hpp"

namespace {

using namespace pneumo;

// A minimal valid component, so that the only defect is the one selected.
class Sink final : public ComponentT<Sink> {
 public:
  static ComponentInfo describe() {
    ComponentInfo i;
#if PNEUMO_TEST_DEFECT == 4
    i.type = "volume";
#else
    i.type = "defective_sink";
#endif
    i.description = "closes a pneumatic port (test plugin)";
    i.ports = {{"port", Domain::pneumatic, Causality::acausal, "port"}};
    return i;
  }
  using ComponentT::ComponentT;
  template <class T>
  void equations(const Eval<T>& e, T* r) const {
    const auto p = e.gas_port(0);
    r[0] = p.m_flow;
    r[1] = p.T_out - p.T_in;
  }
};

void register_sink(Registry& registry) {
#if PNEUMO_TEST_DEFECT == 5
  (void)registry;
  throw std::runtime_error("the sink's license file is missing");
#elif PNEUMO_TEST_DEFECT == 7
  registry.add<Sink>();
  throw 42;
#else
  registry.add<Sink>();
#endif
}

}  // namespace

extern "C" __attribute__((visibility("default"))) const PluginInfo* pneumo_plugin_info() {
#if PNEUMO_TEST_DEFECT == 8
  throw 42;
#endif
  static PluginInfo info{kPluginApiVersion, "defective test plugin", plugin_abi(), &register_sink};
#if PNEUMO_TEST_DEFECT == 1
  info.abi.pneumo_version = "0.0.1";  // as compiled against an older pneumo's headers
#elif PNEUMO_TEST_DEFECT == 2
  info.api_version = kPluginApiVersion + 41;
#elif PNEUMO_TEST_DEFECT == 3
  info.abi.sizes[0] += 64;  // as if its Dual had other kMaxLocal slots
#elif PNEUMO_TEST_DEFECT == 6
  info.abi.pneumo_version = nullptr;
  info.abi.stdlib = nullptr;
  info.abi.compiler = nullptr;
#endif
  return &info;
}
