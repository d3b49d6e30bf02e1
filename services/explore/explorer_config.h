#pragma once

#include <string>

#include "common/yaml_reader.h"
#include "services/explore/frontier.h"
#include "services/explore/nbv_mission.h"
#include "services/explore/reactive_explorer.h"

/// @file
/// cairn-explorer's configuration: the strategy and its parameters. Every key of the YAML file
/// is optional (config/explore/explorer.yaml lists them with their defaults); an unknown key is
/// an error naming its line.

namespace cairn::explore {

enum class ExploreMode {
  kReactive,   ///< seed 003's five-sector explorer on the planar laser
  kStateless,  ///< its stateless baseline (no memory, no reverse)
  kFrontier,   ///< frontier goals on the 2-D occupancy, driven by cairn-navigator
  kNbv,        ///< seed 002's stop-and-scan next-best-view on the turret's 3-D scans
};

/// "reactive", "stateless", "frontier", "nbv". @throws std::invalid_argument listing the known
/// names.
ExploreMode ExploreModeFromName(const std::string& name);
const char* ExploreModeName(ExploreMode mode);

struct FrontierModeParams {
  /// The mapper's 2-D occupancy layer the frontiers are found on (<robot>.MAP.OCCUPANCY).
  std::string layer{"occupancy"};
  /// Occupancy (0..100) at or above which a cell is occupied, at or below which free; between
  /// them a cell is known but neither (it blocks no path and makes no frontier).
  double occupied_threshold_og{65.0};
  double free_threshold_og{49.0};
  FrontierParams frontier;
  /// Unknown cells this close to the robot read as free: it stands there, though its laser
  /// (ahead of the centre, blind behind) has not seen the floor under it.
  double free_around_robot_m{0.4};
  double choose_period_s{1.0};    ///< how often the goal is reconsidered while driving
  double goal_tolerance_m{0.35};  ///< sent with each goal
  /// A goal that brought no progress (0.25 m closer) for this long is given up (and
  /// blacklisted); sim seconds.
  double progress_timeout_s{20.0};
  /// Switch goals while driving only when the new frontier's cost is lower by this much.
  double switch_margin{2.0};
  /// When no frontier is left, wait this long (sim s) for the map to settle before calling the
  /// exploration done.
  double finish_wait_s{10.0};

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// Seed 002's mission: scans asked of the simulator's turret (SIM.CONTROL OP_TRIGGER_SENSOR),
/// its lines on <robot>.TURRET_SCAN, view points sent to cairn-navigator.
struct NbvModeParams {
  /// A preset of seed 002's tables (NbvPresetNames: simple-balanced, greedy, ...).
  std::string preset{"simple-balanced"};
  /// The work area, "x0,y0 x1,y1 x2,y2 ..." (world metres); required in this mode.
  std::string work_area;
  std::string turret_sensor{"turret"};  ///< the sensor kind the request names
  /// How the robot gets to each view point: "navigator" (a goal to cairn-navigator, which
  /// drives there) or "teleport" (SIM.CONTROL OP_RESET_ROBOT puts it there, and the distance
  /// counted is the navigation tree's path: comparing planner presets without the drive).
  std::string drive{"navigator"};
  /// Teleport: the robot's base is put this far above the view point's ground (the mean height
  /// of its cell's points) and drops onto it.
  double teleport_base_height_m{0.3};
  /// The turret's sweep as the simulator's scenario sets it (pan lines over pan_range_deg;
  /// beams tilt_step_deg apart).
  double pan_step_deg{0.5};
  double pan_range_deg{180.0};
  double tilt_step_deg{0.5};
  /// Height of the scanner above the ground under the robot.
  double scanner_height_m{1.0};
  double scan_timeout_s{60.0};  ///< from the request to the last line (sim s)
  int max_scans{40};
  double goal_tolerance_m{1.0};
  double goal_timeout_s{240.0};
  /// A sweep that breaks (lines lost on the bus) is asked for again at most this many times in
  /// a row before the mission fails.
  int max_scan_retries{6};
  int max_skipped_views{3};  ///< NbvMissionParams::max_skipped_views
  /// The robot must stand still this long (sim s) after a goal before a scan is asked for.
  double settle_s{1.0};
  /// The NBV parameters over the preset (seed 002 Appendix A).
  double safe_cnc{0.7};
  double candidate_spacing_m{3.0};
  /// Every cell this near a candidate must be safe too: about the robot's circumscribed radius.
  double candidate_clearance_m{0.45};
  double max_step_m{0.0};          ///< InfoMapParams::max_step_m (the robot's step; 0: none)
  double level_gap_m{0.0};         ///< InfoMapParams::level_gap_m (0: one level per cell)
  double missed_view_step_m{3.0};  ///< NbvParams::missed_view_step_m
  bool fill_surface{true};         ///< NbvMissionParams::fill_surface
  int seed{1};                     ///< candidate sampling (NbvParams::seed)
  double revisit_radius_m{1.5};    ///< NbvParams::revisit_radius_m
  double d_max_m{50.0};
  double min_global_quality{0.0};
  double gain_range_m{20.0};
  double max_slope_deg{20.0};
  double max_descent_deg{0.0};  ///< ScanAnalysisParams::max_descent_rad (0: max_slope_deg)
  double obstacle_band_m{1.0};

  /// @throws std::invalid_argument naming the first bad field (a missing work area included).
  void Validate() const;
  /// The mission's parameters. @throws std::invalid_argument as Validate.
  NbvMissionParams ToMissionParams() const;
};

struct ExplorerConfig {
  ExploreMode mode{ExploreMode::kReactive};
  /// Sim seconds of exploring after the first input; 0: until done (or stopped).
  double duration_s{0.0};
  double status_rate_hz{2.0};
  /// Reactive modes: with no scan for this long (node clock) the robot is told to stop.
  double scan_timeout_s{0.5};
  /// Next-best-view: where the summary table and the renders go at the end ("" none).
  std::string out_dir;
  /// Next-best-view: "site/map" to push-save the information map's layers (explore/*) to
  /// cairn-mapstore at the end ("" none).
  std::string save_to;
  ReactiveParams reactive;
  FrontierModeParams frontier;
  NbvModeParams nbv;

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// @throws common::ConfigError naming the file and line of an unknown key or a bad value.
ExplorerConfig LoadExplorerConfig(common::YamlMap& root);
ExplorerConfig LoadExplorerConfigFile(const std::string& path);

}  // namespace cairn::explore
