#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "common/types.h"
#include "planner/cost_map.h"
#include "planner/global/plan_status.h"

/// @file
/// GlobalPlanner: OMPL geometric planning in SE(2) (or Dubins / Reeds-Shepp) on a CostMap.
///
/// - States are checked by rasterising the footprint on the cost layer (CostMap::IsValid).
/// - The objective is path length plus traversal cost: the integral of
///   1 + traversal_cost_weight · cost / 100 + clearance_weight · proximity along the path.
/// - Only an exact solution counts; an approximate one is PlanStatus::kApproximate.
/// - Before OMPL runs, a grid connectivity check proves "no path" when the goal is not
///   connected to the start (sampling planners cannot prove infeasibility within a budget);
///   with unknown cells traversable, unknown space beyond unknown_horizon_m of the start is
///   not counted on for that check.
/// - States are checked with the footprint grown by CostMapParams::planning_padding_m (except
///   near the start and the goal), so poses between checked states keep clear as well.
/// - After the first exact solution (shortcut), a route searched on a coarse grid of the same
///   cost (CoarseGridRoute) is shortcut and offered as a candidate: it anchors the path to the
///   cheapest homotopy class in a few milliseconds. Only when it offers no valid path are a few
///   more solutions planned within a small budget and merged with OMPL's PathHybridization.
/// - The time budget bounds the whole call: the first solution, the refinement and the checks
///   share it. No exact solution within it: kTimedOut; a solution found but refinement cut
///   short: kSuccess with the best path so far (PlanResult::budget_exhausted).
/// - The simplified and interpolated path is checked again, pose by pose with the robot's own
///   footprint; if it fails, the unsimplified path is used instead.
/// - On a map with one-way cells (a directed layer, cost_map.h) motions are checked for their
///   direction of travel too (CostMap::MotionAllowed), and the connectivity proof follows the
///   one-way steps: up a step the profile may only drive down is kNoPath.

namespace cairn::planner {

enum class StateSpaceKind { kSE2, kDubins, kReedsShepp };

/// "se2", "dubins", "reeds_shepp". @throws std::invalid_argument for an unknown name.
StateSpaceKind StateSpaceKindFromName(const std::string& name);
const char* StateSpaceKindName(StateSpaceKind kind);

struct GlobalPlannerParams {
  /// OMPL planner: RRTConnect, RRTstar, InformedRRTstar, BITstar, PRMstar, or RRT (the one
  /// allowed with Dubins curves, which are directed).
  std::string planner{"RRTConnect"};
  StateSpaceKind state_space{StateSpaceKind::kSE2};
  /// Dubins and Reeds-Shepp turning radius.
  double turning_radius_m{0.5};
  /// Default time budget of one whole plan (every stage; see PlanRequest::time_budget_s).
  double time_budget_s{1.0};
  /// Optimising planners stop at their first exact solution instead of using the whole budget.
  bool stop_at_first_solution{true};
  /// Weight of the traversal cost against length (0: shortest path).
  double traversal_cost_weight{1.0};
  /// Weight of the proximity cost (0..1 per metre, growing as the distance to the nearest
  /// blocking cell falls below the inscribed radius plus clearance_inflation_m): keeps paths
  /// off walls and corners, since the cost layer itself has no inflation.
  double clearance_weight{1.0};
  double clearance_inflation_m{0.4};
  /// Spacing of the states checked along a motion (OMPL's validity checking resolution).
  double validity_resolution_m{0.05};
  /// The planner samples the bounding box of the known cells, the start and the goal, grown by
  /// this margin and clipped to the grid: a mapper's grid is mostly unexplored, and sampling all
  /// of it starves narrow passages of samples.
  double bounds_margin_m{5.0};
  /// Fraction of samples whose heading follows the local free space (along corridors, through
  /// doors) instead of being uniform; narrow passages admit only such headings.
  double aligned_heading_fraction{0.5};
  /// Fraction of samples placed on the medial axis of free space (the ridge cells of the
  /// distance field) instead of uniformly: the middle of corridors and doors.
  double ridge_sample_fraction{0.5};
  /// Planner range (longest motion added at once); 0 keeps OMPL's default.
  double range_m{0.0};
  /// Time cap of the path simplification passes.
  double simplify_time_s{0.05};
  /// When the grid route candidate offers no valid path (or is off): more exact solutions
  /// planned after the first, merged by PathHybridization (0: none) ...
  int improvement_rounds{12};
  /// ... within this time after the first solution.
  double improvement_time_s{0.25};
  /// Also offer the grid route on the same cost layer (CoarseGridRoute) (headings along it,
  /// shortcut by OMPL's simplifier, re-checked with the footprint) as one more candidate: a
  /// sampling planner that stops at its first solutions may take any homotopy class, such as a long
  /// detour through unexplored space, and the grid route anchors the choice to the cheapest class.
  /// The candidate counts only if it is valid and cheaper under the objective.
  bool grid_route_candidate{true};
  /// The grid route is searched over blocks of about this size (CoarseGridRoute: 16 times
  /// fewer nodes than the cost layer's 0.1 m cells at 0.4 m); the layer's resolution or less
  /// searches every cell. When the blocks' route does not fit the padded footprint (it keeps
  /// only the inscribed disc clear, and may pass a tight gap off centre), the route over every
  /// cell is tried before the candidate is dropped.
  double grid_route_cell_m{0.4};
  /// States closer than this to the start or the goal are checked without the padding, so a
  /// robot standing close to an obstacle can still leave (or reach) its spot.
  double escape_radius_m{0.6};
  /// Spacing of the returned poses.
  double interpolation_step_m{0.1};
  /// Goal position tolerance used by OMPL.
  double goal_tolerance_m{0.05};
  /// Headings tried when the goal has no yaw.
  int goal_yaw_samples{16};
  /// A start whose footprint touches blocking cells is moved to the nearest valid pose within
  /// this distance (the path then begins with the real start); beyond it: kStartOccupied.
  double start_rescue_radius_m{0.3};
  /// Run the grid connectivity proof before OMPL.
  bool grid_precheck{true};
  /// With unknown cells traversable, "no path" is also answered when the goal cannot be reached
  /// through known cells plus unknown cells within this distance of the start (or within
  /// unknown_goal_radius_m of the goal): routes through far unexplored space (gaps between
  /// distant lidar rings, unobserved stretches of wall) are not taken on faith. 0 (default):
  /// off, every unknown cell may be explored.
  double unknown_horizon_m{0.0};
  double unknown_goal_radius_m{2.0};
  /// Seed of OMPL's random number generators (0 is not allowed by OMPL).
  uint32_t seed{1};

  /// @throws std::invalid_argument naming the bad field (an unknown planner name included).
  void Validate() const;
};

struct PlanRequest {
  common::Pose2 start;
  common::Pose2 goal;
  bool goal_has_yaw{false};   ///< else any heading at the goal position will do
  double time_budget_s{0.0};  ///< 0: the params' budget
  /// > 0: a goal whose footprint is blocked moves to the nearest valid pose this close (any
  /// heading) instead of failing with kGoalOccupied; PlanResult::goal_moved_m says how far.
  double goal_shift_radius_m{0.0};
};

struct PlanResult {
  PlanStatus status{PlanStatus::kNoPath};
  std::string message;
  std::vector<common::Pose2> poses;  ///< world frame, start to goal, interpolated
  double length_m{0.0};              ///< of `poses`
  double raw_length_m{0.0};          ///< of the planner's path before simplification
  double cost{0.0};                  ///< objective cost of `poses`
  double solve_time_s{0.0};          ///< OMPL solve() time to the first exact solution
  int solutions{0};                  ///< exact solutions found (first plus improvements)
  double total_time_s{0.0};          ///< checks, solve, simplification and re-validation
  bool simplified{false};            ///< the simplified path passed re-validation
  bool grid_route_chosen{false};     ///< the grid route candidate beat the sampled paths
  /// The time budget ran out after the first exact solution: `poses` is the best path so far
  /// (still checked pose by pose), the refinement was cut short.
  bool budget_exhausted{false};
  double start_moved_m{0.0};  ///< how far an occupied start was moved to free space
  double goal_moved_m{0.0};   ///< how far an occupied goal was moved (goal_shift_radius_m)

  bool ok() const { return status == PlanStatus::kSuccess; }
};

/// Plans one path at a time per process: OMPL's seed generator is global, so plans are
/// serialised to stay reproducible.
class GlobalPlanner {
 public:
  /// @throws std::invalid_argument for invalid params.
  explicit GlobalPlanner(GlobalPlannerParams params);
  GlobalPlanner(const GlobalPlanner&) = delete;
  GlobalPlanner& operator=(const GlobalPlanner&) = delete;

  /// Plans on `map` (which must outlive the call). `cancel`, when given, is polled; setting it
  /// ends the plan with kCancelled. Never throws for a bad start or goal: those are statuses.
  PlanResult Plan(const CostMap& map, const PlanRequest& request,
                  const std::atomic<bool>* cancel = nullptr) const;

  const GlobalPlannerParams& params() const { return params_; }

 private:
  GlobalPlannerParams params_;
};

/// Planner names accepted by GlobalPlannerParams::planner.
const std::vector<std::string>& KnownPlannerNames();

}  // namespace cairn::planner
