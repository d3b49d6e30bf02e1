#include "simulator/sensors/planar_laser_sensor.h"

#include <cmath>
#include <limits>

#include "common/check.h"
#include "simulator/sensor_registry.h"

namespace cairn::sim {
void PlanarLaserParams::Validate() const {
  CAIRN_THROW_UNLESS(FinitePositive(fov_deg) && fov_deg <= 360.0,
                     "planar_laser.fov_deg must be in (0, 360]");
  CAIRN_THROW_UNLESS(beams >= 2 && beams <= 100000, "planar_laser.beams must be in [2, 100000]");
  CAIRN_THROW_UNLESS(FinitePositive(max_range_m), "planar_laser.max_range_m must be > 0");
  CAIRN_THROW_UNLESS(FiniteNonNegative(min_range_m) && min_range_m < max_range_m,
                     "planar_laser.min_range_m must be in [0, max_range_m)");
  CAIRN_THROW_UNLESS(FinitePositive(rate_hz), "planar_laser.rate_hz must be > 0");
  CAIRN_THROW_UNLESS(FiniteNonNegative(range_noise_sigma_m),
                     "planar_laser.range_noise_sigma_m must be >= 0");
}

PlanarLaserParams LoadPlanarLaserParams(common::YamlMap& map, const PlanarLaserParams& defaults) {
  PlanarLaserParams p = defaults;
  map.Get("fov_deg", &p.fov_deg);
  map.Get("beams", &p.beams);
  map.Get("max_range_m", &p.max_range_m);
  map.Get("min_range_m", &p.min_range_m);
  map.Get("rate_hz", &p.rate_hz);
  map.Get("range_noise_sigma_m", &p.range_noise_sigma_m);
  map.Get("mount_site", &p.mount_site);
  FinishSensorParams(map, p);
  return p;
}

void FanAngles(double fov_deg, int beams, double* angle_min_rad, double* increment_rad) {
  const double fov = fov_deg * M_PI / 180.0;
  *angle_min_rad = -0.5 * fov;
  *increment_rad = beams > 1 ? fov / (beams - 1) : 0.0;
}

RayPattern BuildFanPattern(double fov_deg, int beams) {
  RayPattern pattern;
  double angle_min = 0.0, increment = 0.0;
  FanAngles(fov_deg, beams, &angle_min, &increment);
  for (int i = 0; i < beams; ++i) {
    const double a = angle_min + increment * i;
    pattern.directions.emplace_back(std::cos(a), std::sin(a), 0.0);
  }
  pattern.warm_stride = 1;
  pattern.BuildGroups(16);
  return pattern;
}

void FillScanRanges(const std::vector<RayHit>& hits, double noise_sigma_m, const NoiseSource& noise,
                    uint64_t noise_base, const SceneRays& rays, common::LaserScan* scan) {
  const size_t beams = hits.size();
  scan->ranges_m.resize(beams);
  scan->intensities.resize(beams);
  for (size_t i = 0; i < beams; ++i) {
    const RayHit& h = hits[i];
    float range = std::numeric_limits<float>::infinity();
    float intensity = 0.f;
    if (h.geom >= 0) {
      double r = h.range_m + noise_sigma_m * noise.Gaussian(noise_base + i);
      if (r > scan->range_max_m) {
        r = std::numeric_limits<double>::infinity();
      } else if (r < scan->range_min_m) {
        r = std::numeric_limits<double>::quiet_NaN();  // too close to measure
      } else {
        intensity = rays.intensity(h.geom);
      }
      range = static_cast<float>(r);
    }
    scan->ranges_m[i] = range;
    scan->intensities[i] = intensity;
  }
}

PlanarLaserSensor::PlanarLaserSensor(const PlanarLaserParams& params, const SensorContext& context)
    : params_(params),
      pattern_(BuildFanPattern(params.fov_deg, params.beams)),
      robot_(context.robot),
      site_(context.RequireSite(params.mount_site)),
      hits_(pattern_.directions.size()),
      noise_(context.Noise()) {
  schedule_.rate_hz = params.rate_hz;
}

void PlanarLaserSensor::Produce(const SensorFrame& frame, SimOutputs* out) {
  schedule_.Advance(frame.now_s);
  const common::Pose3 sensor = SitePose(frame.data, site_);
  frame.CastAll(sensor, pattern_, params_.max_range_m, &hits_);
  common::LaserScan scan;
  scan.utime = frame.utime;
  scan.robot = robot_;
  scan.sensor_pose = sensor;
  FanAngles(params_.fov_deg, params_.beams, &scan.angle_min_rad, &scan.angle_increment_rad);
  scan.range_min_m = params_.min_range_m;
  scan.range_max_m = params_.max_range_m;
  const uint64_t base = static_cast<uint64_t>(schedule_.count) * params_.beams;
  FillScanRanges(hits_, params_.range_noise_sigma_m, noise_, base, *frame.rays, &scan);
  out->Add(kName, std::move(scan));
}

}  // namespace cairn::sim
