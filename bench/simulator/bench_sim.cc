// bench_sim: speed of the simulator on the reference workload, as a user pays it.
//
// Workload: the tunnel world, one Pioneer 3-AT with the full HDL-32E (32 x 1800 rays at 10 Hz,
// 10 slices), its front planar laser, IMU, odometry and ground truth, driving up the 5 degree
// ramp lane.
//
// Headline: what `cairn-sim --speed max` delivers. The real SimService runs the workload flat
// out and publishes every reading (conversion, LCM encoding, sending) and SIM.CLOCK on a
// private LCM bus (udpm, a port of its own, ttl=0: what cairn-sim does by default, loopback
// included; memq:// would skip the sockets). The real-time factor is simulated seconds per
// wall-clock second over 5 s windows of simulated time: the median window is the headline, the
// best and worst beside it, against the seed's Gazebo run (0.3-0.6x, published) and against the
// same run with the sensors' rays cast by a plain single-threaded mj_ray loop (measured here).
//
// Parts, labelled as such: simulated seconds per CPU second of the simulation thread with
// MujocoSim::Step alone (no publishing, best window: the figure this benchmark used to report
// as its headline), and lidar rays per second on one and two threads against the mj_ray loop.

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
using cairn::bench::ProcessCpuSeconds;
using cairn::bench::ThreadCpuSeconds;
using cairn::sim::MujocoSim;
using cairn::sim::Scenario;
using cairn::sim::SimOutputs;
using Clock = std::chrono::steady_clock;

constexpr double kWindowS = 5.0;  // simulated seconds per window

Scenario Workload(int ray_threads) {
  const cairn::sim::SimPaths paths = cairn::sim::SimPaths::InTree(CAIRN_SOURCE_DIR);
  Scenario s;
  s.world = "tunnel";
  s.world_path = paths.WorldPath("tunnel");
  s.seed = 1;
  s.ray_threads = ray_threads;
  cairn::sim::SpawnPose spawn;
  spawn.x_m = 4.0;  // lane 1 (5 deg ramp) start
  spawn.y_m = 6.0;
  cairn::sim::RobotSpec robot = cairn::sim::MakeRobotSpec("p3at", "pioneer3at", "", spawn, paths);
  robot.commands = {{0.0, 60.0, 0.5, 0.0}};
  s.robots.push_back(robot);
  return s;
}

using cairn::bench::Median;

// Real-time factors of the 5 s windows of one run, and what the run did.
struct Windows {
  std::vector<double> wall;  ///< simulated s per wall s, per window
  std::vector<double> cpu;   ///< simulated s per CPU s of the simulation thread, per window
  double sim_s{0}, wall_s{0}, cpu_s{0};
  double rays{0}, ray_s{0};
  double robot_x_m{0};
  double median() const { return Median(wall); }
  double best() const { return *std::max_element(wall.begin(), wall.end()); }
  double worst() const { return *std::min_element(wall.begin(), wall.end()); }
  double best_cpu() const { return *std::max_element(cpu.begin(), cpu.end()); }
  double rays_per_s() const { return rays / ray_s; }
};

// Runs `sim_seconds` of simulated time in 5 s windows; `advance` moves the simulation on by a
// little (a few milliseconds of work).
template <typename Advance>
Windows RunWindows(MujocoSim& sim, double sim_seconds, Advance&& advance) {
  Windows w;
  const double start_sim = sim.time_s();
  const auto start_stats = sim.stats();
  while (sim.time_s() - start_sim < sim_seconds - 1e-9) {
    const double window_start = sim.time_s();
    const auto wall0 = Clock::now();
    const double cpu0 = ThreadCpuSeconds();
    while (sim.time_s() - window_start < kWindowS - 1e-9) advance();
    const double cpu = ThreadCpuSeconds() - cpu0;
    const double wall = std::chrono::duration<double>(Clock::now() - wall0).count();
    const double simulated = sim.time_s() - window_start;
    w.wall.push_back(simulated / wall);
    w.cpu.push_back(simulated / cpu);
    w.cpu_s += cpu;
    w.wall_s += wall;
  }
  w.sim_s = sim.time_s() - start_sim;
  w.rays = static_cast<double>(sim.stats().rays_cast - start_stats.rays_cast);
  w.ray_s = sim.stats().ray_s - start_stats.ray_s;
  // The robot climbed the ramp (the workload really moved through the world).
  w.robot_x_m = sim.RobotPose("p3at").position_m.x();
  return w;
}

// What cairn-sim --speed max does: SimService's loop over a private udpm bus.
Windows RunService(bool use_mj_ray, double sim_seconds) {
  MujocoSim sim(Workload(1));
  sim.set_use_mj_ray(use_mj_ray);
  cairn::runtime::NodeOptions options;
  options.process_name = "cairn-sim";
  options.lcm_url = "udpm://239.255.76.67:" + std::to_string(20000 + getpid() % 20000) + "?ttl=0";
  options.install_signal_handlers = false;
  cairn::runtime::Node node(options);
  cairn::sim::SimServiceParams params;
  params.speed = 0.0;  // --speed max
  cairn::sim::SimService service(node, sim, params);
  const double process_cpu0 = ProcessCpuSeconds();
  Windows w = RunWindows(sim, sim_seconds, [&] { service.RunOnce(0); });
  const double process_cpu = ProcessCpuSeconds() - process_cpu0;
  double bytes = 0.0, messages = 0.0;
  for (const auto& c : node.MakeHealth().channels) {
    if (!c.outgoing) continue;
    bytes += static_cast<double>(c.bytes);
    messages += static_cast<double>(c.messages);
  }
  std::printf(
      "  run: SimService --speed max on %s, %s: %.0f s simulated in %.2f s wall, %.2f s cpu of "
      "the simulation thread (%.1fx per CPU second), %.2f s of the process; 5 s windows "
      "%.1f..%.1fx of wall time, median %.1fx; published %.0f messages, %.1f MB per simulated "
      "second; robot x %.1f m\n",
      node.url().c_str(), use_mj_ray ? "rays by the mj_ray loop" : "rays by the ray caster",
      w.sim_s, w.wall_s, w.cpu_s, w.sim_s / w.cpu_s, process_cpu, w.worst(), w.best(), w.median(),
      messages, bytes / w.sim_s / 1e6, w.robot_x_m);
  return w;
}

// MujocoSim::Step alone, nothing published (a part of the headline).
Windows RunStepsOnly(int ray_threads, double sim_seconds) {
  MujocoSim sim(Workload(ray_threads));
  SimOutputs out;
  Windows w = RunWindows(sim, sim_seconds, [&] {
    sim.Step(&out);
    out.Clear();
  });
  std::printf(
      "  run: MujocoSim::Step only, %d ray thread%s: %.0f s simulated in %.2f s wall, %.2f s "
      "cpu; 5 s windows %.1f..%.1fx per CPU second of the simulation thread; rays %.0f\n",
      ray_threads, ray_threads == 1 ? "" : "s", w.sim_s, w.wall_s, w.cpu_s,
      *std::min_element(w.cpu.begin(), w.cpu.end()), w.best_cpu(), w.rays);
  return w;
}

Figure RealTimeFactor(const std::string& name, double value) {
  Figure f;
  f.name = "simulator.tunnel_p3at_hdl32e." + name;
  f.value = value;
  f.unit = "x";
  f.baseline = "seed 000 Gazebo run, 0.3-0.6x (published; best value)";
  f.baseline_value = 0.6;
  f.higher_is_better = true;
  f.target = "informative";
  f.pass = true;
  return f;
}

}  // namespace

int main() {
  const cairn::bench::StealNote steal_note;
  std::printf(
      "bench_sim: tunnel + Pioneer 3-AT + HDL-32E (57600 rays/rev, 10 Hz) + planar laser, IMU, "
      "odometry, ground truth\n");
  RunStepsOnly(1, 5.0);  // warm up: page in the model, the tables, the caches

  const Windows served = RunService(false, 30.0);
  const Windows mj_ray = RunService(true, kWindowS);
  const Windows steps = RunStepsOnly(1, 30.0);
  const Windows two = RunStepsOnly(2, 10.0);
  const std::string load = LoadAverage();

  // The headline: the median window of what cairn-sim --speed max delivers, on the wall clock.
  Figure rtf = RealTimeFactor("real_time_factor", served.median());
  rtf.target =
      ">= 20x (median 5 s window, wall clock, publishing included; load average " + load + ")";
  rtf.pass = served.median() >= 20.0;
  Report(rtf);
  Report(RealTimeFactor("real_time_factor_best_window", served.best()));
  Report(RealTimeFactor("real_time_factor_worst_window", served.worst()));

  Figure vs_mj_ray = RealTimeFactor("real_time_factor_vs_mj_ray_loop", served.median());
  vs_mj_ray.baseline =
      "same SimService run, rays by a plain single-threaded mj_ray loop (measured, median)";
  vs_mj_ray.baseline_value = mj_ray.median();
  vs_mj_ray.target = "faster than the mj_ray loop";
  vs_mj_ray.pass = served.median() > mj_ray.median();
  Report(vs_mj_ray);

  // Parts.
  Figure cpu =
      RealTimeFactor("part.step_only_real_time_factor_per_sim_thread_cpu_second", steps.best_cpu());
  cpu.target =
      "informative: MujocoSim::Step alone, best window, per CPU second of the simulation "
      "thread (the former headline)";
  Report(cpu);

  Figure rays1;
  rays1.name = "simulator.lidar.rays_per_s_1_thread";
  rays1.value = steps.rays_per_s();
  rays1.unit = "rays/s";
  rays1.baseline = "plain single-threaded mj_ray loop over the same rays (measured)";
  rays1.baseline_value = mj_ray.rays_per_s();
  rays1.higher_is_better = true;
  rays1.target = "faster than the mj_ray loop";
  rays1.pass = steps.rays_per_s() > mj_ray.rays_per_s();
  Report(rays1);

  Figure rays2 = rays1;
  rays2.name = "simulator.lidar.rays_per_s_2_threads";
  rays2.value = two.rays_per_s();
  rays2.baseline = "the ray caster on 1 thread (measured)";
  rays2.baseline_value = steps.rays_per_s();
  rays2.target = "informative (the second core is shared with everything else running)";
  rays2.pass = true;
  Report(rays2);
  // A missed target fails the run (scripts/bench reports it).
  return rtf.pass && vs_mj_ray.pass && rays1.pass ? 0 : 1;
}
