#include "services/explore/explorer_config.h"

#include <cmath>
#include <stdexcept>

namespace cairn::explore {

using common::ConfigError;
using common::YamlMap;

namespace {

void RequirePositive(double v, const char* name) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    throw std::invalid_argument(std::string("explorer: ") + name + " must be positive");
  }
}

void LoadReactive(YamlMap map, ReactiveParams* p) {
  map.Get("safety_distance_m", &p->safety_distance_m);
  map.Get("front_lateral_divisor", &p->front_lateral_divisor);
  map.Get("critical_distance_m", &p->critical_distance_m);
  map.Get("block_time_limit_s", &p->block_time_limit_s);
  map.Get("max_reverse_s", &p->max_reverse_s);
  map.Get("cruise_speed_mps", &p->cruise_speed_mps);
  map.Get("centring_speed_mps", &p->centring_speed_mps);
  map.Get("centring_turn_rate_radps", &p->centring_turn_rate_radps);
  map.Get("side_distance_m", &p->side_distance_m);
  map.Get("turn_rate_radps", &p->turn_rate_radps);
  map.Get("reverse_speed_mps", &p->reverse_speed_mps);
  map.Get("clean_min_range_m", &p->clean_min_range_m);
  map.Get("clean_max_range_m", &p->clean_max_range_m);
  map.Get("clean_replacement_m", &p->clean_replacement_m);
  map.Get("legacy_nan", &p->legacy_nan);
  map.Finish();
}

void LoadFrontier(YamlMap map, FrontierModeParams* p) {
  map.Get("layer", &p->layer);
  map.Get("occupied_threshold_og", &p->occupied_threshold_og);
  map.Get("free_threshold_og", &p->free_threshold_og);
  map.Get("min_frontier_size_m", &p->frontier.min_frontier_size_m);
  map.Get("potential_scale", &p->frontier.potential_scale);
  map.Get("gain_scale", &p->frontier.gain_scale);
  map.Get("clearance_m", &p->frontier.clearance_m);
  map.Get("goal_clearance_m", &p->frontier.goal_clearance_m);
  map.Get("blacklist_radius_m", &p->frontier.blacklist_radius_m);
  map.Get("free_around_robot_m", &p->free_around_robot_m);
  map.Get("choose_period_s", &p->choose_period_s);
  map.Get("goal_tolerance_m", &p->goal_tolerance_m);
  map.Get("progress_timeout_s", &p->progress_timeout_s);
  map.Get("switch_margin", &p->switch_margin);
  map.Get("finish_wait_s", &p->finish_wait_s);
  map.Finish();
}

void LoadNbv(YamlMap map, NbvModeParams* p) {
  map.Get("preset", &p->preset);
  map.Get("work_area", &p->work_area);
  map.Get("turret_sensor", &p->turret_sensor);
  map.Get("drive", &p->drive);
  map.Get("teleport_base_height_m", &p->teleport_base_height_m);
  map.Get("pan_step_deg", &p->pan_step_deg);
  map.Get("pan_range_deg", &p->pan_range_deg);
  map.Get("tilt_step_deg", &p->tilt_step_deg);
  map.Get("scanner_height_m", &p->scanner_height_m);
  map.Get("scan_timeout_s", &p->scan_timeout_s);
  map.Get("max_scans", &p->max_scans);
  map.Get("goal_tolerance_m", &p->goal_tolerance_m);
  map.Get("goal_timeout_s", &p->goal_timeout_s);
  map.Get("max_scan_retries", &p->max_scan_retries);
  map.Get("max_skipped_views", &p->max_skipped_views);
  map.Get("settle_s", &p->settle_s);
  map.Get("safe_cnc", &p->safe_cnc);
  map.Get("candidate_spacing_m", &p->candidate_spacing_m);
  map.Get("candidate_clearance_m", &p->candidate_clearance_m);
  map.Get("missed_view_step_m", &p->missed_view_step_m);
  map.Get("max_step_m", &p->max_step_m);
  map.Get("level_gap_m", &p->level_gap_m);
  map.Get("fill_surface", &p->fill_surface);
  map.Get("seed", &p->seed);
  map.Get("revisit_radius_m", &p->revisit_radius_m);
  map.Get("d_max_m", &p->d_max_m);
  map.Get("min_global_quality", &p->min_global_quality);
  map.Get("gain_range_m", &p->gain_range_m);
  map.Get("max_slope_deg", &p->max_slope_deg);
  map.Get("max_descent_deg", &p->max_descent_deg);
  map.Get("obstacle_band_m", &p->obstacle_band_m);
  map.Finish();
}

}  // namespace

NbvMissionParams NbvModeParams::ToMissionParams() const {
  if (work_area.empty()) {
    throw std::invalid_argument(
        "explorer: nbv.work_area is required (\"x0,y0 x1,y1 x2,y2 ...\", or --work-area)");
  }
  RequirePositive(goal_tolerance_m, "nbv.goal_tolerance_m");
  RequirePositive(teleport_base_height_m, "nbv.teleport_base_height_m");
  if (!(settle_s >= 0.0) || !std::isfinite(settle_s)) {
    throw std::invalid_argument("explorer: nbv.settle_s must be >= 0");
  }
  if (turret_sensor.empty()) throw std::invalid_argument("explorer: nbv.turret_sensor is empty");
  if (drive != "navigator" && drive != "teleport") {
    throw std::invalid_argument("explorer: nbv.drive must be navigator or teleport (got \"" +
                                drive + "\")");
  }
  constexpr double kDeg = M_PI / 180.0;
  NbvMissionParams m;
  m.nbv = NbvPreset(preset);
  m.nbv.safe_cnc = safe_cnc;
  m.nbv.candidate_spacing_m = candidate_spacing_m;
  m.nbv.candidate_clearance_m = candidate_clearance_m;
  m.nbv.missed_view_step_m = missed_view_step_m;
  m.nbv.revisit_radius_m = revisit_radius_m;
  m.fill_surface = fill_surface;
  m.info.max_step_m = max_step_m;
  m.info.level_gap_m = level_gap_m;
  if (seed < 0) throw std::invalid_argument("explorer: nbv.seed must be >= 0");
  m.nbv.seed = static_cast<uint64_t>(seed);
  m.nbv.d_max_m = d_max_m;
  m.nbv.min_global_quality = min_global_quality;
  m.nbv.gain_range_m = gain_range_m;
  m.nbv.scanner_height_m = scanner_height_m;
  m.nbv.pan_step_rad = pan_step_deg * kDeg;
  m.nbv.tilt_step_rad = tilt_step_deg * kDeg;
  m.turret.pan_step_rad = pan_step_deg * kDeg;
  m.turret.pan_range_rad = pan_range_deg * kDeg;
  m.turret.tilt_step_rad = tilt_step_deg * kDeg;
  m.turret.scanner_height_m = scanner_height_m;
  m.turret.timeout_s = scan_timeout_s;
  m.analysis.max_slope_rad = max_slope_deg * kDeg;
  m.analysis.max_descent_rad = max_descent_deg * kDeg;
  m.analysis.obstacle_band_m = obstacle_band_m;
  m.work_area = ParseWorkArea(work_area);
  m.max_scans = max_scans;
  m.goal_timeout_s = goal_timeout_s;
  m.max_scan_retries = max_scan_retries;
  m.max_skipped_views = max_skipped_views;
  try {
    m.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("explorer: nbv: ") + e.what());
  }
  return m;
}

void NbvModeParams::Validate() const { ToMissionParams(); }

ExploreMode ExploreModeFromName(const std::string& name) {
  if (name == "reactive") return ExploreMode::kReactive;
  if (name == "stateless") return ExploreMode::kStateless;
  if (name == "frontier") return ExploreMode::kFrontier;
  if (name == "nbv") return ExploreMode::kNbv;
  throw std::invalid_argument("unknown exploration mode '" + name +
                              "' (known: reactive, stateless, frontier, nbv)");
}

const char* ExploreModeName(ExploreMode mode) {
  switch (mode) {
    case ExploreMode::kReactive:
      return "reactive";
    case ExploreMode::kStateless:
      return "stateless";
    case ExploreMode::kFrontier:
      return "frontier";
    case ExploreMode::kNbv:
      return "nbv";
  }
  return "?";
}

void FrontierModeParams::Validate() const {
  if (layer.empty()) throw std::invalid_argument("explorer: frontier.layer is empty");
  if (!(free_threshold_og >= 0.0 && free_threshold_og < occupied_threshold_og &&
        occupied_threshold_og <= 100.0)) {
    throw std::invalid_argument(
        "explorer: frontier thresholds need 0 <= free_threshold_og < occupied_threshold_og "
        "<= 100");
  }
  frontier.Validate();
  if (!(free_around_robot_m >= 0.0) || !std::isfinite(free_around_robot_m)) {
    throw std::invalid_argument("explorer: frontier.free_around_robot_m must be >= 0");
  }
  RequirePositive(choose_period_s, "frontier.choose_period_s");
  RequirePositive(goal_tolerance_m, "frontier.goal_tolerance_m");
  RequirePositive(progress_timeout_s, "frontier.progress_timeout_s");
  if (!(switch_margin >= 0.0) || !std::isfinite(switch_margin)) {
    throw std::invalid_argument("explorer: frontier.switch_margin must be >= 0");
  }
  if (!(finish_wait_s >= 0.0) || !std::isfinite(finish_wait_s)) {
    throw std::invalid_argument("explorer: frontier.finish_wait_s must be >= 0");
  }
}

void ExplorerConfig::Validate() const {
  if (!save_to.empty()) {
    const auto slash = save_to.find('/');
    if (slash == std::string::npos || slash == 0 || slash + 1 == save_to.size() ||
        save_to.find('/', slash + 1) != std::string::npos) {
      throw std::invalid_argument("explorer: save_to must be \"site/map\" (got \"" + save_to +
                                  "\")");
    }
  }
  if (!(duration_s >= 0.0) || !std::isfinite(duration_s)) {
    throw std::invalid_argument("explorer: duration_s must be >= 0");
  }
  RequirePositive(status_rate_hz, "status_rate_hz");
  RequirePositive(scan_timeout_s, "scan_timeout_s");
  reactive.Validate();
  frontier.Validate();
  if (mode == ExploreMode::kNbv) nbv.Validate();
}

ExplorerConfig LoadExplorerConfig(YamlMap& root) {
  ExplorerConfig c;
  if (root.Has("mode")) {
    const YAML::Node node = root.Raw("mode");
    try {
      c.mode = ExploreModeFromName(node.as<std::string>());
    } catch (const std::invalid_argument& e) {
      root.Fail(node, e.what());
    } catch (const YAML::Exception&) {
      root.Fail(node, "bad value for 'mode'");
    }
  }
  root.Get("duration_s", &c.duration_s);
  root.Get("status_rate_hz", &c.status_rate_hz);
  root.Get("scan_timeout_s", &c.scan_timeout_s);
  root.Get("out_dir", &c.out_dir);
  root.Get("save_to", &c.save_to);
  LoadReactive(root.Child("reactive"), &c.reactive);
  LoadFrontier(root.Child("frontier"), &c.frontier);
  LoadNbv(root.Child("nbv"), &c.nbv);
  root.Finish();
  try {
    c.Validate();
  } catch (const std::invalid_argument& e) {
    throw ConfigError(root.file() + ": " + e.what());
  }
  return c;
}

ExplorerConfig LoadExplorerConfigFile(const std::string& path) {
  YamlMap root = YamlMap::LoadFile(path);
  return LoadExplorerConfig(root);
}

}  // namespace cairn::explore
