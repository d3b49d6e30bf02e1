// bench_sonar: seed 004's imaging sonar as a user pays it.
//
// Workload: the rocks world (seed 004 test 13: a seabed, four rocks, water as the medium) with
// the Sparus II AUV surging at 0.5 m/s and turning gently, its sonar at its real ping rate (a
// round trip to 50 m at 1500 m/s: 15 pings a second, 2001 rays each) beside its IMU, odometry
// and ground truth; the thrusters, buoyancy and depth hold run every step. The detection
// baseline's planar scans come from a Pioneer 3-DX's 683-beam laser in the hall (seed 003's).
//
// Figures:
// - sonar.sim_rtf_with_sonar: simulated seconds per wall second of MujocoSim::Step flat out on
//   one ray thread with the sonar on (the median of 60 s windows), against the same run without
//   it; target >= 20x real time.
// - sonar.pings_per_cpu_second: pings per second of the extra wall time the sonar costs (one
//   core), against the ping rate it must keep (15 per simulated second at 20x: 300 a second).
// - sonar.detection_per_ping_us: one ping's detection and mapping (the peaks of its 50 bins, its
//   rays into the sonar layer's 0.25 m log-odds grid, with config/mapping/underwater.yaml's beam
//   width and vehicle clearing), median over the run's pings, against one 683-beam planar laser
//   scan into seed 003's occupancy grid; target <= 50 us.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/support/figure.h"
#include "services/mapping/occupancy_grid.h"
#include "services/mapping/sonar_mapper_layer.h"
#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "simulator/sensors/sonar_sensor.h"

namespace {

using cairn::bench::Figure;
using cairn::bench::Report;
using cairn::sim::MujocoSim;
using cairn::sim::Scenario;
using cairn::sim::SimOutputs;
using Clock = std::chrono::steady_clock;

constexpr double kWindowS = 60.0;  // the AUV's world is cheap: a window is a fraction of a second
constexpr int kWindows = 4;

// The AUV in the rocks world, with or without its sonar.
Scenario Workload(bool sonar) {
  const cairn::sim::SimPaths paths = cairn::sim::SimPaths::InTree(CAIRN_SOURCE_DIR);
  Scenario s = cairn::sim::MakeScenario("rocks", {"auv:sparus2"}, paths);
  s.seed = 1;
  s.ray_threads = 1;
  cairn::sim::RobotSpec& robot = s.robots[0];
  if (!sonar) robot.sensors.Remove(cairn::sim::SonarSensor::kName);
  robot.commands.push_back({0.0, 1000.0, 0.5, 0.02});
  return s;
}

// The Pioneer 3-DX in the hall: planar scans for the detection baseline.
Scenario LaserWorkload() {
  const cairn::sim::SimPaths paths = cairn::sim::SimPaths::InTree(CAIRN_SOURCE_DIR);
  return cairn::sim::MakeScenario("hall", {"p3dx:p3dx::8,1,90"}, paths);
}

using cairn::bench::Median;

struct Run {
  std::vector<double> rtf;  // per window
  double wall_s{0.0};
  std::vector<cairn::sim::SonarPing> pings;
  std::vector<cairn::common::LaserScan> scans;
};

Run Simulate(bool sonar, int windows = kWindows, bool laser = false) {
  MujocoSim sim(laser ? LaserWorkload() : Workload(sonar));
  Run run;
  SimOutputs out;
  for (int w = 0; w < windows; ++w) {
    const double t0 = sim.time_s();
    const auto c0 = Clock::now();
    while (sim.time_s() < t0 + kWindowS - 1e-9) {
      out.Clear();
      sim.Step(&out);
      for (const auto& p : out.Readings<cairn::sim::SonarSensor>()) run.pings.push_back(p);
      for (const auto& s : out.Readings<cairn::sim::PlanarLaserSensor>()) run.scans.push_back(s);
    }
    const double wall = std::chrono::duration<double>(Clock::now() - c0).count();
    run.wall_s += wall;
    run.rtf.push_back(kWindowS / wall);
  }
  std::printf(
      "  run %s: %.0f s simulated in %.2f s wall (windows %.1fx..%.1fx), "
      "%zu pings, %zu scans\n",
      laser   ? "of the P3-DX's laser"
      : sonar ? "with the sonar"
              : "without the sonar",
      kWindowS * windows, run.wall_s, *std::min_element(run.rtf.begin(), run.rtf.end()),
      *std::max_element(run.rtf.begin(), run.rtf.end()), run.pings.size(), run.scans.size());
  return run;
}

}  // namespace

int main() {
  Simulate(false);  // warm up: page in the model and the tables
  const Run without = Simulate(false);
  const Run with = Simulate(true);
  const Run laser = Simulate(false, 1, true);  // 60 s of the laser: 600 scans
  if (with.pings.empty() || laser.scans.empty()) {
    std::fprintf(stderr, "bench_sonar: no pings or scans\n");
    return 1;
  }

  Figure rtf;
  rtf.name = "sonar.sim_rtf_with_sonar";
  rtf.value = Median(with.rtf);
  rtf.unit = "x";
  rtf.baseline = "the same run without the sonar";
  rtf.baseline_value = Median(without.rtf);
  rtf.higher_is_better = true;
  rtf.target = ">= 20x real time";
  rtf.pass = rtf.value >= 20.0;
  Report(rtf);

  Figure rate;
  rate.name = "sonar.pings_per_cpu_second";
  const double extra_s = std::max(1e-6, with.wall_s - without.wall_s);
  rate.value = static_cast<double>(with.pings.size()) / extra_s;
  rate.unit = "pings/s";
  rate.baseline = "the real ping rate at 20x (15 a simulated second)";
  rate.baseline_value = 15.0 * 20.0;
  rate.higher_is_better = true;
  rate.target = ">= 300 pings/s";
  rate.pass = rate.value >= 300.0;
  Report(rate);

  // Detection and mapping per ping, and a planar scan into seed 003's grid, each timed alone.
  cairn::mapping::SonarMapperLayerParams params;
  params.beam_width_deg = 3.0;
  params.vehicle_centre_behind_head_m = 0.7;
  params.vehicle_clear_radius_m = 1.8;
  cairn::mapping::SonarMapperLayer layer{params};
  std::vector<double> ping_us;
  for (int pass = 0; pass < 3; ++pass) {
    for (const auto& p : with.pings) {
      cairn::mapping::SonarReading r;
      r.stream = "SONAR";
      r.utime = p.utime;
      r.sensor_pose = p.sensor_pose;
      r.pan_rad = p.pan_rad;
      r.range_min_m = p.range_min_m;
      r.range_max_m = p.range_max_m;
      r.bins = p.bins;
      const auto c0 = Clock::now();
      layer.OnReading(r);
      ping_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - c0).count());
    }
  }
  cairn::mapping::OccupancyGrid grid(cairn::mapping::OccupancyParams::Seed003());
  std::vector<double> scan_us;
  for (int pass = 0; pass < 3; ++pass) {
    for (const auto& s : laser.scans) {
      const auto c0 = Clock::now();
      grid.InsertScan(s);
      scan_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - c0).count());
    }
  }
  std::printf(
      "  detection: %zu pings (%lld obstacle bins), best %.1f us; planar scans best %.1f "
      "us\n",
      ping_us.size(), static_cast<long long>(layer.obstacles()),
      *std::min_element(ping_us.begin(), ping_us.end()),
      *std::min_element(scan_us.begin(), scan_us.end()));
  Figure detect;
  detect.name = "sonar.detection_per_ping_us";
  detect.value = Median(ping_us);
  detect.unit = "us";
  detect.baseline = "a 683-beam planar scan into seed 003's occupancy";
  detect.baseline_value = Median(scan_us);
  detect.target = "<= 50 us";
  detect.pass = detect.value <= 50.0;
  Report(detect);
  return 0;
}
