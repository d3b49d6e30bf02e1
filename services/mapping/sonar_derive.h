#pragma once

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/robot_profile.h"
#include "services/mapping/derive.h"

/// @file
/// What a robot profile needs from a stored sonar map (a map that holds the sonar occupancy,
/// sonar_mapper_layer.h, and no elevation): its cost layer and the sonar contacts as obstacles
/// with the profile's verdict. Called by DeriveProfileLayers for maps without an elevation.
///
/// The sonar scans a horizontal plane at the vehicle's depth: it measures where a contact is,
/// never how high it stands. A contact is a wall_or_object of unmeasured height (height_m NaN),
/// which every profile's verdict calls blocked (JudgeObstacle): a vehicle holding its depth
/// cannot pass over what its sonar saw at that depth.

namespace cairn::mapping {

struct SonarDeriveParams {
  /// Occupancy (percent) at and above which a cell is an obstacle, and at and below which it is
  /// free; in between it is graded. The navigator's underwater thresholds.
  double occupied_threshold{65.0};
  double free_threshold{25.0};
  /// Occupied cells this close (m, centre to centre) are one contact: a rock's face is drawn
  /// beam by beam, its cells a cell or two apart, and two faces of one rock seen from two
  /// places meet at its corner, with a gap where the beams that drew them ended.
  double join_distance_m{1.5};
  int min_cells{2};  ///< smaller contacts are single stray echoes, left out of the registry
  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// The cost layer of a sonar occupancy layer (0..100 percent, NaN or negative unknown): free
/// 0, occupied kCostLethal, between graded by the occupancy, unknown NaN. The same for every
/// profile: the navigator keeps each hull's own margin.
common::Layer SonarCost(const common::Layer& occupancy, const SonarDeriveParams& params = {});

/// The contacts of a sonar occupancy layer of `map`: groups of occupied cells, each a
/// wall_or_object with its shape and NaN height, numbered by centroid, without verdicts.
common::ObstacleRegistry ExtractSonarContacts(const common::GridMap& map, const std::string& layer,
                                              const SonarDeriveParams& params = {});

/// `profile`'s layers of a sonar map (`base` holds kSonarOccupancy): cost/<profile>,
/// directed/<profile> (no heading refused: 0 where the cost is known) and the contacts with
/// the profile's verdicts. The base is not modified.
/// @throws std::invalid_argument if the map has no sonar occupancy.
DerivedLayers DeriveSonarProfileLayers(const common::GridMap& base,
                                       const common::RobotProfile& profile,
                                       const SonarDeriveParams& params = {});

}  // namespace cairn::mapping
