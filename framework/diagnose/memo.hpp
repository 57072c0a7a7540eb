// Simulated signals remembered by the name of what was simulated (a model's
// effects and a run): a diagnosis asks for the same model again and again -
// the unpatched model behind every candidate at its null, the chosen
// effects' finite-difference points behind every candidate re-screened
// against them. The least recently used are forgotten beyond a budget of
// stored values; safe to share between threads.
#pragma once

#include <cstddef>
#include <list>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace pneumo::diagnose {

using Signals = std::vector<std::vector<double>>;  // per signal, at the run's measurement times

class SignalMemo {
 public:
  explicit SignalMemo(std::size_t max_values) : max_values_(max_values) {}

  std::optional<Signals> find(const std::string& key);
  void keep(const std::string& key, const Signals& signals);
  std::size_t hits() const;

 private:
  using Order = std::list<std::string>;  // most recently used first
  struct Entry {
    Signals signals;
    std::size_t values = 0;
    Order::iterator at;
  };
  void forget_oldest();

  std::size_t max_values_, values_ = 0, hits_ = 0;
  mutable std::mutex mutex_;
  Order order_;
  std::unordered_map<std::string, Entry> entries_;
};

}  // namespace pneumo::diagnose
