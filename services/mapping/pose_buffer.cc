#include "services/mapping/pose_buffer.h"

#include <algorithm>
#include <cmath>

namespace cairn::mapping {

bool PoseBuffer::Add(int64_t utime, const common::Pose3& pose) {
  if (!pose.position_m.allFinite() || !pose.orientation.coeffs().allFinite() ||
      pose.orientation.norm() < 1e-6) {
    return false;
  }
  common::Pose3 p = pose;
  p.orientation.normalize();
  auto it = std::lower_bound(samples_.begin(), samples_.end(), utime,
                             [](const auto& s, int64_t t) { return s.first < t; });
  if (it != samples_.end() && it->first == utime) {
    it->second = p;
  } else {
    samples_.insert(it, {utime, p});
  }
  const int64_t newest = samples_.back().first;
  while (!samples_.empty() && samples_.front().first < newest - max_age_us_) samples_.pop_front();
  return true;
}

std::optional<common::Pose3> PoseBuffer::At(int64_t utime, double max_gap_s) const {
  if (samples_.empty()) return std::nullopt;
  const int64_t gap = static_cast<int64_t>(std::llround(max_gap_s * 1e6));
  auto after = std::lower_bound(samples_.begin(), samples_.end(), utime,
                                [](const auto& s, int64_t t) { return s.first < t; });
  if (after != samples_.end() && after->first == utime) return after->second;
  const bool has_after = after != samples_.end() && after->first - utime <= gap;
  const bool has_before = after != samples_.begin() && utime - std::prev(after)->first <= gap;
  if (has_before && has_after) {
    const auto& a = *std::prev(after);
    const auto& b = *after;
    const double f = double(utime - a.first) / double(b.first - a.first);
    common::Pose3 p;
    p.position_m = a.second.position_m + f * (b.second.position_m - a.second.position_m);
    p.orientation = a.second.orientation.slerp(f, b.second.orientation);
    return p;
  }
  if (has_before) return std::prev(after)->second;
  if (has_after) return after->second;
  return std::nullopt;
}

std::optional<std::pair<int64_t, common::Pose3>> PoseBuffer::Latest() const {
  if (samples_.empty()) return std::nullopt;
  return samples_.back();
}

}  // namespace cairn::mapping
