#include "framework/diagnose/memo.hpp"

namespace pneumo::diagnose {

std::optional<Signals> SignalMemo::find(const std::string& key) {
  const std::lock_guard lock(mutex_);
  const auto it = entries_.find(key);
  if (it == entries_.end()) return std::nullopt;
  order_.splice(order_.begin(), order_, it->second.at);
  ++hits_;
  return it->second.signals;
}

void SignalMemo::keep(const std::string& key, const Signals& signals) {
  std::size_t n = 0;
  for (const auto& s : signals) n += s.size();
  if (n > max_values_) return;
  const std::lock_guard lock(mutex_);
  if (entries_.count(key)) return;  // another thread simulated it too
  order_.push_front(key);
  entries_.emplace(key, Entry{signals, n, order_.begin()});
  values_ += n;
  while (values_ > max_values_) forget_oldest();
}

std::size_t SignalMemo::hits() const {
  const std::lock_guard lock(mutex_);
  return hits_;
}

void SignalMemo::forget_oldest() {
  const auto it = entries_.find(order_.back());
  values_ -= it->second.values;
  entries_.erase(it);
  order_.pop_back();
}

}  // namespace pneumo::diagnose
