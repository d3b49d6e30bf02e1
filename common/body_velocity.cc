#include "common/body_velocity.h"

namespace cairn::common {

BodyVelocityRequest BridgeVelocity(const Velocity& command, const std::string& frame) {
  BodyVelocityRequest r;
  r.frame = frame;
  r.requester = kBridgeRequester;
  r.goal_id = 0;
  r.priority = kPriorityNormal;
  r.twist = {command.linear_mps, 0.0, 0.0, 0.0, 0.0, command.angular_radps};
  r.disable_axis = {false, true, true, true, true, false};
  return r;
}

SurgeYaw SurgeYawOf(const BodyVelocityRequest& request) {
  SurgeYaw out;
  out.command.linear_mps = request.disable_axis[kSurge] ? 0.0 : request.twist[kSurge];
  out.command.angular_radps = request.disable_axis[kYaw] ? 0.0 : request.twist[kYaw];
  for (int axis : {kSway, kHeave, kRoll, kPitch}) {
    if (!request.disable_axis[axis] && request.twist[axis] != 0.0) out.ignored_axes = true;
  }
  return out;
}

}  // namespace cairn::common
