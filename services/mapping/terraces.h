#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/robot_profile.h"
#include "services/mapping/obstacles.h"

/// @file
/// Terraces (internal to the mapping core): the ramps and faces that lead onto one raised,
/// level platform are one registry entry with its parts (a ramp, its platform and its drop; a
/// slab with its faces), judged as a whole for each profile.

namespace cairn::mapping::internal {

/// A measured feature of the registry with the cells it covers.
struct MeasuredFeature {
  common::Obstacle obstacle;
  std::vector<int64_t> cells;
};

/// Joins the ramps and steps of `features` that lead onto one platform into terraces. A platform
/// is a level region (4-connected known cells outside every feature, flatter than
/// min_ramp_slope_rad, neighbours within surface_continuity_m) no larger than
/// max_terrace_area_m2 and not the largest such region (the ground), which two or more ramps or
/// steps reach at their high side. `label` (map-sized) is nonzero on every cell of a feature,
/// kept or not. Walls, ditches and features on no platform are left as they are.
void JoinTerraces(const common::GridMap& map, const std::vector<int32_t>& label,
                  const ObstacleParams& params, std::vector<MeasuredFeature>* features);

/// A part's verdict for `profile`, and whether the profile may drive it onto the platform and
/// off it.
struct PartJudgement {
  common::ObstacleVerdict verdict;
  bool onto{false};
  bool off{false};
};
PartJudgement JudgePart(const common::ObstaclePart& part, const common::RobotProfile& profile,
                        const std::string& hash);

/// A terrace's verdict from its parts' judgements (see common::Obstacle::parts).
common::ObstacleVerdict JudgeTerrace(const common::Obstacle& terrace,
                                     const common::RobotProfile& profile, const std::string& hash);

}  // namespace cairn::mapping::internal
