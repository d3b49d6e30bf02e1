#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common/point_cloud.h"

/// @file
/// Lidar revolutions in small messages. A revolution sent whole (over a megabyte) is lost with
/// any one of its UDP fragments, so it travels as azimuth slices of under 64 KB: SplitSlice cuts
/// a slice that is too large, RevolutionAssembler gathers slices back into revolutions.

namespace cairn::runtime {

/// Splits one slice into consecutive slices whose encoded size stays under max_bytes; all keep
/// the original pose and revolution, and slice_index/slice_count are renumbered within the
/// given revolution (indices start at first_index, count is total_count or the number made).
std::vector<common::LidarSlice> SplitSlice(const common::LidarSlice& whole, size_t max_bytes);
/// Encoded bytes per point in lcmt_point_cloud_slice (x, y, z, intensity, ring).
inline constexpr size_t kBytesPerLidarPoint = 17;

/// What a RevolutionAssembler holds at most. Slices come from the bus: their counts and
/// revolution numbers are a peer's word, so what they make the assembler keep is bounded.
struct RevolutionLimits {
  int max_slices_per_revolution{4096};
  int max_points_per_slice{65536};     ///< a 256 KB message holds about 15,000
  int64_t max_points_pending{4'000'000};  ///< over every pending revolution (about 80 MB)
  int max_pending_revolutions{4};
  int64_t timeout_us{2'000'000};  ///< of arrival time since a revolution's first slice
};

/// Collects slices into revolutions. A revolution is emitted when its last missing slice
/// arrives, or, incomplete, when a slice of a newer revolution of its robot arrives, when it
/// has waited `timeout_us` since its first slice came, or when room is needed for a newer one
/// (the oldest to arrive goes first). A slice is refused (counted, nothing held changes) when
/// its count exceeds the limits, disagrees with the count of its revolution's other slices, or
/// its points alone exceed the pending budget.
class RevolutionAssembler {
 public:
  RevolutionAssembler() = default;
  explicit RevolutionAssembler(RevolutionLimits limits) : limits_(limits) {}

  /// Returns the revolutions this slice completed or pushed out (oldest first). `arrival_us`: a
  /// monotonic clock of the receiver.
  std::vector<common::LidarRevolution> OnSlice(common::LidarSlice slice, int64_t arrival_us);
  int64_t incomplete_revolutions() const { return incomplete_; }
  int64_t missing_slices() const { return missing_slices_; }
  int64_t refused_slices() const { return refused_slices_; }
  int64_t expired_revolutions() const { return expired_; }
  /// Points held in pending revolutions.
  int64_t pending_points() const { return pending_points_; }

 private:
  struct Pending {
    common::LidarRevolution revolution;
    int64_t first_arrival_us{0};
    int64_t points{0};
  };
  using Key = std::pair<std::string, int64_t>;
  /// Emits a pending revolution, incomplete.
  void Emit(std::map<Key, Pending>::iterator it, std::vector<common::LidarRevolution>* done);
  /// The pending revolution that arrived first, other than `keep`.
  std::map<Key, Pending>::iterator Oldest(const Key& keep);

  RevolutionLimits limits_;
  std::map<Key, Pending> pending_;
  int64_t pending_points_{0};
  int64_t incomplete_{0};
  int64_t missing_slices_{0};
  int64_t refused_slices_{0};
  int64_t expired_{0};
};

}  // namespace cairn::runtime
