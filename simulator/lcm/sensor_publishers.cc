#include "simulator/lcm/sensor_publishers.h"

#include <stdexcept>

#include "cairn/lcmt_imu.hpp"
#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_odometry.hpp"
#include "cairn/lcmt_point_cloud_slice.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sonar_ping.hpp"

#include "common/channels.h"
#include "services/runtime/conversions.h"
#include "simulator/sensors/ground_truth_sensor.h"
#include "simulator/sensors/imu_sensor.h"
#include "simulator/sensors/lidar_sensor.h"
#include "simulator/sensors/odometry_sensor.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "simulator/sensors/sonar_sensor.h"
#include "simulator/sensors/turret_sensor.h"

namespace cairn::sim {
namespace {

// --- conversions: one per sensor kind whose reading has no shared conversion -----------------

/// One turret line: frame "turret", the scanning plane's pose, and the pan angle.
cairn::lcmt_laser_scan TurretLineToLcm(const TurretLine& line) {
  cairn::lcmt_laser_scan m = runtime::ToLcm(line.scan);
  m.frame = "turret";
  m.turret_angle_rad = line.pan_rad;
  m.scan_time_s = static_cast<float>(line.line_period_s);
  return m;
}

/// One sonar ping in frame "sonar": the head's pose and angle, one beam of bins.
cairn::lcmt_sonar_ping SonarToLcm(const SonarPing& ping) {
  cairn::lcmt_sonar_ping m{};
  m.utime = ping.utime;
  m.robot = ping.robot;
  m.frame = "sonar";
  runtime::ToLcm(ping.sensor_pose, m.sensor_position_m, m.sensor_orientation_wxyz);
  m.pan_rad = ping.pan_rad;
  m.range_min_m = ping.range_min_m;
  m.range_max_m = ping.range_max_m;
  m.sound_speed_mps = ping.sound_speed_mps;
  m.num_bins = static_cast<int32_t>(ping.bins.size());
  m.intensities = ping.bins;
  return m;
}

/// Odometry in frame "odom" (which starts at the spawn pose), child frame "base_link".
/// Covariances are left zero: the simulator does not estimate its own drift.
cairn::lcmt_odometry OdometryToLcm(const OdometryReading& r) {
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

/// IMU in frame "imu", with the configured noise variances.
cairn::lcmt_imu ImuToLcm(const ImuReading& r) {
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

/// Ground truth in frame "world", velocities in the world frame.
cairn::lcmt_pose GroundTruthToLcm(const GroundTruthReading& r) {
  cairn::lcmt_pose m = runtime::ToLcmPose(r.pose, r.utime, r.robot, "world");
  for (int i = 0; i < 3; ++i) {
    m.linear_velocity_mps[i] = r.linear_velocity_mps[i];
    m.angular_velocity_radps[i] = r.angular_velocity_radps[i];
  }
  return m;
}

cairn::lcmt_point_cloud_slice LidarToLcm(const common::LidarSlice& s) { return runtime::ToLcm(s); }
cairn::lcmt_laser_scan ScanToLcm(const common::LaserScan& s) { return runtime::ToLcm(s); }

}  // namespace

const SensorPublishers& BuiltinSensorPublishers() {
  // A new sensor kind adds its conversion above and one line here.
  static const SensorPublishers publishers = [] {
    SensorPublishers p;
    p.Add(MakeSensorPublisher(LidarSensor::kName, channels::kLidar, &LidarToLcm));
    p.Add(MakeSensorPublisher(PlanarLaserSensor::kName, channels::kScan, &ScanToLcm));
    p.Add(MakeSensorPublisher(TurretSensor::kName, channels::kTurretScan, &TurretLineToLcm));
    p.Add(MakeSensorPublisher(SonarSensor::kName, channels::kSonar, &SonarToLcm));
    p.Add(MakeSensorPublisher(OdometrySensor::kName, channels::kOdom, &OdometryToLcm));
    p.Add(MakeSensorPublisher(ImuSensor::kName, channels::kImu, &ImuToLcm));
    p.Add(MakeSensorPublisher(GroundTruthSensor::kName, channels::kPose, &GroundTruthToLcm));
    return p;
  }();
  return publishers;
}

void SensorPublishers::Add(SensorPublisher publisher) {
  if (Find(publisher.sensor) != nullptr) {
    throw std::invalid_argument("sensor '" + publisher.sensor + "' has two publishers");
  }
  publishers_.push_back(std::move(publisher));
}

const SensorPublisher* SensorPublishers::Find(const std::string& sensor) const {
  for (const SensorPublisher& p : publishers_) {
    if (p.sensor == sensor) return &p;
  }
  return nullptr;
}

}  // namespace cairn::sim
