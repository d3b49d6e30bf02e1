#pragma once

#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/robot_profile.h"

/// @file
/// The obstacle registry: connected terrain features with their measurements, and per-profile
/// verdicts computed from those measurements alone (so a stored registry can be re-labelled for
/// any profile without the elevation). CONTRACT shared with the map store: keep these signatures.

namespace cairn::mapping {

struct ObstacleParams {
  double min_ramp_slope_rad{0.035};   ///< slopes below this are flat ground
  double min_step_height_m{0.005};    ///< height differences below this are not steps
  int min_cells{3};                   ///< smaller components are noise
};

/// Finds features in a map holding elevation and the geometric layers; no verdicts yet.
common::ObstacleRegistry ExtractObstacles(const common::GridMap& map, const ObstacleParams& params);

/// Whether `profile` can cross `obstacle`, with the reason when not.
common::ObstacleVerdict JudgeObstacle(const common::Obstacle& obstacle,
                                      const common::RobotProfile& profile);

/// Replaces each obstacle's verdict for each of `profiles` (other verdicts are kept).
void LabelObstacles(common::ObstacleRegistry* registry,
                    const std::vector<common::RobotProfile>& profiles);

}  // namespace cairn::mapping
