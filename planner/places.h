#pragma once

#include <string>
#include <vector>

#include "common/types.h"
#include "planner/cost_map.h"

/// @file
/// Named places (rooms, areas) as polygons, and turning a place into a goal pose: the free cell
/// inside the polygon farthest from walls and unknown space (seed 001's semantic goals).

namespace cairn::planner {

struct Place {
  std::string name;
  std::vector<common::Vector2> polygon_m;  ///< world frame, >= 3 vertices
  int label_value{-1};  ///< optional semantic label (seed 001's grey level), -1 when absent
};

/// Reads places from YAML: either a list, or a map whose only key `places` holds the list, of
/// `{name: kitchen, polygon: [[x, y], ...], label_value: 60}` (label_value optional).
/// @throws common::ConfigError naming file and line for a malformed entry, an unknown key, a
/// polygon with fewer than 3 vertices, non-finite coordinates or a duplicate name.
std::vector<Place> LoadPlacesFile(const std::string& path);
std::vector<Place> LoadPlacesString(const std::string& yaml, const std::string& where = "<string>");

/// The place with this name, or nullptr.
const Place* FindPlace(const std::vector<Place>& places, const std::string& name);

struct PlaceGoalParams {
  /// Known cells cheaper than this may be goals (0 = only free cells).
  float max_goal_cost{30.0f};
  /// Headings tried for the footprint check.
  int yaw_samples{16};
  /// The navigator moves a place goal it already chose when the map now shows a cell in the
  /// place this much farther from obstacles than the chosen one (furniture seen only on the
  /// way in). 0 never moves it.
  double move_margin_m{0.3};
};

struct PlaceGoal {
  bool found{false};
  common::Pose2 pose;       ///< cell centre; the yaw is a valid heading there
  double clearance_m{0.0};  ///< distance to the nearest lethal, unknown or off-map cell
  std::string message;      ///< why nothing was found
};

/// Among known cells inside the place whose cost is below max_goal_cost and where the
/// footprint fits at some heading, the one farthest from lethal, unknown and off-map cells
/// (ties: the cheaper cell, then the one nearer the polygon's centroid).
PlaceGoal ResolvePlace(const Place& place, const CostMap& map, const PlaceGoalParams& params = {});

}  // namespace cairn::planner
