// State a component instance keeps per thread: the memoisation the
// component contract allows (framework/model/component.hpp), and a fact of
// the run in progress that changes no equation (a warning said once a run).
// Threads integrate one System at the same time (framework/assembly/
// evaluator.hpp), so such state cannot live in the instance without a lock.
//
// Each thread keeps a few slots per value type, an instance's value in the
// slot its serial number picks; a slot taken over by another instance
// starts again from T{} (a memo then recomputes; a "told" flag may tell
// twice, never not at all). Serial numbers are never reused - an instance
// at a freed one's address is another, and a copy gets a number of its own.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <utility>

namespace pneumo {

template <class T, std::size_t Slots = 16>
class PerThread {
 public:
  PerThread() = default;
  PerThread(const PerThread&) : serial_(next()) {}
  // Assigned, an instance becomes another: its slots of before are not its.
  PerThread& operator=(const PerThread&) {
    serial_ = next();
    return *this;
  }

  // This thread's value for this instance.
  T& get() const {
    static thread_local std::array<std::pair<std::uint64_t, T>, Slots> slots{};
    auto& s = slots[serial_ % Slots];
    if (s.first != serial_) s = {serial_, T{}};
    return s.second;
  }

 private:
  static std::uint64_t next() {
    static std::atomic<std::uint64_t> n{0};
    return ++n;
  }
  std::uint64_t serial_ = next();
};

}  // namespace pneumo
