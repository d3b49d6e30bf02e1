#pragma once

#include <functional>

#include "common/types.h"
#include "planner/cost_map.h"
#include "planner/global/grid_astar.h"

/// @file
/// A coarse grid route for the global planner's grid route candidate: A* over blocks of
/// `stride_cells` x `stride_cells` cells of the cost layer, each block stood for by its cell
/// farthest from blocking cells (the start's and the goal's blocks by their own cells), two
/// neighbouring blocks joined when the straight segment between their cells keeps every cell
/// it passes passable (the grid A*'s rule: the footprint's inscribed disc fits). The cost is the
/// grid A*'s (length times 1 + mean traversal / 100, proximity folded in), integrated a cell
/// apart along each segment. With a stride of 4 the search visits 16 times fewer nodes than
/// the 8-connected A*; a passage narrower than a block may be missed (no route then), which
/// only drops the candidate. A stride of 1 searches the full grid.

namespace cairn::planner {

struct CoarseRouteParams {
  int stride_cells{4};
  double traversal_cost_weight{1.0};
  double clearance_weight{1.0};
  double clearance_inflation_m{0.4};
  /// Within this distance of the start or the goal a cell takes the robot's own footprint,
  /// farther away the padded one (GlobalPlannerParams::escape_radius_m: the OMPL problem's check).
  double escape_radius_m{0.6};
};

/// The route from the cell of `start_m` to the cell of `goal_m` (points at the cells standing
/// for the blocks, start and goal cells included), or not found: either end outside the grid or
/// impassable, no route over the blocks, or `stop` (polled every few hundred expansions, may be
/// empty) returned true.
GridPath CoarseGridRoute(const CostMap& map, const common::Vector2& start_m,
                         const common::Vector2& goal_m, const CoarseRouteParams& params,
                         const std::function<bool()>& stop = {});

}  // namespace cairn::planner
