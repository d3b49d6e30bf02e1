// cairn-sim: MuJoCo simulation of worlds, robots and their sensors on LCM.

#include <cstdio>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "common/flags.h"
#include "common/log.h"
#include "common/yaml_reader.h"
#include "services/runtime/node.h"
#include "simulator/mujoco_model.h"
#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"
#include "simulator/lcm/sim_service.h"

namespace {

using cairn::sim::SimPaths;

std::string WorldsHelp(const SimPaths& paths) {
  std::ostringstream out;
  for (const std::string& world : paths.ShippedWorlds()) {
    out << "  " << world << ": " << paths.WorldSummary(world) << "\n";
  }
  out << "  (or the path of any MJCF file: robots are inserted into it)\n";
  return out.str();
}

std::string RobotsHelp(const SimPaths& paths) {
  std::ostringstream out;
  for (const std::string& name : paths.ShippedRobots()) {
    try {
      const cairn::sim::RobotModel model = cairn::sim::LoadRobotModel(paths, name);
      out << "  " << name << ": " << model.description << "\n      default profile "
          << model.default_profile << "; sensors:";
      for (const std::string& s : model.default_sensors.Names()) out << " " << s;
      out << "\n";
    } catch (const std::exception& e) {
      out << "  " << name << ": (unreadable: " << e.what() << ")\n";
    }
  }
  return out.str();
}

std::string SensorsHelp() {
  std::ostringstream out;
  for (const auto& [name, description] : cairn::sim::SensorCatalogue()) {
    out << "  " << name << ": " << description << "\n";
  }
  return out.str();
}

}  // namespace

int main(int argc, char** argv) {
  cairn::common::SetLogTag("cairn-sim");
  const SimPaths paths = SimPaths::Default();

  std::string scenario_path;
  std::string world = "tunnel";
  std::vector<std::string> robots;
  std::string speed_text = "1";
  int seed = -1;
  int ray_threads = 0;
  bool paused = false;
  std::string lcm_url;
  cairn::common::FlagParser flags(
      "cairn-sim",
      "Simulates a world with robots on MuJoCo and publishes their sensors on LCM:\n"
      "<robot>.LIDAR/.SCAN/.TURRET_SCAN/.ODOM/.POSE/.IMU and SIM.CLOCK; takes <robot>.CMD_VEL\n"
      "and SIM.CONTROL (spawn, move, remove objects, doors, reset, pause, resume, speed, list).\n"
      "Give a scenario file (config/sim/*.yaml), or a world and robots.");
  flags.AddString("scenario", &scenario_path, "scenario YAML file (world, robots, sensors)");
  flags.AddString("world", &world, "world name or MJCF path, when no scenario is given");
  flags.AddStringList("robot", &robots,
                      "robot as id:model[:profile[:x,y[,yaw_deg]]], when no scenario is given");
  flags.AddString("speed", &speed_text, "1 = real time, N = N times real time, max = flat out");
  flags.AddInt("seed", &seed, "noise seed; overrides the scenario's (-1 keeps it)");
  flags.AddInt("ray-threads", &ray_threads, "threads casting lidar rays (0 keeps the scenario's)");
  flags.AddBool("paused", &paused, "start paused (resume through SIM.CONTROL)");
  flags.AddString("lcm-url", &lcm_url, "LCM URL (default: LCM_DEFAULT_URL or udpm ttl=0)");
  flags.AddHelpSection("worlds", WorldsHelp(paths));
  flags.AddHelpSection("robots", RobotsHelp(paths));
  flags.AddHelpSection("sensors", SensorsHelp());
  const int parsed = flags.Parse(argc, argv);
  if (parsed >= 0) return parsed;
  if (!flags.positional().empty()) {
    std::fprintf(stderr, "cairn-sim: unexpected argument '%s' (see --help)\n",
                 flags.positional().front().c_str());
    return 2;
  }

  // Configuration: every problem stops start-up with a message naming its source.
  cairn::sim::InstallMujocoLogHooks();
  cairn::sim::Scenario scenario;
  double speed = 1.0;
  try {
    speed = cairn::sim::ParseSpeed(speed_text);
    if (!scenario_path.empty()) {
      if (!robots.empty()) throw std::invalid_argument("give --scenario or --robot, not both");
      scenario = cairn::sim::LoadScenarioFile(scenario_path, paths);
    } else {
      scenario.world = world;
      scenario.world_path = paths.WorldPath(world);
      for (const std::string& spec : robots) {
        scenario.robots.push_back(cairn::sim::ParseRobotFlag(spec, paths));
      }
    }
    if (seed >= 0) scenario.seed = static_cast<uint64_t>(seed);
    if (ray_threads > 0) scenario.ray_threads = ray_threads;
    scenario.Validate();
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("%s", e.what());
    return 1;
  }

  std::unique_ptr<cairn::sim::MujocoSim> sim;
  try {
    sim = std::make_unique<cairn::sim::MujocoSim>(scenario);
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("cannot start: %s", e.what());
    return 1;
  }
  if (scenario.robots.empty()) CAIRN_LOG_WARN("no robots: simulating the world alone");

  cairn::runtime::NodeOptions options;
  options.process_name = "cairn-sim";
  options.lcm_url = lcm_url;
  std::unique_ptr<cairn::runtime::Node> node;
  try {
    node = std::make_unique<cairn::runtime::Node>(options);
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("cannot open the bus: %s", e.what());
    return 1;
  }

  cairn::sim::SimServiceParams params;
  params.speed = speed;
  params.start_paused = paused;
  cairn::sim::SimService service(*node, *sim, params);
  std::string robot_list;
  for (const auto& r : scenario.robots) {
    robot_list +=
        (robot_list.empty() ? "" : ", ") + r.id + " (" + r.model.name + ", " + r.profile.name + ")";
  }
  node->Event("world %s, %zu robots%s%s, seed %llu, speed %s, timestep %.4f s, bus %s",
              scenario.world.c_str(), scenario.robots.size(), robot_list.empty() ? "" : ": ",
              robot_list.c_str(), static_cast<unsigned long long>(scenario.seed),
              speed == 0.0 ? "max" : speed_text.c_str(), sim->timestep_s(), node->url().c_str());
  return service.Run();
}
