#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/point_cloud.h"
#include "common/types.h"
#include "services/mapping/mapper_layer.h"
#include "services/mapping/pose_buffer.h"
#include "services/mapping/traversability.h"

/// @file
/// MapperInputs: decoded sensor data made ready for MapperCore. It keeps the recent ground-truth,
/// odometry and IMU samples, resolves each lidar slice's and laser scan's sensor pose per
/// pose_source (measuring a sensor's mount once when it is not configured), drops bad points,
/// and gives the robot's pose at a revolution's end. No transport: the LCM service converts
/// messages and hands them here.
///
/// Sensor poses. ground_truth: the pose the producer reported with the data, accepted only when
/// a ground-truth sample lies within max_pose_gap_s of its time. odometry: the odometry pose at
/// that time (roll and pitch from the IMU when imu_attitude is on) composed with the sensor's
/// mount, which is configured (the lidar's) or measured once against the first reported pose.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

enum class PoseSource { kGroundTruth, kOdometry };

/// "ground_truth" or "odometry".
const char* PoseSourceName(PoseSource source);
/// @throws std::invalid_argument for another name.
PoseSource PoseSourceFromName(const std::string& name);

struct MapperInputsParams {
  PoseSource pose_source{PoseSource::kGroundTruth};
  double max_pose_gap_s{0.15};  ///< a slice needs a pose sample this close to its time
  bool imu_attitude{true};      ///< odometry poses take roll and pitch from the IMU
  double max_imu_gap_s{0.25};
  /// Base-to-lidar transform for odometry poses; without it, measured from the first slice.
  std::optional<common::Pose3> lidar_mount;

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads a mount section {x_m, y_m, z_m, roll_deg, pitch_deg, yaw_deg} (every key optional, 0).
/// @throws common::ConfigError naming the file and line of a bad or unknown key.
common::Pose3 LoadMountPose(common::YamlMap& map);

/// A revolution ready for MapperCore::ProcessRevolution.
struct PreparedRevolution {
  common::LidarRevolution revolution;  ///< slices with a pose, their bad points dropped
  RobotContext robot;                  ///< the base pose at the last slice (none without one)
  double time_s{0.0};                  ///< the last slice's time
};

/// What preparing a revolution dropped.
struct RevolutionDrops {
  bool incomplete{false};  ///< slices of the revolution never arrived
  int64_t bad_points{0};   ///< not finite, or beyond the slice's max_range_m
  int64_t slices_without_pose{0};
};

class MapperInputs {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit MapperInputs(const MapperInputsParams& params);

  /// Pose samples (non-finite ones are refused: false).
  bool AddGroundTruth(int64_t utime, const common::Pose3& pose);
  bool AddOdometry(int64_t utime, const common::Pose3& pose);
  /// The IMU's attitude (its position is ignored).
  bool AddImu(int64_t utime, const common::Pose3& attitude);

  /// The robot base pose at `utime` per pose_source; nullopt without a sample near it.
  std::optional<common::Pose3> BasePose(int64_t utime) const;
  /// The world pose of `sensor` at `utime` whose producer reported `reported`, per pose_source;
  /// nullopt without a pose near that time. `sensor` keys the measured mount.
  std::optional<common::Pose3> SensorPose(const std::string& sensor, int64_t utime,
                                          const common::Pose3& reported);

  /// Resolves every slice's pose ("lidar") and drops bad points; nullopt when no slice is left.
  std::optional<PreparedRevolution> PrepareRevolution(common::LidarRevolution revolution,
                                                      RevolutionDrops* drops);
  /// Resolves a scan's pose ("scan"); nullopt without a pose near its time.
  std::optional<common::LaserScan> PrepareScan(common::LaserScan scan);
  /// Resolves a reading's sensor pose (its stream keys the mount); false without a pose near
  /// its time.
  bool PrepareReading(SensorReading* reading);

  /// Mounts measured (or configured) since the last call, by sensor: for the process's log.
  std::vector<std::pair<std::string, common::Pose3>> TakeNewMounts();
  const MapperInputsParams& params() const { return params_; }

 private:
  MapperInputsParams params_;
  PoseBuffer ground_truth_;
  PoseBuffer odometry_;
  PoseBuffer imu_;                               // orientation only
  std::map<std::string, common::Pose3> mounts_;  // base -> sensor (odometry poses)
  std::vector<std::pair<std::string, common::Pose3>> new_mounts_;
};

}  // namespace cairn::mapping
