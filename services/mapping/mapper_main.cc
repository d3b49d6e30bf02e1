// cairn-mapper: one robot's mapper (terrain, traversability per profile, obstacle registry,
// occupancy, OctoMap, dynamic layers), live on the bus or offline from an lcm-logger file.

#include <cstdio>
#include <string>
#include <vector>

#include "common/flags.h"
#include "common/log.h"
#include "services/mapping/lcm/mapper_process.h"
#include "services/mapping/lcm/mapper_service.h"
#include "services/mapping/mapper_config.h"
#include "services/runtime/node.h"

namespace cairn::mapping {
namespace {

struct Flags {
  std::string robot, config, profiles, profiles_dir = CAIRN_CONFIG_DIR "/profiles";
  std::string lcm_url, replay, output, pose_source, static_map, long_term_store;
  std::string explore_config, work_area;
};

// Parses the command line; returns an exit code when the process is done (help, bad flags).
int ParseFlags(int argc, char** argv, Flags* f) {
  common::FlagParser flags(
      "cairn-mapper",
      "One robot's mapper: fuses the lidar into a site-fixed elevation map, derives slope, step, "
      "roughness, ditches and a cost layer for every robot profile it serves, keeps the obstacle "
      "registry with each profile's verdicts, the 2-D occupancy and the OctoMap, and publishes "
      "them as tiles on <robot>.MAP.*. With --replay it builds the same maps from an lcm-logger "
      "file as fast as the machine goes.");
  flags.AddString("robot", &f->robot, "robot name (channel prefix), required");
  flags.AddString("config", &f->config,
                  "mapper YAML (config/mapping/mapper.yaml); defaults if empty");
  flags.AddString("profiles", &f->profiles,
                  "comma-separated profiles to serve (names in --profiles-dir or YAML paths); "
                  "overrides the config");
  flags.AddString("profiles-dir", &f->profiles_dir, "where profile names are looked up");
  flags.AddString("pose-source", &f->pose_source, "ground_truth or odometry; overrides the config");
  flags.AddString("static-map", &f->static_map,
                  "a map_server YAML: turns the dynamic layers (seed 001) on over that map");
  flags.AddString("explore-config", &f->explore_config,
                  "an explorer YAML with an nbv section (config/explore/*_nbv.yaml): turns the "
                  "information-map layer (explore/*, seed 002) on with its parameters, built from "
                  "<robot>.TURRET_SCAN");
  flags.AddString("work-area", &f->work_area,
                  "with --explore-config: the information map's work area (\"x0,y0 x1,y1 ...\"), "
                  "over the configuration's");
  flags.AddString("long-term-store", &f->long_term_store,
                  "SITE/MAP in cairn-mapstore: restore the long-term layer from there at start "
                  "and save it there periodically (dynamic.long_term_save_period_s); overrides "
                  "the config");
  flags.AddString("lcm-url", &f->lcm_url, "LCM URL (default LCM_DEFAULT_URL, else udpm ttl=0)");
  flags.AddString("replay", &f->replay, "an lcm-logger file to map offline instead of the bus");
  flags.AddString("output", &f->output,
                  "with --replay: directory for the maps (raw float32 layers, "
                  "map.yaml, obstacles.yaml, octomap.bt)");
  flags.AddHelpSection(
      "Channels",
      "in:  <robot>.LIDAR_RANGES (or .LIDAR, points) .SCAN .POSE .ODOM .IMU .MAP.CONTROL\n"
      "     <robot>.MAP.TILE_RESEND\n"
      "     <robot>.TURRET_SCAN (with the explore layer), <robot>.SONAR (with the sonar layer)\n"
      "out: <robot>.MAP.TILES .MAP.MANIFEST .MAP.OCCUPANCY .MAP.OBSTACLES "
      ".MAP.OCTOMAP .MAP.CONTROL_REPLY, HEALTH\n"
      "     <robot>.SONAR_DETECTIONS (with the sonar layer: each ping's obstacles)\n"
      "with --long-term-store: MAPSTORE.REQUEST (load at start, periodic pull "
      "saves), MAPSTORE.REPLY, MAPSTORE.TILES, MAPSTORE.TILE_BATCHES, MAPSTORE.MANIFEST");
  flags.AddHelpSection("Control (<robot>.MAP.CONTROL)",
                       "OP_ADD_PROFILE (a name in --profiles-dir, never a path, or the profile "
                       "data itself), OP_REMOVE_PROFILE, "
                       "OP_PUBLISH_ALL, OP_RESET, OP_SNAPSHOT (writes the maps under "
                       "snapshot_dir), OP_CLEAR_SHORT_TERM");
  const int parsed = flags.Parse(argc, argv);
  if (parsed >= 0) return parsed;
  if (f->robot.empty()) {
    std::fprintf(stderr, "cairn-mapper: --robot is required (see --help)\n");
    return 2;
  }
  return -1;
}

// The configuration file with the flags over it, and the profiles it names.
MapperConfig LoadConfig(const Flags& f, std::vector<common::RobotProfile>* profiles) {
  MapperConfig config = f.config.empty() ? MapperConfig() : LoadMapperConfigFile(f.config);
  MapperParams& params = config.params;
  params.robot = f.robot;
  if (!f.profiles.empty()) config.profiles = SplitList(f.profiles);
  if (!f.static_map.empty()) {
    params.core.SetListed(kDynamicLayerName, true);
    params.core.dynamic.static_map_path = f.static_map;
  }
  if (!f.explore_config.empty() || !f.work_area.empty()) {
    ExploreMapperLayerParams& explore = params.core.explore;
    if (!f.explore_config.empty()) explore.explorer_config = f.explore_config;
    if (!f.work_area.empty()) explore.work_area = f.work_area;
    if (explore.explorer_config.empty()) {
      throw std::invalid_argument(
          "--work-area needs --explore-config (or explore.explorer_config)");
    }
    ReadExplorerConfig(&explore);
    params.core.SetListed(kExploreLayerName, true);
  }
  if (!f.long_term_store.empty()) params.long_term_store = f.long_term_store;
  if (!f.pose_source.empty()) {
    try {
      params.inputs.pose_source = PoseSourceFromName(f.pose_source);
    } catch (const std::invalid_argument&) {
      throw std::invalid_argument("--pose-source must be ground_truth or odometry");
    }
  }
  for (const auto& name : config.profiles) {
    auto profile = ResolveProfile(f.profiles_dir, name);
    if (!profile.ok()) throw std::invalid_argument(profile.status().message());
    profiles->push_back(*profile);
  }
  return config;
}

int Main(int argc, char** argv) {
  Flags f;
  const int done = ParseFlags(argc, argv, &f);
  if (done >= 0) return done;
  common::SetLogTag("cairn-mapper[" + f.robot + "]");
  std::vector<common::RobotProfile> profiles;
  MapperConfig config;
  try {
    config = LoadConfig(f, &profiles);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-mapper: %s\n", e.what());
    return 2;
  }
  try {
    runtime::NodeOptions options;
    options.process_name = "cairn-mapper";
    options.robot = f.robot;
    options.lcm_url = f.replay.empty() ? MapperLcmUrl(f.lcm_url) : "memq://";
    options.follow_sim_clock = f.replay.empty();
    runtime::Node node(options);
    const std::string dir = f.profiles_dir;
    // Profiles named on the bus come from the profiles folder, by name only.
    ProfileResolver resolver = [dir](const std::string& name) {
      return ResolveProfileByName(dir, name);
    };
    MapperParams& params = config.params;
    if (!f.replay.empty()) {
      MapperService service(node, params, profiles, resolver, MapperService::Mode::kReplay);
      return ReplayLog(node, service, f.replay, f.output);
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
