#pragma once

#include <cstdint>
#include <vector>

#include "common/point_cloud.h"
#include "services/mapping/raytrace.h"

/// @file
/// The 3-D lidar's obstacle band as planar rays for the 2-D layers (occupancy_grid.h,
/// dynamic_layers.h): points between a minimum and a maximum height over the local ground are
/// obstacles in 2-D.
///
/// A revolution of ~70,000 points is first binned by azimuth around the sensor. Each bin gives
/// at most one ray: to its nearest band point (a hit), or, when the bin has no band point, to
/// its farthest point below the band (ground seen that far, so the band is free up to it, a
/// no-return ray). A revolution therefore costs `azimuth_bins` rays, not one per point.
///
/// Local ground. The height of a point is measured from the lowest point of its bin whose
/// horizontal range lies within `ground_window_m` before it (a wall's foot, the floor just in
/// front of a box), but never from higher than the robot's ground plus a slope allowance
/// (`ground_z_m + range · tan(max_ground_slope_rad)`). A ramp therefore stays ground while it
/// rises less than `min_height_m` over `ground_window_m` (17 deg at the defaults), and a wall
/// whose foot is hidden still stands out above its lowest visible point.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

struct ObstacleBandParams {
  double min_height_m{0.15};    ///< lower edge of the band over the local ground
  double max_height_m{1.8};     ///< upper edge (points above, e.g. a ceiling, are ignored)
  int azimuth_bins{1800};       ///< rays per revolution (0.2 deg)
  double min_range_m{0.4};      ///< horizontal; closer points (the robot itself) are ignored
  double max_range_m{30.0};     ///< horizontal; farther points are ignored
  double ground_window_m{0.5};  ///< slopes up to atan(min_height / window) stay ground
  double max_ground_slope_rad{0.2618};  ///< 15 deg
  /// Sensor height above the ground under the robot, used when no ground height is given.
  double sensor_height_m{0.9};

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// Reads a `band` section (every key optional) over the defaults.
/// @throws common::ConfigError naming the file and line of a bad or unknown key.
ObstacleBandParams LoadObstacleBandParams(common::YamlMap& map);

struct ObstacleBandStats {
  int64_t points{0};
  int64_t points_invalid{0};  ///< NaN or infinite coordinates
  int64_t points_out_of_range{0};
  int64_t hit_rays{0};
  int64_t free_rays{0};
};

/// Projects revolutions' obstacle bands to planar rays, keeping its working memory between
/// revolutions (a 70,000-point revolution then costs no allocation). Not thread-safe.
class ObstacleBand {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit ObstacleBand(const ObstacleBandParams& params = {});
  ObstacleBand(const ObstacleBand&) = default;
  ObstacleBand& operator=(const ObstacleBand&) = default;
  ObstacleBand(ObstacleBand&&) = default;
  ObstacleBand& operator=(ObstacleBand&&) = default;

  /// Planar rays (world metres) of a revolution. Points are in each slice's sensor frame and
  /// placed with that slice's sensor pose; a ray starts at the sensor position of the slice
  /// its point came from. `ground_z_m` is the world height of the ground under the robot; NaN
  /// takes each slice's sensor height minus `sensor_height_m`. Deterministic: the same
  /// revolution gives the same rays in the same order (by bin). The reference stays valid
  /// until the next call.
  const std::vector<PlanarRay>& Project(const common::LidarRevolution& revolution,
                                        double ground_z_m, ObstacleBandStats* stats = nullptr);

  const ObstacleBandParams& params() const { return params_; }

 private:
  struct Point {
    int32_t bin;
    int32_t slice;
    float range_m;  // horizontal, from the slice's sensor
    float z_m;
    float ground_cap_m;  // robot ground + slope allowance at this range
    double x_m, y_m;
  };
  struct Record {  // what the per-bin pass reads, in bin order
    float range_m;
    float z_m;
    float ground_cap_m;
    int32_t point;  // index into points_
  };
  // The stages of Project: points in world with their bin and range (points_, origins_),
  // sorted by bin and range (start_, sorted_), then one ray per bin (rays_).
  void TransformPoints(const common::LidarRevolution& revolution, double ground_z_m,
                       ObstacleBandStats* stats);
  void SortByBinAndRange();
  void ChooseRays(ObstacleBandStats* stats);

  ObstacleBandParams params_;
  std::vector<Point> points_;
  std::vector<int32_t> start_;
  std::vector<Record> sorted_;
  std::vector<int32_t> window_;
  std::vector<common::Vector2> origins_;
  std::vector<PlanarRay> rays_;
};

/// ObstacleBand(params).Project(revolution, ground_z_m, stats), for one-off use.
std::vector<PlanarRay> ProjectObstacleBand(const common::LidarRevolution& revolution,
                                           const ObstacleBandParams& params, double ground_z_m,
                                           ObstacleBandStats* stats = nullptr);

}  // namespace cairn::mapping
