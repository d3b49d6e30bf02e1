#pragma once

#include <optional>
#include <string>

#include "common/grid_map.h"
#include "common/robot_profile.h"

/// @file
/// Traversability from an elevation map (seed 000), per robot profile.
/// CONTRACT shared with the map store and the planner: keep these signatures.

namespace cairn::mapping {

struct TraversabilityParams {
  double normal_radius_m{0.3};        ///< PCA window for normals (3 x 3 cells at 0.2 m)
  double blind_zone_half_size_m{0.5};  ///< cells within this of the robot count as free
  bool imu_pitch_compensation{false};  ///< add the robot's pitch to the map slope
  bool unknown_is_lethal{false};       ///< else unknown stays NaN in the cost layer
  double graded_cost_max{90.0};        ///< highest graded cost (free terrain costs 0)
};

/// Adds the profile-independent layers (layers::kSlope, kStepMax, kRoughness) computed from
/// layers::kElevation. @throws std::invalid_argument if the map has no elevation layer.
void ComputeGeometricLayers(common::GridMap* map, const TraversabilityParams& params);

/// Adds layers::CostLayer(profile.name): 0 free, (0,100) graded, 100 lethal, NaN unknown.
/// Computes the geometric layers first when they are missing. `robot_xy_m` applies the
/// blind-zone rule around the robot; `robot_pitch_rad` the IMU compensation when enabled.
void ComputeCostLayer(common::GridMap* map, const common::RobotProfile& profile,
                      const TraversabilityParams& params,
                      std::optional<common::Vector2> robot_xy_m = std::nullopt,
                      double robot_pitch_rad = 0.0);

}  // namespace cairn::mapping
