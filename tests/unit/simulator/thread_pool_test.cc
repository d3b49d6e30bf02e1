#include "simulator/thread_pool.h"

#include <atomic>
#include <vector>

#include <gtest/gtest.h>

namespace cairn::sim {
namespace {

TEST(ThreadPoolTest, RunsEveryTaskOnce) {
  ThreadPool pool(3);
  EXPECT_EQ(pool.threads(), 3);
  for (int round = 0; round < 50; ++round) {
    std::vector<std::atomic<int>> counts(37);
    pool.ParallelFor(37, [&](int i) { counts[i]++; });
    for (auto& c : counts) ASSERT_EQ(c.load(), 1);
  }
}

TEST(ThreadPoolTest, OneThreadRunsInlineAndNothingToDoReturns) {
  ThreadPool pool(1);
  EXPECT_EQ(pool.threads(), 1);
  std::vector<int> order;
  pool.ParallelFor(4, [&](int i) { order.push_back(i); });
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3}));
  ThreadPool two(2);
  two.ParallelFor(0, [&](int) { FAIL() << "no task to run"; });
}

}  // namespace
}  // namespace cairn::sim
