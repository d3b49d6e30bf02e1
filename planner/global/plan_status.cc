#include "planner/global/plan_status.h"

namespace cairn::planner {

const char* PlanStatusName(PlanStatus status) {
  switch (status) {
    case PlanStatus::kSuccess:
      return "SUCCESS";
    case PlanStatus::kStartOccupied:
      return "START_OCCUPIED";
    case PlanStatus::kGoalOccupied:
      return "GOAL_OCCUPIED";
    case PlanStatus::kOutOfBounds:
      return "OUT_OF_BOUNDS";
    case PlanStatus::kNoPath:
      return "NO_PATH";
    case PlanStatus::kTimedOut:
      return "TIMED_OUT";
    case PlanStatus::kCancelled:
      return "CANCELLED";
    case PlanStatus::kApproximate:
      return "APPROXIMATE";
  }
  return "UNKNOWN";
}

}  // namespace cairn::planner
