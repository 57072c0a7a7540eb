// libFuzzer target: the netlist reader. Any byte string is read as a netlist
// and elaborated with the built-in components. A clear InputError (file:line,
// component, parameter) or StructureError is the expected answer to bad
// input; any other exception, a crash or a sanitizer report is a defect.
#include <cstddef>
#include <cstdint>
#include <string>

#include "components/builtin.hpp"
#include "framework/core/error.hpp"
#include "framework/netlist/netlist.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const pneumo::Netlist netlist = pneumo::parse_netlist(text, "fuzz.yaml");
    (void)pneumo::elaborate(netlist, pneumo::builtin_registry());
  } catch (const pneumo::InputError&) {
  } catch (const pneumo::StructureError&) {
  }
  return 0;
}
