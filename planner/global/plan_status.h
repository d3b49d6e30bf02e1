#pragma once

/// @file
/// Outcomes of a global plan (house style 8.4: expected outcomes are values). Each maps one to
/// one onto a REASON_* constant of lcmt_nav_status.

namespace cairn::planner {

enum class PlanStatus {
  kSuccess,        ///< an exact, re-validated path
  kStartOccupied,  ///< the footprint at the start touches a lethal (or blocking unknown) cell
  kGoalOccupied,   ///< no heading puts the footprint at the goal on free cells
  kOutOfBounds,    ///< start or goal lies outside the cost layer
  kNoPath,         ///< start and goal are not connected (proved on the grid)
  kTimedOut,       ///< the budget ran out without any solution
  kCancelled,      ///< the caller cancelled the plan
  kApproximate,    ///< the planner only came close to the goal: a failure, never a success
};

/// "SUCCESS", "START_OCCUPIED", ... (the lcmt_nav_status constant names without "REASON_").
const char* PlanStatusName(PlanStatus status);

}  // namespace cairn::planner
