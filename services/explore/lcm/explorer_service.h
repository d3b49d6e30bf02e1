#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "cairn/lcmt_explore_status.hpp"
#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_nav_status.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"

#include "common/grid_map.h"
#include "common/robot_profile.h"
#include "planner/lcm/lcm_map_client.h"
#include "services/explore/explorer_config.h"
#include "services/explore/frontier_explorer.h"
#include "services/explore/nbv_mission.h"
#include "services/explore/reactive_explorer.h"
#include "services/runtime/node.h"

/// @file
/// ExplorerService: cairn-explorer's LCM side, one robot per process.
///
/// Reactive modes (reactive, stateless):
///   reads  <robot>.SCAN (lcmt_laser_scan), <robot>.POSE (for the distance driven);
///   writes <robot>.CMD_VEL (lcmt_velocity_command, one per scan; zero when the scans stop, at
///          the end and on shutdown).
/// Frontier mode:
///   reads  <robot>.MAP.OCCUPANCY / <robot>.MAP.MANIFEST (the 2-D occupancy layer),
///          <robot>.POSE, <robot>.NAV_STATUS (the navigator's result for each goal);
///   writes <robot>.GOAL (lcmt_goal: a frontier's goal, or a cancel), <robot>.MAP.TILE_RESEND.
/// Next-best-view mode (seed 002, stop and scan):
///   reads  <robot>.TURRET_SCAN (the turret's lines), <robot>.POSE, <robot>.NAV_STATUS,
///          SIM.CONTROL_REPLY (refused scan requests are logged);
///   writes SIM.CONTROL (OP_TRIGGER_SENSOR "<robot>/<turret>": one full sweep, asked when the
///          robot has stood still nbv.settle_s), <robot>.GOAL (each view point, or a cancel).
/// All write <robot>.EXPLORE_STATUS (lcmt_explore_status) at status_rate_hz and on every
/// change of state. Times are simulation time (the scans' stamps, SIM.CLOCK).

namespace cairn::explore {

class ExplorerService {
 public:
  /// Subscribes on `node` and adds the timers.
  /// @throws std::invalid_argument for an invalid configuration or profile.
  ExplorerService(runtime::Node& node, ExplorerConfig config, common::RobotProfile profile);
  ~ExplorerService();
  ExplorerService(const ExplorerService&) = delete;
  ExplorerService& operator=(const ExplorerService&) = delete;

  /// Handlers and the periodic step (public for tests over memq://).
  void OnScan(const cairn::lcmt_laser_scan& msg);
  void OnPose(const cairn::lcmt_pose& msg);
  void OnNavStatus(const cairn::lcmt_nav_status& msg);
  void OnTurretLine(const cairn::lcmt_laser_scan& msg);
  void Tick();
  void PublishStatus();
  /// Stops the robot (reactive: a zero command; frontier: cancels the goal).
  void Halt(const std::string& why);
  /// After the loop, outside every LCM handler (it talks to the map store): the next-best-view
  /// summary table, the save to the map store (save_to) and the renders (out_dir). Once.
  void WrapUp();

  bool done() const { return done_; }
  /// Done, but the mission failed (next-best-view: scans or goals kept failing).
  bool failed() const { return nbv_ && nbv_->failed(); }
  const cairn::lcmt_explore_status& status() const { return status_; }
  /// The next-best-view mission (nullptr in the other modes).
  const NbvMission* nbv() const { return nbv_.get(); }

 private:
  double NowS() const;
  void PublishCommand(double v_mps, double omega_radps);
  void Finish(const std::string& why);
  void SendGoal(const FrontierAction& action);
  void SetBehaviour(const std::string& behaviour, const std::string& message = "");
  void TickNbv(double now_s);
  void CarryOut(const NbvAction& action, double now_s);
  void SendScanRequest();
  void SendNbvGoal(const Candidate& goal);
  void UpdateNbvStatus();
  void SaveInfoMap();
  void OnSimControlReply(const cairn::lcmt_sim_control_reply& msg);

  runtime::Node& node_;
  ExplorerConfig config_;
  common::RobotProfile profile_;
  std::string robot_;
  ReactiveExplorer reactive_;
  StatelessExplorer stateless_;
  FrontierExplorer frontier_;
  std::unique_ptr<planner::LcmMapClient> map_client_;
  std::shared_ptr<const planner::CostMap> grid_source_;  ///< the snapshot grid_ was made from
  common::GridMap grid_;
  cairn::lcmt_explore_status status_{};
  std::optional<double> start_s_;
  std::optional<double> last_scan_node_s_;
  bool stopped_for_silence_{false};
  std::optional<common::Vector2> last_xy_;
  common::Vector2 robot_xy_{0.0, 0.0};
  bool have_pose_{false};
  bool done_{false};
  // Next-best-view mode.
  std::unique_ptr<NbvMission> nbv_;
  std::optional<double> trigger_at_s_;  ///< ask the turret for a scan at this time
  std::optional<int64_t> nbv_goal_id_;
  /// Teleport drive: the OP_RESET_ROBOT request that carries the robot to the view point.
  std::optional<int64_t> teleport_request_;
  std::vector<common::Vector2> teleport_path_m_;
  int64_t next_goal_id_{1};
  int64_t next_request_id_{1};
  bool wrapped_up_{false};
};

}  // namespace cairn::explore
