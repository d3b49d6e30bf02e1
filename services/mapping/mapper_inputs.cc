#include "services/mapping/mapper_inputs.h"

#include <algorithm>
#include <cmath>

#include "common/check.h"
#include "common/yaml_reader.h"

namespace cairn::mapping {
namespace {

common::Pose3 Compose(const common::Pose3& a, const common::Pose3& b) {
  common::Pose3 p;
  p.position_m = a.position_m + a.orientation * b.position_m;
  p.orientation = (a.orientation * b.orientation).normalized();
  return p;
}

common::Pose3 Inverse(const common::Pose3& a) {
  common::Pose3 p;
  p.orientation = a.orientation.conjugate();
  p.position_m = -(p.orientation * a.position_m);
  return p;
}

// A sensor point is bad input when not finite or beyond what the sensor can measure.
bool BadPoint(const common::LidarPoint& p, double max_range_m) {
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.z_m)) return true;
  if (max_range_m > 0) {
    const double r2 = double(p.x_m) * p.x_m + double(p.y_m) * p.y_m + double(p.z_m) * p.z_m;
    if (r2 > max_range_m * max_range_m * 1.0001) return true;
  }
  return false;
}

}  // namespace

const char* PoseSourceName(PoseSource source) {
  return source == PoseSource::kOdometry ? "odometry" : "ground_truth";
}

PoseSource PoseSourceFromName(const std::string& name) {
  if (name == "ground_truth") return PoseSource::kGroundTruth;
  if (name == "odometry") return PoseSource::kOdometry;
  throw std::invalid_argument("pose_source must be 'ground_truth' or 'odometry', got '" + name +
                              "'");
}

void MapperInputsParams::Validate() const {
  CAIRN_THROW_UNLESS(max_pose_gap_s > 0, "max_pose_gap_s must be positive");
  CAIRN_THROW_UNLESS(max_imu_gap_s > 0, "max_imu_gap_s must be positive");
}

common::Pose3 LoadMountPose(common::YamlMap& mount) {
  constexpr double kDeg = M_PI / 180.0;
  double x = 0, y = 0, z = 0, roll = 0, pitch = 0, yaw = 0;
  mount.Get("x_m", &x);
  mount.Get("y_m", &y);
  mount.Get("z_m", &z);
  mount.Get("roll_deg", &roll);
  mount.Get("pitch_deg", &pitch);
  mount.Get("yaw_deg", &yaw);
  mount.Finish();
  common::Pose3 pose;
  pose.position_m = {x, y, z};
  pose.orientation = Eigen::AngleAxisd(yaw * kDeg, Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(pitch * kDeg, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(roll * kDeg, Eigen::Vector3d::UnitX());
  return pose;
}

MapperInputs::MapperInputs(const MapperInputsParams& params)
    : params_((params.Validate(), params)) {}

bool MapperInputs::AddGroundTruth(int64_t utime, const common::Pose3& pose) {
  return ground_truth_.Add(utime, pose);
}

bool MapperInputs::AddOdometry(int64_t utime, const common::Pose3& pose) {
  return odometry_.Add(utime, pose);
}

bool MapperInputs::AddImu(int64_t utime, const common::Pose3& attitude) {
  return imu_.Add(utime, attitude);
}

std::optional<common::Pose3> MapperInputs::BasePose(int64_t utime) const {
  if (params_.pose_source == PoseSource::kGroundTruth) {
    return ground_truth_.At(utime, params_.max_pose_gap_s);
  }
  auto base = odometry_.At(utime, params_.max_pose_gap_s);
  if (!base) return std::nullopt;
  if (params_.imu_attitude) {
    // Heading and position from odometry, roll and pitch from the IMU.
    if (auto imu = imu_.At(utime, params_.max_imu_gap_s)) {
      const double dyaw = base->yaw_rad() - imu->yaw_rad();
      base->orientation =
          (Eigen::AngleAxisd(dyaw, Eigen::Vector3d::UnitZ()) * imu->orientation).normalized();
    }
  }
  return base;
}

std::optional<common::Pose3> MapperInputs::SensorPose(const std::string& sensor, int64_t utime,
                                                      const common::Pose3& reported) {
  if (params_.pose_source == PoseSource::kGroundTruth) {
    if (!ground_truth_.At(utime, params_.max_pose_gap_s)) return std::nullopt;
    return reported;
  }
  auto base = BasePose(utime);
  if (!base) return std::nullopt;
  auto it = mounts_.find(sensor);
  if (it == mounts_.end()) {
    // The mount: configured for the lidar, else measured once against the producer's pose.
    const common::Pose3 mount = (sensor == "lidar" && params_.lidar_mount)
                                    ? *params_.lidar_mount
                                    : Compose(Inverse(*base), reported);
    it = mounts_.emplace(sensor, mount).first;
    new_mounts_.emplace_back(sensor, mount);
  }
  return Compose(*base, it->second);
}

std::optional<PreparedRevolution> MapperInputs::PrepareRevolution(
    common::LidarRevolution revolution, RevolutionDrops* drops) {
  *drops = RevolutionDrops();
  drops->incomplete = !revolution.complete();
  // Resolve each slice's sensor pose; drop bad points (not finite, beyond the sensor's range).
  std::vector<common::LidarSlice> kept;
  for (auto& slice : revolution.slices) {
    auto pose = SensorPose("lidar", slice.utime, slice.sensor_pose);
    if (!pose) {
      ++drops->slices_without_pose;
      continue;
    }
    slice.sensor_pose = *pose;
    const size_t before = slice.points.size();
    slice.points.erase(
        std::remove_if(slice.points.begin(), slice.points.end(),
                       [&](const common::LidarPoint& p) { return BadPoint(p, slice.max_range_m); }),
        slice.points.end());
    drops->bad_points += static_cast<int64_t>(before - slice.points.size());
    kept.push_back(std::move(slice));
  }
  if (kept.empty()) return std::nullopt;
  revolution.slices = std::move(kept);
  PreparedRevolution out;
  const int64_t utime = revolution.slices.back().utime;
  out.time_s = utime * 1e-6;
  if (auto base = BasePose(utime)) {
    out.robot.xy_m = common::Vector2(base->position_m.x(), base->position_m.y());
    out.robot.yaw_rad = base->yaw_rad();
    out.robot.pitch_rad = base->pitch_rad();
    if (auto imu = imu_.At(utime, params_.max_imu_gap_s)) out.robot.pitch_rad = imu->pitch_rad();
  }
  out.revolution = std::move(revolution);
  return out;
}

std::optional<common::LaserScan> MapperInputs::PrepareScan(common::LaserScan scan) {
  auto pose = SensorPose("scan", scan.utime, scan.sensor_pose);
  if (!pose) return std::nullopt;
  scan.sensor_pose = *pose;
  return scan;
}

bool MapperInputs::PrepareReading(SensorReading* reading) {
  auto pose = SensorPose(reading->stream, reading->utime, reading->sensor_pose);
  if (!pose) return false;
  reading->sensor_pose = *pose;
  return true;
}

std::vector<std::pair<std::string, common::Pose3>> MapperInputs::TakeNewMounts() {
  std::vector<std::pair<std::string, common::Pose3>> out;
  out.swap(new_mounts_);
  return out;
}

}  // namespace cairn::mapping
