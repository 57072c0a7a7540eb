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
  struct Entry {
    std::shared_ptr<const ComponentInfo> info;
    Factory make;
  };

  template <class C>
  void add() {
    add(C::describe(), [](const Construction& c) { return std::make_unique<C>(c); });
  }
  // Throws std::invalid_argument if the type name is taken.
  void add(ComponentInfo info, Factory make);
  // Adds an entry of another registry as it is (plugins register into a
  // staging registry first). Throws std::invalid_argument if the type is taken.
  void add_entry(const Entry& entry);

  const Entry* find(const std::string& type) const;
  std::vector<std::string> types() const;

 private:
  std::map<std::string, Entry> entries_;
};

}  // namespace pneumo
