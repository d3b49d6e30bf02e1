#include "simulator/sensors/turret_sensor.h"

#include <algorithm>
#include <cmath>

#include "common/check.h"
#include "simulator/sensor_registry.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include <Eigen/Geometry>

namespace cairn::sim {
void TurretParams::Validate() const {
  CAIRN_THROW_UNLESS(FinitePositive(fan_fov_deg) && fan_fov_deg <= 360.0,
                     "turret.fan_fov_deg must be in (0, 360]");
  CAIRN_THROW_UNLESS(fan_beams >= 2 && fan_beams <= 100000, "turret.fan_beams must be >= 2");
  CAIRN_THROW_UNLESS(FinitePositive(max_range_m), "turret.max_range_m must be > 0");
  CAIRN_THROW_UNLESS(FiniteNonNegative(min_range_m) && min_range_m < max_range_m,
                     "turret.min_range_m must be in [0, max_range_m)");
  CAIRN_THROW_UNLESS(FinitePositive(line_rate_hz), "turret.line_rate_hz must be > 0");
  CAIRN_THROW_UNLESS(FinitePositive(pan_step_deg), "turret.pan_step_deg must be > 0");
  CAIRN_THROW_UNLESS(
      FinitePositive(pan_range_deg) && pan_range_deg <= 360.0 && pan_range_deg >= pan_step_deg,
      "turret.pan_range_deg must be in [pan_step_deg, 360]");
  CAIRN_THROW_UNLESS(FiniteNonNegative(range_noise_sigma_m),
                     "turret.range_noise_sigma_m must be >= 0");
}

TurretParams LoadTurretParams(common::YamlMap& map, const TurretParams& defaults) {
  TurretParams p = defaults;
  map.Get("fan_fov_deg", &p.fan_fov_deg);
  map.Get("fan_beams", &p.fan_beams);
  map.Get("max_range_m", &p.max_range_m);
  map.Get("min_range_m", &p.min_range_m);
  map.Get("line_rate_hz", &p.line_rate_hz);
  map.Get("pan_step_deg", &p.pan_step_deg);
  map.Get("pan_range_deg", &p.pan_range_deg);
  map.Get("range_noise_sigma_m", &p.range_noise_sigma_m);
  map.Get("mount_site", &p.mount_site);
  map.Get("on_request", &p.on_request);
  FinishSensorParams(map, p);
  return p;
}

Eigen::Matrix3d TurretLineRotation(double pan_rad) {
  const double c = std::cos(pan_rad), s = std::sin(pan_rad);
  Eigen::Matrix3d r;
  // Columns: line x (up), line y (pan direction), line z = x cross y.
  r << 0.0, c, -s,  //
      0.0, s, c,    //
      1.0, 0.0, 0.0;
  return r;
}

TurretSensor::TurretSensor(const TurretParams& params, const SensorContext& context)
    : params_(params),
      pattern_(BuildFanPattern(params.fan_fov_deg, params.fan_beams)),
      robot_(context.robot),
      site_(context.RequireSite(params.mount_site)),
      pan_steps_(
          std::max(1, static_cast<int>(std::lround(params.pan_range_deg / params.pan_step_deg)))),
      hits_(pattern_.directions.size()),
      noise_(context.Noise()) {
  schedule_.rate_hz = params.line_rate_hz;
}

common::Status TurretSensor::Trigger(double now_s) {
  if (!params_.on_request) return common::Status::Ok();
  // The first line comes at the first line time after now_s, however long it was idle.
  schedule_.SkipTo(now_s);
  sweep_step_ = 0;
  return common::Status::Ok();
}

void TurretSensor::Produce(const SensorFrame& frame, SimOutputs* out) {
  schedule_.Advance(frame.now_s);
  const TurretParams& p = params_;
  int64_t line = 0;
  int step = 0;
  if (p.on_request) {
    if (sweep_step_ < 0) return;  // idle (not due)
    line = lines_++;
    step = sweep_step_++;
    if (sweep_step_ >= pan_steps_) sweep_step_ = -1;
  } else {
    line = schedule_.count - 1;
    step = static_cast<int>(line % pan_steps_);
  }
  const double pan = step * p.pan_step_deg * M_PI / 180.0;
  const common::Pose3 mount = SitePose(frame.data, site_);
  common::Pose3 sensor;
  sensor.position_m = mount.position_m;
  sensor.orientation =
      (mount.orientation * common::Quaternion(TurretLineRotation(pan))).normalized();
  frame.CastAll(sensor, pattern_, p.max_range_m, &hits_);
  TurretLine out_line;
  out_line.pan_rad = pan;
  out_line.line = line;
  out_line.line_period_s = 1.0 / p.line_rate_hz;
  common::LaserScan& scan = out_line.scan;
  scan.utime = frame.utime;
  scan.robot = robot_;
  scan.sensor_pose = sensor;
  FanAngles(p.fan_fov_deg, p.fan_beams, &scan.angle_min_rad, &scan.angle_increment_rad);
  scan.range_min_m = p.min_range_m;
  scan.range_max_m = p.max_range_m;
  const uint64_t base = static_cast<uint64_t>(line) * p.fan_beams;
  FillScanRanges(hits_, p.range_noise_sigma_m, noise_, base, *frame.rays, &scan);
  out->Add(kName, std::move(out_line));
}

}  // namespace cairn::sim
