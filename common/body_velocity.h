#pragma once

#include <array>
#include <string>

#include "common/velocity_limits.h"

/// @file
/// Seed 004's velocity bridge (twist2bvr): a base-frame velocity command (forward speed and yaw
/// rate) becomes a body-velocity request with only surge and yaw commanded, and back: the
/// (v, w) a surge-and-yaw vehicle takes from a request.

namespace cairn::common {

enum BodyAxis { kSurge = 0, kSway = 1, kHeave = 2, kRoll = 3, kPitch = 4, kYaw = 5 };

struct BodyVelocityRequest {
  std::string frame;
  std::string requester;
  int goal_id{0};
  int priority{10};               ///< lcmt_body_velocity_request::PRIORITY_NORMAL
  std::array<double, 6> twist{};  ///< x, y, z (m/s), roll, pitch, yaw (rad/s)
  std::array<bool, 6> disable_axis{{true, true, true, true, true, true}};
};

inline constexpr char kBridgeRequester[] = "Twist2BVR";
inline constexpr int kPriorityNormal = 10;

/// The bridge: the command's twist copied (linear x, angular z), x and yaw enabled, every other
/// axis disabled, priority normal, requester "Twist2BVR", goal id 0, `frame` as given.
BodyVelocityRequest BridgeVelocity(const Velocity& command, const std::string& frame);

/// What a surge-and-yaw vehicle takes from a request.
struct SurgeYaw {
  Velocity command;  ///< disabled axes read as 0
  /// An enabled axis it cannot follow (sway, heave, roll, pitch) asked for a non-zero speed:
  /// that part of the request is ignored.
  bool ignored_axes{false};
};
SurgeYaw SurgeYawOf(const BodyVelocityRequest& request);

}  // namespace cairn::common
