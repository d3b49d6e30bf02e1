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
/// its ranges rounded to that resolution) instead of 17 a point; the points themselves are not
/// rounded.
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
};

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
