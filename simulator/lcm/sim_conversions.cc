#include "simulator/lcm/sim_conversions.h"

#include "services/runtime/conversions.h"

namespace cairn::sim {

cairn::lcmt_odometry ToLcm(const OdometryReading& r) {
  cairn::lcmt_odometry m{};
  m.utime = r.utime;
  m.robot = r.robot;
  m.frame = "odom";
  m.child_frame = "base_link";
  runtime::ToLcm(r.pose, m.position_m, m.orientation_wxyz);
  for (int i = 0; i < 3; ++i) {
    m.linear_velocity_mps[i] = r.linear_velocity_mps[i];
    m.angular_velocity_radps[i] = r.angular_velocity_radps[i];
  }
  for (int i = 0; i < 36; ++i) {
    m.pose_covariance[i] = 0.0;
    m.twist_covariance[i] = 0.0;
  }
  return m;
}

cairn::lcmt_pose ToLcm(const GroundTruthReading& r) {
  cairn::lcmt_pose m = runtime::ToLcmPose(r.pose, r.utime, r.robot, "world");
  for (int i = 0; i < 3; ++i) {
    m.linear_velocity_mps[i] = r.linear_velocity_mps[i];
    m.angular_velocity_radps[i] = r.angular_velocity_radps[i];
  }
  return m;
}

cairn::lcmt_imu ToLcm(const ImuReading& r) {
  cairn::lcmt_imu m{};
  m.utime = r.utime;
  m.robot = r.robot;
  m.frame = "imu";
  m.orientation_wxyz[0] = r.orientation.w();
  m.orientation_wxyz[1] = r.orientation.x();
  m.orientation_wxyz[2] = r.orientation.y();
  m.orientation_wxyz[3] = r.orientation.z();
  for (int i = 0; i < 3; ++i) {
    m.angular_velocity_radps[i] = r.angular_velocity_radps[i];
    m.linear_acceleration_mps2[i] = r.linear_acceleration_mps2[i];
  }
  m.orientation_variance_rad2 = r.orientation_variance_rad2;
  m.angular_velocity_variance = r.angular_velocity_variance;
  m.linear_acceleration_variance = r.linear_acceleration_variance;
  return m;
}

cairn::lcmt_laser_scan ToLcm(const TurretLine& line, double line_period_s) {
  cairn::lcmt_laser_scan m = runtime::ToLcm(line.scan);
  m.frame = "turret";
  m.turret_angle_rad = line.pan_rad;
  m.scan_time_s = static_cast<float>(line_period_s);
  return m;
}

}  // namespace cairn::sim
