#pragma once

#include <optional>

#include "common/types.h"
#include "planner/cost_map.h"

/// @file
/// Approach through known space: when the goal lies in or behind space the map does not show
/// yet (unknown cells block), the pose nearest the goal that the robot can reach through known,
/// passable cells. Seed 004's AUV "only navigates through discovered cells": it drives to the
/// edge of what its sonar has shown towards the goal, and sees more from there.

namespace cairn::planner {

/// A breadth-first search from the start's cell over the cells where the footprint's inscribed
/// disc (with the planner's padding) clears every blocking cell, and near the start every
/// passable cell; of the cells reached where the robot can turn at any heading (its
/// circumscribed circle clear), the one nearest the goal, facing the goal when the footprint
/// fits so (else at one of 16 headings). nullopt when the start is outside the map or no such
/// cell is reached.
std::optional<common::Pose2> ApproachPose(const CostMap& map, const common::Pose2& start,
                                          const common::Vector2& goal);

}  // namespace cairn::planner
