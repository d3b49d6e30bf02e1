#include "simulator/lcm/sensor_publishers.h"

#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

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

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the fast encoding swaps bytes");

// A float as LCM writes it: big-endian, one swap.
inline void PutFloatBigEndian(float value, uint8_t* out) {
  uint32_t v;
  std::memcpy(&v, &value, sizeof(v));
  v = __builtin_bswap32(v);
  std::memcpy(out, &v, sizeof(v));
}

/// The lidar's publisher: slices with a range resolution go out as ranges (3 bytes a ray) on
/// <robot>.LIDAR_RANGES, others as points through FastPointCloudSlice on <robot>.LIDAR.
SensorPublisher LidarPublisher() {
  SensorPublisher p;
  p.sensor = LidarSensor::kName;
  p.stream = channels::kLidarRanges;
  p.publish = [](runtime::Node& node, const ReadingGroup& group) {
    const std::vector<common::LidarSlice>* slices = group.As<common::LidarSlice>();
    CAIRN_DEMAND(slices != nullptr);
    for (const common::LidarSlice& slice : *slices) {
      if (slice.grid.range_resolution_m > 0.0) {
        node.Publish(channels::ForRobot(slice.robot, channels::kLidarRanges),
                     FastLidarRanges(slice));
      } else {
        node.Publish(channels::ForRobot(slice.robot, channels::kLidar), FastPointCloudSlice(slice));
      }
    }
  };
  return p;
}

cairn::lcmt_laser_scan ScanToLcm(const common::LaserScan& s) { return runtime::ToLcm(s); }

}  // namespace

const SensorPublishers& BuiltinSensorPublishers() {
  // A new sensor kind adds its conversion above and one line here.
  static const SensorPublishers publishers = [] {
    SensorPublishers p;
    p.Add(LidarPublisher());
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

FastPointCloudSlice::FastPointCloudSlice(const common::LidarSlice& slice)
    : slice_(&slice), head_(runtime::ToLcmWithoutPoints(slice)) {}

int FastPointCloudSlice::getEncodedSize() const {
  const int64_t size = head_.getEncodedSize() + 17 * static_cast<int64_t>(slice_->points.size());
  return size <= std::numeric_limits<int32_t>::max() ? static_cast<int>(size) : -1;
}

int FastPointCloudSlice::encode(void* buf, int offset, int maxlen) const {
  const int size = getEncodedSize();
  if (size < 0 || offset < 0 || maxlen < size || !slice_->range_steps.empty()) return -1;
  // The fields up to num_points, by the generated code: the message without its points ends
  // with num_points = 0, which then gets the real count.
  const int head = head_.encode(buf, offset, maxlen);
  const std::vector<common::LidarPoint>& points = slice_->points;
  const size_t n = points.size();
  if (head < 4 || head + 17 * static_cast<int64_t>(n) != size) return -1;
  uint8_t* out = static_cast<uint8_t*>(buf) + offset + head;
  const uint32_t count = __builtin_bswap32(static_cast<uint32_t>(n));
  std::memcpy(out - 4, &count, sizeof(count));
  uint8_t* const x = out;
  uint8_t* const y = out + 4 * n;
  uint8_t* const z = out + 8 * n;
  uint8_t* const intensity = out + 12 * n;
  uint8_t* const ring = out + 16 * n;
  for (size_t i = 0; i < n; ++i) {
    const common::LidarPoint& p = points[i];
    PutFloatBigEndian(p.x_m, x + 4 * i);
    PutFloatBigEndian(p.y_m, y + 4 * i);
    PutFloatBigEndian(p.z_m, z + 4 * i);
    PutFloatBigEndian(p.intensity, intensity + 4 * i);
    ring[i] = static_cast<uint8_t>(static_cast<int8_t>(p.ring));
  }
  return size;
}

FastLidarRanges::FastLidarRanges(const common::LidarSlice& slice) : slice_(&slice) {
  if (!common::HasRangeGrid(slice)) return;  // encode() refuses it
  head_ = runtime::ToLcmRangesWithoutRays(slice);
  rays_ = static_cast<int64_t>(head_.num_columns) * head_.num_rings;
}

int FastLidarRanges::getEncodedSize() const {
  if (!common::HasRangeGrid(*slice_)) return -1;
  const int64_t size = head_.getEncodedSize() + 3 * rays_;
  return size <= std::numeric_limits<int32_t>::max() ? static_cast<int>(size) : -1;
}

int FastLidarRanges::encode(void* buf, int offset, int maxlen) const {
  const int size = getEncodedSize();
  if (size < 0 || offset < 0 || maxlen < size) return -1;
  // The fields up to num_rays by the generated code, then the real count and the arrays.
  const int head = head_.encode(buf, offset, maxlen);
  if (head < 4 || head + 3 * rays_ != size) return -1;
  uint8_t* out = static_cast<uint8_t*>(buf) + offset + head;
  const uint32_t count = __builtin_bswap32(static_cast<uint32_t>(rays_));
  std::memcpy(out - 4, &count, sizeof(count));
  uint8_t* const ranges = out;  // big-endian 16-bit steps
  uint8_t* const intensity = out + 2 * rays_;
  if (common::HasRangeImage(*slice_)) {
    // The sensor's own range image: one byte swap per range.
    const uint16_t* steps = slice_->range_steps.data();
    for (int64_t i = 0; i < rays_; ++i) {
      const uint16_t v = __builtin_bswap16(steps[i]);
      std::memcpy(ranges + 2 * i, &v, sizeof(v));
    }
    std::memcpy(intensity, slice_->range_intensity.data(), static_cast<size_t>(rays_));
    return size;
  }
  std::memset(out, 0, static_cast<size_t>(3 * rays_));
  const int rings = head_.num_rings;
  const int columns = head_.num_columns;
  const float steps_per_m = static_cast<float>(1.0 / head_.range_resolution_m);
  for (const common::LidarPoint& p : slice_->points) {
    if (p.ring < 0 || p.ring >= rings || p.column >= columns) return -1;
    const size_t ray = static_cast<size_t>(p.column) * rings + p.ring;
    const uint16_t steps = runtime::LidarRangeSteps(p, steps_per_m);
    ranges[2 * ray] = static_cast<uint8_t>(steps >> 8);
    ranges[2 * ray + 1] = static_cast<uint8_t>(steps);
    intensity[ray] = common::LidarIntensityByte(p.intensity);
  }
  return size;
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
