#pragma once

#include <string>
#include <vector>

#include "common/types.h"
#include "planner/cost_map.h"
#include "planner/local/trajectory_generator.h"

/// @file
/// Recovery behaviours, tried in order before a goal is declared failed (Nav2's behaviour
/// server: Spin, BackUp, DriveOnHeading, Wait, plus clearing the mapper's short-term layer). Each is a small
/// controller stepped once per control cycle; every command it returns lies inside the dynamic
/// window of the previous one, and motions stop when the footprint would hit something.

namespace cairn::planner {

enum class RecoveryKind { kRotate, kBackUp, kDriveForward, kWait, kClearShortTerm };

/// "rotate", "back_up", "drive_forward", "wait", "clear_short_term".
const char* RecoveryKindName(RecoveryKind kind);
/// @throws std::invalid_argument for an unknown name.
RecoveryKind RecoveryKindFromName(const std::string& name);

struct RecoveryParams {
  std::vector<RecoveryKind> sequence{RecoveryKind::kRotate, RecoveryKind::kBackUp,
                                     RecoveryKind::kDriveForward, RecoveryKind::kWait,
                                     RecoveryKind::kClearShortTerm};
  double rotate_angle_rad{1.57};  ///< how far "rotate" turns (Nav2 Spin default)
  double rotate_speed_radps{0.6};
  double backup_distance_m{0.3};
  double backup_speed_mps{0.1};
  double forward_distance_m{0.3};  ///< how far "drive_forward" drives (Nav2 DriveOnHeading)
  double forward_speed_mps{0.1};
  double wait_s{2.0};
  double clear_wait_s{1.0};           ///< pause after asking the mapper to clear
  double behaviour_timeout_s{15.0};   ///< a behaviour that has not finished by then stops
  double collision_lookahead_s{0.5};  ///< motions check the footprint this far ahead

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// One control cycle of a behaviour.
struct RecoveryStep {
  Velocity command;
  bool done{false};
  bool request_clear_short_term{false};  ///< ask the mapper to clear (once)
  /// Set when done: the behaviour's motion was blocked before it moved at all, so the next
  /// behaviour may start at once (a plan from the same pose would only meet the same pocket).
  bool blocked{false};
  std::string note;                      ///< set when done: how it ended
};

class RecoveryBehaviour {
 public:
  RecoveryBehaviour(const TrajectoryGenerator& generator, const RecoveryParams& params);

  /// Starts `kind` from `pose` at time now_s (seconds).
  void Start(RecoveryKind kind, const common::Pose2& pose, double now_s);
  /// Advances it. `map` may be null (motions then stop at once).
  RecoveryStep Step(const common::Pose2& pose, const Velocity& last_command, const CostMap* map,
                    double now_s);
  RecoveryKind kind() const { return kind_; }

 private:
  const TrajectoryGenerator& generator_;
  RecoveryParams params_;
  RecoveryKind kind_{RecoveryKind::kWait};
  common::Pose2 start_pose_;
  common::Pose2 last_pose_;
  double start_s_{0.0};
  double turned_rad_{0.0};
  double rotate_sign_{1.0};  ///< the direction "rotate" turns: counter-clockwise unless blocked
  bool clear_sent_{false};
  bool blocked_{false};
  bool stopping_{false};
  std::string stop_note_;
};

/// True when driving at constant `velocity` from `pose` keeps the footprint valid for
/// `lookahead_s` (checked every 0.1 s). When the footprint at `pose` already touches blocking
/// cells, those count as free (the robot may move away from them). On a map with one-way cells
/// each 0.1 s step must also be a motion they allow (CostMap::MotionAllowed): backing up a step
/// the robot may only drive down is not clear. False without a map.
bool MotionClear(const CostMap* map, const common::Pose2& pose, const Velocity& velocity,
                 double lookahead_s);

/// Yaw-rate command that turns by `error_rad` and stops there: as fast as allowed, but slow
/// enough to brake within the acceleration limit, then clipped to the dynamic window.
Velocity RotateInPlaceCommand(const TrajectoryGenerator& generator, const Velocity& last_command,
                              double error_rad, double max_speed_radps);

}  // namespace cairn::planner
