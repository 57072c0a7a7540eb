// Component types by name. Built-in components register in
// components/builtin.cpp; plugins add theirs the same way.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "framework/model/component.hpp"

namespace pneumo {

class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Component>(const Construction&)>;
  // Per-instance refinement of a type's info from its parameter values
  // (optional chambers, ports, internal variables, roots that exist only for
  // some parameter sets). Receives the type's info, returns the instance's.
  using Refine = std::function<ComponentInfo(ComponentInfo, const ParameterValues&)>;
  struct Entry {
    std::shared_ptr<const ComponentInfo> info;  // the type's (what 'pneumo components' lists)
    Factory make;
    Refine refine;  // empty: every instance has `info`

    // The info of an instance with these (checked, SI) parameter values. May
    // throw ParameterError for a combination the refinement rejects.
    std::shared_ptr<const ComponentInfo> instance_info(const ParameterValues& values) const {
      if (!refine) return info;
      return std::make_shared<const ComponentInfo>(refine(*info, values));
    }
  };

  // A component type C may define
  //   static ComponentInfo instance_info(ComponentInfo base, const ParameterValues&);
  // to add ports, variables, observables or roots per instance; its
  // describe() then lists everything an instance can have, so that parameter
  // checks and documentation see the whole type.
  template <class C>
  void add() {
    Refine refine;
    if constexpr (requires(ComponentInfo i, const ParameterValues& v) { C::instance_info(std::move(i), v); })
      refine = [](ComponentInfo i, const ParameterValues& v) { return C::instance_info(std::move(i), v); };
    add(C::describe(), [](const Construction& c) { return std::make_unique<C>(c); }, std::move(refine));
  }
  // Throws std::invalid_argument if the type name is taken.
  void add(ComponentInfo info, Factory make, Refine refine = {});
  // Adds an entry of another registry as it is (plugins register into a
  // staging registry first). Throws std::invalid_argument if the type is taken.
  void add_entry(const Entry& entry);

  const Entry* find(const std::string& type) const;
  std::vector<std::string> types() const;

 private:
  std::map<std::string, Entry> entries_;
};

}  // namespace pneumo
