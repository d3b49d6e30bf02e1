#include "simulator/sensors.h"

#include <array>
#include <cmath>

#include "common/check.h"
#include "common/robot_profile.h"

namespace cairn::sim {
namespace {

// SplitMix64: a strong 64-bit mixer, enough for simulation noise.
uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double ToUnit(uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

double DegToRad(double deg) { return deg * M_PI / 180.0; }

constexpr int kQuantileBits = 12;
constexpr int kQuantiles = 1 << kQuantileBits;

// Standard normal quantiles at (i + 0.5) / (kQuantiles + 1), i = 0..kQuantiles.
const std::array<double, kQuantiles + 1>& QuantileTable() {
  static const std::array<double, kQuantiles + 1> table = [] {
    std::array<double, kQuantiles + 1> t{};
    for (int i = 0; i <= kQuantiles; ++i) {
      const double p = (i + 0.5) / (kQuantiles + 1);
      // Bisection on the CDF 0.5 * erfc(-x / sqrt(2)).
      double lo = -10.0, hi = 10.0;
      for (int k = 0; k < 100; ++k) {
        const double mid = 0.5 * (lo + hi);
        if (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p) {
          lo = mid;
        } else {
          hi = mid;
        }
      }
      t[i] = 0.5 * (lo + hi);
    }
    return t;
  }();
  return table;
}

}  // namespace

// --- noise -------------------------------------------------------------------------------------

NoiseSource::NoiseSource(uint64_t seed, uint64_t stream) : key_(Mix(Mix(seed) ^ stream)) {}

double NoiseSource::Uniform(uint64_t index) const { return ToUnit(Mix(key_ ^ Mix(index))); }

double NoiseSource::Gaussian(uint64_t index) const {
  // Inverse-CDF sampling: the top 12 bits of one hash pick a cell of the quantile table, the
  // next 32 bits interpolate inside it. No transcendental functions per sample (a lidar draws
  // half a million samples per simulated second); tails are clipped at |z| = 3.67.
  const std::array<double, kQuantiles + 1>& table = QuantileTable();
  const uint64_t h = Mix(key_ ^ (index * 0xd1b54a32d192ed03ULL));
  const uint64_t cell = h >> (64 - kQuantileBits);
  const double frac =
      static_cast<double>((h >> (64 - kQuantileBits - 32)) & 0xffffffffULL) * 0x1.0p-32;
  return table[cell] + (table[cell + 1] - table[cell]) * frac;
}

uint64_t NoiseStream(const std::string& name) { return common::Fnv1a64(name.data(), name.size()); }

// --- 3-D lidar ---------------------------------------------------------------------------------

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
        RayPattern group;
        for (int k = k0; k < k1; ++k) {
          const double az = LidarAzimuthRad(p, k);
          const double ca = std::cos(az), sa = std::sin(az);
          for (int r = r0; r < r1; ++r) {
            group.directions.emplace_back(cos_el[r] * ca, cos_el[r] * sa, sin_el[r]);
            out.ring.push_back(static_cast<int16_t>(r));
            out.azimuth_step.push_back(k);
          }
        }
        group.BuildGroups(static_cast<int>(group.directions.size()));
        RayPattern::Group g = group.groups.front();
        g.begin = static_cast<int>(rays.directions.size());
        g.end = g.begin + static_cast<int>(group.directions.size());
        rays.directions.insert(rays.directions.end(), group.directions.begin(),
                               group.directions.end());
        rays.groups.push_back(g);
      }
    }
  }
  out.slice_ray_begin.push_back(static_cast<int>(rays.directions.size()));
  out.slice_group_begin.push_back(static_cast<int>(rays.groups.size()));
  return out;
}

// --- planar lasers -----------------------------------------------------------------------------

void FanAngles(double fov_deg, int beams, double* angle_min_rad, double* increment_rad) {
  const double fov = DegToRad(fov_deg);
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

Eigen::Matrix3d TurretLineRotation(double pan_rad) {
  const double c = std::cos(pan_rad), s = std::sin(pan_rad);
  Eigen::Matrix3d r;
  // Columns: line x (up), line y (pan direction), line z = x cross y.
  r << 0.0, c, -s,  //
      0.0, s, c,    //
      1.0, 0.0, 0.0;
  return r;
}

// --- wheel odometry ----------------------------------------------------------------------------

WheelOdometry::WheelOdometry(const OdometryParams& params, double wheel_radius_m, double track_m,
                             NoiseSource noise)
    : params_(params), wheel_radius_m_(wheel_radius_m), track_m_(track_m), noise_(noise) {
  CAIRN_THROW_UNLESS(wheel_radius_m > 0.0 && track_m > 0.0,
                     "odometry needs a positive wheel radius and track");
}

void WheelOdometry::Reset(const common::Pose2& pose) {
  pose_ = pose;
  linear_mps_ = 0.0;
  angular_radps_ = 0.0;
}

void WheelOdometry::Integrate(double left_delta_rad, double right_delta_rad, double dt_s) {
  double left_m = left_delta_rad * wheel_radius_m_;
  double right_m = right_delta_rad * wheel_radius_m_;
  if (params_.slip_noise_ratio > 0.0) {
    left_m *= 1.0 + params_.slip_noise_ratio * noise_.Gaussian(counter_++);
    right_m *= 1.0 + params_.slip_noise_ratio * noise_.Gaussian(counter_++);
  }
  const double ds = 0.5 * (left_m + right_m);
  const double dtheta = (right_m - left_m) / track_m_;
  const double theta = pose_.yaw_rad;
  if (std::abs(dtheta) > 1e-9) {
    // Exact arc of constant curvature.
    const double radius = ds / dtheta;
    pose_.x_m += radius * (std::sin(theta + dtheta) - std::sin(theta));
    pose_.y_m -= radius * (std::cos(theta + dtheta) - std::cos(theta));
  } else {
    pose_.x_m += ds * std::cos(theta + 0.5 * dtheta);
    pose_.y_m += ds * std::sin(theta + 0.5 * dtheta);
  }
  pose_.yaw_rad = common::WrapAngle(theta + dtheta);
  if (dt_s > 0.0) {
    linear_mps_ = ds / dt_s;
    angular_radps_ = dtheta / dt_s;
  }
}

}  // namespace cairn::sim
