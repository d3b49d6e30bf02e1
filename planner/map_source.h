#pragma once

#include <cstdint>
#include <memory>
#include <mutex>

#include "planner/cost_map.h"

/// @file
/// MapSource: where the navigator gets its cost-layer snapshots. Callers cannot tell a local
/// source (InMemoryMapSource, for tests and tools) from a remote one (the LCM map client of
/// cairn-navigator, which reassembles the mapper's tiles).

namespace cairn::planner {

class MapSource {
 public:
  virtual ~MapSource() = default;
  /// The newest snapshot, or nullptr before the first. Snapshots are immutable and shared.
  virtual std::shared_ptr<const CostMap> Latest() const = 0;
  /// When the map's producer was last heard from (µs, the caller's clock), 0 if never. A
  /// producer that re-announces an unchanged layer keeps the snapshot current.
  virtual int64_t last_heard_utime() const = 0;
};

/// A MapSource fed directly (thread-safe).
class InMemoryMapSource : public MapSource {
 public:
  InMemoryMapSource() = default;
  InMemoryMapSource(const InMemoryMapSource&) = delete;
  InMemoryMapSource& operator=(const InMemoryMapSource&) = delete;

  void Set(std::shared_ptr<const CostMap> map, int64_t utime) {
    std::lock_guard<std::mutex> lock(mutex_);
    map_ = std::move(map);
    heard_utime_ = utime;
  }
  void Heard(int64_t utime) {
    std::lock_guard<std::mutex> lock(mutex_);
    heard_utime_ = utime;
  }
  std::shared_ptr<const CostMap> Latest() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return map_;
  }
  int64_t last_heard_utime() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return heard_utime_;
  }

 private:
  mutable std::mutex mutex_;
  std::shared_ptr<const CostMap> map_;
  int64_t heard_utime_{0};
};

}  // namespace cairn::planner
