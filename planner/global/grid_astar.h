#pragma once

#include <cstdint>
#include <vector>

#include "common/types.h"
#include "planner/cost_map.h"

/// @file
/// Grid A*: 8-connected search on the cost layer with the footprint's inscribed disc as the
/// inflation, and its any-angle variant (Theta*: Daniel, Nash, Koenig and Felner, JAIR 2010),
/// whose path segments join any two cells in line of sight instead of the 8 grid directions.
/// They are the benchmark baselines of the OMPL planner (and A* its grid route candidate), with
/// the same cost: length times (1 + weight · mean cell cost / 100 + clearance weight · mean
/// proximity). On a map with one-way cells (a directed layer) a step towards heading bin k, and
/// a Theta* segment of heading class k, is taken only when no one-way cell refusing that class
/// lies within the clearance disc of its cells (CostMap::MaybeConnected's rule).

namespace cairn::planner {

struct GridAStarParams {
  /// Multiplies the traversal cost (cost/100) added to each metre travelled.
  double traversal_cost_weight{1.0};
  /// Proximity cost as in GlobalPlannerParams (same weight and inflation by default).
  double clearance_weight{1.0};
  double clearance_inflation_m{0.4};
  /// A cell is passable when its centre is at least this far (m) from every blocking cell.
  /// Negative: the footprint's inscribed radius less (half a cell diagonal - half a cell), the
  /// most permissive inflation that never closes a gap the footprint fits through.
  double clearance_m{-1.0};
  /// Theta*: a cell's parent may be any cell in line of sight (every cell the straight segment
  /// between the two centres passes, sampled every quarter cell, passable); the segment's cost
  /// is integrated along it a cell apart (the OMPL objective's rule). Paths are nearly taut, so
  /// their length compares with a sampling planner's shortcut paths; 8-connected ones are up to
  /// 8 % longer than the straight line.
  bool any_angle{false};
};

struct GridPath {
  bool found{false};
  std::vector<common::Vector2> points_m;  ///< cell centres, world frame, start to goal
  double length_m{0.0};
  double cost{0.0};
  int64_t expanded{0};  ///< cells taken off the open list
};

/// Searches from the cell holding `start_m` to the cell holding `goal_m`. Not found when
/// either is outside the grid or impassable, or when they are not connected.
GridPath GridAStar(const CostMap& map, const common::Vector2& start_m,
                   const common::Vector2& goal_m, const GridAStarParams& params = {});

}  // namespace cairn::planner
