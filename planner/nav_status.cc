#include "planner/nav_status.h"

namespace cairn::planner {

const char* NavStateName(NavState state) {
  switch (state) {
    case NavState::kIdle:
      return "IDLE";
    case NavState::kPlanning:
      return "PLANNING";
    case NavState::kDriving:
      return "DRIVING";
    case NavState::kRecovering:
      return "RECOVERING";
    case NavState::kReached:
      return "REACHED";
    case NavState::kFailed:
      return "FAILED";
    case NavState::kCancelled:
      return "CANCELLED";
    case NavState::kStopped:
      return "STOPPED";
  }
  return "UNKNOWN";
}

const char* NavReasonName(NavReason reason) {
  switch (reason) {
    case NavReason::kNone:
      return "NONE";
    case NavReason::kSuccess:
      return "SUCCESS";
    case NavReason::kStartOccupied:
      return "START_OCCUPIED";
    case NavReason::kGoalOccupied:
      return "GOAL_OCCUPIED";
    case NavReason::kOutOfBounds:
      return "OUT_OF_BOUNDS";
    case NavReason::kNoPath:
      return "NO_PATH";
    case NavReason::kTimedOut:
      return "TIMED_OUT";
    case NavReason::kCancelled:
      return "CANCELLED";
    case NavReason::kApproximate:
      return "APPROXIMATE";
    case NavReason::kStaleOdom:
      return "STALE_ODOM";
    case NavReason::kStaleMap:
      return "STALE_MAP";
    case NavReason::kUnknownPlace:
      return "UNKNOWN_PLACE";
    case NavReason::kRecoveryExhausted:
      return "RECOVERY_EXHAUSTED";
    case NavReason::kNoMap:
      return "NO_MAP";
  }
  return "UNKNOWN";
}

NavReason ReasonOf(PlanStatus status) {
  switch (status) {
    case PlanStatus::kSuccess:
      return NavReason::kSuccess;
    case PlanStatus::kStartOccupied:
      return NavReason::kStartOccupied;
    case PlanStatus::kGoalOccupied:
      return NavReason::kGoalOccupied;
    case PlanStatus::kOutOfBounds:
      return NavReason::kOutOfBounds;
    case PlanStatus::kNoPath:
      return NavReason::kNoPath;
    case PlanStatus::kTimedOut:
      return NavReason::kTimedOut;
    case PlanStatus::kCancelled:
      return NavReason::kCancelled;
    case PlanStatus::kApproximate:
      return NavReason::kApproximate;
  }
  return NavReason::kNone;
}

}  // namespace cairn::planner
