// cairn-mission: runs the demo mission against a running graph (see scripts/demo).

#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/flags.h"
#include "services/mission/lcm/demo_mission.h"
#include "services/runtime/node.h"

using namespace cairn;

namespace {

bool ParseGoal(const std::string& text, mission::MissionParams* params) {
  std::stringstream ss(text);
  std::string part;
  std::vector<double> values;
  while (std::getline(ss, part, ',')) {
    char* end = nullptr;
    const double v = std::strtod(part.c_str(), &end);
    if (end == part.c_str() || *end != '\0' || !std::isfinite(v)) return false;
    values.push_back(v);
  }
  if (values.size() != 2 && values.size() != 3) return false;
  params->goal = {values[0], values[1], values.size() == 3 ? values[2] : 0.0};
  params->goal_has_yaw = values.size() == 3;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  mission::MissionParams params;
  std::string lcm_url, goal_text = "21,38", share = "rover";
  common::FlagParser flags(
      "cairn-mission",
      "Runs the demo mission against a running graph: sends the robot to a goal, waits until it\n"
      "arrives, has cairn-mapstore save the map the mapper built, shares it with other robot\n"
      "profiles, prints a summary (distance, time, real-time factor, obstacles with each\n"
      "profile's verdict) and writes PNG renders, a CSV of planned against driven X(t), Y(t)\n"
      "and, when the robot has a sonar, the fan of its last sweep. Exits 0 only when all of it\n"
      "succeeded.");
  flags.AddString("robot", &params.robot, "robot id (channel prefix)");
  flags.AddString("profile", &params.source_profile, "the robot's own profile");
  flags.AddString("share", &share, "comma-separated profiles to share the stored map with");
  flags.AddString("profiles-dir", &params.profiles_dir, "folder of profile YAML files");
  flags.AddString("goal", &goal_text, "goal as x,y or x,y,yaw (world frame, m and rad)");
  flags.AddString("site", &params.site, "site name in the map store");
  flags.AddString("map", &params.map_name, "map name in the map store");
  flags.AddString("out", &params.out_dir, "folder for the PNG renders and track.csv");
  flags.AddString("map-layer", &params.map_layer,
                  "stored base layer rendered with the path and obstacles: elevation, or "
                  "sonar/occupancy for the AUV");
  flags.AddDouble("timeout", &params.timeout_s, "seconds (wall clock) allowed for the drive");
  flags.AddDouble("ready-timeout", &params.ready_timeout_s, "seconds to wait for the graph");
  flags.AddString("lcm-url", &lcm_url, "LCM URL (default LCM_DEFAULT_URL, else udpm ttl=0)");
  const int parsed = flags.Parse(argc, argv);
  if (parsed >= 0) return parsed;
  if (!ParseGoal(goal_text, &params)) {
    std::fprintf(stderr, "cairn-mission: bad --goal '%s' (x,y or x,y,yaw)\n", goal_text.c_str());
    return 2;
  }
  params.share_profiles.clear();
  std::stringstream ss(share);
  std::string p;
  while (std::getline(ss, p, ',')) {
    if (!p.empty()) params.share_profiles.push_back(p);
  }
  try {
    runtime::NodeOptions options;
    options.process_name = "cairn-mission";
    options.robot = params.robot;
    options.lcm_url = lcm_url;
    runtime::Node node(options);
    node.SetState(runtime::HealthState::kReady);
    mission::DemoMission mission(&node, params);
    const mission::MissionReport report = mission.Run();
    std::fputs(mission::FormatReport(params, report).c_str(), stdout);
    return report.ok() ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cairn-mission: %s\n", e.what());
    return 2;
  }
}
