#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

/// @file
/// ThreadPool: the workers that split a ray cast (RayCaster) over several cores.

namespace cairn::sim {

/// A small pool of worker threads for splitting a cast. Zero extra threads runs inline.
class ThreadPool {
 public:
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  /// Runs task(i) for i in [0, count) on the workers and the calling thread; returns when all
  /// are done.
  void ParallelFor(int count, const std::function<void(int)>& task);

 private:
  void WorkerLoop();
  void RunTasks();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  const std::function<void(int)>* task_{nullptr};
  int count_{0};
  std::atomic<int> next_{0};
  int busy_{0};
  uint64_t generation_{0};
  bool quit_{false};
};

}  // namespace cairn::sim
