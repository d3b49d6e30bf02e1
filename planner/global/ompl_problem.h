#pragma once

#include <memory>
#include <vector>

#include <ompl/base/OptimizationObjective.h>
#include <ompl/base/Planner.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/State.h>
#include <ompl/base/spaces/SE2StateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/SimpleSetup.h>

#include "common/types.h"
#include "planner/cost_map.h"
#include "planner/global/global_planner.h"

/// @file
/// The OMPL side of GlobalPlanner (internal to cairn::planner): the pieces of one planning
/// problem on a CostMap (state space and sampler, validity checker, goal, objective, planner)
/// and the conversions between OMPL states and poses.

namespace cairn::planner::internal {

namespace ob = ompl::base;
namespace og = ompl::geometric;

/// Routes OMPL's console output to the product log (once per process).
void InstallOmplLogForwarder();

/// A yaw in OMPL's SO(2) range [-pi, pi).
double OmplYaw(double yaw_rad);
/// An SE(2) state (also a Dubins or Reeds-Shepp one) as a pose.
common::Pose2 ToPose(const ob::State* state);
/// Length of the polyline through the poses' positions (m).
double PositionLength(const std::vector<common::Pose2>& poses);
/// Every pose of an interpolated path with the robot's own footprint (the padding used while
/// planning covers the space between these poses), and on a map with one-way cells every
/// motion between consecutive poses (CostMap::MotionAllowed).
bool PathStillValid(const CostMap& map, og::PathGeometric& path);

/// One plan's OMPL problem, set up (SimpleSetup::setup() called) and ready to solve.
struct OmplProblem {
  std::shared_ptr<ob::SE2StateSpace> space;
  std::unique_ptr<og::SimpleSetup> setup;
  ob::SpaceInformationPtr si;
  ob::OptimizationObjectivePtr objective;
  ob::PlannerPtr planner;
};

/// The problem of planning from `start` to `goal` on `map` (which must outlive it): the state
/// space of params.state_space bounded by the known cells, start and goal grown by
/// bounds_margin_m within the grid, sampling ridge cells and aligned headings; states checked
/// with the padded footprint away from the ends; on a map with one-way cells, motions also
/// checked for their direction of travel (CostMap::MotionAllowed); the goal a state
/// (`goal_has_yaw`) or the goal position with any of `goal_yaws`; the objective length plus
/// traversal cost; the named planner with its range.
OmplProblem SetUpProblem(const CostMap& map, const GlobalPlannerParams& params,
                         const common::Pose2& start, const common::Pose2& goal, bool goal_has_yaw,
                         const std::vector<double>& goal_yaws);

/// `path` with states spread evenly along every motion by OMPL's metric (position plus weighted
/// heading, or arc length for Dubins and Reeds-Shepp), never farther apart than `step_m`.
og::PathGeometric Interpolate(const ob::SpaceInformationPtr& si, og::PathGeometric& path,
                              double step_m);

/// A grid route (at least two points) as an OMPL path from `start`, headings along the route,
/// ending on `goal_state` (a goal state the planner accepts) in place of the route's last point.
og::PathGeometric RouteAsPath(const OmplProblem& problem,
                              const std::vector<common::Vector2>& points,
                              const common::Pose2& start, const ob::State* goal_state);

/// Makes a route from RouteAsPath drivable where it can: a state whose footprint is blocked at
/// the route's heading is turned to the nearest of 16 headings where it fits (or dropped when
/// none does), and a motion that fails its check is bridged by midpoints turned the same way.
/// The route keeps the footprint's inscribed disc off blocking cells, so what fails is the
/// footprint's corners at the route's heading (a diagonal gap an axis-aligned robot fits
/// through). False when some motion could not be bridged (the route is then partly repaired).
bool RepairRoute(const OmplProblem& problem, og::PathGeometric* route);

}  // namespace cairn::planner::internal
