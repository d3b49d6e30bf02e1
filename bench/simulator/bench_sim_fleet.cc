// bench_sim_fleet: many robots in one simulator, as `cairn-sim --speed max` serves them.
//
// Workload: the tunnel world with 1, 2, 4 and 8 Pioneer 3-ATs, each with its model's default
// sensors (the full HDL-32E: 32 x 1800 rays at 10 Hz in 10 slices, the 180 deg planar laser,
// IMU, odometry, ground truth), one per lane (x 4 m, y 2, 6, 10, ... m), all driving along
// their lanes at 0.5 m/s. The real SimService runs flat out and publishes every reading and
// SIM.CLOCK on a private udpm bus (a port of its own, ttl=0: cairn-sim's default transport).
//
// Figures: for each robot count, the real-time factor (simulated seconds per wall-clock second,
// the median 5 s window of 20 s) against the one-robot run measured in the same process (the
// ratio is how much of the single-robot speed is kept; 1/N would be linear slow-down). The
// headline is 8 robots, target >= 5x. Parts: where a simulated second of the 8-robot run goes
// (physics, sensors, the rest of the service: conversion, encoding, sending, reading back), in
// wall seconds per simulated second, and the real-time factor per CPU second of the simulation
// thread (what the run would make with a core to itself); MujocoSim::Step alone with 1 and 8
// robots (CPU per robot per simulated second, and the ray caster's rays per second).
//
// The command line: scripts/bench simulator (or build/bin/bench_sim_fleet).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <time.h>
#include <unistd.h>

#include "bench/support/figure.h"
#include "services/runtime/node.h"
#include "simulator/lcm/sim_service.h"
#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"

namespace {

using cairn::bench::Figure;
using cairn::bench::LoadAverage;
using cairn::bench::Report;
using cairn::bench::ThreadCpuSeconds;
using cairn::sim::MujocoSim;
using cairn::sim::Scenario;
using Clock = std::chrono::steady_clock;

constexpr double kWindowS = 5.0;    // simulated seconds per window
constexpr double kRunS = 20.0;      // simulated seconds per robot count
constexpr double kTargetRtf = 5.0;  // 8 robots, median window

Scenario Fleet(int robots) {
  const cairn::sim::SimPaths paths = cairn::sim::SimPaths::InTree(CAIRN_SOURCE_DIR);
  Scenario s;
  s.world = "tunnel";
  s.world_path = paths.WorldPath("tunnel");
  s.seed = 1;
  s.ray_threads = 1;
  for (int i = 0; i < robots; ++i) {
    cairn::sim::SpawnPose spawn;
    spawn.x_m = 4.0;
    spawn.y_m = 2.0 + 4.0 * i;  // lane i, between the walls at 4i and 4i + 4
    cairn::sim::RobotSpec robot =
        cairn::sim::MakeRobotSpec("p" + std::to_string(i), "pioneer3at", "", spawn, paths);
    robot.commands = {{0.0, 600.0, 0.5, 0.0}};
    s.robots.push_back(robot);
  }
  return s;
}

using cairn::bench::Median;

struct Run {
  int robots{0};
  std::vector<double> wall;  ///< real-time factor per window
  double sim_s{0}, wall_s{0}, cpu_s{0};
  double physics_s{0}, sensors_s{0};
  double start_s{0};  ///< MujocoSim construction, wall
  double messages{0}, bytes{0};
  double median() const { return Median(wall); }
  double best() const { return *std::max_element(wall.begin(), wall.end()); }
  /// Wall time outside MujocoSim::Step: publishing, handling the bus, pacing.
  double rest_s() const { return wall_s - physics_s - sensors_s; }
  double worst() const { return *std::min_element(wall.begin(), wall.end()); }
};

Run Serve(int robots) {
  Run r;
  r.robots = robots;
  const auto build0 = Clock::now();
  MujocoSim sim(Fleet(robots));
  r.start_s = std::chrono::duration<double>(Clock::now() - build0).count();
  cairn::runtime::NodeOptions options;
  options.process_name = "cairn-sim";
  options.lcm_url =
      "udpm://239.255.76.67:" + std::to_string(20000 + (getpid() + 7 * robots) % 20000) + "?ttl=0";
  options.install_signal_handlers = false;
  cairn::runtime::Node node(options);
  cairn::sim::SimServiceParams params;
  params.speed = 0.0;  // --speed max
  cairn::sim::SimService service(node, sim, params);
  const auto stats0 = sim.stats();
  while (sim.time_s() < kRunS - 1e-9) {
    const double window_start = sim.time_s();
    const auto wall0 = Clock::now();
    const double cpu0 = ThreadCpuSeconds();
    while (sim.time_s() - window_start < kWindowS - 1e-9) service.RunOnce(0);
    const double wall = std::chrono::duration<double>(Clock::now() - wall0).count();
    r.cpu_s += ThreadCpuSeconds() - cpu0;
    r.wall_s += wall;
    r.wall.push_back((sim.time_s() - window_start) / wall);
  }
  r.sim_s = sim.time_s();
  r.physics_s = sim.stats().physics_s - stats0.physics_s;
  r.sensors_s = sim.stats().sensors_s - stats0.sensors_s;
  for (const auto& c : node.MakeHealth().channels) {
    if (!c.outgoing) continue;
    r.bytes += static_cast<double>(c.bytes);
    r.messages += static_cast<double>(c.messages);
  }
  std::printf(
      "  run: %d robot%s, SimService --speed max on %s: started in %.3f s; %.0f s simulated in "
      "%.2f s wall (%.2f s cpu of the simulation thread); 5 s windows %.1f..%.1fx, median "
      "%.1fx (%.1fx per CPU second); per simulated second (wall) %.3f s physics, %.3f s "
      "sensors, %.3f s the rest (publishing); %.0f messages, %.1f MB per simulated second\n",
      robots, robots == 1 ? "" : "s", node.url().c_str(), r.start_s, r.sim_s, r.wall_s, r.cpu_s,
      r.worst(), r.best(), r.median(), r.sim_s / r.cpu_s, r.physics_s / r.sim_s,
      r.sensors_s / r.sim_s, r.rest_s() / r.sim_s, r.messages / r.sim_s, r.bytes / r.sim_s / 1e6);
  return r;
}

// MujocoSim::Step alone (nothing published), `robots` robots, 10 s simulated after 1 s of
// warm-up: CPU of this thread per robot per simulated second, and the caster's rays per second.
struct StepOnly {
  double cpu_per_robot_s{0};
  double rays_per_s{0};
};

StepOnly RunStepOnly(int robots) {
  MujocoSim sim(Fleet(robots));
  cairn::sim::SimOutputs out;
  while (sim.time_s() < 1.0 - 1e-9) {
    sim.Step(&out);
    out.Clear();
  }
  const auto stats0 = sim.stats();
  const double t0 = sim.time_s();
  const double cpu0 = ThreadCpuSeconds();
  while (sim.time_s() - t0 < 10.0 - 1e-9) {
    sim.Step(&out);
    out.Clear();
  }
  const double cpu = ThreadCpuSeconds() - cpu0;
  const double simulated = sim.time_s() - t0;
  StepOnly r;
  r.cpu_per_robot_s = cpu / simulated / robots;
  r.rays_per_s = static_cast<double>(sim.stats().rays_cast - stats0.rays_cast) /
                 (sim.stats().ray_s - stats0.ray_s);
  std::printf(
      "  run: MujocoSim::Step only, %d robot%s: %.3f s of CPU per robot per simulated second; "
      "%.1f M rays/s\n",
      robots, robots == 1 ? "" : "s", r.cpu_per_robot_s, r.rays_per_s / 1e6);
  return r;
}

}  // namespace

int main() {
  const cairn::bench::StealNote steal_note;
  std::printf(
      "bench_sim_fleet: tunnel + N Pioneer 3-ATs, each with HDL-32E (57600 rays/rev, 10 Hz), "
      "planar laser, IMU, odometry, ground truth; SimService --speed max publishing on udpm\n");
  std::vector<Run> runs;
  for (int robots : {1, 2, 4, 8}) runs.push_back(Serve(robots));
  const StepOnly step_one = RunStepOnly(1);
  const StepOnly step_eight = RunStepOnly(8);
  const std::string load = LoadAverage();
  const Run& one = runs.front();
  bool pass = true;
  for (const Run& r : runs) {
    Figure f;
    f.name = "simulator.fleet_tunnel_p3at_hdl32e." + std::to_string(r.robots) + "_robot" +
             (r.robots == 1 ? "" : "s") + ".real_time_factor";
    f.value = r.median();
    f.unit = "x";
    f.higher_is_better = true;
    if (r.robots == 1) {
      f.baseline = "seed 000 Gazebo run with one robot, 0.3-0.6x (published; best value)";
      f.baseline_value = 0.6;
      f.target = "informative (median 5 s window, wall clock, publishing included)";
    } else {
      f.baseline = "the same benchmark with 1 robot (measured in this run, median)";
      f.baseline_value = one.median();
      f.target = "informative (1/" + std::to_string(r.robots) + " of the 1-robot figure = linear)";
    }
    if (r.robots == 8) {
      char target[160];
      std::snprintf(target, sizeof(target),
                    ">= %.0fx (median 5 s window, wall clock, one simulation thread, publishing "
                    "included; load average %s)",
                    kTargetRtf, load.c_str());
      f.target = target;
      f.pass = r.median() >= kTargetRtf;
      pass = pass && f.pass;
    }
    Report(f);
  }
  // Where the 8-robot run's time goes, per simulated second (CPU of the simulation thread).
  const Run& eight = runs.back();
  const auto part = [&](const std::string& name, double value, const std::string& what) {
    Figure f;
    f.name = "simulator.fleet_tunnel_p3at_hdl32e.8_robots.part." + name;
    f.value = value;
    f.unit = "s/sim s";
    f.baseline = "the 1-robot run's (measured in this run)";
    f.higher_is_better = false;
    f.target = "informative: " + what;
    f.pass = true;
    return f;
  };
  Figure physics = part("physics_s_per_sim_s", eight.physics_s / eight.sim_s,
                        "MuJoCo stepping, drives, odometry");
  physics.baseline_value = one.physics_s / one.sim_s;
  Report(physics);
  Figure sensors = part("sensors_s_per_sim_s", eight.sensors_s / eight.sim_s,
                        "readings: ray casting, point slices, IMU, odometry, pose");
  sensors.baseline_value = one.sensors_s / one.sim_s;
  Report(sensors);
  Figure rest = part("publishing_s_per_sim_s", eight.rest_s() / eight.sim_s,
                     "conversion, LCM encoding, sending, reading the group back, pacing");
  rest.baseline_value = one.rest_s() / one.sim_s;
  Report(rest);
  Figure cpu = part("real_time_factor_per_cpu_second", eight.sim_s / eight.cpu_s,
                    "simulated seconds per CPU second of the simulation thread");
  cpu.unit = "x";
  cpu.higher_is_better = true;
  cpu.baseline = "the same with 1 robot (measured in this run)";
  cpu.baseline_value = one.sim_s / one.cpu_s;
  Report(cpu);
  Figure step_cpu = part("step_only_cpu_s_per_robot_per_sim_s", step_eight.cpu_per_robot_s,
                         "MujocoSim::Step alone, CPU of the thread per robot (linear scaling: "
                         "equal to the baseline)");
  step_cpu.baseline = "the same with 1 robot (measured in this run)";
  step_cpu.baseline_value = step_one.cpu_per_robot_s;
  Report(step_cpu);
  Figure rays = part("rays_per_s", step_eight.rays_per_s,
                     "the ray caster's rays per second of casting, 8 robots");
  rays.unit = "rays/s";
  rays.higher_is_better = true;
  rays.baseline = "the same with 1 robot (measured in this run)";
  rays.baseline_value = step_one.rays_per_s;
  Report(rays);
  Figure start = part("start_s", eight.start_s, "composing, compiling, sizing and placing");
  start.name = "simulator.fleet_tunnel_p3at_hdl32e.8_robots.start_s";
  start.unit = "s";
  start.baseline_value = one.start_s;
  start.target = "<= 2 s (MujocoSim construction, wall clock)";
  start.pass = eight.start_s <= 2.0;
  pass = pass && start.pass;
  Report(start);
  return pass ? 0 : 1;
}
