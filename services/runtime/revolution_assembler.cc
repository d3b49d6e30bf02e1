#include "services/runtime/revolution_assembler.h"

#include <algorithm>

namespace cairn::runtime {

std::vector<common::LidarSlice> SplitSlice(const common::LidarSlice& whole, size_t max_bytes) {
  constexpr size_t kHeaderBytes = 512;
  const size_t per_slice =
      max_bytes > kHeaderBytes
          ? std::max<size_t>(1, (max_bytes - kHeaderBytes) / kBytesPerLidarPoint)
          : 1;
  const size_t n = whole.points.size();
  const size_t count = std::max<size_t>(1, (n + per_slice - 1) / per_slice);
  std::vector<common::LidarSlice> slices;
  slices.reserve(count);
  const double span = whole.azimuth_end_rad - whole.azimuth_start_rad;
  for (size_t i = 0; i < count; ++i) {
    common::LidarSlice s;
    s.utime = whole.utime;
    s.robot = whole.robot;
    s.revolution = whole.revolution;
    s.slice_index = static_cast<int32_t>(i);
    s.slice_count = static_cast<int32_t>(count);
    s.azimuth_start_rad = whole.azimuth_start_rad + span * i / count;
    s.azimuth_end_rad = whole.azimuth_start_rad + span * (i + 1) / count;
    s.max_range_m = whole.max_range_m;
    s.sensor_pose = whole.sensor_pose;
    const size_t begin = i * per_slice, end = std::min(n, begin + per_slice);
    s.points.assign(whole.points.begin() + begin, whole.points.begin() + end);
    slices.push_back(std::move(s));
  }
  return slices;
}

std::vector<common::LidarRevolution> RevolutionAssembler::OnSlice(common::LidarSlice slice) {
  std::vector<common::LidarRevolution> done;
  const auto key = std::make_pair(slice.robot, slice.revolution);
  // Older pending revolutions of the same robot are superseded by a newer one.
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (it->first.first == slice.robot && it->first.second < slice.revolution) {
      ++incomplete_;
      missing_slices_ +=
          it->second.expected_slices - static_cast<int64_t>(it->second.slices.size());
      done.push_back(std::move(it->second));
      it = pending_.erase(it);
    } else {
      ++it;
    }
  }
  common::LidarRevolution& rev = pending_[key];
  rev.revolution = slice.revolution;
  rev.robot = slice.robot;
  rev.expected_slices = slice.slice_count;
  const bool duplicate = std::any_of(rev.slices.begin(), rev.slices.end(), [&](const auto& s) {
    return s.slice_index == slice.slice_index;
  });
  if (!duplicate) {
    auto pos =
        std::lower_bound(rev.slices.begin(), rev.slices.end(), slice.slice_index,
                         [](const common::LidarSlice& s, int idx) { return s.slice_index < idx; });
    rev.slices.insert(pos, std::move(slice));
  }
  if (rev.complete()) {
    done.push_back(std::move(rev));
    pending_.erase(key);
  }
  return done;
}

}  // namespace cairn::runtime
