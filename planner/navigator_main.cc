// cairn-navigator: global (OMPL) and local (DWA) navigation for one robot over LCM.

#include <cstdio>
#include <exception>
#include <string>

#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "common/flags.h"
#include "common/log.h"
#include "common/robot_profile.h"
#include "common/yaml_reader.h"
#include "planner/lcm/navigator_service.h"
#include "planner/local/critic_registry.h"
#include "planner/navigator_config.h"
#include "planner/places.h"
#include "services/runtime/node.h"

namespace {

using namespace cairn;

struct Options {
  std::string robot;
  std::string profile = "pioneer3at";
  std::string config_dir = CAIRN_CONFIG_DIR;
  std::string config_path;
  std::string places_path;
  std::string pose_source;
  std::string lcm_url;
};

void AddFlags(common::FlagParser* flags, Options* o) {
  flags->AddString("robot", &o->robot, "robot name, the prefix of its channels (required)");
  flags->AddString("profile", &o->profile,
                   "robot profile: a name under <config-dir>/profiles or a YAML path");
  flags->AddString("config", &o->config_path,
                   "navigator configuration (default <config-dir>/navigator/navigator.yaml)");
  flags->AddString("config-dir", &o->config_dir, "directory holding profiles/ and navigator/");
  flags->AddString("places", &o->places_path,
                   "YAML list of named places {name, polygon: [[x, y], ...]} for place goals");
  flags->AddString("pose-source", &o->pose_source,
                   "override the configuration: pose (<robot>.POSE) or odom (<robot>.ODOM)");
  flags->AddString("lcm-url", &o->lcm_url, "LCM URL (default: LCM_DEFAULT_URL or udpm with ttl=0)");
  flags->AddHelpSection("Channels",
                        "reads  <robot>.GOAL, <robot>.POSE or <robot>.ODOM, <robot>.MAP.TILES\n"
                        "       (or <robot>.MAP.OCCUPANCY with map.encoding occupancy),\n"
                        "       <robot>.MAP.MANIFEST, SIM.CLOCK\n"
                        "writes <robot>.CMD_VEL, <robot>.PATH, <robot>.NAV_STATUS,\n"
                        "       <robot>.MAP.TILE_RESEND, <robot>.MAP.CONTROL, HEALTH");
  std::string critics;
  for (const std::string& name : planner::BuiltinCritics().names()) {
    critics += (critics.empty() ? "" : ", ") + name;
  }
  flags->AddHelpSection("Planners",
                        "RRTConnect, RRTstar, InformedRRTstar, BITstar, PRMstar, RRT "
                        "(global_planner.planner); state spaces se2, dubins (with RRT), "
                        "reeds_shepp; DWA critics (local_planner.critics): " +
                            critics);
}

// A profile argument is a path when it names a file, else a name under <config-dir>/profiles.
std::string ProfilePath(const std::string& profile, const std::string& config_dir) {
  if (profile.find('/') != std::string::npos ||
      (profile.size() > 5 && profile.compare(profile.size() - 5, 5, ".yaml") == 0)) {
    return profile;
  }
  return config_dir + "/profiles/" + profile + ".yaml";
}

// Loads the profile, configuration and places, and runs the service until a signal.
void Run(const Options& o) {
  const common::RobotProfile profile =
      common::LoadRobotProfileFile(ProfilePath(o.profile, o.config_dir));
  const std::string config_path =
      o.config_path.empty() ? o.config_dir + "/navigator/navigator.yaml" : o.config_path;
  planner::NavigatorConfig config = planner::LoadNavigatorConfigFile(config_path);
  if (!o.pose_source.empty()) config.pose_source = planner::PoseSourceFromName(o.pose_source);
  std::vector<planner::Place> places;
  if (!o.places_path.empty()) places = planner::LoadPlacesFile(o.places_path);

  runtime::NodeOptions options;
  options.process_name = "cairn-navigator";
  options.robot = o.robot;
  options.lcm_url = o.lcm_url;
  runtime::Node node(options);
  CAIRN_LOG_INFO("profile %s, config %s, %zu places, bus %s", profile.name.c_str(),
                 config_path.c_str(), places.size(), node.url().c_str());
  planner::NavigatorService service(node, config, profile, places);
  node.Spin();
  // Leaving: a robot we were driving must not keep its last command.
  if (service.navigator().active()) {
    cairn::lcmt_velocity_command stop{};
    stop.utime = node.NowUtime();
    stop.robot = o.robot;
    stop.source = "cairn-navigator";
    node.Publish(channels::ForRobot(o.robot, channels::kCmdVel), stop);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  common::FlagParser flags(
      "cairn-navigator",
      "Navigates one robot to goals: an OMPL global planner on the mapper's cost layer for the "
      "robot's profile (or, with map.encoding occupancy, on a 2-D occupancy layer such as the "
      "dynamic map server's final layer), a DWA local planner, recovery behaviours and a safety "
      "stop when the pose or the map goes stale.");
  AddFlags(&flags, &options);
  const int rc = flags.Parse(argc, argv);
  if (rc >= 0) return rc;
  if (options.robot.empty()) {
    std::fprintf(stderr, "cairn-navigator: --robot is required (see --help)\n");
    return 2;
  }
  common::SetLogTag("cairn-navigator[" + options.robot + "]");
  try {
    Run(options);
    CAIRN_LOG_INFO("stopped");
    return 0;
  } catch (const common::ConfigError& e) {
    CAIRN_LOG_ERROR("configuration error: %s", e.what());
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("%s", e.what());
  }
  return 1;
}
