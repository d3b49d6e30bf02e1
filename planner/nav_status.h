#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "planner/global/plan_status.h"

/// @file
/// The navigator's status vocabulary: its states and reasons (one to one with lcmt_nav_status's
/// STATE_* and REASON_* constants) and the status it reports.

namespace cairn::planner {

/// Navigation states; values equal lcmt_nav_status STATE_* constants.
enum class NavState : int8_t {
  kIdle = 0,
  kPlanning = 1,
  kDriving = 2,
  kRecovering = 3,
  kReached = 4,
  kFailed = 5,
  kCancelled = 6,
  kStopped = 7,
};

/// Why the navigator is in its state; values equal lcmt_nav_status REASON_* constants. The
/// plan outcomes map one to one onto PlanStatus.
enum class NavReason : int8_t {
  kNone = 0,
  kSuccess = 1,
  kStartOccupied = 2,
  kGoalOccupied = 3,
  kOutOfBounds = 4,
  kNoPath = 5,
  kTimedOut = 6,
  kCancelled = 7,
  kApproximate = 8,
  kStaleOdom = 9,
  kStaleMap = 10,
  kUnknownPlace = 11,
  kRecoveryExhausted = 12,
  kNoMap = 13,
};

const char* NavStateName(NavState state);
const char* NavReasonName(NavReason reason);
NavReason ReasonOf(PlanStatus status);

/// What the navigator reports about its goal (lcmt_nav_status without the transport).
struct NavStatus {
  int64_t goal_id{0};
  NavState state{NavState::kIdle};
  NavReason reason{NavReason::kNone};
  std::string message;
  double progress{0.0};              ///< 0..1 along the current path
  double distance_remaining_m{0.0};  ///< along the path from the robot
  double distance_travelled_m{0.0};
  int32_t replans{0};
  int32_t recoveries{0};
  std::vector<std::string> critic_names;
  std::vector<int64_t> critic_rejections;
};

}  // namespace cairn::planner
