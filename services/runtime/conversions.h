#pragma once

#include "cairn/lcmt_laser_scan.hpp"
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

cairn::lcmt_point_cloud_slice ToLcm(const common::LidarSlice& slice);
/// The same without the points (num_points 0): what a fast encoder writes before them.
cairn::lcmt_point_cloud_slice ToLcmWithoutPoints(const common::LidarSlice& slice);
/// Points with non-finite coordinates are kept (the mapper counts and drops them); a size
/// mismatch or a bad pose is an error.
common::Result<common::LidarSlice> FromLcm(const cairn::lcmt_point_cloud_slice& msg);

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
