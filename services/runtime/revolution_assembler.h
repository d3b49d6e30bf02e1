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

/// Collects slices into revolutions. A revolution is emitted when its last missing slice
/// arrives, or, incomplete, when a slice of a newer revolution arrives.
class RevolutionAssembler {
 public:
  /// Returns the revolutions this slice completed or superseded (oldest first).
  std::vector<common::LidarRevolution> OnSlice(common::LidarSlice slice);
  int64_t incomplete_revolutions() const { return incomplete_; }
  int64_t missing_slices() const { return missing_slices_; }

 private:
  std::map<std::pair<std::string, int64_t>, common::LidarRevolution> pending_;
  int64_t incomplete_{0};
  int64_t missing_slices_{0};
};

}  // namespace cairn::runtime
