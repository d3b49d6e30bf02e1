#include "simulator/sensors/sonar_sensor.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/check.h"
#include "simulator/sensor_registry.h"

namespace cairn::sim {

namespace {
constexpr double kDeg = M_PI / 180.0;
}  // namespace

void SonarParams::Validate() const {
  CAIRN_THROW_UNLESS(mode == "default" || mode == "faithful",
                     "sonar.mode must be default or faithful, got '" << mode << "'");
  CAIRN_THROW_UNLESS(FinitePositive(sound_speed_mps), "sonar.sound_speed_mps must be > 0");
  CAIRN_THROW_UNLESS(FiniteNonNegative(ping_overhead_s), "sonar.ping_overhead_s must be >= 0");
  CAIRN_THROW_UNLESS(FiniteNonNegative(intensity_noise_sigma),
                     "sonar.intensity_noise_sigma must be >= 0");
  Fan().Validate();
  Sweep().Validate();
}

SonarFanParams SonarParams::Fan() const {
  SonarFanParams f;
  f.rays = rays;
  f.half_aperture_rad = half_aperture_deg * kDeg;
  f.range_min_m = range_min_m;
  f.range_max_m = range_max_m;
  f.bin_m = bin_m;
  f.model = faithful() ? SonarEchoModel::kFaithful : SonarEchoModel::kGeometric;
  return f;
}

SonarSweepParams SonarParams::Sweep() const {
  SonarSweepParams s;
  s.limit_rad = sector_deg * kDeg;
  s.step_rad = step_rad;
  s.start_rad = start_deg * kDeg;
  s.continuous = continuous;
  return s;
}

double SonarParams::PingPeriodS() const {
  return PingTimeS(range_max_m, sound_speed_mps, true) + ping_overhead_s;
}

SonarParams LoadSonarParams(common::YamlMap& map, const SonarParams& defaults) {
  SonarParams p = defaults;
  map.Get("mode", &p.mode);
  map.Get("rays", &p.rays);
  map.Get("half_aperture_deg", &p.half_aperture_deg);
  map.Get("range_min_m", &p.range_min_m);
  map.Get("range_max_m", &p.range_max_m);
  map.Get("bin_m", &p.bin_m);
  map.Get("sector_deg", &p.sector_deg);
  map.Get("step_rad", &p.step_rad);
  map.Get("start_deg", &p.start_deg);
  map.Get("continuous", &p.continuous);
  map.Get("sound_speed_mps", &p.sound_speed_mps);
  map.Get("ping_overhead_s", &p.ping_overhead_s);
  map.Get("intensity_noise_sigma", &p.intensity_noise_sigma);
  map.Get("mount_site", &p.mount_site);
  FinishSensorParams(map, p);
  return p;
}

RayPattern BuildSonarFanPattern(const SonarFanParams& fan) {
  RayPattern pattern;
  for (int i = 0; i < fan.rays; ++i) {
    const double e = fan.RayElevationRad(i);
    pattern.directions.emplace_back(std::cos(e), 0.0, std::sin(e));
  }
  pattern.warm_stride = 1;
  pattern.BuildGroups(64);
  return pattern;
}

SonarSensor::SonarSensor(const SonarParams& params, const SensorContext& context)
    : params_((params.Validate(), params)),
      fan_(params.Fan()),
      pattern_(BuildSonarFanPattern(fan_)),
      sweep_(params.Sweep()),
      robot_(context.robot),
      site_(context.RequireSite(params.mount_site)),
      hits_(pattern_.directions.size()),
      ranges_(pattern_.directions.size()),
      noise_(context.Noise()) {
  schedule_.rate_hz = 1.0 / params.PingPeriodS();
}

void SonarSensor::Produce(const SensorFrame& frame, SimOutputs* out) {
  schedule_.Advance(frame.now_s);
  const double pan = sweep_.angle_rad();
  const common::Pose3 mount = SitePose(frame.data, site_);
  common::Pose3 head;
  head.position_m = mount.position_m;
  head.orientation =
      (mount.orientation * common::Quaternion(Eigen::AngleAxisd(pan, Eigen::Vector3d::UnitZ())))
          .normalized();
  frame.CastAll(head, pattern_, params_.range_max_m, &hits_);
  for (size_t i = 0; i < hits_.size(); ++i) {
    ranges_[i] = hits_[i].geom >= 0 ? hits_[i].range_m : std::numeric_limits<double>::infinity();
  }
  SonarPing ping;
  ping.utime = frame.utime;
  ping.robot = robot_;
  ping.sensor_pose = head;
  ping.range_min_m = params_.range_min_m;
  ping.range_max_m = params_.range_max_m;
  ping.sound_speed_mps = params_.sound_speed_mps;
  ping.bins = EchoProfile(ranges_, fan_);
  const double next = sweep_.Advance();
  if (params_.faithful()) {
    ping.pan_rad = next;  // the thesis published the head's angle after the step
  } else {
    ping.pan_rad = pan;
    if (params_.intensity_noise_sigma > 0.0) {
      const uint64_t base = static_cast<uint64_t>(schedule_.count) * ping.bins.size();
      for (size_t k = 0; k < ping.bins.size(); ++k) {
        if (ping.bins[k] == 0) continue;  // a shadow stays silent
        const double v = ping.bins[k] + params_.intensity_noise_sigma * noise_.Gaussian(base + k);
        ping.bins[k] = static_cast<uint8_t>(std::clamp(std::lround(v), 1L, 255L));
      }
    }
  }
  out->Add(kName, std::move(ping));
}

}  // namespace cairn::sim
