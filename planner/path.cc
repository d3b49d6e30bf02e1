#include "planner/path.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/check.h"

namespace cairn::planner {

using common::Pose2;
using common::Vector2;

Path::Path(std::vector<Pose2> poses) : poses_(std::move(poses)) {
  cumulative_m_.resize(poses_.size(), 0.0);
  for (size_t i = 1; i < poses_.size(); ++i) {
    cumulative_m_[i] =
        cumulative_m_[i - 1] + (poses_[i].position() - poses_[i - 1].position()).norm();
  }
}

PathProjection Path::Project(const Vector2& p, size_t first_segment, size_t last_segment) const {
  CAIRN_DEMAND(!poses_.empty());
  PathProjection best;
  best.distance_m = std::numeric_limits<double>::infinity();
  if (poses_.size() == 1) {
    best.point_m = poses_[0].position();
    best.distance_m = (p - best.point_m).norm();
    return best;
  }
  const size_t last = std::min(last_segment, poses_.size() - 2);
  for (size_t i = std::min(first_segment, last); i <= last; ++i) {
    const Vector2 a = poses_[i].position();
    const Vector2 b = poses_[i + 1].position();
    const Vector2 ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const Vector2 q = a + t * ab;
    const double d = (p - q).norm();
    if (d < best.distance_m) {
      best.distance_m = d;
      best.segment = i;
      best.point_m = q;
      best.arc_length_m = cumulative_m_[i] + t * std::sqrt(len2);
    }
  }
  return best;
}

size_t Path::IndexAt(double arc_length_m) const {
  const auto it = std::lower_bound(cumulative_m_.begin(), cumulative_m_.end(), arc_length_m);
  if (it == cumulative_m_.end()) return poses_.empty() ? 0 : poses_.size() - 1;
  return static_cast<size_t>(it - cumulative_m_.begin());
}

Pose2 Path::PoseAt(double arc_length_m) const {
  CAIRN_DEMAND(!poses_.empty());
  if (poses_.size() == 1 || arc_length_m <= 0.0) return poses_.front();
  if (arc_length_m >= length_m()) return poses_.back();
  const size_t j = std::max<size_t>(1, IndexAt(arc_length_m));
  const size_t i = j - 1;
  const double seg = cumulative_m_[j] - cumulative_m_[i];
  const double t = seg > 0.0 ? (arc_length_m - cumulative_m_[i]) / seg : 0.0;
  const Vector2 a = poses_[i].position();
  const Vector2 b = poses_[j].position();
  const Vector2 q = a + t * (b - a);
  const double yaw = seg > 0.0 ? std::atan2(b.y() - a.y(), b.x() - a.x()) : poses_[j].yaw_rad;
  return {q.x(), q.y(), yaw};
}

}  // namespace cairn::planner
