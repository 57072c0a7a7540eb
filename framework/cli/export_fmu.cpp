// pneumo export-fmu NETLIST -o NAME.fmu [--input NAME ...] [--output NAME ...]
//
// An FMI 2.0 co-simulation FMU of the netlist: modelDescription.xml,
// binaries/linux64/NAME.so (pneumo's FMU runtime, framework/fmi, with the
// pneumo libraries it needs beside it) and the netlist with the chosen
// interface as resources. The archive is made by zip (Debian package zip),
// run without a shell in a private folder, and written atomically to -o.
#include <dlfcn.h>
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "components/builtin.hpp"
#include "framework/cli/command.hpp"
#include "framework/core/error.hpp"
#include "framework/fmi/description.hpp"
#include "framework/io/files.hpp"
#include "framework/io/spawn.hpp"
#include "framework/netlist/netlist.hpp"
#include "framework/run/model.hpp"

namespace pneumo::cli {

namespace {

namespace fs = std::filesystem;

struct ExportArgs {
  std::string netlist, output;
  std::vector<std::string> inputs, outputs;
};

// The file a loaded library was found as (its soname's path), by one of its
// functions.
std::string library_of(const void* function) {
  Dl_info info{};
  if (dladdr(function, &info) == 0 || !info.dli_fname)
    throw std::runtime_error("cannot find the pneumo library to put into the FMU");
  return info.dli_fname;
}

// libpneumo_fmu.so beside the pneumo libraries (installed or built), else
// where it was built.
std::string fmu_runtime(const std::string& framework_library) {
  const fs::path beside = fs::path(framework_library).parent_path() / "libpneumo_fmu.so";
  if (fs::is_regular_file(beside)) return beside.string();
  if (fs::is_regular_file(PNEUMO_FMU_RUNTIME)) return PNEUMO_FMU_RUNTIME;
  throw std::runtime_error("the FMU runtime libpneumo_fmu.so is not installed beside pneumo (build the target "
                           "pneumo_fmu)");
}

void copy_binary(const std::string& from, const std::string& to) {
  write_text_atomic(to, read_input_file(fs::canonical(from).string(), "library"));
}

std::string identifier_of(const std::string& output) {
  const std::string id = fs::path(output).stem().string();
  bool ok = !id.empty() && !std::isdigit(static_cast<unsigned char>(id[0]));
  for (char c : id) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (!ok)
    throw std::invalid_argument("-o " + output + ": the FMU's name (" + id +
                                ") is its model identifier, a C name: letters, digits and _, not starting with a digit");
  return id;
}

int export_command(const ExportArgs& a) {
  if (fs::path(a.output).extension() != ".fmu") throw std::invalid_argument("-o " + a.output + ": give NAME.fmu");
  const std::string id = identifier_of(a.output);
  check_output_file(a.output, "-o", {a.netlist});
  const Model model = load_model(a.netlist, builtin_registry());
  if (!model.netlist.plugins.empty())
    throw InputError({model.netlist.file, 1, 1}, "", "", "an FMU carries no plugins: its netlist may use pneumo's "
                                                         "own components only");
  const fmi::Selection selection{a.inputs, a.outputs};
  const fmi::Description d = fmi::describe(model, selection);
  PrivateFolder folder;
  const std::string root = folder.path("fmu");
  write_text_atomic(root + "/modelDescription.xml", fmi::model_description_xml(d, id));
  write_text_atomic(root + "/resources/netlist.yaml", model.text);
  write_text_atomic(root + "/resources/interface.txt", fmi::selection_text(selection));
  const std::string bin = root + "/binaries/linux64/";
  const std::string framework = library_of(reinterpret_cast<const void*>(&pneumo::load_model));
  copy_binary(fmu_runtime(framework), bin + id + ".so");
  for (const std::string& lib : {framework, library_of(reinterpret_cast<const void*>(&pneumo::builtin_registry))})
    copy_binary(lib, bin + fs::path(lib).filename().string());
  const std::string archive = folder.path("archive.zip");
  run_program({"zip", "-q", "-r", "-X", archive, "modelDescription.xml", "binaries", "resources"}, folder.path("zip.log"),
              "zip", root);
  write_text_atomic(a.output, read_input_file(archive, "FMU archive"));
  int inputs = 0, outputs = 0, parameters = 0;
  for (const auto& v : d.variables)
    (v.causality == fmi::Variable::Causality::input    ? inputs
     : v.causality == fmi::Variable::Causality::output ? outputs
                                                       : parameters)++;
  std::cout << "exported " << a.output << ": FMI 2.0 co-simulation, " << inputs << " inputs, " << outputs
            << " outputs, " << parameters << " parameters\n";
  return 0;
}

}  // namespace

Command add_export_fmu_command(CLI::App& app) {
  auto a = std::make_shared<ExportArgs>();
  auto* cmd = app.add_subcommand("export-fmu", "export a netlist as an FMI 2.0 co-simulation FMU (Linux 64-bit) that "
                                               "runs the circuit with pneumo's solver");
  cmd->add_option("netlist", a->netlist, "netlist file (YAML)")->required();
  cmd->add_option("-o", a->output, "NAME.fmu (NAME: the model identifier)")->required();
  cmd->add_option("--input", a->inputs,
                  "an external_input component the FMU offers as an input (default: all of them)")
      ->take_all();
  cmd->add_option("--output", a->outputs, "a netlist output the FMU offers (default: all)")->take_all();
  return {.app = cmd, .run = [a] { return export_command(*a); }, .input = [a] { return a->netlist; }};
}

}  // namespace pneumo::cli
