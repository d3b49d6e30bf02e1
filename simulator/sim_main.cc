// cairn-sim: MuJoCo simulation of worlds, robots and their sensors on LCM.

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "common/flags.h"
#include "common/log.h"
#include "services/runtime/node.h"
#include "simulator/catalogue.h"
#include "simulator/lcm/sim_service.h"
#include "simulator/mujoco_model.h"
#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"

namespace {

// An environment variable when set and not empty, else the fallback.
std::string EnvOr(const char* name, const std::string& fallback) {
  const char* value = std::getenv(name);
  return value != nullptr && *value != '\0' ? value : fallback;
}

struct Flags {
  std::string scenario_path;
  std::string world = "tunnel";
  std::vector<std::string> robots;
  std::string speed = "1";
  int seed = -1;
  int ray_threads = 0;
  bool paused = false;
  std::string lcm_url;
};

void AddFlags(cairn::common::FlagParser& flags, Flags* f, cairn::sim::SimPaths* paths) {
  flags.AddString("scenario", &f->scenario_path, "scenario YAML file (world, robots, sensors)");
  flags.AddString("world", &f->world, "world name or MJCF path, when no scenario is given");
  flags.AddStringList("robot", &f->robots,
                      "robot as id:model[:profile[:x,y[,yaw_deg]]], when no scenario is given");
  flags.AddString("speed", &f->speed, "1 = real time, N = N times real time, max = flat out");
  flags.AddInt("seed", &f->seed, "noise seed; overrides the scenario's (-1 keeps it)");
  flags.AddInt("ray-threads", &f->ray_threads,
               "threads casting lidar rays (0 keeps the scenario's)");
  flags.AddBool("paused", &f->paused, "start paused (resume through SIM.CONTROL)");
  flags.AddString("lcm-url", &f->lcm_url, "LCM URL (default: LCM_DEFAULT_URL or udpm ttl=0)");
  flags.AddString("data-dir", &paths->data_dir,
                  "folder of the shipped worlds/ and robots/ (env CAIRN_SIM_DATA_DIR)");
  flags.AddString("config-dir", &paths->config_dir,
                  "folder of the robot profiles/ (env CAIRN_CONFIG_DIR)");
  // The catalogues of the default (or environment's) folders.
  flags.AddHelpSection("worlds", cairn::sim::DescribeWorlds(*paths));
  flags.AddHelpSection("robots", cairn::sim::DescribeRobots(*paths));
  flags.AddHelpSection("sensors", cairn::sim::DescribeSensors());
}

// The scenario the flags ask for: a scenario file, or a world and robots.
cairn::sim::Scenario LoadFromFlags(const Flags& f, const cairn::sim::SimPaths& paths) {
  if (!f.scenario_path.empty() && !f.robots.empty()) {
    throw std::invalid_argument("give --scenario or --robot, not both");
  }
  cairn::sim::Scenario scenario = f.scenario_path.empty()
                                      ? cairn::sim::MakeScenario(f.world, f.robots, paths)
                                      : cairn::sim::LoadScenarioFile(f.scenario_path, paths);
  if (f.seed >= 0) scenario.seed = static_cast<uint64_t>(f.seed);
  if (f.ray_threads > 0) scenario.ray_threads = f.ray_threads;
  scenario.Validate();
  return scenario;
}

}  // namespace

int main(int argc, char** argv) {
  cairn::common::SetLogTag("cairn-sim");
  // Shipped worlds, robots and profiles: the source tree's unless the environment or the
  // flags say otherwise.
  cairn::sim::SimPaths paths;
  paths.data_dir = EnvOr("CAIRN_SIM_DATA_DIR", CAIRN_SIM_DATA_DIR);
  paths.config_dir = EnvOr("CAIRN_CONFIG_DIR", CAIRN_CONFIG_DIR);

  Flags f;
  cairn::common::FlagParser flags(
      "cairn-sim",
      "Simulates a world with robots on MuJoCo and publishes their sensors on LCM:\n"
      "<robot>.LIDAR_RANGES/.SCAN/.TURRET_SCAN/.ODOM/.POSE/.IMU and SIM.CLOCK; takes\n"
      "<robot>.CMD_VEL "
      "and SIM.CONTROL (spawn, move, remove objects, doors, reset, pause, resume, speed, list).\n"
      "Give a scenario file (config/sim/*.yaml), or a world and robots.");
  AddFlags(flags, &f, &paths);
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
    speed = cairn::sim::ParseSpeed(f.speed);
    scenario = LoadFromFlags(f, paths);
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("%s", e.what());
    return 1;
  }

  std::unique_ptr<cairn::sim::MujocoSim> sim;
  std::unique_ptr<cairn::runtime::Node> node;
  std::unique_ptr<cairn::sim::SimService> service;
  const char* failure = "cannot start";
  try {
    sim = std::make_unique<cairn::sim::MujocoSim>(scenario);
    failure = "cannot open the bus";
    cairn::runtime::NodeOptions options;
    options.process_name = "cairn-sim";
    // Commands and control requests arrive beside the simulator's own lidar traffic.
    options.lcm_url = cairn::runtime::WithReceiveBuffer(cairn::runtime::ResolveLcmUrl(f.lcm_url),
                                                        cairn::runtime::kLargeReceiveBufferBytes);
    node = std::make_unique<cairn::runtime::Node>(options);
    failure = "cannot start";
    cairn::sim::SimServiceParams params;
    params.speed = speed;
    params.start_paused = f.paused;
    service = std::make_unique<cairn::sim::SimService>(*node, *sim, params);
  } catch (const std::exception& e) {
    CAIRN_LOG_ERROR("%s: %s", failure, e.what());
    return 1;
  }
  if (scenario.robots.empty()) CAIRN_LOG_WARN("no robots: simulating the world alone");

  std::string robot_list;
  for (const auto& r : scenario.robots) {
    robot_list +=
        (robot_list.empty() ? "" : ", ") + r.id + " (" + r.model.name + ", " + r.profile.name + ")";
  }
  node->Event("world %s, %zu robots%s%s, seed %llu, speed %s, timestep %.4f s, bus %s",
              scenario.world.c_str(), scenario.robots.size(), robot_list.empty() ? "" : ": ",
              robot_list.c_str(), static_cast<unsigned long long>(scenario.seed),
              speed == 0.0 ? "max" : f.speed.c_str(), sim->timestep_s(), node->url().c_str());
  return service->Run();
}
