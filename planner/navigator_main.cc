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
#include "planner/navigator_config.h"
#include "planner/lcm/navigator_service.h"
#include "planner/places.h"
#include "services/runtime/node.h"

namespace {

// A profile argument is a path when it names a file, else a name under <config-dir>/profiles.
std::string ProfilePath(const std::string& profile, const std::string& config_dir) {
  if (profile.find('/') != std::string::npos ||
      (profile.size() > 5 && profile.compare(profile.size() - 5, 5, ".yaml") == 0)) {
    return profile;
  }
  return config_dir + "/profiles/" + profile + ".yaml";
}

}  // namespace

int main(int argc, char** argv) {
  using namespace cairn;
  std::string robot;
  std::string profile_arg = "pioneer3at";
  std::string config_dir = CAIRN_CONFIG_DIR;
  std::string config_path;
  std::string places_path;
  std::string pose_source;
  std::string lcm_url;
  common::FlagParser flags(
      "cairn-navigator",
      "Navigates one robot to goals: an OMPL global planner on the mapper's cost layer for the "
      "robot's profile (or, with map.encoding occupancy, on a 2-D occupancy layer such as the "
      "dynamic map server's final layer), a DWA local planner, recovery behaviours and a safety stop when the pose "
      "or the map goes stale.");
  flags.AddString("robot", &robot, "robot name, the prefix of its channels (required)");
  flags.AddString("profile", &profile_arg,
                  "robot profile: a name under <config-dir>/profiles or a YAML path");
  flags.AddString("config", &config_path,
                  "navigator configuration (default <config-dir>/navigator/navigator.yaml)");
  flags.AddString("config-dir", &config_dir, "directory holding profiles/ and navigator/");
  flags.AddString("places", &places_path,
                  "YAML list of named places {name, polygon: [[x, y], ...]} for place goals");
  flags.AddString("pose-source", &pose_source,
                  "override the configuration: pose (<robot>.POSE) or odom (<robot>.ODOM)");
  flags.AddString("lcm-url", &lcm_url, "LCM URL (default: LCM_DEFAULT_URL or udpm with ttl=0)");
  flags.AddHelpSection("Channels",
                       "reads  <robot>.GOAL, <robot>.POSE or <robot>.ODOM, <robot>.MAP.TILES\n"
                       "       (or <robot>.MAP.OCCUPANCY with map.encoding occupancy),\n"
                       "       <robot>.MAP.MANIFEST, SIM.CLOCK\n"
                       "writes <robot>.CMD_VEL, <robot>.PATH, <robot>.NAV_STATUS,\n"
                       "       <robot>.MAP.TILE_RESEND, <robot>.MAP.CONTROL, HEALTH");
  flags.AddHelpSection(
      "Planners",
      "RRTConnect, RRTstar, InformedRRTstar, BITstar, PRMstar, RRT "
      "(global_planner.planner); state spaces se2, dubins (with RRT), reeds_shepp");
  const int rc = flags.Parse(argc, argv);
  if (rc >= 0) return rc;
  if (robot.empty()) {
    std::fprintf(stderr, "cairn-navigator: --robot is required (see --help)\n");
    return 2;
  }
  common::SetLogTag("cairn-navigator[" + robot + "]");

  try {
    const common::RobotProfile profile =
        common::LoadRobotProfileFile(ProfilePath(profile_arg, config_dir));
    if (config_path.empty()) config_path = config_dir + "/navigator/navigator.yaml";
    planner::NavigatorConfig config = planner::LoadNavigatorConfigFile(config_path);
    if (!pose_source.empty()) config.pose_source = planner::PoseSourceFromName(pose_source);
    std::vector<planner::Place> places;
    if (!places_path.empty()) places = planner::LoadPlacesFile(places_path);

    runtime::NodeOptions options;
    options.process_name = "cairn-navigator";
    options.robot = robot;
    options.lcm_url = lcm_url;
    runtime::Node node(options);
    CAIRN_LOG_INFO("profile %s, config %s, %zu places, bus %s", profile.name.c_str(),
                   config_path.c_str(), places.size(), node.url().c_str());
    {
      planner::NavigatorService service(node, config, profile, places);
      node.Spin();
      // Leaving: a robot we were driving must not keep its last command.
      if (service.navigator().active()) {
        cairn::lcmt_velocity_command stop{};
        stop.utime = node.NowUtime();
        stop.robot = robot;
        stop.source = "cairn-navigator";
        node.Publish(channels::ForRobot(robot, channels::kCmdVel), stop);
      }
    }
    CAIRN_LOG_INFO("stopped");
    return 0;
  } catch (const common::ConfigError& e) {
    CAIRN_LOG_ERROR("configuration error: %s", e.what());
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("%s", e.what());
  }
  return 1;
}
