#include "services/runtime/conversions.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "services/runtime/tiler.h"

namespace cairn::runtime {

using common::InvalidArgumentError;
using common::Result;

void ToLcm(const common::Pose3& pose, double position_m[3], double orientation_wxyz[4]) {
  for (int i = 0; i < 3; ++i) position_m[i] = pose.position_m[i];
  orientation_wxyz[0] = pose.orientation.w();
  orientation_wxyz[1] = pose.orientation.x();
  orientation_wxyz[2] = pose.orientation.y();
  orientation_wxyz[3] = pose.orientation.z();
}

Result<common::Pose3> PoseFromArrays(const double position_m[3], const double orientation_wxyz[4]) {
  common::Pose3 pose;
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(position_m[i])) return InvalidArgumentError("pose position is not finite");
    pose.position_m[i] = position_m[i];
  }
  const common::Quaternion q(orientation_wxyz[0], orientation_wxyz[1], orientation_wxyz[2],
                             orientation_wxyz[3]);
  if (!q.coeffs().allFinite()) return InvalidArgumentError("pose orientation is not finite");
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    return InvalidArgumentError("pose orientation is not a unit quaternion (norm " +
                                std::to_string(norm) + ")");
  }
  pose.orientation = q.normalized();
  return pose;
}

namespace {

// The fields a lidar slice's two messages share (points and ranges), both ways.
template <typename Msg>
void SliceHeaderToLcm(const common::LidarSlice& slice, Msg* m) {
  m->utime = slice.utime;
  m->robot = slice.robot;
  m->frame = "lidar";
  m->revolution = slice.revolution;
  m->slice_index = slice.slice_index;
  m->slice_count = slice.slice_count;
  m->azimuth_start_rad = slice.azimuth_start_rad;
  m->max_range_m = slice.max_range_m;
  ToLcm(slice.sensor_pose, m->sensor_position_m, m->sensor_orientation_wxyz);
}

// The shared fields of a slice message, checked (slice index within its count, a valid pose);
// `what` names the message in the error.
template <typename Msg>
Result<common::LidarSlice> SliceHeaderFromLcm(const Msg& m, const char* what) {
  if (m.slice_count <= 0 || m.slice_index < 0 || m.slice_index >= m.slice_count) {
    return InvalidArgumentError(std::string(what) + " index " + std::to_string(m.slice_index) +
                                " of " + std::to_string(m.slice_count) + " is out of range");
  }
  auto pose = PoseFromArrays(m.sensor_position_m, m.sensor_orientation_wxyz);
  if (!pose.ok()) return InvalidArgumentError(std::string(what) + ": " + pose.status().message());
  common::LidarSlice s;
  s.utime = m.utime;
  s.robot = m.robot;
  s.revolution = m.revolution;
  s.slice_index = m.slice_index;
  s.slice_count = m.slice_count;
  s.azimuth_start_rad = m.azimuth_start_rad;
  s.max_range_m = m.max_range_m;
  s.sensor_pose = *pose;
  return s;
}

}  // namespace

cairn::lcmt_point_cloud_slice ToLcmWithoutPoints(const common::LidarSlice& slice) {
  cairn::lcmt_point_cloud_slice m{};
  SliceHeaderToLcm(slice, &m);
  m.azimuth_end_rad = slice.azimuth_end_rad;
  m.num_points = 0;
  return m;
}

cairn::lcmt_point_cloud_slice ToLcm(const common::LidarSlice& slice) {
  if (common::HasRangeImage(slice)) {
    common::LidarSlice points = slice;
    common::ExpandRangeImage(&points);
    return ToLcm(points);
  }
  cairn::lcmt_point_cloud_slice m = ToLcmWithoutPoints(slice);
  const size_t n = slice.points.size();
  m.num_points = static_cast<int32_t>(n);
  m.x_m.resize(n);
  m.y_m.resize(n);
  m.z_m.resize(n);
  m.intensity.resize(n);
  m.ring.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const auto& p = slice.points[i];
    m.x_m[i] = p.x_m;
    m.y_m[i] = p.y_m;
    m.z_m[i] = p.z_m;
    m.intensity[i] = p.intensity;
    m.ring[i] = static_cast<int8_t>(p.ring);
  }
  return m;
}

Result<common::LidarSlice> FromLcm(const cairn::lcmt_point_cloud_slice& m) {
  const size_t n = static_cast<size_t>(std::max(0, m.num_points));
  if (m.x_m.size() != n || m.y_m.size() != n || m.z_m.size() != n || m.intensity.size() != n ||
      m.ring.size() != n) {
    return InvalidArgumentError("lidar slice arrays disagree with num_points");
  }
  Result<common::LidarSlice> header = SliceHeaderFromLcm(m, "lidar slice");
  if (!header.ok()) return header;
  common::LidarSlice s = std::move(header.value());
  s.azimuth_end_rad = m.azimuth_end_rad;
  s.points.resize(n);
  for (size_t i = 0; i < n; ++i) {
    s.points[i] = {m.x_m[i], m.y_m[i], m.z_m[i], m.intensity[i], m.ring[i]};
  }
  return s;
}

cairn::lcmt_lidar_ranges ToLcmRangesWithoutRays(const common::LidarSlice& slice) {
  const common::LidarGrid& grid = slice.grid;
  if (!common::HasRangeGrid(slice)) {
    throw std::invalid_argument("ToLcmRanges: the slice has no grid of ranges");
  }
  cairn::lcmt_lidar_ranges m{};
  SliceHeaderToLcm(slice, &m);
  m.azimuth_step_rad = grid.azimuth_step_rad;
  m.range_resolution_m = grid.range_resolution_m;
  const int rings = static_cast<int>(grid.ring_elevation_rad.size());
  m.num_rings = static_cast<int16_t>(rings);
  m.ring_elevation_rad = grid.ring_elevation_rad;
  m.num_columns = grid.columns;
  m.num_rays = 0;
  return m;
}

cairn::lcmt_lidar_ranges ToLcmRanges(const common::LidarSlice& slice) {
  cairn::lcmt_lidar_ranges m = ToLcmRangesWithoutRays(slice);
  const common::LidarGrid& grid = slice.grid;
  const int rings = m.num_rings;
  m.num_rays = grid.columns * rings;
  if (common::HasRangeImage(slice)) {
    m.ranges.resize(slice.range_steps.size());
    std::memcpy(m.ranges.data(), slice.range_steps.data(), m.ranges.size() * sizeof(int16_t));
    m.intensity = slice.range_intensity;
    return m;
  }
  m.ranges.assign(static_cast<size_t>(m.num_rays), 0);
  m.intensity.assign(static_cast<size_t>(m.num_rays), 0);
  const float steps_per_m = static_cast<float>(1.0 / grid.range_resolution_m);
  for (const common::LidarPoint& p : slice.points) {
    if (p.ring < 0 || p.ring >= rings || p.column >= grid.columns) {
      throw std::invalid_argument("ToLcmRanges: a point lies outside the slice's grid");
    }
    const size_t ray = static_cast<size_t>(p.column) * rings + p.ring;
    m.ranges[ray] = static_cast<int16_t>(LidarRangeSteps(p, steps_per_m));
    m.intensity[ray] = common::LidarIntensityByte(p.intensity);
  }
  return m;
}

Result<common::LidarSlice> FromLcm(const cairn::lcmt_lidar_ranges& m) {
  Result<common::LidarSlice> header = SliceHeaderFromLcm(m, "lidar ranges slice");
  if (!header.ok()) return header;
  if (m.num_rings < 1 || m.num_rings > 127 || m.num_columns < 1 || m.num_columns > 65535 ||
      static_cast<int64_t>(m.num_rings) * m.num_columns != m.num_rays ||
      m.ring_elevation_rad.size() != static_cast<size_t>(m.num_rings) ||
      m.ranges.size() != static_cast<size_t>(m.num_rays) ||
      m.intensity.size() != static_cast<size_t>(m.num_rays)) {
    return InvalidArgumentError("lidar ranges: " + std::to_string(m.num_rays) + " rays for " +
                                std::to_string(m.num_rings) + " rings (1 to 127) by " +
                                std::to_string(m.num_columns) +
                                " columns, or arrays that disagree");
  }
  if (!std::isfinite(m.range_resolution_m) || m.range_resolution_m <= 0.0 ||
      m.range_resolution_m > 1.0) {
    return InvalidArgumentError("lidar ranges: range resolution " +
                                std::to_string(m.range_resolution_m) + " m is not in (0, 1]");
  }
  if (!std::isfinite(m.azimuth_start_rad) || !std::isfinite(m.azimuth_step_rad) ||
      std::abs(m.azimuth_start_rad) > 8.0 * M_PI ||
      std::abs(m.azimuth_step_rad) * m.num_columns > 2.0 * M_PI + 1e-6) {
    return InvalidArgumentError(
        "lidar ranges: the columns' azimuths are not finite or exceed a turn");
  }
  for (const float elevation : m.ring_elevation_rad) {
    if (!(std::abs(elevation) <= static_cast<float>(M_PI / 2.0))) {
      return InvalidArgumentError("lidar ranges: a ring elevation is not in [-pi/2, pi/2]");
    }
  }
  common::LidarSlice s = std::move(header.value());
  s.azimuth_end_rad = m.azimuth_start_rad + m.azimuth_step_rad * m.num_columns;
  s.grid.ring_elevation_rad = m.ring_elevation_rad;
  s.grid.azimuth_step_rad = m.azimuth_step_rad;
  s.grid.columns = m.num_columns;
  s.grid.range_resolution_m = m.range_resolution_m;
  s.range_steps.resize(m.ranges.size());
  std::memcpy(s.range_steps.data(), m.ranges.data(), m.ranges.size() * sizeof(int16_t));
  s.range_intensity = m.intensity;
  common::ExpandRangeImage(&s);
  return s;
}

cairn::lcmt_laser_scan ToLcm(const common::LaserScan& scan) {
  cairn::lcmt_laser_scan m{};
  m.utime = scan.utime;
  m.robot = scan.robot;
  m.frame = "laser";
  ToLcm(scan.sensor_pose, m.sensor_position_m, m.sensor_orientation_wxyz);
  m.turret_angle_rad = 0.0;
  m.angle_min_rad = static_cast<float>(scan.angle_min_rad);
  m.angle_increment_rad = static_cast<float>(scan.angle_increment_rad);
  m.range_min_m = static_cast<float>(scan.range_min_m);
  m.range_max_m = static_cast<float>(scan.range_max_m);
  m.scan_time_s = 0.f;
  m.num_ranges = static_cast<int32_t>(scan.ranges_m.size());
  m.ranges_m = scan.ranges_m;
  m.num_intensities = static_cast<int32_t>(scan.intensities.size());
  m.intensities = scan.intensities;
  return m;
}

Result<common::LaserScan> FromLcm(const cairn::lcmt_laser_scan& m) {
  if (m.num_ranges < 0 || m.ranges_m.size() != static_cast<size_t>(m.num_ranges) ||
      m.num_intensities < 0 || m.intensities.size() != static_cast<size_t>(m.num_intensities)) {
    return InvalidArgumentError("laser scan arrays disagree with their counts");
  }
  if (!std::isfinite(m.angle_min_rad) || !std::isfinite(m.angle_increment_rad) ||
      !std::isfinite(m.range_max_m) || m.range_max_m <= 0.f) {
    return InvalidArgumentError("laser scan geometry is not finite");
  }
  auto pose = PoseFromArrays(m.sensor_position_m, m.sensor_orientation_wxyz);
  if (!pose.ok()) return InvalidArgumentError("laser scan: " + pose.status().message());
  common::LaserScan s;
  s.utime = m.utime;
  s.robot = m.robot;
  s.sensor_pose = *pose;
  // Float fields widen to double exactly, so the round trip is exact.
  s.angle_min_rad = m.angle_min_rad;
  s.angle_increment_rad = m.angle_increment_rad;
  s.range_min_m = m.range_min_m;
  s.range_max_m = m.range_max_m;
  s.ranges_m = m.ranges_m;
  s.intensities = m.intensities;
  return s;
}

cairn::lcmt_robot_profile ToLcm(const common::RobotProfile& p) {
  cairn::lcmt_robot_profile m{};
  m.name = p.name;
  m.content_hash = p.ContentHash();
  switch (p.drive) {
    case common::DriveKind::kDifferential:
      m.drive = cairn::lcmt_robot_profile::DRIVE_DIFFERENTIAL;
      break;
    case common::DriveKind::kSkidSteer:
      m.drive = cairn::lcmt_robot_profile::DRIVE_SKID_STEER;
      break;
    case common::DriveKind::kAuv:
      m.drive = cairn::lcmt_robot_profile::DRIVE_AUV;
      break;
  }
  m.num_footprint = static_cast<int32_t>(p.footprint_m.size());
  for (const auto& v : p.footprint_m) {
    m.footprint_x_m.push_back(v.x());
    m.footprint_y_m.push_back(v.y());
  }
  m.max_slope_up_rad = p.max_slope_up_rad;
  m.max_slope_down_rad = p.max_slope_down_rad;
  m.max_step_up_m = p.max_step_up_m;
  m.max_step_down_m = p.max_step_down_m;
  m.max_ditch_width_m = p.max_ditch_width_m;
  m.ground_clearance_m = p.ground_clearance_m;
  m.max_roughness_m = p.max_roughness_m;
  m.max_vel_x_mps = p.max_vel_x_mps;
  m.min_vel_x_mps = p.min_vel_x_mps;
  m.max_vel_theta_radps = p.max_vel_theta_radps;
  m.acc_lim_x_mps2 = p.acc_lim_x_mps2;
  m.acc_lim_theta_radps2 = p.acc_lim_theta_radps2;
  m.num_sensors = static_cast<int32_t>(p.sensors.size());
  m.sensors = p.sensors;
  return m;
}

Result<common::RobotProfile> FromLcm(const cairn::lcmt_robot_profile& m) {
  if (m.num_footprint < 0 || m.footprint_x_m.size() != static_cast<size_t>(m.num_footprint) ||
      m.footprint_y_m.size() != static_cast<size_t>(m.num_footprint) || m.num_sensors < 0 ||
      m.sensors.size() != static_cast<size_t>(m.num_sensors)) {
    return InvalidArgumentError("robot profile arrays disagree with their counts");
  }
  common::RobotProfile p;
  p.name = m.name;
  switch (m.drive) {
    case cairn::lcmt_robot_profile::DRIVE_DIFFERENTIAL:
      p.drive = common::DriveKind::kDifferential;
      break;
    case cairn::lcmt_robot_profile::DRIVE_SKID_STEER:
      p.drive = common::DriveKind::kSkidSteer;
      break;
    case cairn::lcmt_robot_profile::DRIVE_AUV:
      p.drive = common::DriveKind::kAuv;
      break;
    default:
      return InvalidArgumentError("robot profile has unknown drive " + std::to_string(m.drive));
  }
  for (int i = 0; i < m.num_footprint; ++i)
    p.footprint_m.emplace_back(m.footprint_x_m[i], m.footprint_y_m[i]);
  p.max_slope_up_rad = m.max_slope_up_rad;
  p.max_slope_down_rad = m.max_slope_down_rad;
  p.max_step_up_m = m.max_step_up_m;
  p.max_step_down_m = m.max_step_down_m;
  p.max_ditch_width_m = m.max_ditch_width_m;
  p.ground_clearance_m = m.ground_clearance_m;
  p.max_roughness_m = m.max_roughness_m;
  p.max_vel_x_mps = m.max_vel_x_mps;
  p.min_vel_x_mps = m.min_vel_x_mps;
  p.max_vel_theta_radps = m.max_vel_theta_radps;
  p.acc_lim_x_mps2 = m.acc_lim_x_mps2;
  p.acc_lim_theta_radps2 = m.acc_lim_theta_radps2;
  p.sensors = m.sensors;
  try {
    p.Validate();
  } catch (const std::invalid_argument& e) {
    return InvalidArgumentError(e.what());
  }
  return p;
}

cairn::lcmt_pose ToLcmPose(const common::Pose3& pose, int64_t utime, const std::string& robot,
                           const std::string& frame) {
  cairn::lcmt_pose m{};
  m.utime = utime;
  m.robot = robot;
  m.frame = frame;
  ToLcm(pose, m.position_m, m.orientation_wxyz);
  for (int i = 0; i < 3; ++i) m.linear_velocity_mps[i] = m.angular_velocity_radps[i] = 0.0;
  return m;
}

Result<common::Pose3> FromLcm(const cairn::lcmt_pose& m) {
  return PoseFromArrays(m.position_m, m.orientation_wxyz);
}

Result<common::Pose3> FromLcm(const cairn::lcmt_odometry& m) {
  return PoseFromArrays(m.position_m, m.orientation_wxyz);
}

static_assert(cairn::lcmt_obstacle::MAX_PARTS == common::kMaxObstacleParts,
              "the message's part limit is the registry's");

namespace {

// What an obstacle and a terrace's part share on the bus: kind, centroid, outline, size and
// verdicts (`In` is common::Obstacle or ObstaclePart, `Msg` lcmt_obstacle or lcmt_obstacle_part).
template <typename In, typename Msg>
void SharedToLcm(const In& o, Msg* m) {
  m->kind = static_cast<int8_t>(o.kind);
  m->centroid_m[0] = o.centroid_m.x();
  m->centroid_m[1] = o.centroid_m.y();
  m->num_outline = static_cast<int32_t>(o.outline_m.size());
  for (const auto& v : o.outline_m) {
    m->outline_x_m.push_back(v.x());
    m->outline_y_m.push_back(v.y());
  }
  m->slope_rad = o.slope_rad;
  m->height_m = o.height_m;
  m->width_m = o.width_m;
  m->length_m = o.length_m;
  m->area_m2 = o.area_m2;
  m->num_cells = o.num_cells;
  m->num_verdicts = static_cast<int32_t>(o.verdicts.size());
  for (const auto& v : o.verdicts) {
    cairn::lcmt_obstacle_verdict mv{};
    mv.profile = v.profile;
    mv.profile_hash = v.profile_hash;
    mv.crossable = v.crossable;
    mv.reason = v.reason;
    m->verdicts.push_back(mv);
  }
}

// The inverse; false when an array disagrees with its count.
template <typename Msg, typename Out>
bool SharedFromLcm(const Msg& m, Out* o) {
  if (m.num_outline < 0 || m.outline_x_m.size() != static_cast<size_t>(m.num_outline) ||
      m.outline_y_m.size() != static_cast<size_t>(m.num_outline) || m.num_verdicts < 0 ||
      m.verdicts.size() != static_cast<size_t>(m.num_verdicts)) {
    return false;
  }
  o->kind = static_cast<common::ObstacleKind>(m.kind);
  o->centroid_m = {m.centroid_m[0], m.centroid_m[1]};
  for (int i = 0; i < m.num_outline; ++i) {
    o->outline_m.emplace_back(m.outline_x_m[i], m.outline_y_m[i]);
  }
  o->slope_rad = m.slope_rad;
  o->height_m = m.height_m;
  o->width_m = m.width_m;
  o->length_m = m.length_m;
  o->area_m2 = m.area_m2;
  o->num_cells = m.num_cells;
  for (const auto& mv : m.verdicts) {
    o->verdicts.push_back({mv.profile, mv.profile_hash, mv.crossable != 0, mv.reason});
  }
  return true;
}

Result<common::ObstaclePart> PartFromLcm(const cairn::lcmt_obstacle_part& m) {
  if (m.kind != cairn::lcmt_obstacle::KIND_RAMP && m.kind != cairn::lcmt_obstacle::KIND_STEP_UP) {
    return InvalidArgumentError("obstacle part has kind " + std::to_string(m.kind) +
                                " (a part is a ramp or a face: kinds 1 and 2)");
  }
  common::ObstaclePart p;
  if (!SharedFromLcm(m, &p)) {
    return InvalidArgumentError("obstacle part arrays disagree with their counts");
  }
  p.heading_in_rad = m.heading_in_rad;
  return p;
}

}  // namespace

cairn::lcmt_obstacle ToLcm(const common::Obstacle& o) {
  cairn::lcmt_obstacle m{};
  m.id = o.id;
  SharedToLcm(o, &m);
  m.depth_m = o.depth_m;
  m.downhill_heading_rad = o.downhill_heading_rad;
  m.num_parts = static_cast<int32_t>(o.parts.size());
  for (const auto& p : o.parts) {
    cairn::lcmt_obstacle_part mp{};
    SharedToLcm(p, &mp);
    mp.heading_in_rad = p.heading_in_rad;
    m.parts.push_back(std::move(mp));
  }
  return m;
}

Result<common::Obstacle> FromLcm(const cairn::lcmt_obstacle& m) {
  if (m.kind < cairn::lcmt_obstacle::KIND_RAMP || m.kind > cairn::lcmt_obstacle::KIND_TERRACE) {
    return InvalidArgumentError("obstacle has unknown kind " + std::to_string(m.kind));
  }
  if (m.num_parts < 0 || m.parts.size() != static_cast<size_t>(m.num_parts) ||
      m.num_parts > cairn::lcmt_obstacle::MAX_PARTS ||
      (m.num_parts > 0) != (m.kind == cairn::lcmt_obstacle::KIND_TERRACE)) {
    return InvalidArgumentError(
        "obstacle of kind " + std::to_string(m.kind) + " has " + std::to_string(m.parts.size()) +
        " parts (num_parts " + std::to_string(m.num_parts) + "; a terrace has 1 to " +
        std::to_string(cairn::lcmt_obstacle::MAX_PARTS) + ", every other kind none)");
  }
  common::Obstacle o;
  o.id = m.id;
  if (!SharedFromLcm(m, &o))
    return InvalidArgumentError("obstacle arrays disagree with their counts");
  o.depth_m = m.depth_m;
  o.downhill_heading_rad = m.downhill_heading_rad;
  for (const auto& mp : m.parts) {
    auto p = PartFromLcm(mp);
    if (!p.ok()) return p.status();
    o.parts.push_back(std::move(p).value());
  }
  return o;
}

cairn::lcmt_obstacle_registry ToLcm(const common::ObstacleRegistry& r, int64_t utime,
                                    const std::string& robot, const std::string& map_name) {
  cairn::lcmt_obstacle_registry m{};
  m.utime = utime;
  m.robot = robot;
  m.map_name = map_name;
  m.map_version = r.map_version;
  m.num_obstacles = static_cast<int32_t>(r.obstacles.size());
  for (const auto& o : r.obstacles) m.obstacles.push_back(ToLcm(o));
  return m;
}

Result<common::ObstacleRegistry> FromLcm(const cairn::lcmt_obstacle_registry& m) {
  if (m.num_obstacles < 0 || m.obstacles.size() != static_cast<size_t>(m.num_obstacles)) {
    return InvalidArgumentError("obstacle registry size disagrees with num_obstacles");
  }
  common::ObstacleRegistry r;
  r.map_version = m.map_version;
  for (const auto& mo : m.obstacles) {
    auto o = FromLcm(mo);
    if (!o.ok()) return o.status();
    r.obstacles.push_back(std::move(o.value()));
  }
  return r;
}

bool FitRegistryToMessageLimit(cairn::lcmt_obstacle_registry* msg) {
  if (msg->getEncodedSize() <= static_cast<int>(kMaxMessageBytes)) return false;
  for (auto& o : msg->obstacles) {
    o.num_outline = 0;
    o.outline_x_m.clear();
    o.outline_y_m.clear();
    for (auto& p : o.parts) {
      p.num_outline = 0;
      p.outline_x_m.clear();
      p.outline_y_m.clear();
    }
  }
  return true;
}

}  // namespace cairn::runtime
