#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/types.h"

/// @file
/// Lidar data as the core libraries see it. A revolution arrives as azimuth slices; each slice
/// carries the sensor pose at its own time, so a moving robot yields an undistorted cloud.

namespace cairn::common {

struct LidarPoint {
  float x_m{0.f};  ///< sensor frame
  float y_m{0.f};
  float z_m{0.f};
  float intensity{0.f};
  int16_t ring{0};
  uint16_t column{0};  ///< azimuth step within its slice, when the slice has a grid
};

/// How a spinning lidar lays out one slice, when its source has a grid of rays (the simulator's
/// lidar, a Velodyne): `columns` azimuth steps `azimuth_step_rad` apart from the slice's
/// azimuth_start_rad, by the rings at `ring_elevation_rad`. A point's ring and column name its
/// ray. When `range_resolution_m` > 0 the slice travels as 3 bytes a ray (lcmt_lidar_ranges,
/// its ranges rounded to that resolution) instead of 17 a point, and its source may fill the
/// slice's range image instead of its points (LidarSlice).
struct LidarGrid {
  std::vector<float> ring_elevation_rad;  ///< ring 0 first
  double azimuth_step_rad{0.0};
  int32_t columns{0};
  double range_resolution_m{0.0};
};

struct LidarSlice {
  int64_t utime{0};
  std::string robot;
  int64_t revolution{0};   ///< counter of revolutions since start
  int32_t slice_index{0};  ///< 0 .. slice_count-1
  int32_t slice_count{1};
  double azimuth_start_rad{0.0};
  double azimuth_end_rad{0.0};
  double max_range_m{0.0};
  Pose3 sensor_pose;       ///< sensor in world at this slice's time
  std::vector<LidarPoint> points;
  LidarGrid grid;  ///< columns == 0: the points have no grid
  /// The range image: the slice as a gridded sensor measures it, a range and an intensity per
  /// ray, column by column and ring by ring within (grid.columns x rings), ranges in steps of
  /// grid.range_resolution_m, 0 for no return. The simulator's HDL-32E fills these instead of
  /// the points (they go on the bus as they are); a consumer that needs points calls
  /// ExpandRangeImage. Empty when the slice carries points.
  std::vector<uint16_t> range_steps;
  std::vector<uint8_t> range_intensity;
};

/// A range in steps of `steps_per_m`, rounded to the nearest: 0 (no return) when not a number
/// or under half a step, at most 65535.
inline uint16_t LidarRangeToSteps(float range_m, float steps_per_m) {
  const float steps = range_m * steps_per_m + 0.5f;
  return steps >= 1.f ? (steps < 65535.f ? static_cast<uint16_t>(steps) : uint16_t{65535}) : 0;
}
/// An intensity as a range image carries it: rounded, within 0..255.
inline uint8_t LidarIntensityByte(float intensity) {
  const float v = intensity + 0.5f;
  return v >= 1.f ? (v < 255.f ? static_cast<uint8_t>(v) : uint8_t{255}) : 0;
}

/// Whether `slice` has a grid of ranges that lcmt_lidar_ranges can carry (1 to 127 rings, 1 to
/// 65535 columns, a resolution above 0).
bool HasRangeGrid(const LidarSlice& slice);

/// Whether `slice` carries a range image: a range grid (HasRangeGrid) with a resolution of at
/// most 1 m, and both arrays of columns x rings values.
bool HasRangeImage(const LidarSlice& slice);

/// Replaces `slice`'s range image by its points, appended after any it has: one per ray that
/// returned (range > 0), at its ring's elevation and its column's azimuth
/// (azimuth_start_rad + column * grid.azimuth_step_rad), ring and column set. The grid is
/// kept. A slice without a range image is left as it is.
void ExpandRangeImage(LidarSlice* slice);

/// A full revolution: its slices in order; a missing slice leaves a gap.
struct LidarRevolution {
  int64_t revolution{0};
  std::string robot;
  std::vector<LidarSlice> slices;
  int32_t expected_slices{0};
  bool complete() const { return static_cast<int32_t>(slices.size()) == expected_slices; }
  size_t num_points() const {
    size_t n = 0;
    for (const auto& s : slices) n += s.points.size();
    return n;
  }
};

/// A planar laser scan (angles in the sensor frame, counter-clockwise from x).
struct LaserScan {
  int64_t utime{0};
  std::string robot;
  Pose3 sensor_pose;
  double angle_min_rad{0.0};
  double angle_increment_rad{0.0};
  double range_min_m{0.0};
  double range_max_m{0.0};
  std::vector<float> ranges_m;  ///< +inf for no return
  std::vector<float> intensities;
};

}  // namespace cairn::common
