// pneumo components [TYPE] [--plugin FILE ...]
#include <iostream>
#include <memory>

#include "components/builtin.hpp"
#include "framework/cli/command.hpp"
#include "framework/plugin/plugin.hpp"

namespace pneumo::cli {

namespace {

struct ComponentsArgs {
  std::string type;
  std::vector<std::string> plugins;
};

void print_component(const ComponentInfo& info, std::ostream& out) {
  out << info.type << "\n  " << info.description << "\n";
  out << "  ports:\n";
  for (const auto& p : info.ports) {
    out << "    " << p.name << " (" << domain_name(p.domain);
    if (p.causality == Causality::input) out << " input";
    if (p.causality == Causality::output) out << " output";
    if (p.optional) out << ", optional";
    out << ")  " << p.description << "\n";
  }
  if (!info.parameters.empty()) out << "  parameters:\n";
  for (const auto& p : info.parameters) {
    out << "    " << p.name;
    if (p.kind == ParameterKind::scalar) {
      out << " [" << p.unit << "]";
      if (p.default_value) out << " default " << *p.default_value;
      else out << (p.is_optional ? " optional" : " required");
      out << ", " << p.range_text();
    } else if (p.kind == ParameterKind::table) {
      out << " [table of rows (";
      for (std::size_t i = 0; i < p.columns.size(); ++i) out << (i ? ", " : "") << p.columns[i];
      out << ")]" << (p.required_table ? " required" : " optional");
    } else {
      out << " [text";
      if (!p.choices.empty()) {
        out << ": ";
        for (std::size_t i = 0; i < p.choices.size(); ++i) out << (i ? "|" : "") << p.choices[i];
      }
      out << "]";
      if (p.default_text) out << " default " << *p.default_text;
    }
    out << "  " << p.description << "\n";
  }
  if (!info.variables.empty() || !info.observables.empty()) out << "  outputs:\n";
  for (const auto& v : info.variables) out << "    " << v.name << " [" << v.unit << "]  " << v.description << "\n";
  for (const auto& v : info.observables) out << "    " << v.name << " [" << v.unit << "]  " << v.description << "\n";
}

int components_command(const ComponentsArgs& a) {
  Registry reg = builtin_registry();
  TypeOrigins origins;
  for (const auto& p : a.plugins) load_plugin(p, SourceLocation{"--plugin", 0, 0}, reg, origins);
  if (!a.type.empty()) {
    const auto* entry = reg.find(a.type);
    if (!entry) {
      std::cerr << "pneumo: no component type '" << a.type << "' (run 'pneumo components' for the list)\n";
      return 2;
    }
    print_component(*entry->info, std::cout);
    return 0;
  }
  for (const auto& t : reg.types()) print_component(*reg.find(t)->info, std::cout);
  return 0;
}

}  // namespace

Command add_components_command(CLI::App& app) {
  auto a = std::make_shared<ComponentsArgs>();
  auto* comps = app.add_subcommand("components", "list component types, or show one");
  comps->add_option("type", a->type, "component type to describe");
  comps->add_option("--plugin", a->plugins, "also list the types of this component plugin (shared library)")
      ->allow_extra_args(false);
  return {.app = comps, .run = [a] { return components_command(*a); }};
}

}  // namespace pneumo::cli
