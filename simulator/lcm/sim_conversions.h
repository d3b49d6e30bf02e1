#pragma once

#include "cairn/lcmt_imu.hpp"
#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_odometry.hpp"
#include "cairn/lcmt_pose.hpp"

#include "simulator/mujoco_sim.h"

/// @file
/// ToLcm for the simulator's readings (the LCM seam of cairn-sim). Lidar slices and planar scans
/// use services/runtime/conversions.h.

namespace cairn::sim {

/// Odometry in frame "odom" (which starts at the spawn pose), child frame "base_link".
/// Covariances are left zero: the simulator does not estimate its own drift.
cairn::lcmt_odometry ToLcm(const OdometryReading& reading);
/// Ground truth in frame "world", velocities in the world frame.
cairn::lcmt_pose ToLcm(const GroundTruthReading& reading);
/// IMU in frame "imu", with the configured noise variances.
cairn::lcmt_imu ToLcm(const ImuReading& reading);
/// One turret line: frame "turret", the scanning plane's pose, and the pan angle.
cairn::lcmt_laser_scan ToLcm(const TurretLine& line, double line_period_s);

}  // namespace cairn::sim
