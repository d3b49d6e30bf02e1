// cairn-mapper: one robot's mapper (terrain, traversability per profile, obstacle registry,
// occupancy, OctoMap), live on the bus or offline from an lcm-logger file.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "common/flags.h"
#include "common/layers.h"
#include "common/log.h"
#include "common/robot_profile.h"
#include "common/yaml_reader.h"
#include "mapstore/lcm/mapstore_client.h"
#include "services/mapping/lcm/mapper_service.h"
#include "services/runtime/node.h"

namespace cairn::mapping {
namespace {

constexpr double kDeg = M_PI / 180.0;

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b != std::string::npos) out.push_back(item.substr(b, e - b + 1));
  }
  return out;
}

// A profile by name (in the profiles directory) or by path (contains '/' or ends in .yaml).
common::Result<common::RobotProfile> ResolveProfile(const std::string& dir,
                                                    const std::string& name) {
  const bool is_path = name.find('/') != std::string::npos ||
                       (name.size() > 5 && name.substr(name.size() - 5) == ".yaml");
  if (!is_path) {
    for (char c : name) {
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) {
        return common::InvalidArgumentError("bad profile name '" + name + "'");
      }
    }
  }
  const std::string path = is_path ? name : dir + "/" + name + ".yaml";
  if (!std::filesystem::exists(path)) {
    return common::NotFoundError("no profile '" + name + "' (looked for " + path + ")");
  }
  try {
    return common::LoadRobotProfileFile(path);
  } catch (const std::exception& e) {
    return common::InvalidArgumentError(e.what());
  }
}

void LoadFilter(common::YamlMap m, ElevationFilterParams* p) {
  m.Get("range_noise_m", &p->range_noise_m);
  m.Get("beam_constant_m", &p->beam_constant_m);
  m.Get("beam_angle_rad", &p->beam_angle_rad);
  m.Get("mahalanobis_threshold", &p->mahalanobis_threshold);
  m.Get("multi_height_noise_m2", &p->multi_height_noise_m2);
  m.Get("min_variance_m2", &p->min_variance_m2);
  m.Get("max_variance_m2", &p->max_variance_m2);
  m.Get("increase_height_alpha", &p->increase_height_alpha);
  double spread_deg = p->max_spread_slope_rad * 180.0 / M_PI;
  m.Get("max_spread_slope_deg", &spread_deg);
  p->max_spread_slope_rad = spread_deg * M_PI / 180.0;
  m.Finish();
}

void LoadTraversability(common::YamlMap m, TraversabilityParams* p) {
  m.Get("normal_radius_m", &p->normal_radius_m);
  m.Get("blind_zone_half_size_m", &p->blind_zone_half_size_m);
  m.Get("imu_pitch_compensation", &p->imu_pitch_compensation);
  m.Get("unknown_is_lethal", &p->unknown_is_lethal);
  m.Get("graded_cost_max", &p->graded_cost_max);
  m.Get("free_fraction", &p->free_fraction);
  m.Get("min_ditch_depth_m", &p->min_ditch_depth_m);
  m.Get("unseen_drop_m", &p->unseen_drop_m);
  m.Get("max_ditch_search_m", &p->max_ditch_search_m);
  m.Get("height_tolerance_m", &p->height_tolerance_m);
  m.Get("min_step_edge_cells", &p->min_step_edge_cells);
  m.Finish();
}

void LoadObstacles(common::YamlMap m, ObstacleParams* p) {
  m.Get("min_ramp_slope_rad", &p->min_ramp_slope_rad);
  m.Get("min_step_height_m", &p->min_step_height_m);
  m.Get("min_cells", &p->min_cells);
  m.Get("step_contrast", &p->step_contrast);
  m.Get("wall_min_height_m", &p->wall_min_height_m);
  m.Get("min_drop_height_m", &p->min_drop_height_m);
  m.Get("min_ramp_area_m2", &p->min_ramp_area_m2);
  m.Get("small_step_height_m", &p->small_step_height_m);
  m.Get("min_small_step_length_m", &p->min_small_step_length_m);
  m.Get("min_small_step_elongation", &p->min_small_step_elongation);
  m.Get("surface_continuity_m", &p->surface_continuity_m);
  m.Get("outline_tolerance_cells", &p->outline_tolerance_cells);
  m.Finish();
}

void LoadTerrain(common::YamlMap m, TerrainMapParams* p) {
  m.Get("resolution_m", &p->resolution_m);
  m.Get("tile_size_cells", &p->tile_size_cells);
  m.Get("min_range_m", &p->min_range_m);
  m.Get("max_range_m", &p->max_range_m);
  m.Get("self_filter_radius_m", &p->self_filter_radius_m);
  m.Get("max_height_above_sensor_m", &p->max_height_above_sensor_m);
  m.Get("ray_bound_length_m", &p->ray_bound_length_m);
  m.Get("ray_bound_max_range_m", &p->ray_bound_max_range_m);
  m.Get("ray_bound_margin_m", &p->ray_bound_margin_m);
  m.Get("commit_epsilon_m", &p->commit_epsilon_m);
  m.Get("visibility_tolerance_m", &p->visibility_tolerance_m);
  m.Get("max_visibility_conflict_m", &p->max_visibility_conflict_m);
  if (m.Has("filter")) LoadFilter(m.Child("filter"), &p->filter);
  if (m.Has("traversability")) LoadTraversability(m.Child("traversability"), &p->traversability);
  if (m.Has("obstacles")) LoadObstacles(m.Child("obstacles"), &p->obstacles);
  m.Finish();
}

void LoadOccupancy(common::YamlMap m, MapperCoreParams* core) {
  m.Get("enabled", &core->occupancy_enabled);
  std::string preset = "octomap";
  m.Get("preset", &preset);
  OccupancyParams& p = core->occupancy;
  if (preset == "seed003") {
    p = OccupancyParams::Seed003();
  } else if (preset != "octomap") {
    m.Fail(m.Raw("preset"), "occupancy.preset must be 'octomap' or 'seed003'");
  }
  m.Get("hit_logodds", &p.hit_logodds);
  m.Get("miss_logodds", &p.miss_logodds);
  m.Get("clamp_min_logodds", &p.clamp_min_logodds);
  m.Get("clamp_max_logodds", &p.clamp_max_logodds);
  m.Get("resolution_m", &p.resolution_m);
  m.Get("size_x_cells", &p.size_x_cells);
  m.Get("size_y_cells", &p.size_y_cells);
  m.Get("origin_x_m", &p.origin_x_m);
  m.Get("origin_y_m", &p.origin_y_m);
  m.Get("min_range_m", &p.min_range_m);
  m.Get("max_range_m", &p.max_range_m);
  m.Get("no_return_range_m", &p.no_return_range_m);
  if (m.Has("band")) {
    common::YamlMap b = m.Child("band");
    ObstacleBandParams& band = core->band;
    b.Get("min_height_m", &band.min_height_m);
    b.Get("max_height_m", &band.max_height_m);
    b.Get("azimuth_bins", &band.azimuth_bins);
    b.Get("min_range_m", &band.min_range_m);
    b.Get("max_range_m", &band.max_range_m);
    b.Get("ground_window_m", &band.ground_window_m);
    b.Get("max_ground_slope_rad", &band.max_ground_slope_rad);
    b.Get("sensor_height_m", &band.sensor_height_m);
    b.Finish();
  }
  m.Finish();
}

void LoadOctomap(common::YamlMap m, MapperParams* params) {
  m.Get("enabled", &params->core.octomap_enabled);
  OctomapLayerParams& p = params->core.octomap;
  m.Get("resolution_m", &p.resolution_m);
  m.Get("prob_hit", &p.prob_hit);
  m.Get("prob_miss", &p.prob_miss);
  m.Get("clamp_min", &p.clamp_min);
  m.Get("clamp_max", &p.clamp_max);
  m.Get("max_range_m", &p.max_range_m);
  m.Get("min_range_m", &p.min_range_m);
  m.Get("every_revolutions", &params->octomap_every_revolutions);
  m.Get("publish_period_s", &params->octomap_period_s);
  m.Finish();
}

void LoadDynamic(common::YamlMap m, MapperParams* params) {
  MapperCoreParams* core = &params->core;
  m.Get("enabled", &core->dynamic_enabled);
  m.Get("long_term_store", &params->long_term_store);
  m.Get("long_term_save_period_s", &params->long_term_save_period_s);
  m.Get("long_term_load_timeout_s", &params->long_term_load_timeout_s);
  m.Get("static_map", &core->static_map_path);
  double origin_x = -20.0, origin_y = -20.0, size_x = 40.0, size_y = 40.0, res = 0.05;
  m.Get("origin_x_m", &origin_x);
  m.Get("origin_y_m", &origin_y);
  m.Get("size_x_m", &size_x);
  m.Get("size_y_m", &size_y);
  m.Get("resolution_m", &res);
  if (!(res > 0) || !(size_x > 0) || !(size_y > 0)) {
    m.Fail(m.Raw("resolution_m"), "dynamic: resolution and size must be positive");
  }
  core->dynamic_extent.resolution_m = res;
  core->dynamic_extent.size_x = static_cast<int>(std::lround(size_x / res));
  core->dynamic_extent.size_y = static_cast<int>(std::lround(size_y / res));
  core->dynamic_extent.origin = {origin_x, origin_y, 0.0};
  DynamicLayersParams& p = core->dynamic;
  m.Get("cost_inc", &p.cost_inc);
  m.Get("cost_dec", &p.cost_dec);
  m.Get("min_length_m", &p.min_length_m);
  m.Get("max_length_m", &p.max_length_m);
  m.Get("update_hz", &p.update_hz);
  m.Get("longterm_add_og", &p.longterm_add_og);
  m.Get("longterm_free_og", &p.longterm_free_og);
  m.Get("longterm_cost_dec", &p.longterm_cost_dec);
  m.Get("static_wall_og", &p.static_wall_og);
  m.Finish();
}

// The mapper's YAML file: every key optional, unknown keys are errors naming file and line.
void LoadMapperConfig(const std::string& path, MapperParams* params,
                      std::vector<std::string>* profiles) {
  common::YamlMap m = common::YamlMap::LoadFile(path);
  m.Get("map_name", &params->map_name);
  std::string source;
  if (m.Get("pose_source", &source)) {
    if (source == "ground_truth") {
      params->pose_source = PoseSource::kGroundTruth;
    } else if (source == "odometry") {
      params->pose_source = PoseSource::kOdometry;
    } else {
      m.Fail(m.Raw("pose_source"), "pose_source must be 'ground_truth' or 'odometry'");
    }
  }
  m.Get("max_pose_gap_s", &params->max_pose_gap_s);
  m.Get("imu_attitude", &params->imu_attitude);
  m.Get("max_imu_gap_s", &params->max_imu_gap_s);
  if (m.Has("lidar_mount")) {
    common::YamlMap mount = m.Child("lidar_mount");
    double x = 0, y = 0, z = 0, roll = 0, pitch = 0, yaw = 0;
    mount.Get("x_m", &x);
    mount.Get("y_m", &y);
    mount.Get("z_m", &z);
    mount.Get("roll_deg", &roll);
    mount.Get("pitch_deg", &pitch);
    mount.Get("yaw_deg", &yaw);
    mount.Finish();
    common::Pose3 pose;
    pose.position_m = {x, y, z};
    pose.orientation = Eigen::AngleAxisd(yaw * kDeg, Eigen::Vector3d::UnitZ()) *
                       Eigen::AngleAxisd(pitch * kDeg, Eigen::Vector3d::UnitY()) *
                       Eigen::AngleAxisd(roll * kDeg, Eigen::Vector3d::UnitX());
    params->lidar_mount = pose;
  }
  if (m.Has("profiles")) *profiles = m.Raw("profiles").as<std::vector<std::string>>();
  m.Get("publish_period_s", &params->publish_period_s);
  m.Get("slow_publish_period_s", &params->slow_publish_period_s);
  m.Get("registry_period_s", &params->registry_period_s);
  m.Get("occupancy_period_s", &params->occupancy_period_s);
  m.Get("max_pending_revolutions", &params->max_pending_revolutions);
  m.Get("tiles_per_burst", &params->tiles_per_burst);
  m.Get("burst_pause_ms", &params->burst_pause_ms);
  m.Get("snapshot_dir", &params->snapshot_dir);
  if (m.Has("terrain")) LoadTerrain(m.Child("terrain"), &params->core.terrain);
  if (m.Has("occupancy")) LoadOccupancy(m.Child("occupancy"), &params->core);
  if (m.Has("octomap")) LoadOctomap(m.Child("octomap"), params);
  if (m.Has("dynamic")) LoadDynamic(m.Child("dynamic"), params);
  m.Finish();
}

int Replay(runtime::Node& node, MapperService& service, const std::string& log_path,
           const std::string& output) {
  lcm::LogFile log(log_path, "r");
  if (!log.good()) {
    CAIRN_LOG_ERROR("cannot read log %s", log_path.c_str());
    return 1;
  }
  const auto start = std::chrono::steady_clock::now();
  int64_t events = 0;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    service.HandleLogged(event->channel, event->data, event->datalen);
    ++events;
    if (runtime::ShutdownRequested()) break;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  node.Event("replayed %lld messages, %lld revolutions in %.2f s (%.1f revolutions/s)",
             static_cast<long long>(events), static_cast<long long>(service.revolutions()), seconds,
             seconds > 0 ? service.revolutions() / seconds : 0.0);
  if (!output.empty()) {
    const common::Status status = service.WriteOutputs(output);
    if (!status.ok()) {
      CAIRN_LOG_ERROR("%s", status.ToString().c_str());
      return 1;
    }
    node.Event("maps written to %s", output.c_str());
  }
  return 0;
}

// Seed 001's memory across runs: the long-term layer last saved to the store. Returns false
// (after saying why) when the mapper must not start: the store did not answer, or failed.
bool RestoreLongTerm(runtime::Node& node, MapperParams* params) {
  const std::string& where = params->long_term_store;
  const auto slash = where.find('/');
  if (slash == std::string::npos) return true;  // Validate() reports the bad name
  mapstore::MapstoreClientOptions options;
  options.total_timeout_s = params->long_term_load_timeout_s;
  mapstore::MapstoreClient client(node.lcm(), "cairn-mapper-" + params->robot, options);
  auto loaded = client.Load(where.substr(0, slash), where.substr(slash + 1), /*version=*/0,
                            /*profile=*/"", {layers::kLongTerm});
  if (loaded.ok()) {
    node.Event("long-term layer restored from %s version %lld", where.c_str(),
               static_cast<long long>(loaded->reply.version));
    params->core.long_term_restore = std::move(loaded->layers);
    return true;
  }
  if (loaded.status().code() == common::StatusCode::kNotFound) {
    node.Event("no long-term layer stored as %s yet: it starts as the static map", where.c_str());
    return true;
  }
  CAIRN_LOG_ERROR("cannot restore the long-term layer from %s: %s", where.c_str(),
                  loaded.status().ToString().c_str());
  return false;
}

int Main(int argc, char** argv) {
  std::string robot, config, profiles_flag, profiles_dir = CAIRN_CONFIG_DIR "/profiles";
  std::string lcm_url, replay, output, pose_source, static_map, long_term_store;
  common::FlagParser flags(
      "cairn-mapper",
      "One robot's mapper: fuses the lidar into a site-fixed elevation map, derives slope, step, "
      "roughness, ditches and a cost layer for every robot profile it serves, keeps the obstacle "
      "registry with each profile's verdicts, the 2-D occupancy and the OctoMap, and publishes "
      "them as tiles on <robot>.MAP.*. With --replay it builds the same maps from an lcm-logger "
      "file as fast as the machine goes.");
  flags.AddString("robot", &robot, "robot name (channel prefix), required");
  flags.AddString("config", &config, "mapper YAML (config/mapping/mapper.yaml); defaults if empty");
  flags.AddString("profiles", &profiles_flag,
                  "comma-separated profiles to serve (names in --profiles-dir or YAML paths); "
                  "overrides the config");
  flags.AddString("profiles-dir", &profiles_dir, "where profile names are looked up");
  flags.AddString("pose-source", &pose_source, "ground_truth or odometry; overrides the config");
  flags.AddString("static-map", &static_map,
                  "a map_server YAML: turns the dynamic layers (seed 001) on over that map");
  flags.AddString("long-term-store", &long_term_store,
                  "SITE/MAP in cairn-mapstore: restore the long-term layer from there at start "
                  "and save it there periodically (dynamic.long_term_save_period_s); overrides "
                  "the config");
  flags.AddString("lcm-url", &lcm_url, "LCM URL (default LCM_DEFAULT_URL, else udpm ttl=0)");
  flags.AddString("replay", &replay, "an lcm-logger file to map offline instead of the bus");
  flags.AddString("output", &output,
                  "with --replay: directory for the maps (raw float32 layers, "
                  "map.yaml, obstacles.yaml, octomap.bt)");
  flags.AddHelpSection(
      "Channels",
      "in:  <robot>.LIDAR .SCAN .POSE .ODOM .IMU .MAP.CONTROL .MAP.TILE_RESEND\n"
      "out: <robot>.MAP.TILES .MAP.MANIFEST .MAP.OCCUPANCY .MAP.OBSTACLES "
      ".MAP.OCTOMAP .MAP.CONTROL_REPLY, HEALTH\n"
      "with --long-term-store: MAPSTORE.REQUEST (load at start, periodic pull "
      "saves), MAPSTORE.REPLY, MAPSTORE.TILES, MAPSTORE.TILE_BATCHES, MAPSTORE.MANIFEST");
  flags.AddHelpSection("Control (<robot>.MAP.CONTROL)",
                       "OP_ADD_PROFILE (by name or with profile data), OP_REMOVE_PROFILE, "
                       "OP_PUBLISH_ALL, OP_RESET, OP_SNAPSHOT (writes the maps under "
                       "snapshot_dir), OP_CLEAR_SHORT_TERM");
  const int parsed = flags.Parse(argc, argv);
  if (parsed >= 0) return parsed;
  if (robot.empty()) {
    std::fprintf(stderr, "cairn-mapper: --robot is required (see --help)\n");
    return 2;
  }
  common::SetLogTag("cairn-mapper[" + robot + "]");

  MapperParams params;
  params.robot = robot;
  std::vector<std::string> profile_names{"pioneer3at"};
  try {
    if (!config.empty()) LoadMapperConfig(config, &params, &profile_names);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-mapper: %s\n", e.what());
    return 2;
  }
  if (!profiles_flag.empty()) profile_names = SplitList(profiles_flag);
  if (!static_map.empty()) {
    params.core.dynamic_enabled = true;
    params.core.static_map_path = static_map;
  }
  if (!long_term_store.empty()) params.long_term_store = long_term_store;
  if (pose_source == "odometry") {
    params.pose_source = PoseSource::kOdometry;
  } else if (pose_source == "ground_truth") {
    params.pose_source = PoseSource::kGroundTruth;
  } else if (!pose_source.empty()) {
    std::fprintf(stderr, "cairn-mapper: --pose-source must be ground_truth or odometry\n");
    return 2;
  }
  std::vector<common::RobotProfile> profiles;
  for (const auto& name : profile_names) {
    auto profile = ResolveProfile(profiles_dir, name);
    if (!profile.ok()) {
      std::fprintf(stderr, "cairn-mapper: %s\n", profile.status().message().c_str());
      return 2;
    }
    profiles.push_back(*profile);
  }

  try {
    runtime::NodeOptions options;
    options.process_name = "cairn-mapper";
    options.robot = robot;
    options.lcm_url = replay.empty() ? lcm_url : "memq://";
    options.follow_sim_clock = replay.empty();
    runtime::Node node(options);
    ProfileResolver resolver = [profiles_dir](const std::string& name) {
      return ResolveProfile(profiles_dir, name);
    };
    if (!replay.empty()) {
      MapperService service(node, params, profiles, resolver, MapperService::Mode::kReplay);
      return Replay(node, service, replay, output);
    }
    if (!params.long_term_store.empty()) {
      params.Validate();  // a bad SITE/MAP is reported before anything is asked
      if (!RestoreLongTerm(node, &params)) return 1;
    }
    MapperService service(node, params, profiles, resolver, MapperService::Mode::kLive);
    const int code = node.Spin();
    node.SetState(runtime::HealthState::kStopping);
    service.Stop();
    node.Event("stopped after %lld revolutions", static_cast<long long>(service.revolutions()));
    return code;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-mapper: %s\n", e.what());
    return 1;
  }
}

}  // namespace
}  // namespace cairn::mapping

int main(int argc, char** argv) { return cairn::mapping::Main(argc, argv); }
