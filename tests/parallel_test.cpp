// parallel_for, the one way sweeps, sensitivity designs and the diagnosis
// run independent work on threads.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "framework/core/parallel.hpp"

namespace pneumo {
namespace {

TEST(ParallelFor, EveryIndexOnceAndEachWorkerIdOnOneThread) {
  const long n = 1000;
  std::vector<std::atomic<int>> seen(n);
  std::mutex m;
  std::map<int, std::thread::id> thread_of;
  parallel_for(n, 4, [&](int w, long i) {
    ++seen[i];
    std::lock_guard<std::mutex> lock(m);
    auto [it, fresh] = thread_of.emplace(w, std::this_thread::get_id());
    EXPECT_EQ(it->second, std::this_thread::get_id()) << "worker " << w;
    EXPECT_GE(w, 0);
    EXPECT_LT(w, 4);
  });
  for (long i = 0; i < n; ++i) EXPECT_EQ(seen[i], 1) << i;
}

TEST(ParallelFor, OneThreadRunsInOrderOnTheCaller) {
  std::vector<long> order;
  const auto caller = std::this_thread::get_id();
  parallel_for(5, 1, [&](int w, long i) {
    EXPECT_EQ(w, 0);
    EXPECT_EQ(std::this_thread::get_id(), caller);
    order.push_back(i);
  });
  EXPECT_EQ(order, (std::vector<long>{0, 1, 2, 3, 4}));
}

TEST(ParallelFor, AnExceptionStopsFurtherClaimsAndIsRethrown) {
  std::atomic<long> ran{0};
  std::atomic<bool> thrown{false};
  EXPECT_THROW(parallel_for(100000, 2,
                            [&](int, long i) {
                              ++ran;
                              if (i == 10) {
                                thrown = true;
                                throw std::runtime_error("run 10 failed");
                              }
                              // Later runs take 1 ms once run 10 has failed,
                              // so that a loaded machine's scheduling cannot
                              // let the other worker race through the rest
                              // before the failure is seen.
                              if (i > 10) {
                                while (!thrown) std::this_thread::yield();
                                std::this_thread::sleep_for(std::chrono::milliseconds(1));
                              }
                            }),
               std::runtime_error);
  // Index 10 and what the other thread had claimed by then, not the rest.
  EXPECT_LT(ran.load(), 1000);
}

}  // namespace
}  // namespace pneumo
