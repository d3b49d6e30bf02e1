#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/types.h"

/// @file
/// Frontier exploration on a 2-D occupancy grid (Yamauchi 1997, as in ROS explore_lite): the
/// frontier-based goal selector that seed 003 names as its first future-work item (§3.6, §6.5).
///
/// Cells. The layer holds occupancy as 100·p (layers::kOccupancy) with NaN for unknown. A cell
/// is free when its value is below free_threshold, occupied above occupied_threshold, unknown
/// when NaN; anything else is uncertain (neither free nor unknown: not traversable and not a
/// frontier). Cells outside the grid are not unknown: the grid edge is no frontier.
///
/// Frontiers. A frontier cell is a free cell with at least one unknown 4-neighbour. Frontier
/// cells are grouped into 8-connected clusters; a cluster's size is its number of cells times
/// the resolution (explore_lite's measure), and clusters smaller than min_frontier_size_m are
/// dropped.
///
/// Reachability. A Dijkstra search runs from the robot's cell over free cells, 8-connected
/// (step length one cell or √2 cells); a diagonal step needs both cells it cuts past to be free,
/// so the search never slips through a diagonal wall or round an unknown corner. The robot's own
/// cell is the start whatever its value: the robot stands there, so an unknown (or uncertain,
/// or occupied) cell under it counts as free. Cells closer than clearance_m (centre to centre)
/// to an occupied cell may only be entered without getting closer to the nearest occupied cell
/// than the cell being left: a robot that starts near a wall can move away from it, but the
/// search never squeezes into a gap narrower than the clearance. A frontier none of whose cells
/// is reached is dropped.
///
/// Goal and cost. A frontier's goal candidates are its reached cells: first those at least
/// goal_clearance_m (centre to centre) from every occupied cell, nearest the centroid first, then
/// the others in the same order (ties: the shorter path, then the lower cell index). The robot
/// must fit at its goal whatever way it faces, and a cell beside a wall is often a cell the
/// navigator refuses (GOAL_OCCUPIED) however near the centroid it lies. The goal is the first
/// candidate, `distance_m` the Dijkstra path length from the robot to it, and
/// cost = potential_scale·distance_m − gain_scale·size_m (explore_lite's weights, with the path
/// length in place of its straight-line distance): low cost is better.
///
/// Failed goals. ChooseFrontierGoal skips the candidates within blacklist_radius_m of a failed
/// goal and takes the frontier's next one, so a frontier is given up only when all its reached
/// cells are near failed goals (explore_lite gives up the whole frontier at its first failure).
///
/// Cost. Time and memory (about 20 bytes per cell) grow with the number of cells of the whole
/// grid, plus (2·r/resolution + 1)² per occupied cell, r the larger of clearance_m and
/// goal_clearance_m: pass the local window being explored, not a site-sized grid.

namespace cairn::explore {

struct FrontierParams {
  float free_threshold{25.f};       ///< known cells with a value (100·p) below this are free
  float occupied_threshold{65.f};   ///< cells with a value above this are occupied
  double min_frontier_size_m{0.5};  ///< smaller clusters are dropped (explore_lite default)
  double potential_scale{3.0};      ///< weight of the path distance (explore_lite default)
  double gain_scale{1.0};           ///< weight of the frontier size (explore_lite default)
  /// Keep-out distance from occupied cells for the reachability search (about the robot's
  /// radius: the P3DX half-width is about 0.19 m). 0: only occupied cells block.
  double clearance_m{0.2};
  /// Goal cells at least this far (centre to centre) from every occupied cell are preferred:
  /// about the robot's circumscribed radius plus a cell (the P3DX's is 0.30 m), so that the
  /// footprint fits at the goal in any heading. 0: every reached cell is as good.
  double goal_clearance_m{0.35};
  /// A goal candidate within this distance (inclusive) of a failed goal is skipped by
  /// ChooseFrontierGoal (explore_lite: 5 cells, 0.25 m at 0.05 m).
  double blacklist_radius_m{0.25};

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// A reached cell of a frontier that may serve as its goal.
struct FrontierGoalCandidate {
  common::CellIndex cell;
  common::Vector2 position_m{0.0, 0.0};  ///< its centre, world metres
  double distance_m{0.0};                ///< path length from the robot
  bool clear{false};                     ///< at least goal_clearance_m from occupied cells
};

struct Frontier {
  std::vector<common::CellIndex> cells;  ///< the cluster's cells, by linear index
  double size_m{0.0};                    ///< cells.size() · resolution
  common::Vector2 centroid_m{0.0, 0.0};  ///< mean of the cell centres, world metres
  /// The reached cells in order of preference (see the file comment); never empty.
  std::vector<FrontierGoalCandidate> candidates;
  common::CellIndex goal_cell;       ///< the chosen candidate (the first, unless blacklisted)
  common::Vector2 goal_m{0.0, 0.0};  ///< its centre, world metres
  double distance_m{0.0};            ///< path length from the robot to the goal
  double cost{0.0};                  ///< potential_scale·distance_m − gain_scale·size_m
};

/// potential_scale·distance_m − gain_scale·size_m: a frontier's cost with its goal that far.
inline double FrontierCost(const FrontierParams& params, double distance_m, double size_m) {
  return params.potential_scale * distance_m - params.gain_scale * size_m;
}

/// All reachable frontiers of `layer` seen from `robot_m` (world metres), sorted by
/// increasing cost (ties: shorter distance, then lower goal index).
/// @throws std::invalid_argument for invalid params, a missing layer, or a robot position that
/// is not finite or lies outside the grid.
std::vector<Frontier> FindFrontiers(const common::GridMap& map, const std::string& layer,
                                    const common::Vector2& robot_m,
                                    const FrontierParams& params = {});

/// The lowest-cost frontier with a goal candidate farther than blacklist_radius_m from every
/// failed goal (world metres), its goal, distance and cost those of its first such candidate;
/// nullopt when there is none (exploration finished or all blacklisted). A frontier without
/// candidates (built by hand) stands for its goal alone. Does not assume `frontiers` is sorted;
/// among equal costs the first wins.
/// @throws std::invalid_argument for invalid params or a non-finite failed goal.
std::optional<Frontier> ChooseFrontierGoal(const std::vector<Frontier>& frontiers,
                                           const std::vector<common::Vector2>& failed_goals_m,
                                           const FrontierParams& params = {});

/// FindFrontiers followed by ChooseFrontierGoal.
std::optional<Frontier> ChooseFrontierGoal(const common::GridMap& map, const std::string& layer,
                                           const common::Vector2& robot_m,
                                           const std::vector<common::Vector2>& failed_goals_m,
                                           const FrontierParams& params = {});

}  // namespace cairn::explore
