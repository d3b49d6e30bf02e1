#include "simulator/sensors/lidar_sensor.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <tuple>

#include "common/check.h"
#include "simulator/sensor_registry.h"

namespace cairn::sim {
namespace {

double DegToRad(double deg) { return deg * M_PI / 180.0; }

}  // namespace

void LidarParams::Validate() const {
  CAIRN_THROW_UNLESS(rings >= 1 && rings <= 127, "hdl32e.rings must be in [1, 127]");
  CAIRN_THROW_UNLESS(std::isfinite(min_elevation_deg) && std::isfinite(max_elevation_deg) &&
                         min_elevation_deg <= max_elevation_deg && min_elevation_deg >= -90.0 &&
                         max_elevation_deg <= 90.0,
                     "hdl32e elevations must satisfy -90 <= min <= max <= 90");
  CAIRN_THROW_UNLESS(azimuth_steps >= 1, "hdl32e.azimuth_steps must be >= 1");
  CAIRN_THROW_UNLESS(FinitePositive(rate_hz), "hdl32e.rate_hz must be > 0");
  CAIRN_THROW_UNLESS(slices_per_revolution >= 1 && slices_per_revolution <= azimuth_steps,
                     "hdl32e.slices_per_revolution must be in [1, azimuth_steps]");
  CAIRN_THROW_UNLESS(FinitePositive(max_range_m), "hdl32e.max_range_m must be > 0");
  CAIRN_THROW_UNLESS(FiniteNonNegative(min_range_m) && min_range_m < max_range_m,
                     "hdl32e.min_range_m must be in [0, max_range_m)");
  CAIRN_THROW_UNLESS(FiniteNonNegative(range_noise_sigma_m),
                     "hdl32e.range_noise_sigma_m must be >= 0");
  // 16 bits of range steps must reach the maximum range.
  CAIRN_THROW_UNLESS(range_resolution_m == 0.0 ||
                         (FinitePositive(range_resolution_m) && range_resolution_m <= 1.0 &&
                          max_range_m / range_resolution_m <= 65535.0),
                     "hdl32e.range_resolution_m must be 0 or in [max_range_m / 65535, 1]");
  CAIRN_THROW_UNLESS(azimuths_per_ray_group >= 1, "hdl32e.azimuths_per_ray_group must be >= 1");
  CAIRN_THROW_UNLESS(rings_per_ray_group >= 1, "hdl32e.rings_per_ray_group must be >= 1");
  // One slice must fit a UDP-friendly message (17 bytes per point, 3 per ray as ranges), and
  // so its columns a 16-bit index.
  const int64_t steps_per_slice =
      (azimuth_steps + slices_per_revolution - 1) / slices_per_revolution;
  const int64_t bytes_per_ray = range_resolution_m > 0.0 ? 3 : 17;
  CAIRN_THROW_UNLESS(steps_per_slice * rings * bytes_per_ray <= 64 * 1024,
                     "hdl32e: a slice of " << steps_per_slice * rings << " rays at "
                                           << bytes_per_ray
                                           << " bytes each exceeds 64 KB; raise "
                                              "slices_per_revolution");
}

LidarParams LoadLidarParams(common::YamlMap& map, const LidarParams& defaults) {
  LidarParams p = defaults;
  map.Get("rings", &p.rings);
  map.Get("min_elevation_deg", &p.min_elevation_deg);
  map.Get("max_elevation_deg", &p.max_elevation_deg);
  map.Get("azimuth_steps", &p.azimuth_steps);
  map.Get("rate_hz", &p.rate_hz);
  map.Get("slices_per_revolution", &p.slices_per_revolution);
  map.Get("max_range_m", &p.max_range_m);
  map.Get("min_range_m", &p.min_range_m);
  map.Get("range_noise_sigma_m", &p.range_noise_sigma_m);
  map.Get("range_resolution_m", &p.range_resolution_m);
  map.Get("azimuths_per_ray_group", &p.azimuths_per_ray_group);
  map.Get("rings_per_ray_group", &p.rings_per_ray_group);
  map.Get("mount_site", &p.mount_site);
  FinishSensorParams(map, p);
  return p;
}

// --- layout ------------------------------------------------------------------------------------

double LidarRingElevationRad(const LidarParams& p, int ring) {
  if (p.rings == 1) return DegToRad(p.min_elevation_deg);
  const double step = (p.max_elevation_deg - p.min_elevation_deg) / (p.rings - 1);
  return DegToRad(p.min_elevation_deg + step * ring);
}

double LidarAzimuthRad(const LidarParams& p, int step) {
  return 2.0 * M_PI * static_cast<double>(step) / static_cast<double>(p.azimuth_steps);
}

int LidarSliceBegin(const LidarParams& p, int slice) {
  return static_cast<int>(static_cast<int64_t>(slice) * p.azimuth_steps / p.slices_per_revolution);
}

namespace {

// Appends the rays of azimuth steps [k0, k1) x rings [r0, r1) as one group of `out`.
void AppendLidarGroup(const LidarParams& p, const std::vector<double>& cos_el,
                      const std::vector<double>& sin_el, int k0, int k1, int r0, int r1,
                      LidarPattern* out) {
  RayPattern& rays = out->rays;
  RayPattern group;
  for (int k = k0; k < k1; ++k) {
    const double az = LidarAzimuthRad(p, k);
    const double ca = std::cos(az), sa = std::sin(az);
    for (int r = r0; r < r1; ++r) {
      group.directions.emplace_back(cos_el[r] * ca, cos_el[r] * sa, sin_el[r]);
      out->ring.push_back(static_cast<int16_t>(r));
      out->azimuth_step.push_back(k);
    }
  }
  group.BuildGroups(static_cast<int>(group.directions.size()));
  RayPattern::Group g = group.groups.front();
  g.begin = static_cast<int>(rays.directions.size());
  g.end = g.begin + static_cast<int>(group.directions.size());
  rays.directions.insert(rays.directions.end(), group.directions.begin(), group.directions.end());
  rays.groups.push_back(g);
}

}  // namespace

LidarPattern BuildLidarPattern(const LidarParams& p) {
  LidarPattern out;
  RayPattern& rays = out.rays;
  const size_t n = static_cast<size_t>(p.rings) * p.azimuth_steps;
  rays.directions.reserve(n);
  out.ring.reserve(n);
  out.azimuth_step.reserve(n);
  std::vector<double> cos_el(p.rings), sin_el(p.rings);
  for (int r = 0; r < p.rings; ++r) {
    cos_el[r] = std::cos(LidarRingElevationRad(p, r));
    sin_el[r] = std::sin(LidarRingElevationRad(p, r));
  }
  const int band = std::min(p.rings, p.rings_per_ray_group);
  rays.warm_stride = band;  // the same ring one azimuth step earlier (within a group)
  for (int s = 0; s < p.slices_per_revolution; ++s) {
    out.slice_ray_begin.push_back(static_cast<int>(rays.directions.size()));
    out.slice_group_begin.push_back(static_cast<int>(rays.groups.size()));
    const int k_begin = LidarSliceBegin(p, s);
    const int k_end = LidarSliceBegin(p, s + 1);
    for (int r0 = 0; r0 < p.rings; r0 += band) {
      const int r1 = std::min(p.rings, r0 + band);
      for (int k0 = k_begin; k0 < k_end; k0 += p.azimuths_per_ray_group) {
        const int k1 = std::min(k_end, k0 + p.azimuths_per_ray_group);
        AppendLidarGroup(p, cos_el, sin_el, k0, k1, r0, r1, &out);
      }
    }
  }
  out.slice_ray_begin.push_back(static_cast<int>(rays.directions.size()));
  out.slice_group_begin.push_back(static_cast<int>(rays.groups.size()));
  rays.BuildComponents();
  return out;
}

std::shared_ptr<const LidarPattern> SharedLidarPattern(const LidarParams& p) {
  // Everything BuildLidarPattern reads.
  using Key = std::tuple<int, double, double, int, int, int, int>;
  const Key key{p.rings,
                p.min_elevation_deg,
                p.max_elevation_deg,
                p.azimuth_steps,
                p.slices_per_revolution,
                p.azimuths_per_ray_group,
                p.rings_per_ray_group};
  static std::mutex mutex;
  static std::map<Key, std::weak_ptr<const LidarPattern>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  std::weak_ptr<const LidarPattern>& slot = cache[key];
  std::shared_ptr<const LidarPattern> pattern = slot.lock();
  if (pattern == nullptr) {
    pattern = std::make_shared<const LidarPattern>(BuildLidarPattern(p));
    slot = pattern;
  }
  return pattern;
}

// --- the sensor --------------------------------------------------------------------------------

LidarSensor::LidarSensor(const LidarParams& params, const SensorContext& context)
    : params_(params),
      pattern_(SharedLidarPattern(params)),
      robot_(context.robot),
      site_(context.RequireSite(params.mount_site)),
      noise_(context.Noise()) {
  size_t largest = 0;
  for (size_t s = 0; s + 1 < pattern_->slice_ray_begin.size(); ++s) {
    largest = std::max(largest, static_cast<size_t>(pattern_->slice_ray_begin[s + 1] -
                                                    pattern_->slice_ray_begin[s]));
  }
  hits_.resize(largest);
  noisy_m_.resize(largest);
  for (int r = 0; r < params_.rings; ++r) {
    ring_elevation_rad_.push_back(static_cast<float>(LidarRingElevationRad(params_, r)));
  }
}

bool LidarSensor::Due(double now_s) const {
  return static_cast<double>(slices_done_ + 1) /
             (params_.rate_hz * params_.slices_per_revolution) <=
         now_s + 1e-9;
}

void LidarSensor::Produce(const SensorFrame& frame, SimOutputs* out) {
  const int slices = params_.slices_per_revolution;
  while (Due(frame.now_s)) {
    const int64_t revolution = slices_done_ / slices;
    const int slice = static_cast<int>(slices_done_ % slices);
    ++slices_done_;
    const common::Pose3 sensor = SitePose(frame.data, site_);
    const int g0 = pattern_->slice_group_begin[slice];
    const int g1 = pattern_->slice_group_begin[slice + 1];
    if (g1 <= g0) continue;
    frame.Cast(sensor, pattern_->rays, g0, g1, params_.max_range_m, hits_.data(),
               pattern_->slice_ray_begin[slice]);
    out->Add(kName, MakeSlice(frame, revolution, slice, sensor));
  }
}

common::LidarSlice LidarSensor::MakeSlice(const SensorFrame& frame, int64_t revolution, int slice,
                                          const common::Pose3& sensor) {
  const LidarParams& p = params_;
  const LidarPattern& pattern = *pattern_;
  const RayPattern& rays = pattern.rays;
  common::LidarSlice s;
  s.utime = frame.utime;
  s.robot = robot_;
  s.revolution = revolution;
  s.slice_index = slice;
  s.slice_count = p.slices_per_revolution;
  s.azimuth_start_rad = LidarAzimuthRad(p, LidarSliceBegin(p, slice));
  s.azimuth_end_rad = LidarAzimuthRad(p, LidarSliceBegin(p, slice + 1));
  s.max_range_m = p.max_range_m;
  s.sensor_pose = sensor;
  const int k_begin = LidarSliceBegin(p, slice);
  s.grid.ring_elevation_rad = ring_elevation_rad_;
  s.grid.azimuth_step_rad = LidarAzimuthRad(p, 1);
  s.grid.columns = LidarSliceBegin(p, slice + 1) - k_begin;
  s.grid.range_resolution_m = p.range_resolution_m;
  const int first = pattern.slice_ray_begin[slice];
  const int last = pattern.slice_ray_begin[slice + 1];
  const uint64_t noise_base =
      static_cast<uint64_t>(revolution) * static_cast<uint64_t>(rays.directions.size());
  // Half a million rays per simulated second: plain pointers, nothing reloaded per ray.
  const RayHit* hits = hits_.data();  // the slice's rays: hits[i - first]
  const int16_t* rings = pattern.ring.data();
  const int32_t* steps = pattern.azimuth_step.data();
  const float* intensity = frame.rays->intensities();
  // Locals: the compiler cannot keep members in registers across the stores to the output.
  const double min_range_m = p.min_range_m, max_range_m = p.max_range_m;
  const double sigma_m = p.range_noise_sigma_m;
  if (p.range_resolution_m > 0.0) {
    // The range image, which goes on the bus as it is: no point per ray, no square root to
    // find its range again.
    const size_t ring_count = static_cast<size_t>(p.rings);
    const size_t ray_count = static_cast<size_t>(s.grid.columns) * ring_count;
    s.range_steps.assign(ray_count, 0);
    s.range_intensity.assign(ray_count, 0);
    uint16_t* range_steps = s.range_steps.data();
    uint8_t* range_intensity = s.range_intensity.data();
    // Two passes, measured cheaper than one: the noisy ranges of every ray, without a branch
    // (a ray that missed draws noise too, which changes nothing: a draw is a pure function of
    // the ray's number), then each ray's range step and intensity. Validate() bounds
    // max_range_m in 16 bits of steps; a ray without a return reads 0.
    const int count = last - first;
    double* noisy_m = noisy_m_.data();
    for (int k = 0; k < count; ++k) {
      noisy_m[k] = hits[k].range_m + sigma_m * noise_.Gaussian(noise_base + first + k);
    }
    const double steps_per_m = 1.0 / p.range_resolution_m;
    for (int i = first; i < last; ++i) {
      const RayHit& h = hits[i - first];
      const double range = noisy_m[i - first];
      const bool returned = h.geom >= 0 && range >= min_range_m && range <= max_range_m;
      const size_t ray = static_cast<size_t>(steps[i] - k_begin) * ring_count + rings[i];
      range_steps[ray] = returned ? static_cast<uint16_t>(range * steps_per_m + 0.5) : 0;
      range_intensity[ray] = returned ? common::LidarIntensityByte(intensity[h.geom]) : 0;
    }
    return s;
  }
  // Sized for every ray and trimmed at the end: the points are written in place, field by
  // field (a point built aside and pushed back stalled on its 2-byte ring store).
  s.points.resize(last - first);
  common::LidarPoint* out = s.points.data();
  const Eigen::Vector3d* directions = rays.directions.data();
  for (int i = first; i < last; ++i) {
    const RayHit& h = hits[i - first];
    if (h.geom < 0) continue;
    double range = h.range_m;
    if (sigma_m > 0.0) range += sigma_m * noise_.Gaussian(noise_base + i);
    if (range < min_range_m || range > max_range_m) continue;
    const Eigen::Vector3d& dir = directions[i];
    out->x_m = static_cast<float>(dir.x() * range);
    out->y_m = static_cast<float>(dir.y() * range);
    out->z_m = static_cast<float>(dir.z() * range);
    out->intensity = intensity[h.geom];
    out->ring = rings[i];
    out->column = static_cast<uint16_t>(steps[i] - k_begin);
    ++out;
  }
  s.points.resize(out - s.points.data());
  return s;
}

}  // namespace cairn::sim
