#pragma once

#include <cmath>
#include <cstdint>

#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_lidar_ranges.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_odometry.hpp"
#include "cairn/lcmt_point_cloud_slice.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_robot_profile.hpp"

#include "common/obstacle.h"
#include "common/point_cloud.h"
#include "common/robot_profile.h"
#include "common/status.h"
#include "common/types.h"

/// @file
/// ToLcm / FromLcm: the only seam between core types and LCM messages (house style 8.1).
/// FromLcm validates what arrives (array sizes, finite values) and says what was wrong.

namespace cairn::runtime {

void ToLcm(const common::Pose3& pose, double position_m[3], double orientation_wxyz[4]);
/// @returns an error for non-finite values or a quaternion far from unit length.
common::Result<common::Pose3> PoseFromArrays(const double position_m[3],
                                             const double orientation_wxyz[4]);

/// A slice that carries a range image is sent as the image's points (common::ExpandRangeImage).
cairn::lcmt_point_cloud_slice ToLcm(const common::LidarSlice& slice);
/// The same without the points (num_points 0): what a fast encoder writes before them.
cairn::lcmt_point_cloud_slice ToLcmWithoutPoints(const common::LidarSlice& slice);
/// Points with non-finite coordinates are kept (the mapper counts and drops them); a size
/// mismatch or a bad pose is an error.
common::Result<common::LidarSlice> FromLcm(const cairn::lcmt_point_cloud_slice& msg);

/// A point's range in steps of `steps_per_m`, as lcmt_lidar_ranges carries it (see
/// common::LidarRangeToSteps).
inline uint16_t LidarRangeSteps(const common::LidarPoint& p, float steps_per_m) {
  return common::LidarRangeToSteps(std::sqrt(p.x_m * p.x_m + p.y_m * p.y_m + p.z_m * p.z_m),
                                   steps_per_m);
}
/// A slice with a grid and a range resolution (LidarGrid) as ranges, 3 bytes a ray: its range
/// image as it is (common::HasRangeImage), or else each point's range, rounded to the
/// resolution, at its ring and column; rays without a point read 0.
/// @throws std::invalid_argument when the slice has no grid or a point lies outside it.
cairn::lcmt_lidar_ranges ToLcmRanges(const common::LidarSlice& slice);
/// The points of the rays that returned (range > 0), each at its ring's elevation and its
/// column's azimuth (common::ExpandRangeImage), with the grid kept. Counts that disagree, more than
/// 127 rings, a bad resolution, elevation, azimuth or pose are errors.
common::Result<common::LidarSlice> FromLcm(const cairn::lcmt_lidar_ranges& msg);
/// The same without the rays (num_rays 0, arrays empty): what a fast encoder writes before them.
/// @throws std::invalid_argument when the slice has no grid.
cairn::lcmt_lidar_ranges ToLcmRangesWithoutRays(const common::LidarSlice& slice);

cairn::lcmt_laser_scan ToLcm(const common::LaserScan& scan);
common::Result<common::LaserScan> FromLcm(const cairn::lcmt_laser_scan& msg);

cairn::lcmt_robot_profile ToLcm(const common::RobotProfile& profile);
/// @returns an error if the message does not describe a valid profile.
common::Result<common::RobotProfile> FromLcm(const cairn::lcmt_robot_profile& msg);

/// Ground-truth pose message <-> Pose3 (velocities are not part of Pose3).
cairn::lcmt_pose ToLcmPose(const common::Pose3& pose, int64_t utime, const std::string& robot,
                           const std::string& frame);
common::Result<common::Pose3> FromLcm(const cairn::lcmt_pose& msg);
common::Result<common::Pose3> FromLcm(const cairn::lcmt_odometry& msg);

cairn::lcmt_obstacle ToLcm(const common::Obstacle& obstacle);
common::Result<common::Obstacle> FromLcm(const cairn::lcmt_obstacle& msg);
cairn::lcmt_obstacle_registry ToLcm(const common::ObstacleRegistry& registry, int64_t utime,
                                    const std::string& robot, const std::string& map_name);
common::Result<common::ObstacleRegistry> FromLcm(const cairn::lcmt_obstacle_registry& msg);
/// Keeps a registry message under the bus limit (tiler.h, kMaxMessageBytes): when it is larger,
/// the outlines are left out. Returns whether they were.
bool FitRegistryToMessageLimit(cairn::lcmt_obstacle_registry* msg);

}  // namespace cairn::runtime
