#pragma once

#include <string>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/robot_profile.h"
#include "services/mapping/obstacles.h"
#include "services/mapping/traversability.h"

/// @file
/// Everything a robot profile needs from stored robot-agnostic layers: one call, used by the
/// map store to share a map with another profile. CONTRACT shared with the map store.

namespace cairn::mapping {

/// Changes whenever derivation results could change; part of the derived-layer cache key.
extern const char kMappingCodeVersion[];

struct DerivedLayers {
  common::GridMap layers;             ///< slope, step, roughness and cost/<profile>
  common::ObstacleRegistry registry;  ///< obstacles with this profile's verdict
};

/// Derives the profile layers from `base` (which must hold layers::kElevation; its ground bound
/// and elevation variance are read when present, as the live map reads them). A sonar map (the
/// sonar occupancy and no elevation) is derived by DeriveSonarProfileLayers (sonar_derive.h).
/// The base map is not modified. @throws std::invalid_argument if neither layer is there.
DerivedLayers DeriveProfileLayers(const common::GridMap& base, const common::RobotProfile& profile,
                                  const TraversabilityParams& traversability = {},
                                  const ObstacleParams& obstacles = {});

}  // namespace cairn::mapping
