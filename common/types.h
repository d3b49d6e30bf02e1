#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

/// @file
/// Shared geometric types (grid_map TypeDefs style). Units: metres, radians, seconds.

namespace cairn::common {

using Vector2 = Eigen::Vector2d;
using Vector3 = Eigen::Vector3d;
using Quaternion = Eigen::Quaterniond;

/// Wraps an angle to (-pi, pi].
inline double WrapAngle(double angle_rad) {
  angle_rad = std::fmod(angle_rad + M_PI, 2.0 * M_PI);
  if (angle_rad <= 0.0) angle_rad += 2.0 * M_PI;
  return angle_rad - M_PI;
}

/// A planar pose: position in metres and heading in radians, in a named frame.
struct Pose2 {
  double x_m{0.0};
  double y_m{0.0};
  double yaw_rad{0.0};

  Vector2 position() const { return {x_m, y_m}; }
  /// this ∘ other: `other` expressed in this pose's frame, returned in the parent frame.
  Pose2 Compose(const Pose2& other) const {
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    return {x_m + c * other.x_m - s * other.y_m, y_m + s * other.x_m + c * other.y_m,
            WrapAngle(yaw_rad + other.yaw_rad)};
  }
  Pose2 Inverse() const {
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    return {-(c * x_m + s * y_m), -(-s * x_m + c * y_m), WrapAngle(-yaw_rad)};
  }
  /// Maps a point from this pose's frame to the parent frame.
  Vector2 Transform(const Vector2& p) const {
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    return {x_m + c * p.x() - s * p.y(), y_m + s * p.x() + c * p.y()};
  }
  bool operator==(const Pose2& o) const {
    return x_m == o.x_m && y_m == o.y_m && yaw_rad == o.yaw_rad;
  }
};

/// A rigid 3-D pose: position in metres and orientation as a unit quaternion.
struct Pose3 {
  Vector3 position_m{Vector3::Zero()};
  Quaternion orientation{Quaternion::Identity()};

  Vector3 Transform(const Vector3& p) const { return position_m + orientation * p; }
  double yaw_rad() const {
    const Eigen::Matrix3d r = orientation.toRotationMatrix();
    return std::atan2(r(1, 0), r(0, 0));
  }
  /// Pitch, nose up positive (the x axis rising above the horizontal), and roll, in radians.
  /// Note: this is the opposite sign of the aerospace ZYX pitch about +y.
  double pitch_rad() const {
    const Eigen::Matrix3d r = orientation.toRotationMatrix();
    return std::asin(std::clamp(r(2, 0), -1.0, 1.0));
  }
  double roll_rad() const {
    const Eigen::Matrix3d r = orientation.toRotationMatrix();
    return std::atan2(r(2, 1), r(2, 2));
  }
  Pose2 ToPose2() const { return {position_m.x(), position_m.y(), yaw_rad()}; }
};

}  // namespace cairn::common
