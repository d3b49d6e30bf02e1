#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "common/types.h"
#include "services/explore/info_map.h"
#include "services/explore/interest_zone.h"
#include "services/explore/nbv.h"
#include "services/explore/scan_features.h"
#include "services/explore/scan_integration.h"
#include "services/explore/scan_mesh.h"
#include "services/explore/turret_scan.h"
#include "services/explore/work_area.h"

/// @file
/// Seed 002's stop-and-scan mission as a pure state machine: ask for a full 3-D scan where the
/// robot stands, assemble the turret's lines (TurretScanAssembler), mesh and analyse the scan,
/// add its points to the information map, update the interest zones, decide the next best view
/// (NbvPlanner), send it as a goal, wait for the navigator's result, and scan again; until the
/// stop rule holds, no candidate is left, or a bound is reached.
///
/// The caller owns the transport: it carries out each NbvAction (ask the simulator's turret
/// for a scan, send a goal) and feeds back turret lines, the robot's position and the
/// navigator's results. Times are simulation seconds.
///
/// Interest zones: after each scan the zones a view from the scan's cell sees (ViewEvaluator's
/// zones_seen) leave the list, then the scan's own zones join it; the list keeps the
/// max_zones largest.

namespace cairn::explore {

struct NbvMissionParams {
  NbvParams nbv;
  MeshParams mesh;
  ScanAnalysisParams analysis;
  InfoMapParams info;
  TurretScanParams turret;
  WorkArea work_area;  ///< required
  int max_scans{40};   ///< the mission ends after this many scans
  /// A goal with no result after this long (sim s) is given up: the robot scans where it is.
  double goal_timeout_s{240.0};
  /// A scan that times out is asked for again, at most this many times in a row.
  int max_scan_retries{3};
  /// The mission ends after this many goals in a row failed.
  int max_goal_failures{3};
  /// A view point where no whole sweep comes (max_scan_retries + 1 requests) is skipped: the
  /// next view is decided without its scan. The mission fails after this many in a row (0: at
  /// the first).
  int max_skipped_views{3};
  int max_zones{200};
  /// Cells under the scan's accepted triangles that no point fell in are explored too
  /// (FillSurfaceCells): the far ground rings leave such cells between them.
  bool fill_surface{true};

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
  /// How each scan goes onto the information map (mesh, analysis, fill_surface).
  ScanIntegrationParams Integration() const {
    ScanIntegrationParams p;
    p.mesh = mesh;
    p.analysis = analysis;
    p.fill_surface = fill_surface;
    return p;
  }
};

/// What the caller must do now.
struct NbvAction {
  bool request_scan{false};
  std::optional<Candidate> goal;  ///< drive here (the chosen view point)
  bool done{false};
  std::string event;  ///< one line for the log when something notable happened
};

/// One scan of the mission.
struct ViewPoint {
  common::Vector2 position_m{0.0, 0.0};
  /// The info-map node the robot stood on (the level by the scanner's height; -1 off the map)
  /// and its ground under the scanner.
  int64_t node{-1};
  float ground_z_m{std::numeric_limits<float>::quiet_NaN()};
  double time_s{0.0};
  int64_t points_used{0};    ///< points that fell on the information map
  double coverage{0.0};      ///< of the work area, after the scan
  double mean_quality{0.0};  ///< over the explored work area, after the scan
  int zones{0};              ///< in the list after the scan
  // Wall-clock time of each stage (seed 002 Table 6-10), milliseconds.
  double mesh_ms{0.0};      ///< triangulation
  double analysis_ms{0.0};  ///< per-point features and zones
  double map_ms{0.0};       ///< information map update and zone list
  double decision_ms{0.0};  ///< candidates, navigation tree, gains, choice
};

/// One leg of the mission as chosen: the navigation tree's path to a view point, as info-map
/// nodes, each node's C_nc when it was chosen (NaN for unexplored cells in the blind cone under
/// the robot, which the tree lets it cross) and its ground then.
struct NbvLeg {
  std::vector<int64_t> nodes;
  std::vector<float> cnc_when_chosen;
  /// Each node's ground when chosen (its parent's across the blind cone): a later scan may find
  /// a lower surface under it and make the node's level the upper one.
  std::vector<float> ground_z_m;
};

class NbvMission {
 public:
  enum class State { kIdle, kScanning, kDriving, kDone };

  /// @throws std::invalid_argument for invalid params.
  explicit NbvMission(const NbvMissionParams& params);

  /// Starts: the first scan where the robot stands.
  NbvAction Start(double now_s);
  /// One turret line (sensor_pose the scanning plane's pose). When it completes a scan the scan
  /// is analysed and the next view decided.
  NbvAction OnTurretLine(const common::LaserScan& line, double pan_rad, double now_s);
  /// The navigator's result for the current goal.
  NbvAction OnGoalResult(bool reached, const std::string& reason, double now_s);
  /// Timeouts (a scan that never completes, a goal with no result).
  NbvAction Tick(double now_s);
  /// The robot's position, for the distance driven.
  void OnPosition(const common::Vector2& xy_m);
  /// Ends the mission (stopped from outside).
  void Stop(const std::string& why);

  State state() const { return state_; }
  const char* state_name() const;
  const InfoMap& info_map() const { return info_; }
  const std::vector<InterestZone>& zones() const { return zones_; }
  const std::vector<ViewPoint>& view_points() const { return view_points_; }
  const std::vector<common::Vector2>& path_m() const { return path_m_; }
  const std::vector<NbvLeg>& legs() const { return legs_; }
  const std::optional<NbvDecision>& last_decision() const { return last_decision_; }
  const std::optional<Candidate>& goal() const { return goal_; }
  int scans() const { return static_cast<int>(view_points_.size()); }
  int goals_sent() const { return goals_sent_; }
  int goals_reached() const { return goals_reached_; }
  int goals_failed() const { return goals_failed_; }
  double distance_m() const { return distance_m_; }
  const std::string& end_reason() const { return end_reason_; }
  /// Done because scans or goals kept failing (not by the stop rule or a limit).
  bool failed() const { return failed_; }
  const TurretScanAssembler& assembler() const { return assembler_; }

 private:
  NbvAction RequestScan(double now_s, const std::string& event);
  NbvAction OnScan(const OrderedScan& scan, double now_s);
  NbvAction Finish(const std::string& why, bool failed = false);
  /// The next view from `from_m` (the planner's decision, then a goal or the end).
  NbvAction DecideNext(const common::Vector2& from_m, double now_s, double* decision_ms);
  NbvAction ScanFailed(const std::string& why, double now_s);

  NbvMissionParams params_;
  InfoMap info_;
  NbvPlanner planner_;
  TurretScanAssembler assembler_;
  ScanMesh mesh_;
  std::vector<InterestZone> zones_;
  MissedViews missed_;  ///< per cell: the scans that should have seen it and did not
  /// The ground under the last scan (NaN before one): the level the robot stands on.
  float ground_z_m_{std::numeric_limits<float>::quiet_NaN()};
  std::vector<ViewPoint> view_points_;
  std::vector<NbvLeg> legs_;
  std::vector<common::Vector2> path_m_;
  std::optional<NbvDecision> last_decision_;
  std::optional<Candidate> goal_;
  State state_{State::kIdle};
  double goal_sent_s_{0.0};
  int scan_retries_{0};
  int skipped_in_row_{0};
  std::vector<common::Vector2> skipped_;  ///< view points skipped (never candidates again)
  int goals_sent_{0};
  int goals_reached_{0};
  int goals_failed_{0};
  int failures_in_a_row_{0};
  double distance_m_{0.0};
  std::string end_reason_;
  bool failed_{false};
};

}  // namespace cairn::explore
