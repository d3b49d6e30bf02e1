// cairn-explorer: explores with one robot (see services/explore/README.md).

#include <cstdio>
#include <string>

#include "common/channels.h"
#include "common/flags.h"
#include "common/log.h"
#include "common/robot_profile.h"
#include "common/yaml_reader.h"
#include "services/explore/explorer_config.h"
#include "services/explore/lcm/explorer_service.h"
#include "services/runtime/node.h"

using namespace cairn;

namespace {

struct Options {
  std::string robot;
  std::string profile;
  std::string config_path;
  std::string config_dir = CAIRN_CONFIG_DIR;
  std::string mode;
  std::string work_area;
  std::string preset;
  int max_scans = 0;
  int seed = -1;
  std::string out_dir;
  std::string save_to;
  std::string drive;
  double duration_s = -1.0;
  std::string lcm_url;
};

// A profile argument is a path when it names a file, else a name under <config-dir>/profiles.
std::string ProfilePath(const std::string& profile, const std::string& config_dir) {
  if (profile.find('/') != std::string::npos ||
      (profile.size() > 5 && profile.compare(profile.size() - 5, 5, ".yaml") == 0)) {
    return profile;
  }
  return config_dir + "/profiles/" + profile + ".yaml";
}

int Run(const Options& o) {
  const common::RobotProfile profile =
      common::LoadRobotProfileFile(ProfilePath(o.profile, o.config_dir));
  const std::string config_path =
      o.config_path.empty() ? o.config_dir + "/explore/explorer.yaml" : o.config_path;
  explore::ExplorerConfig config = explore::LoadExplorerConfigFile(config_path);
  if (!o.mode.empty()) config.mode = explore::ExploreModeFromName(o.mode);
  if (o.duration_s >= 0.0) config.duration_s = o.duration_s;
  if (!o.work_area.empty()) config.nbv.work_area = o.work_area;
  if (!o.preset.empty()) config.nbv.preset = o.preset;
  if (o.max_scans > 0) config.nbv.max_scans = o.max_scans;
  if (o.seed >= 0) config.nbv.seed = o.seed;
  if (!o.out_dir.empty()) config.out_dir = o.out_dir;
  if (!o.save_to.empty()) config.save_to = o.save_to;
  if (!o.drive.empty()) config.nbv.drive = o.drive;
  config.Validate();

  runtime::NodeOptions options;
  options.process_name = "cairn-explorer";
  options.robot = o.robot;
  // The next-best-view mode takes the turret's lines (about 2 KB each, 50 a second) beside
  // the lidar's traffic on the same multicast group: a large receive buffer keeps bursts.
  options.lcm_url = runtime::WithReceiveBuffer(runtime::ResolveLcmUrl(o.lcm_url),
                                               runtime::kLargeReceiveBufferBytes);
  runtime::Node node(options);
  CAIRN_LOG_INFO("profile %s, config %s, mode %s, bus %s", profile.name.c_str(),
                 config_path.c_str(), explore::ExploreModeName(config.mode), node.url().c_str());
  explore::ExplorerService service(node, config, profile);
  while (node.SpinOnce(50) && !service.done()) {
  }
  if (!service.done()) service.Halt("stopped by a signal");
  service.WrapUp();
  // The last status (and the stop command) reach the bus before the socket closes.
  service.PublishStatus();
  for (int i = 0; i < 4; ++i) node.SpinOnce(5);
  return service.failed() ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  common::FlagParser flags(
      "cairn-explorer",
      "Explores with one robot. Modes: 'reactive', seed 003's five-sector explorer on the planar\n"
      "laser (cruise, corridor centring, turn in place toward the freer side with direction\n"
      "memory, reverse when cornered or blocked over 2 s); 'stateless', its baseline without\n"
      "memory or reverse; 'frontier', goals on the frontiers of the mapper's 2-D occupancy,\n"
      "driven by cairn-navigator; 'nbv', seed 002's stop-and-scan next-best-view: a full 3-D\n"
      "scan asked of the simulator's turret at each view point, the information map over the\n"
      "work area, the next view point chosen by utility and driven to by cairn-navigator.\n"
      "Exits when the exploration is done (the time given by --duration, no frontier left, or\n"
      "the next-best-view stop rule), or on SIGINT/SIGTERM, stopping the robot first; exit 1\n"
      "when a next-best-view mission failed (scans or goals kept failing).");
  flags.AddString("robot", &o.robot, "robot name, the prefix of its channels (required)");
  flags.AddString("profile", &o.profile,
                  "robot profile: a name under <config-dir>/profiles or a file");
  flags.AddString("config", &o.config_path,
                  "explorer YAML (default <config-dir>/explore/explorer.yaml)");
  flags.AddString("config-dir", &o.config_dir, "directory holding profiles/ and explore/");
  flags.AddString("mode", &o.mode, "reactive, stateless, frontier or nbv (overrides the config)");
  flags.AddString("work-area", &o.work_area,
                  "nbv: the work area polygon \"x0,y0 x1,y1 x2,y2 ...\" in world metres");
  flags.AddString("preset", &o.preset,
                  "nbv: a preset of seed 002's tables (simple-balanced, greedy, ...)");
  flags.AddString("out", &o.out_dir,
                  "nbv: write the summary table and the information map's renders (PNG) here");
  flags.AddString("save", &o.save_to,
                  "nbv: \"site/map\": save the information map to cairn-mapstore at the end");
  flags.AddString("drive", &o.drive,
                  "nbv: navigator (drive to each view point) or teleport (the simulator puts the "
                  "robot there; the distance is the navigation tree's path)");
  flags.AddInt("max-scans", &o.max_scans, "nbv: end after this many scans (overrides the config)");
  flags.AddInt("seed", &o.seed, "nbv: the candidate sampling's seed (overrides the config)");
  flags.AddDouble("duration", &o.duration_s,
                  "simulated seconds of exploring, 0 = until done (overrides the config)");
  flags.AddString("lcm-url", &o.lcm_url, "LCM URL (default: LCM_DEFAULT_URL or udpm with ttl=0)");
  flags.AddHelpSection(
      "Channels",
      "reads <robot>.SCAN, <robot>.POSE; frontier mode also <robot>.MAP.OCCUPANCY,\n"
      "<robot>.MAP.MANIFEST, <robot>.NAV_STATUS; nbv mode <robot>.TURRET_SCAN,\n"
      "<robot>.NAV_STATUS, SIM.CONTROL_REPLY. Writes <robot>.CMD_VEL (reactive modes),\n"
      "<robot>.GOAL (frontier and nbv modes), SIM.CONTROL (nbv: OP_TRIGGER_SENSOR),\n"
      "<robot>.EXPLORE_STATUS.");
  const int rc = flags.Parse(argc, argv);
  if (rc >= 0) return rc;
  if (o.robot.empty() || o.profile.empty()) {
    std::fprintf(stderr, "cairn-explorer: --robot and --profile are required (see --help)\n");
    return 2;
  }
  common::SetLogTag("cairn-explorer[" + o.robot + "]");
  try {
    const int result = Run(o);
    CAIRN_LOG_INFO("stopped");
    return result;
  } catch (const common::ConfigError& e) {
    CAIRN_LOG_ERROR("configuration error: %s", e.what());
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("%s", e.what());
  }
  return 1;
}
