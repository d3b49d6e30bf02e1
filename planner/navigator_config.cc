#include "planner/navigator_config.h"

#include <stdexcept>

#include "common/check.h"
#include "common/layers.h"
#include "planner/local/critic_registry.h"

namespace cairn::planner {

using common::ConfigError;
using common::YamlMap;

namespace {

// Reads an enum-valued key through a name parser, reporting a bad name at its line.
template <typename T, typename Parse>
void GetNamed(YamlMap& map, const std::string& key, T* out, Parse parse) {
  if (!map.Has(key)) return;
  const YAML::Node node = map.Raw(key);
  try {
    *out = parse(node.as<std::string>());
  } catch (const std::invalid_argument& e) {
    map.Fail(node, e.what());
  } catch (const YAML::Exception&) {
    map.Fail(node, "bad value for '" + key + "'");
  }
}

void LoadCostMap(YamlMap map, CostMapParams* p) {
  map.Get("unknown_is_traversable", &p->unknown_is_traversable);
  map.Get("unknown_cost", &p->unknown_cost);
  map.Get("lethal_cost", &p->lethal_cost);
  map.Get("one_way_cost", &p->one_way_cost);
  map.Get("planning_padding_m", &p->planning_padding_m);
  map.Get("footprint_padding_m", &p->footprint_padding_m);
  map.Finish();
}

void LoadMapLayer(YamlMap map, MapLayerConfig* p) {
  map.Get("layer", &p->layer);
  GetNamed(map, "encoding", &p->encoding, MapEncodingFromName);
  map.Get("directed", &p->directed);
  map.Get("look_at_unseen_drops", &p->look_at_unseen_drops);
  map.Get("occupied_threshold_og", &p->occupancy.occupied_threshold_og);
  map.Get("free_threshold_og", &p->occupancy.free_threshold_og);
  map.Finish();
}

void LoadGlobal(YamlMap map, GlobalPlannerParams* p) {
  map.Get("planner", &p->planner);
  GetNamed(map, "state_space", &p->state_space, StateSpaceKindFromName);
  map.Get("turning_radius_m", &p->turning_radius_m);
  map.Get("time_budget_s", &p->time_budget_s);
  map.Get("stop_at_first_solution", &p->stop_at_first_solution);
  map.Get("traversal_cost_weight", &p->traversal_cost_weight);
  map.Get("clearance_weight", &p->clearance_weight);
  map.Get("clearance_inflation_m", &p->clearance_inflation_m);
  map.Get("validity_resolution_m", &p->validity_resolution_m);
  map.Get("range_m", &p->range_m);
  map.Get("bounds_margin_m", &p->bounds_margin_m);
  map.Get("aligned_heading_fraction", &p->aligned_heading_fraction);
  map.Get("ridge_sample_fraction", &p->ridge_sample_fraction);
  map.Get("improvement_rounds", &p->improvement_rounds);
  map.Get("grid_route_candidate", &p->grid_route_candidate);
  map.Get("grid_route_cell_m", &p->grid_route_cell_m);
  map.Get("improvement_time_s", &p->improvement_time_s);
  map.Get("escape_radius_m", &p->escape_radius_m);
  map.Get("simplify_time_s", &p->simplify_time_s);
  map.Get("interpolation_step_m", &p->interpolation_step_m);
  map.Get("goal_tolerance_m", &p->goal_tolerance_m);
  map.Get("goal_yaw_samples", &p->goal_yaw_samples);
  map.Get("grid_precheck", &p->grid_precheck);
  map.Get("unknown_horizon_m", &p->unknown_horizon_m);
  map.Get("unknown_goal_radius_m", &p->unknown_goal_radius_m);
  map.Get("start_rescue_radius_m", &p->start_rescue_radius_m);
  map.Get("seed", &p->seed);
  map.Finish();
}

// One critic's own key: a number, or a boolean (1 or 0).
double CriticValue(const YamlMap& entry, const YAML::Node& value, const std::string& key) {
  try {
    double number = 0.0;
    if (YAML::convert<double>::decode(value, number)) return number;
    bool flag = false;
    if (YAML::convert<bool>::decode(value, flag)) return flag ? 1.0 : 0.0;
  } catch (const YAML::Exception&) {
  }
  // A key yaml-cpp cannot look up again (a null key) gives an invalid node, whose place is
  // unknown (found by fuzz_yaml_loaders: it escaped as YAML::InvalidNode).
  entry.Fail(value.IsDefined() ? value : YAML::Node(),
             "critic key '" + key + "' must be a number or true/false");
}

// local_planner.critics: a list of {name, scale, <the critic's own keys>...} in scoring order,
// each checked against the shipped critics (an unknown name or key is an error at its line).
void LoadCritics(YamlMap& map, std::vector<CriticConfig>* out) {
  if (!map.Has("critics")) return;
  const YAML::Node list = map.Raw("critics");
  if (!list.IsSequence()) {
    map.Fail(list, "local_planner.critics must be a list of {name, scale, ...} in scoring order");
  }
  out->clear();
  for (const YAML::Node& item : list) {
    YamlMap entry = map.Wrap(item, "local_planner.critics");
    CriticConfig critic;
    critic.name = entry.Require<std::string>("name");
    critic.scale = entry.Require<double>("scale");
    for (const std::string& key : entry.Keys()) {
      if (key != "name" && key != "scale") critic.params[key] = CriticValue(entry, item[key], key);
    }
    try {
      BuiltinCritics().Check(critic);
    } catch (const std::invalid_argument& e) {
      entry.Fail(item, e.what());
    }
    out->push_back(std::move(critic));
  }
}

void LoadLocal(YamlMap map, DwaParams* p) {
  map.Get("vx_samples", &p->generator.vx_samples);
  map.Get("vtheta_samples", &p->generator.vtheta_samples);
  map.Get("sim_time_s", &p->generator.sim_time_s);
  map.Get("sim_step_s", &p->generator.sim_step_s);
  map.Get("path_tracking", &p->path_tracking);
  map.Get("stall_speed_mps", &p->stall_speed_mps);
  map.Get("tracking_lookaheads_m", &p->tracking_lookaheads_m);
  map.Get("tracking_turn_in_place_rad", &p->tracking_turn_in_place_rad);
  map.Get("tracking_min_radius_m", &p->tracking_min_radius_m);
  map.Get("tracking_slow_distance_m", &p->tracking_slow_distance_m);
  LoadCritics(map, &p->critics);
  map.Finish();
}

void LoadRecovery(YamlMap map, RecoveryParams* p) {
  if (map.Has("sequence")) {
    const YAML::Node seq = map.Raw("sequence");
    if (!seq.IsSequence()) map.Fail(seq, "recovery.sequence must be a list");
    p->sequence.clear();
    for (const auto& item : seq) {
      try {
        p->sequence.push_back(RecoveryKindFromName(map.As<std::string>(item, "a recovery name")));
      } catch (const std::invalid_argument& e) {
        map.Fail(item, e.what());
      } catch (const YAML::Exception&) {
        map.Fail(item, "a recovery must be a name");
      }
    }
  }
  map.Get("rotate_angle_rad", &p->rotate_angle_rad);
  map.Get("rotate_speed_radps", &p->rotate_speed_radps);
  map.Get("backup_distance_m", &p->backup_distance_m);
  map.Get("backup_speed_mps", &p->backup_speed_mps);
  map.Get("forward_distance_m", &p->forward_distance_m);
  map.Get("forward_speed_mps", &p->forward_speed_mps);
  map.Get("wait_s", &p->wait_s);
  map.Get("clear_wait_s", &p->clear_wait_s);
  map.Get("behaviour_timeout_s", &p->behaviour_timeout_s);
  map.Get("collision_lookahead_s", &p->collision_lookahead_s);
  map.Finish();
}

void LoadNavigator(YamlMap map, NavigatorParams* p) {
  map.Get("xy_goal_tolerance_m", &p->xy_goal_tolerance_m);
  map.Get("yaw_goal_tolerance_rad", &p->yaw_goal_tolerance_rad);
  map.Get("max_pose_age_s", &p->max_pose_age_s);
  map.Get("max_map_age_s", &p->max_map_age_s);
  map.Get("max_clock_skew_s", &p->max_clock_skew_s);
  map.Get("lookahead_m", &p->lookahead_m);
  map.Get("min_lookahead_m", &p->min_lookahead_m);
  map.Get("local_path_window_m", &p->local_path_window_m);
  map.Get("rotate_to_heading_threshold_rad", &p->rotate_to_heading_threshold_rad);
  map.Get("max_path_deviation_m", &p->max_path_deviation_m);
  map.Get("path_check_ahead_m", &p->path_check_ahead_m);
  map.Get("min_replan_interval_s", &p->min_replan_interval_s);
  map.Get("replan_period_s", &p->replan_period_s);
  map.Get("replace_path_ratio", &p->replace_path_ratio);
  map.Get("plan_time_budget_s", &p->plan_time_budget_s);
  map.Get("no_valid_trajectory_patience_s", &p->no_valid_trajectory_patience_s);
  map.Get("wait_for_map_s", &p->wait_for_map_s);
  map.Get("approach_through_known", &p->approach_through_known);
  map.Get("approach_min_gain_m", &p->approach_min_gain_m);
  map.Get("progress_distance_m", &p->progress_distance_m);
  map.Get("progress_timeout_s", &p->progress_timeout_s);
  map.Get("occupied_goal_far_m", &p->occupied_goal_far_m);
  map.Get("occupied_goal_shift_m", &p->occupied_goal_shift_m);
  map.Get("recovery_reset_distance_m", &p->recovery_reset_distance_m);
  map.Get("stop_repeat_cycles", &p->stop_repeat_cycles);
  map.Finish();
}

void LoadPlaceGoal(YamlMap map, PlaceGoalParams* p) {
  map.Get("max_goal_cost", &p->max_goal_cost);
  map.Get("yaw_samples", &p->yaw_samples);
  map.Get("move_margin_m", &p->move_margin_m);
  map.Finish();
}

}  // namespace

const char* PoseSourceName(PoseSource source) {
  return source == PoseSource::kOdom ? "odom" : "pose";
}

PoseSource PoseSourceFromName(const std::string& name) {
  if (name == "pose") return PoseSource::kPose;
  if (name == "odom") return PoseSource::kOdom;
  CAIRN_THROW_UNLESS(false, "unknown pose source '" << name << "' (pose, odom)");
  return PoseSource::kPose;
}

std::string MapLayerConfig::LayerFor(const std::string& profile) const {
  if (!layer.empty()) return layer;
  return encoding == MapEncoding::kOccupancy ? std::string(layers::kFinal)
                                             : layers::CostLayer(profile);
}

std::string MapLayerConfig::DirectedLayerFor(const std::string& profile) const {
  const std::string cost = LayerFor(profile);
  if (!directed || encoding != MapEncoding::kCost || !layers::IsCostLayer(cost)) return "";
  return layers::DirectedLayer(cost.substr(std::string("cost/").size()));
}

void NavigatorConfig::Finalize() {
  CAIRN_THROW_UNLESS(control_rate_hz > 0.0 && control_rate_hz <= 1000.0,
                     "control_rate_hz must lie in (0, 1000]");
  CAIRN_THROW_UNLESS(status_rate_hz > 0.0, "status_rate_hz must be positive");
  CAIRN_THROW_UNLESS(resend_interval_s > 0.0, "resend_interval_s must be positive");
  CAIRN_THROW_UNLESS(incomplete_map_timeout_s >= 0.0, "incomplete_map_timeout_s must be >= 0");
  navigator.control_period_s = 1.0 / control_rate_hz;
  local_planner.generator.control_period_s = navigator.control_period_s;
  navigator.plan_time_budget_s = global_planner.time_budget_s;
  cost_map.Validate();
  if (map.encoding == MapEncoding::kOccupancy) map.occupancy.Validate();
  global_planner.Validate();
  local_planner.Validate();
  navigator.Validate();
}

NavigatorConfig LoadNavigatorConfig(YamlMap& root) {
  NavigatorConfig c;
  GetNamed(root, "pose_source", &c.pose_source, PoseSourceFromName);
  GetNamed(root, "command_output", &c.command_output, CommandOutputFromName);
  GetNamed(root, "control_clock", &c.control_clock, ControlClockFromName);
  root.Get("control_rate_hz", &c.control_rate_hz);
  root.Get("status_rate_hz", &c.status_rate_hz);
  root.Get("map_name", &c.map_name);
  root.Get("resend_interval_s", &c.resend_interval_s);
  root.Get("incomplete_map_timeout_s", &c.incomplete_map_timeout_s);
  root.Get("map_thread", &c.map_thread);
  LoadMapLayer(root.Child("map"), &c.map);
  LoadCostMap(root.Child("cost_map"), &c.cost_map);
  LoadGlobal(root.Child("global_planner"), &c.global_planner);
  LoadLocal(root.Child("local_planner"), &c.local_planner);
  LoadNavigator(root.Child("navigator"), &c.navigator);
  LoadRecovery(root.Child("recovery"), &c.navigator.recovery);
  LoadPlaceGoal(root.Child("place_goal"), &c.navigator.place);
  root.Finish();
  try {
    c.Finalize();
  } catch (const std::invalid_argument& e) {
    throw ConfigError(root.file() + ": " + e.what());
  }
  return c;
}

NavigatorConfig LoadNavigatorConfigFile(const std::string& path) {
  YamlMap root = YamlMap::LoadFile(path);
  return LoadNavigatorConfig(root);
}

ControlClock ControlClockFromName(const std::string& name) {
  if (name == "wall") return ControlClock::kWall;
  if (name == "pose") return ControlClock::kPose;
  CAIRN_THROW_UNLESS(false, "unknown control clock '" << name << "' (wall, pose)");
  return ControlClock::kWall;
}

const char* ControlClockName(ControlClock clock) {
  return clock == ControlClock::kPose ? "pose" : "wall";
}

CommandOutput CommandOutputFromName(const std::string& name) {
  if (name == "velocity") return CommandOutput::kVelocity;
  if (name == "body_velocity") return CommandOutput::kBodyVelocity;
  CAIRN_THROW_UNLESS(false, "unknown command output '" << name << "' (velocity, body_velocity)");
  return CommandOutput::kVelocity;
}

}  // namespace cairn::planner
