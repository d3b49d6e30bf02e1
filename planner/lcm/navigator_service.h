#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_nav_status.hpp"
#include "cairn/lcmt_odometry.hpp"
#include "cairn/lcmt_pose.hpp"

#include "common/robot_profile.h"
#include "planner/global/global_planner.h"
#include "planner/lcm/lcm_map_client.h"
#include "planner/navigator.h"
#include "planner/navigator_config.h"
#include "planner/places.h"
#include "services/runtime/node.h"

/// @file
/// NavigatorService: cairn-navigator's LCM side, one robot per process.
///
/// Reads  <robot>.GOAL (lcmt_goal), <robot>.POSE (lcmt_pose) or <robot>.ODOM (lcmt_odometry),
///        <robot>.MAP.TILES / <robot>.MAP.MANIFEST (the "cost/<profile>" layer), SIM.CLOCK.
/// Writes <robot>.CMD_VEL (lcmt_velocity_command), <robot>.PATH (lcmt_path),
///        <robot>.NAV_STATUS (lcmt_nav_status: on every change and at status_rate_hz),
///        <robot>.MAP.TILE_RESEND (missing tiles), <robot>.MAP.CONTROL (clear short-term layer).
///
/// Times are the node's clock: simulation time when SIM.CLOCK runs, wall time otherwise.
/// Global plans run on a worker thread so the control loop keeps its rate (and its safety
/// stop) while OMPL works; a new plan cancels the running one.

namespace cairn::planner {

class NavigatorService {
 public:
  /// Subscribes on `node` and adds the control and status timers.
  /// @throws std::invalid_argument for an invalid profile or configuration.
  NavigatorService(runtime::Node& node, NavigatorConfig config, common::RobotProfile profile,
                   std::vector<Place> places);
  ~NavigatorService();
  NavigatorService(const NavigatorService&) = delete;
  NavigatorService& operator=(const NavigatorService&) = delete;

  /// One control cycle (the control timer calls it).
  void Tick();
  /// The wall timer: a tick, unless control_clock is pose and the poses ticked lately.
  void OnControlTimer();
  /// Publishes the navigation status now.
  void PublishStatus();
  /// Blocks until no plan is queued or running (its result waits for the next Tick), or until
  /// `timeout_s` of wall time passed; returns whether the planner is idle. For tests that drive
  /// the service's clock themselves: plans run in wall time on the worker thread.
  bool WaitForPlanner(double timeout_s);
  /// The newest cost map the map client built (tests).
  std::shared_ptr<const CostMap> latest_map() const { return map_client_.Latest(); }

  const Navigator& navigator() const { return navigator_; }
  const LcmMapClient& map_client() const { return map_client_; }
  /// The status message of the current state (for tests and logs).
  cairn::lcmt_nav_status MakeStatus() const;

  void OnGoal(const cairn::lcmt_goal& goal);
  void OnPose(const cairn::lcmt_pose& pose);
  void OnOdometry(const cairn::lcmt_odometry& odometry);

 private:
  struct Job {
    PlanJob job;
  };
  void WorkerLoop();
  void StartPlan(PlanJob job);
  void CancelPlan();
  void HandlePlanResults(double now_s);
  void FeedMap();
  void AskToClearShortTerm();
  void PublishCommand(const Velocity& command, bool emergency_stop);
  void PublishPath();
  void ReportState(bool status_changed);
  void AcceptPose(const common::Pose3& pose, int64_t utime);
  void RefuseGoal(const cairn::lcmt_goal& goal, const std::string& why);
  double NowS() const { return static_cast<double>(node_.NowUtime()) * 1e-6; }

  runtime::Node& node_;
  NavigatorConfig config_;
  common::RobotProfile profile_;
  std::string robot_;
  Navigator navigator_;
  GlobalPlanner planner_;
  LcmMapClient map_client_;
  std::shared_ptr<const CostMap> fed_map_;
  int64_t fed_heard_utime_{0};
  std::chrono::steady_clock::time_point last_tick_wall_{};
  int64_t last_tick_stamp_{0};  ///< the pose stamp of the last pose-paced tick
  int64_t map_control_requests_{0};
  NavState last_logged_state_{NavState::kIdle};
  NavReason last_logged_reason_{NavReason::kNone};
  int64_t last_logged_goal_{-1};
  int64_t last_goal_id_{0};  // the newest goal id taken (re-sends of it are ignored)
  bool stopped_degraded_{false};

  // Planner worker: one job at a time, the newest wins.
  std::thread worker_;
  std::mutex worker_mutex_;
  std::condition_variable worker_cv_;
  std::condition_variable idle_cv_;  // a job finished
  bool worker_exit_{false};
  bool worker_busy_{false};  // a job is being planned
  std::optional<PlanJob> queued_;
  std::atomic<bool> cancel_current_{false};
  std::vector<std::pair<int64_t, PlanResult>> results_;
};

}  // namespace cairn::planner
