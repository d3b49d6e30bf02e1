#include "common/obstacle.h"

namespace cairn::common {

const char* ObstacleKindName(ObstacleKind kind) {
  switch (kind) {
    case ObstacleKind::kRamp:
      return "ramp";
    case ObstacleKind::kStepUp:
      return "step_up";
    case ObstacleKind::kStepDown:
      return "step_down";
    case ObstacleKind::kDitch:
      return "ditch";
    case ObstacleKind::kWallOrObject:
      return "wall_or_object";
    case ObstacleKind::kTerrace:
      return "terrace";
  }
  return "unknown";
}

}  // namespace cairn::common
