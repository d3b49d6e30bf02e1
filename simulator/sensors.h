#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/types.h"
#include "simulator/ray_caster.h"
#include "simulator/sensor_params.h"
#include <Eigen/Core>

/// @file
/// Sensor geometry and models that do not need the physics: lidar ring and azimuth layout,
/// ray patterns, seeded noise, wheel odometry.

namespace cairn::sim {

/// Counter-based noise: the value for (seed, stream, index) is fixed, whichever thread asks and
/// in whatever order, so runs with the same seed repeat exactly.
class NoiseSource {
 public:
  NoiseSource() = default;
  NoiseSource(uint64_t seed, uint64_t stream);
  /// Standard normal sample number `index`.
  double Gaussian(uint64_t index) const;
  /// Uniform sample in [0, 1).
  double Uniform(uint64_t index) const;

 private:
  uint64_t key_{0};
};

/// Stream id for a named noise source of a robot ("rover1/hdl32e").
uint64_t NoiseStream(const std::string& name);

// --- 3-D lidar layout --------------------------------------------------------------------------

/// Elevation of ring r (0 = lowest), evenly spaced from min to max elevation.
double LidarRingElevationRad(const LidarParams& params, int ring);
/// Azimuth of step k, counter-clockwise from the sensor's x axis: k * 360 deg / azimuth_steps.
double LidarAzimuthRad(const LidarParams& params, int step);
/// First azimuth step of slice s; slice s covers [SliceBegin(s), SliceBegin(s + 1)).
int LidarSliceBegin(const LidarParams& params, int slice);
/// All rays of one revolution, ordered so that every slice, and within it every ray group, is a
/// contiguous range: slice by slice, then by elevation band (rings_per_ray_group rings), then
/// azimuth step, then ring. Groups span azimuths_per_ray_group steps of one band.
struct LidarPattern {
  RayPattern rays;
  std::vector<int16_t> ring;           ///< per ray
  std::vector<int32_t> azimuth_step;   ///< per ray
  std::vector<int> slice_ray_begin;    ///< slice s owns rays [begin[s], begin[s + 1])
  std::vector<int> slice_group_begin;  ///< slice s owns groups [begin[s], begin[s + 1])
};
LidarPattern BuildLidarPattern(const LidarParams& params);

// --- planar lasers -----------------------------------------------------------------------------

/// Angle of the first beam and the step between beams for a fan of `beams` over `fov_deg`
/// centred on the x axis (one beam on each edge).
void FanAngles(double fov_deg, int beams, double* angle_min_rad, double* increment_rad);
/// Beams in the sensor's x-y plane, counter-clockwise from angle_min.
RayPattern BuildFanPattern(double fov_deg, int beams);
/// Rotation from a turret line's scanning frame to the turret frame at pan angle `pan_rad`:
/// the line's x axis is the turret's up axis and its y axis the horizontal pan direction, so
/// beam angle 0 points up and +90 deg points horizontally along the pan direction.
Eigen::Matrix3d TurretLineRotation(double pan_rad);

// --- wheel odometry ----------------------------------------------------------------------------

/// Planar dead reckoning from left and right wheel rotation. Each increment is integrated as an
/// arc of constant curvature, so noise-free input reproduces the true path of a rolling robot.
class WheelOdometry {
 public:
  WheelOdometry(const OdometryParams& params, double wheel_radius_m, double track_m,
                NoiseSource noise);

  void Reset(const common::Pose2& pose);
  /// Adds one step: wheel rotation increments (rad) over dt_s.
  void Integrate(double left_delta_rad, double right_delta_rad, double dt_s);

  const common::Pose2& pose() const { return pose_; }
  double linear_mps() const { return linear_mps_; }
  double angular_radps() const { return angular_radps_; }

 private:
  OdometryParams params_;
  double wheel_radius_m_;
  double track_m_;
  NoiseSource noise_;
  uint64_t counter_{0};
  common::Pose2 pose_;
  double linear_mps_{0.0};
  double angular_radps_{0.0};
};

}  // namespace cairn::sim
