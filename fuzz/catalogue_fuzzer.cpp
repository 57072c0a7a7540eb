// libFuzzer target: the effect catalogue reader of pneumo diagnose, against
// the cushion rig it was written for. The reader takes a path, so each input
// goes through one scratch file of this process. Expected answers to bad
// input as in netlist_fuzzer.cpp: InputError or StructureError, nothing else.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "components/builtin.hpp"
#include "framework/core/error.hpp"
#include "framework/diagnose/catalogue.hpp"
#include "framework/netlist/netlist.hpp"

namespace {
const std::string kModelFile = std::string(PNEUMO_SOURCE_DIR) + "/netlists/cushion_rig.yaml";
const std::string kScratch = "/tmp/pneumo_catalogue_fuzz_" + std::to_string(getpid()) + ".yaml";
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const pneumo::Netlist model = pneumo::load_netlist(kModelFile);
  {
    std::ofstream out(kScratch, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    (void)pneumo::diagnose::load_catalogue(kScratch, model, pneumo::builtin_registry());
  } catch (const pneumo::InputError&) {
  } catch (const pneumo::StructureError&) {
  }
  return 0;
}
