#pragma once

#include <string>

#include "common/yaml_reader.h"
#include "services/explore/frontier.h"
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
};

/// "reactive", "stateless", "frontier". @throws std::invalid_argument listing the known names.
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

struct ExplorerConfig {
  ExploreMode mode{ExploreMode::kReactive};
  /// Sim seconds of exploring after the first input; 0: until done (or stopped).
  double duration_s{0.0};
  double status_rate_hz{2.0};
  /// Reactive modes: with no scan for this long (node clock) the robot is told to stop.
  double scan_timeout_s{0.5};
  ReactiveParams reactive;
  FrontierModeParams frontier;

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// @throws common::ConfigError naming the file and line of an unknown key or a bad value.
ExplorerConfig LoadExplorerConfig(common::YamlMap& root);
ExplorerConfig LoadExplorerConfigFile(const std::string& path);

}  // namespace cairn::explore
