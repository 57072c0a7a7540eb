#include "framework/model/registry.hpp"

#include <stdexcept>

namespace pneumo {

void Registry::add(ComponentInfo info, Factory make, Refine refine) {
  const std::string type = info.type;
  if (entries_.count(type))
    throw std::invalid_argument("component type '" + type + "' is already registered");
  entries_.emplace(type, Entry{std::make_shared<const ComponentInfo>(std::move(info)), std::move(make), std::move(refine)});
}

void Registry::add_entry(const Entry& entry) {
  const std::string type = entry.info->type;
  if (entries_.count(type))
    throw std::invalid_argument("component type '" + type + "' is already registered");
  entries_.emplace(type, entry);
}

const Registry::Entry* Registry::find(const std::string& type) const {
  auto it = entries_.find(type);
  return it == entries_.end() ? nullptr : &it->second;
}

std::vector<std::string> Registry::types() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : entries_) out.push_back(k);
  return out;
}

}  // namespace pneumo
