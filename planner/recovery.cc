#include "planner/recovery.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "common/check.h"

namespace cairn::planner {

using common::Pose2;

namespace {

constexpr double kDoneAngleRad = 0.05;

std::string Format(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, value);
  return buf;
}

bool Stopped(const Velocity& v) {
  return std::abs(v.linear_mps) < 1e-9 && std::abs(v.angular_radps) < 1e-9;
}

}  // namespace

const char* RecoveryKindName(RecoveryKind kind) {
  switch (kind) {
    case RecoveryKind::kRotate:
      return "rotate";
    case RecoveryKind::kBackUp:
      return "back_up";
    case RecoveryKind::kDriveForward:
      return "drive_forward";
    case RecoveryKind::kWait:
      return "wait";
    case RecoveryKind::kClearShortTerm:
      return "clear_short_term";
  }
  return "wait";
}

RecoveryKind RecoveryKindFromName(const std::string& name) {
  if (name == "rotate") return RecoveryKind::kRotate;
  if (name == "back_up") return RecoveryKind::kBackUp;
  if (name == "drive_forward") return RecoveryKind::kDriveForward;
  if (name == "wait") return RecoveryKind::kWait;
  if (name == "clear_short_term") return RecoveryKind::kClearShortTerm;
  CAIRN_THROW_UNLESS(false,
                     "unknown recovery '" << name
                                          << "' (rotate, back_up, drive_forward, wait, "
                                             "clear_short_term)");
  return RecoveryKind::kWait;
}

void RecoveryParams::Validate() const {
  CAIRN_THROW_UNLESS(rotate_angle_rad > 0.0, "rotate_angle_rad must be positive");
  CAIRN_THROW_UNLESS(rotate_speed_radps > 0.0, "rotate_speed_radps must be positive");
  CAIRN_THROW_UNLESS(backup_distance_m > 0.0, "backup_distance_m must be positive");
  CAIRN_THROW_UNLESS(backup_speed_mps > 0.0, "backup_speed_mps must be positive");
  CAIRN_THROW_UNLESS(forward_distance_m > 0.0, "forward_distance_m must be positive");
  CAIRN_THROW_UNLESS(forward_speed_mps > 0.0, "forward_speed_mps must be positive");
  CAIRN_THROW_UNLESS(wait_s >= 0.0, "wait_s must not be negative");
  CAIRN_THROW_UNLESS(clear_wait_s >= 0.0, "clear_wait_s must not be negative");
  CAIRN_THROW_UNLESS(behaviour_timeout_s > 0.0, "behaviour_timeout_s must be positive");
  CAIRN_THROW_UNLESS(collision_lookahead_s > 0.0, "collision_lookahead_s must be positive");
}

bool MotionClear(const CostMap* map, const Pose2& pose, const Velocity& v, double lookahead_s) {
  if (map == nullptr) return false;
  // A robot already touching blocking cells may move as long as it touches no others.
  const std::vector<int64_t> escaping =
      map->IsValid(pose) ? std::vector<int64_t>{} : map->BlockingCellsUnder(pose);
  const double step = 0.1;
  Pose2 previous = pose;  // one-way cells: each step's direction of travel too
  for (double t = step; t <= lookahead_s + 1e-9; t += step) {
    const double yaw = pose.yaw_rad + v.angular_radps * t;
    Pose2 p = pose;
    if (std::abs(v.angular_radps) < 1e-9) {
      p.x_m += v.linear_mps * t * std::cos(pose.yaw_rad);
      p.y_m += v.linear_mps * t * std::sin(pose.yaw_rad);
    } else {
      const double r = v.linear_mps / v.angular_radps;
      p.x_m += r * (std::sin(yaw) - std::sin(pose.yaw_rad));
      p.y_m -= r * (std::cos(yaw) - std::cos(pose.yaw_rad));
    }
    p.yaw_rad = common::WrapAngle(yaw);
    const bool valid =
        escaping.empty() ? map->IsValid(p) : map->CheckFootprintIgnoring(p, escaping).valid;
    if (!valid || !map->MotionAllowed(previous, p)) return false;
    previous = p;
  }
  return true;
}

Velocity RotateInPlaceCommand(const TrajectoryGenerator& generator, const Velocity& last_command,
                              double error_rad, double max_speed_radps) {
  const double acc = generator.limits().acc_lim_theta_radps2;
  // Fastest speed from which the remaining angle still suffices to brake.
  const double braking = std::sqrt(2.0 * acc * std::abs(error_rad));
  const double speed = std::min({max_speed_radps, generator.limits().max_vel_theta_radps, braking});
  return generator.Toward(last_command, {0.0, std::copysign(speed, error_rad)});
}

RecoveryBehaviour::RecoveryBehaviour(const TrajectoryGenerator& generator,
                                     const RecoveryParams& params)
    : generator_(generator), params_(params) {
  params_.Validate();
}

void RecoveryBehaviour::Start(RecoveryKind kind, const Pose2& pose, double now_s) {
  kind_ = kind;
  start_pose_ = pose;
  last_pose_ = pose;
  start_s_ = now_s;
  turned_rad_ = 0.0;
  rotate_sign_ = 1.0;
  clear_sent_ = false;
  blocked_ = false;
  stopping_ = false;
  stop_note_.clear();
}

RecoveryStep RecoveryBehaviour::Step(const Pose2& pose, const Velocity& last_command,
                                     const CostMap* map, double now_s) {
  RecoveryStep out;
  turned_rad_ += std::abs(common::WrapAngle(pose.yaw_rad - last_pose_.yaw_rad));
  last_pose_ = pose;
  auto stop = [&](const std::string& note) {
    stopping_ = true;
    stop_note_ = note;
  };
  // A motion blocked before the behaviour moved: the next one may start at once.
  auto blocked = [&](const std::string& note) {
    blocked_ = (pose.position() - start_pose_.position()).norm() < 0.01 && turned_rad_ < 0.02;
    stop(note);
  };
  // Straight at `speed_mps` (negative: backwards) until `distance_m` from the start, unless the
  // footprint ahead would hit something.
  auto straight = [&](double speed_mps, double distance_m, const char* moved_format,
                      const char* blocked_note) {
    const double travelled = (pose.position() - start_pose_.position()).norm();
    if (travelled >= distance_m) {
      stop(Format(moved_format, travelled));
      return;
    }
    const Velocity target{speed_mps, 0.0};
    if (!MotionClear(map, pose, target, params_.collision_lookahead_s)) {
      blocked(blocked_note);
      return;
    }
    out.command = generator_.Toward(last_command, target);
  };
  if (!stopping_ && now_s - start_s_ > params_.behaviour_timeout_s) stop("timed out");

  if (!stopping_) {
    switch (kind_) {
      case RecoveryKind::kRotate: {
        const double remaining = params_.rotate_angle_rad - turned_rad_;
        if (remaining <= kDoneAngleRad) {
          stop(Format("turned %.2f rad", turned_rad_));
          break;
        }
        const auto clear = [&](double sign) {
          return MotionClear(map, pose, {0.0, sign * params_.rotate_speed_radps},
                             params_.collision_lookahead_s);
        };
        // Counter-clockwise, or clockwise where only that way is clear (checked before it
        // turns: once turning, it keeps its direction).
        bool turn_clear = clear(rotate_sign_);
        if (!turn_clear && turned_rad_ < 0.02 && clear(-rotate_sign_)) {
          rotate_sign_ = -rotate_sign_;
          turn_clear = true;
        }
        if (!turn_clear) {
          blocked("rotation blocked");
          break;
        }
        out.command = RotateInPlaceCommand(generator_, last_command, rotate_sign_ * remaining,
                                           params_.rotate_speed_radps);
        break;
      }
      case RecoveryKind::kBackUp: {
        const double reverse = -generator_.limits().min_vel_x_mps;
        if (reverse <= 0.0) {
          stop("the profile cannot reverse");
          break;
        }
        straight(-std::min(params_.backup_speed_mps, reverse), params_.backup_distance_m,
                 "backed up %.2f m", "backing up is blocked");
        break;
      }
      case RecoveryKind::kDriveForward: {
        // Out of a pocket the other way: where turning and reversing touch something, the way
        // ahead may be the one that is clear.
        const double forward = generator_.limits().max_vel_x_mps;
        if (forward <= 0.0) {
          blocked("driving forward is blocked");
          break;
        }
        straight(std::min(params_.forward_speed_mps, forward), params_.forward_distance_m,
                 "drove forward %.2f m", "driving forward is blocked");
        break;
      }
      case RecoveryKind::kWait:
        out.command = generator_.Brake(last_command);
        if (now_s - start_s_ >= params_.wait_s) {
          out.done = Stopped(out.command);
          if (out.done) out.note = "waited";
        }
        return out;
      case RecoveryKind::kClearShortTerm:
        if (!clear_sent_) {
          out.request_clear_short_term = true;
          clear_sent_ = true;
        }
        out.command = generator_.Brake(last_command);
        if (now_s - start_s_ >= params_.clear_wait_s) {
          out.done = Stopped(out.command);
          if (out.done) out.note = "asked the mapper to clear the short-term layer";
        }
        return out;
    }
  }
  if (stopping_) {
    // Brake within the acceleration limits; done once at rest.
    out.command = generator_.Brake(last_command);
    if (Stopped(out.command)) {
      out.done = true;
      out.note = stop_note_;
      out.blocked = blocked_;
    }
  }
  return out;
}

}  // namespace cairn::planner
