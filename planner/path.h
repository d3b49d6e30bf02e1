#pragma once

#include <cstddef>
#include <vector>

#include "common/types.h"

/// @file
/// A planned path (world poses) with arc lengths, and projection of a point onto it.

namespace cairn::planner {

/// Where a point falls on a path.
struct PathProjection {
  size_t segment{0};         ///< index of the segment's first pose
  double arc_length_m{0.0};  ///< arc length of the projected point from the path start
  double distance_m{0.0};    ///< distance from the point to the path
  common::Vector2 point_m{common::Vector2::Zero()};
};

/// Poses in the world frame with cumulative arc lengths. A value type.
class Path {
 public:
  Path() = default;
  explicit Path(std::vector<common::Pose2> poses);

  const std::vector<common::Pose2>& poses() const { return poses_; }
  bool empty() const { return poses_.empty(); }
  size_t size() const { return poses_.size(); }
  double length_m() const { return cumulative_m_.empty() ? 0.0 : cumulative_m_.back(); }
  /// Arc length from the start to pose i.
  double arc_length_m(size_t i) const { return cumulative_m_[i]; }

  /// Nearest point on the segments [first_segment, last_segment] (clamped to the path).
  /// Searching a window ahead of the last projection keeps the answer from jumping to a
  /// crossing part of the path. The path must not be empty.
  PathProjection Project(const common::Vector2& p, size_t first_segment = 0,
                         size_t last_segment = static_cast<size_t>(-1)) const;
  /// The point at a given arc length (clamped to the path), with the heading of its segment.
  common::Pose2 PoseAt(double arc_length_m) const;
  /// Index of the first pose at or beyond an arc length.
  size_t IndexAt(double arc_length_m) const;

 private:
  std::vector<common::Pose2> poses_;
  std::vector<double> cumulative_m_;
};

}  // namespace cairn::planner
