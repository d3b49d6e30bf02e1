// cairn-explorer closed loop in the arena (seed 003 §7.5): cairn-sim (a Pioneer 3-DX with its
// 240 deg laser), cairn-mapper (seed 003's log-odds occupancy from the scans), cairn-explorer,
// and for the frontier mode cairn-navigator, as real processes on a private bus. The test
// records every scan, pose and command, and at the end has the mapper write its maps
// (OP_SNAPSHOT) and reads the occupancy it built.
//
// Tests 37 and 38 of seed 003 compare strategies over the same simulated time; they run the
// simulator at 4x real time, and every bound below is in simulated time. Tests 34, 35 and 36 map
// without an explorer (OccupancyRig: the test spins the robot or changes the world).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "cairn/lcmt_explore_status.hpp"
#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_map_control_reply.hpp"
#include "cairn/lcmt_map_control_request.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"
#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "common/grid_map.h"
#include "common/yaml_reader.h"
#include "mapstore/map_eval.h"
#include "simulator/ground_truth.h"
#include "tests/support/harness.h"

namespace cairn::explore {
namespace {

namespace ch = cairn::channels;
using testing::Bus;
using testing::ProcessSet;
using testing::WaitFor;

constexpr char kRobot[] = "p3dx";
constexpr double kDurationS = 600.0;  // seed 003 test 37: ten simulated minutes
constexpr char kSpeed[] = "4";

// What one exploration run measured.
struct ExploreRun {
  double min_range_m{INFINITY};  // closest reading of any scan: below 0.1 m is a collision
  double longest_still_s{0.0};   // longest time without motion and without a reverse command
  int stalls{0};                 // times the robot stood still over 2 s without reversing
  int trapped_windows{0};        // 30 s windows in which it stayed within 1 m of where it was
  int reverses{0};
  double distance_m{0.0};
  double sim_s{0.0};          // simulated time the run lasted
  common::GridMap occupancy;  // the mapper's occupancy at the end
  std::string explorer_log;
};

struct Box {
  double x0, x1, y0, y1;
};

// The arena's furniture (simulator/worlds/generate_worlds.py): the footprints seed 003 says its
// map shows.
const Box kArmchair{3.05, 4.35, 0.15, 1.1};
const Box kChair{2.785, 3.215, 8.285, 8.715};  // the four legs (r 0.015) at (3 +- 0.2, 8.5 +- 0.2)
const Box kTable{8.77, 10.23, 8.07, 8.93};     // the four legs (r 0.03) at (9.5 +- 0.7, 8.5 +- 0.4)
const double kBalls[6][2] = {{1.5, 2.5}, {6.5, 1.2},  {9.8, 4.5},
                             {5.5, 4.2}, {10.8, 1.0}, {2.2, 4.8}};

common::GridMap ReadLayer(const std::string& dir, const std::string& layer) {
  common::YamlMap root = common::YamlMap::LoadFile(dir + "/map.yaml");
  common::YamlMap section = root.Child("occupancy");
  common::GridGeometry g;
  g.resolution_m = section.Require<double>("resolution_m");
  g.size_x = section.Require<int>("size_x");
  g.size_y = section.Require<int>("size_y");
  const auto origin = section.Require<std::vector<double>>("origin");
  g.origin = {origin.at(0), origin.at(1), origin.at(2)};
  common::GridMap map(g);
  common::Layer& cells = map.AddLayer(layer);
  std::ifstream in(dir + "/" + layer + ".f32", std::ios::binary);
  in.read(reinterpret_cast<char*>(cells.data()),
          static_cast<std::streamsize>(cells.size() * sizeof(float)));
  EXPECT_TRUE(in.good()) << "cannot read " << dir << "/" << layer << ".f32";
  return map;
}

constexpr char kLogOdds[] = "occupancy_logodds";

// Known cells inside the arena's outer walls over them: seed 003's reading of its log-odds
// (l > 0 occupied, l < 0 free, 0 unknown).
double KnownFraction(const common::GridMap& map) {
  const common::Layer& occ = map.at(kLogOdds);
  int64_t inside = 0, known = 0;
  for (int iy = 0; iy < map.size_y(); ++iy) {
    for (int ix = 0; ix < map.size_x(); ++ix) {
      const common::Vector2 c = map.CenterOf({ix, iy});
      if (c.x() < 0.0 || c.x() > 12.0 || c.y() < 0.0 || c.y() > 10.0) continue;
      ++inside;
      const float v = occ(ix, iy);
      if (std::isfinite(v) && v != 0.f) ++known;
    }
  }
  return inside > 0 ? static_cast<double>(known) / inside : 0.0;
}

// An occupied cell (l > 0) within one cell of the box (its outline grown by a cell).
bool FoundNear(const common::GridMap& map, const Box& b) {
  const common::Layer& occ = map.at(kLogOdds);
  const double r = map.resolution_m();
  for (int iy = 0; iy < map.size_y(); ++iy) {
    for (int ix = 0; ix < map.size_x(); ++ix) {
      const common::Vector2 c = map.CenterOf({ix, iy});
      if (c.x() < b.x0 - 1.5 * r || c.x() > b.x1 + 1.5 * r || c.y() < b.y0 - 1.5 * r ||
          c.y() > b.y1 + 1.5 * r) {
        continue;
      }
      if (occ(ix, iy) > 0.f) return true;
    }
  }
  return false;
}

// One exploration stack on its own private bus: the simulator, the mapper, the explorer in one
// mode (and the navigator for the frontier mode). Several run side by side.
class ExploreRig {
 public:
  ExploreRig(std::string mode, const std::string& dir)
      : mode_(std::move(mode)), procs_(testing::PrivateLcmUrl(), dir), bus_(procs_.url()) {
    {
      // The shipped arena mapper configuration, with the snapshots in the test's folder.
      std::ifstream in(testing::SourcePath("config/mapping/arena.yaml"));
      std::ofstream out(dir + "/mapper.yaml");
      out << in.rdbuf() << "\nsnapshot_dir: " << dir << "/snapshots\nallow_snapshot: true\n";
    }
    for (const char* c : {ch::kScan, ch::kPose, ch::kCmdVel}) bus_.Keep(ch::ForRobot(kRobot, c));
    procs_.Start("cairn-sim", {"--scenario", testing::SourcePath("config/sim/arena_p3dx.yaml"),
                               "--speed", kSpeed});
    procs_.Start("cairn-mapper", {"--robot", kRobot, "--config", dir + "/mapper.yaml"});
    if (mode_ == "frontier") {
      procs_.Start("cairn-navigator", {"--robot", kRobot, "--profile", "p3dx", "--config",
                                       testing::SourcePath("config/navigator/arena.yaml")});
    }
    explorer_ = &procs_.Start(
        "cairn-explorer", {"--robot", kRobot, "--profile", "p3dx", "--mode", mode_, "--duration",
                           std::to_string(static_cast<int>(kDurationS))});
  }

  const std::string& mode() const { return mode_; }
  // Handles what has arrived (several rigs share the test's thread: none may fall behind).
  void Pump() {
    for (int i = 0; i < 1000 && bus_.lcm().handleTimeout(0) > 0; ++i) {
    }
  }
  // The explorer exits when its exploration is done.
  bool Done() { return !explorer_->Running(); }

  // After Done(): the explorer's exit, the figures, and the map the mapper built (OP_SNAPSHOT
  // writes it under the test's folder).
  ExploreRun Finish() {
    EXPECT_TRUE(explorer_->WaitExit(10.0).has_value())
        << mode_ << ": the explorer did not exit when done";
    ExploreRun run;
    run.explorer_log = explorer_->Log();
    const auto status = bus_.Last<cairn::lcmt_explore_status>(StatusChannel());
    EXPECT_TRUE(status && status->state == cairn::lcmt_explore_status::STATE_DONE)
        << mode_ << ": the explorer's last status does not say done";
    if (status) {
      run.reverses = status->reverses;
      run.distance_m = status->distance_m;
      run.sim_s = status->elapsed_s;
    }
    Analyse(&run);
    cairn::lcmt_map_control_request req{};
    req.request_id = 1;
    req.requester = "explore_stack_test";
    req.op = cairn::lcmt_map_control_request::OP_SNAPSHOT;
    std::string snapshot;
    const std::string reply_channel = ch::ForRobot(kRobot, ch::kMapControlReply);
    EXPECT_TRUE(WaitFor(
        [&] {
          bus_.Publish(ch::ForRobot(kRobot, ch::kMapControl), req);
          for (int i = 0; i < 10; ++i) bus_.Pump(20);
          const auto reply = bus_.Last<cairn::lcmt_map_control_reply>(reply_channel);
          if (!reply || reply->request_id != 1) return false;
          EXPECT_EQ(reply->status, +cairn::lcmt_map_control_reply::STATUS_OK) << reply->message;
          snapshot = reply->message;
          return true;
        },
        20.0))
        << mode_ << ": no snapshot from the mapper";
    if (!snapshot.empty()) run.occupancy = ReadLayer(snapshot, kLogOdds);
    return run;
  }

 private:
  std::string StatusChannel() const { return ch::ForRobot(kRobot, ch::kExploreStatus); }

  // Collisions, stalls and reverses from the recorded traffic.
  void Analyse(ExploreRun* run) {
    for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kScan))) {
      cairn::lcmt_laser_scan s;
      if (s.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) continue;
      for (float r : s.ranges_m) {
        if (std::isfinite(r) && r >= s.range_min_m) {
          run->min_range_m = std::min<double>(run->min_range_m, r);
        }
      }
    }
    std::vector<int64_t> reverse_times;
    for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kCmdVel))) {
      cairn::lcmt_velocity_command c;
      if (c.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) continue;
      if (c.linear_mps < 0.0) reverse_times.push_back(c.utime);
    }
    std::sort(reverse_times.begin(), reverse_times.end());
    auto reversed_between = [&](int64_t a, int64_t b) {
      const auto it = std::lower_bound(reverse_times.begin(), reverse_times.end(), a);
      return it != reverse_times.end() && *it <= b;
    };
    // Trapped: a 30 s window (back to back from the first pose) that ends within 1 m of where it
    // began and never left that circle.
    {
      bool open = false;
      double wx = 0.0, wy = 0.0, far = 0.0;
      int64_t wt = 0;
      for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kPose))) {
        cairn::lcmt_pose p;
        if (p.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) continue;
        if (!open) {
          open = true;
          wx = p.position_m[0], wy = p.position_m[1], wt = p.utime, far = 0.0;
          continue;
        }
        far = std::max(far, std::hypot(p.position_m[0] - wx, p.position_m[1] - wy));
        if (p.utime - wt >= 30'000'000) {
          if (far < 1.0) ++run->trapped_windows;
          open = false;
        }
      }
    }
    // Still: within 2 cm and 0.05 rad of where it was (turning in place is motion).
    bool anchored = false, counted = false;
    double ax = 0.0, ay = 0.0, ayaw = 0.0;
    int64_t at = 0;
    for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kPose))) {
      cairn::lcmt_pose p;
      if (p.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) continue;
      const double x = p.position_m[0], y = p.position_m[1];
      const double w = p.orientation_wxyz[0], qx = p.orientation_wxyz[1];
      const double qy = p.orientation_wxyz[2], qz = p.orientation_wxyz[3];
      const double yaw = std::atan2(2.0 * (w * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz));
      const double turned = std::abs(std::remainder(yaw - ayaw, 2.0 * M_PI));
      if (!anchored || std::hypot(x - ax, y - ay) > 0.02 || turned > 0.05) {
        anchored = true;
        counted = false;
        ax = x, ay = y, ayaw = yaw, at = p.utime;
        continue;
      }
      if (reversed_between(at, p.utime)) continue;
      const double still_s = static_cast<double>(p.utime - at) * 1e-6;
      run->longest_still_s = std::max(run->longest_still_s, still_s);
      if (still_s > 2.0 && !counted) {
        ++run->stalls;
        counted = true;
      }
    }
  }

  std::string mode_;
  ProcessSet procs_;
  Bus bus_;
  testing::ChildProcess* explorer_{nullptr};
};

// Runs the rigs side by side until every explorer is done (ten simulated minutes at 4x take
// 150 s; the bound allows for a slow machine).
std::vector<ExploreRun> ExploreSideBySide(const std::vector<std::string>& modes) {
  const std::string dir = testing::TestTempDir();
  std::vector<std::unique_ptr<ExploreRig>> rigs;
  for (const auto& m : modes) rigs.push_back(std::make_unique<ExploreRig>(m, dir + "/" + m));
  const bool done = WaitFor(
      [&] {
        bool all = true;
        for (auto& r : rigs) all = r->Done() && all;
        return all;
      },
      kDurationS,
      [&] {
        for (auto& r : rigs) r->Pump();
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      });
  EXPECT_TRUE(done) << "an explorer did not finish";
  for (int i = 0; i < 20; ++i) {
    for (auto& r : rigs) r->Pump();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::vector<ExploreRun> runs;
  for (auto& r : rigs) runs.push_back(r->Finish());
  return runs;
}

std::string Describe(const ExploreRun& r) {
  char line[300];
  std::snprintf(line, sizeof(line),
                "%.0f s simulated, %.1f m driven, %d reverses, min range %.3f m, %d stalls "
                "(longest still %.1f s), trapped in %d of 20 windows of 30 s, known %.1f %% of "
                "the arena",
                r.sim_s, r.distance_m, r.reverses, r.min_range_m, r.stalls, r.longest_still_s,
                r.trapped_windows, 100.0 * KnownFraction(r.occupancy));
  return line;
}

// cairn-map eval's figures for a run: the log-odds as a 0..100 occupancy layer (unknown where
// the log-odds is 0), judged against the arena's geometry that a planar laser 0.30 m above the
// floor can see (the band 0.25..0.35 m: walls, the armchair, the balls, the legs of the chair and
// the table; not the table top, which the laser passes under), reachable from the start.
mapstore::MapEvalReport Evaluate(const common::GridMap& logodds, const std::string& world = "arena",
                                 const common::Vector2& start_m = {5.5, 3.0}) {
  common::GridMap map(logodds.geometry());
  common::Layer& occ = map.AddLayer("occupancy");
  const common::Layer& l = logodds.at(kLogOdds);
  for (int64_t i = 0; i < l.size(); ++i) {
    const float v = l.data()[i];
    occ.data()[i] = (std::isfinite(v) && v != 0.f) ? 100.f / (1.f + std::exp(-v)) : NAN;
  }
  sim::TruthRasterParams truth_params;
  truth_params.band_low_m = 0.25;
  truth_params.band_high_m = 0.35;
  const common::GridMap truth = sim::RasteriseGroundTruth(
      testing::SourcePath("simulator/worlds/" + world + ".xml"), map.geometry(), truth_params);
  mapstore::MapEvalParams params;
  params.layer = "occupancy";
  params.occupied_above = 50.0;  // seed 003: l > 0 occupied, l < 0 free
  params.free_below = 50.0;
  params.start_m = start_m;
  return mapstore::EvaluateMap(map, truth, params);
}

int BallsFound(const common::GridMap& map) {
  int balls = 0;
  for (const auto& b : kBalls) {
    balls += FoundNear(map, Box{b[0] - 0.2, b[0] + 0.2, b[1] - 0.2, b[1] + 0.2});
  }
  return balls;
}

// Seed 003 tests 37 and 38, and the frontier mode against them: the three strategies explore
// the multi-room scene for the same ten simulated minutes, side by side.
TEST(ExploreStackTest, TenMinutesOfReactiveStatelessAndFrontierExplorationInTheArena) {
  const std::vector<ExploreRun> runs = ExploreSideBySide({"reactive", "stateless", "frontier"});
  ASSERT_EQ(runs.size(), 3u);
  const ExploreRun& reactive = runs[0];
  const ExploreRun& stateless = runs[1];
  const ExploreRun& frontier = runs[2];
  std::printf("reactive:  %s\nstateless: %s\nfrontier:  %s\n", Describe(reactive).c_str(),
              Describe(stateless).c_str(), Describe(frontier).c_str());
  for (const ExploreRun* r : {&reactive, &stateless, &frontier}) {
    ASSERT_GT(r->occupancy.size_x(), 0) << "no map";
  }
  const mapstore::MapEvalReport reactive_eval = Evaluate(reactive.occupancy);
  const mapstore::MapEvalReport stateless_eval = Evaluate(stateless.occupancy);
  const mapstore::MapEvalReport frontier_eval = Evaluate(frontier.occupancy);
  std::printf("cairn-map eval, reactive:  %s\n",
              mapstore::MapEvalReportToJson(reactive_eval).c_str());
  std::printf("cairn-map eval, stateless: %s\n",
              mapstore::MapEvalReportToJson(stateless_eval).c_str());
  std::printf("cairn-map eval, frontier:  %s\n",
              mapstore::MapEvalReportToJson(frontier_eval).c_str());
  // Known poses and seed 003's sensor model: what the map calls occupied lies on the geometry
  // (within a cell) and what it calls free is free, for every strategy. A doubled wall would be
  // a pose error, and the poses are the simulator's: none (two crossings of margin).
  for (const auto* e : {&reactive_eval, &stateless_eval, &frontier_eval}) {
    EXPECT_GE(e->occupied_precision, 0.95);
    EXPECT_GE(e->free_precision, 0.98);
    EXPECT_LE(e->double_wall_length_m, 0.1);
  }

  // Test 37: ten minutes with no collision (no reading under 0.1 m), no stall over 2 s without
  // a reverse, and the furniture in the map: the armchair, the chair in the room the robot may
  // never enter (seen through its doorway), the table, and most of the balls.
  EXPECT_GE(reactive.sim_s, kDurationS - 1.0);
  EXPECT_GE(reactive.min_range_m, 0.1) << "a collision (a reading under 0.1 m)";
  EXPECT_EQ(reactive.stalls, 0) << "stood still over 2 s without reversing";
  EXPECT_TRUE(FoundNear(reactive.occupancy, kArmchair)) << "armchair";
  EXPECT_TRUE(FoundNear(reactive.occupancy, kChair)) << "chair";
  EXPECT_TRUE(FoundNear(reactive.occupancy, kTable)) << "table";
  EXPECT_GE(BallsFound(reactive.occupancy), 4) << "balls";
  // About 60 % of the arena's floor is free space a 0.45 m robot reaches through 1 m doorways;
  // the reactive explorer sees most of it in ten minutes.
  EXPECT_GE(KnownFraction(reactive.occupancy), 0.6);
  EXPECT_GE(reactive_eval.coverage, 0.8);

  // Test 38: the stateful explorer covers about what the stateless baseline covers, and gets
  // stuck no more. The laser's 5.6 m reach sees most of the 12 x 10 m arena from anywhere: in six
  // runs both mapped 84 to 98 % of the reachable floor, and which of the two came out ahead by a
  // point or two was chance (the simulator and the processes are not in lockstep), so coverage
  // is compared within 5 points. Being stuck is where they differ: in five of those runs the
  // baseline swung between sides in front of an obstacle and stayed put (8 to 18 of the twenty
  // 30 s windows within 1 m of where they began), in one it wandered free (0); the stateful
  // explorer, with direction memory and reverse, was stuck in none, and later in at most one.
  // So "no more" is a bound of two windows (a tenth of the run) rather than the baseline's count:
  // compared with a baseline that wandered free, one window of the stateful explorer's failed a
  // run for chance.
  EXPECT_GE(reactive_eval.coverage, stateless_eval.coverage - 0.05);
  EXPECT_LE(reactive.trapped_windows, 2);

  // The frontier mode covers what the reactive mode covers in a fraction of the time: it stops
  // when no frontier is left, after three to five simulated minutes against the reactive mode's
  // ten. Both can come near the 99.9 % of the reachable floor the laser sees (in ten runs the
  // frontier mode mapped 99.85-99.87 %, but once 95 % on a machine overloaded with compile jobs,
  // and the reactive mode 97.2-99.9 %), and there which of the two ends a few cells ahead is
  // chance; so the frontier mode is held within a tenth of a point. Once it mapped 94.1 %: five
  // goals on wall-side cells were refused (GOAL_OCCUPIED) and their frontiers given up whole.
  // Goals are now chosen 0.35 m clear of walls, and a refused goal moves along its frontier
  // (frontier.h); two runs since mapped 99.86 and 99.87 %.
  EXPECT_GE(frontier_eval.coverage, reactive_eval.coverage - 0.001);
  EXPECT_LE(frontier.sim_s, 0.75 * reactive.sim_s) << frontier.explorer_log;
  EXPECT_GE(frontier_eval.coverage, 0.97) << frontier.explorer_log;
  EXPECT_NE(frontier.explorer_log.find("goal 1:"), std::string::npos) << frontier.explorer_log;
}

// Seed 003's occupancy mapping without an explorer: cairn-sim with a scenario and cairn-mapper
// with config/mapping/arena.yaml (its occupancy grid resized to `size_x_cells` x `size_y_cells`
// from (-1, -1) when given, and `occupancy_keys`, YAML lines, added to its occupancy section) on a
// private bus. The test drives the robot, changes the world and takes the mapper's snapshots.
class OccupancyRig {
 public:
  OccupancyRig(const std::string& scenario, int size_x_cells = 0, int size_y_cells = 0,
               const std::string& occupancy_keys = "")
      : procs_(testing::PrivateLcmUrl()), bus_(procs_.url()) {
    std::ifstream in(testing::SourcePath("config/mapping/arena.yaml"));
    std::stringstream text;
    text << in.rdbuf();
    std::string yaml = text.str();
    if (size_x_cells > 0) {
      yaml = std::regex_replace(yaml, std::regex("size_x_cells: [0-9]+[^\n]*"),
                                "size_x_cells: " + std::to_string(size_x_cells));
      yaml = std::regex_replace(yaml, std::regex("size_y_cells: [0-9]+[^\n]*"),
                                "size_y_cells: " + std::to_string(size_y_cells));
    }
    const std::string preset = "  preset: seed003\n";
    const size_t at = yaml.find(preset);
    EXPECT_NE(at, std::string::npos) << "arena.yaml no longer sets the seed003 preset";
    if (at != std::string::npos) yaml.insert(at + preset.size(), occupancy_keys);
    std::ofstream(procs_.dir() + "/mapper.yaml")
        << yaml << "\nsnapshot_dir: " << procs_.dir() << "/snapshots\nallow_snapshot: true\n";
    bus_.Keep(ch::ForRobot(kRobot, ch::kMapManifest));
    procs_.Start("cairn-sim", {"--scenario", testing::SourcePath(scenario), "--speed", kSpeed});
    procs_.Start("cairn-mapper", {"--robot", kRobot, "--config", procs_.dir() + "/mapper.yaml"});
  }

  // Up once the robot has a pose and the mapper's first occupancy is out.
  bool WaitReady() {
    return WaitFor([&] { return Yaw().has_value() && OccupancyVersion() > 0; }, 30.0,
                   [&] { bus_.Pump(20); });
  }

  std::optional<double> Yaw() {
    const auto p = bus_.Last<cairn::lcmt_pose>(ch::ForRobot(kRobot, ch::kPose));
    if (!p) return std::nullopt;
    const double w = p->orientation_wxyz[0], qx = p->orientation_wxyz[1];
    const double qy = p->orientation_wxyz[2], qz = p->orientation_wxyz[3];
    return std::atan2(2.0 * (w * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz));
  }

  // Spins in place at `radps` until it has turned `angle_rad`, then stops; false on timeout.
  bool Spin(double radps, double angle_rad, double timeout_s) {
    cairn::lcmt_velocity_command spin{};
    spin.robot = kRobot;
    spin.source = "explore_stack_test";
    spin.angular_radps = radps;
    double turned = 0.0, last = Yaw().value_or(0.0);
    const bool done = WaitFor(
        [&] {
          const double yaw = Yaw().value_or(last);
          turned += std::abs(std::remainder(yaw - last, 2.0 * M_PI));
          last = yaw;
          return turned >= angle_rad;
        },
        timeout_s,
        [&] {
          bus_.Publish(ch::ForRobot(kRobot, ch::kCmdVel), spin);
          for (int i = 0; i < 5; ++i) bus_.Pump(10);
        });
    spin.angular_radps = 0.0;
    bus_.Publish(ch::ForRobot(kRobot, ch::kCmdVel), spin);
    EXPECT_TRUE(done) << "turned " << turned << " rad of " << angle_rad;
    return done;
  }

  // Once up, one turn in place at 0.6 rad/s (seed 003 test 34), two more scans, then the map
  // (empty when a step failed; the failure is reported).
  common::GridMap SpinOnceAndSnapshot() {
    if (!WaitReady()) {
      ADD_FAILURE() << "the simulator or the mapper did not come up";
      return {};
    }
    if (!Spin(0.6, 2.0 * M_PI + 0.2, 60.0)) return {};
    WaitScans(OccupancyVersion(), 2, 10.0);
    return Snapshot();
  }

  // The highest version of the occupancy layer in a manifest so far: it grows by one with every
  // scan the mapper has applied.
  int64_t OccupancyVersion() {
    int64_t v = 0;
    for (const auto& bytes : bus_.Kept(ch::ForRobot(kRobot, ch::kMapManifest))) {
      cairn::lcmt_grid_manifest m;
      if (m.decode(bytes.data(), 0, static_cast<int>(bytes.size())) >= 0 &&
          m.layer == "occupancy") {
        v = std::max(v, m.layer_version);
      }
    }
    return v;
  }
  // Waits until the mapper has applied `scans` more scans than at `version`.
  bool WaitScans(int64_t version, int scans, double timeout_s) {
    return WaitFor([&] { return OccupancyVersion() >= version + scans; }, timeout_s,
                   [&] { bus_.Pump(20); });
  }

  // The mapper's log-odds, through OP_SNAPSHOT.
  common::GridMap Snapshot() {
    cairn::lcmt_map_control_request req{};
    req.request_id = ++requests_;
    req.requester = "explore_stack_test";
    req.op = cairn::lcmt_map_control_request::OP_SNAPSHOT;
    std::string dir;
    const bool ok = WaitFor(
        [&] {
          bus_.Publish(ch::ForRobot(kRobot, ch::kMapControl), req);
          for (int i = 0; i < 10; ++i) bus_.Pump(20);
          const auto reply =
              bus_.Last<cairn::lcmt_map_control_reply>(ch::ForRobot(kRobot, ch::kMapControlReply));
          if (!reply || reply->request_id != req.request_id) return false;
          dir = reply->message;
          return reply->status == cairn::lcmt_map_control_reply::STATUS_OK;
        },
        20.0);
    EXPECT_TRUE(ok) << "no snapshot";
    return ok ? ReadLayer(dir, kLogOdds) : common::GridMap();
  }

  // A box on the floor (half sizes), spawned or removed through SIM.CONTROL.
  bool SimBox(int8_t op, const std::string& name, double x, double y, double hx, double hy,
              double hz) {
    cairn::lcmt_sim_control_request r{};
    r.request_id = ++requests_;
    r.requester = "explore_stack_test";
    r.op = op;
    r.name = name;
    r.shape = cairn::lcmt_sim_control_request::SHAPE_BOX;
    r.size_m[0] = hx;
    r.size_m[1] = hy;
    r.size_m[2] = hz;
    r.position_m[0] = x;
    r.position_m[1] = y;
    r.position_m[2] = hz;
    bus_.Publish(ch::kSimControl, r);
    return WaitFor(
        [&] {
          auto reply = bus_.Last<cairn::lcmt_sim_control_reply>(ch::kSimControlReply);
          return reply && reply->request_id == r.request_id &&
                 reply->status == cairn::lcmt_sim_control_reply::STATUS_OK;
        },
        10.0, [&] { bus_.Pump(20); });
  }

 private:
  ProcessSet procs_;
  Bus bus_;
  int64_t requests_{0};
};

// Seed 003 test 34: in a closed 6 x 4 m room a robot at the centre spins once in place at
// 0.6 rad/s with perfect poses. Afterwards at least 95 % of the wall cells within 4.9 m are
// occupied (l > 0; all of them are within 4.9 m here), at least 95 % of the interior cells are
// free (l < 0), and no occupied cell lies more than a cell from a true wall.
TEST(ExploreStackTest, ARobotSpinningInAClosedRoomMapsItsWallsAndItsFloor) {
  OccupancyRig rig("config/sim/room_p3dx.yaml");
  const common::GridMap logodds = rig.SpinOnceAndSnapshot();
  ASSERT_TRUE(logodds.HasLayer(kLogOdds));
  const common::Layer& l = logodds.at(kLogOdds);
  int64_t interior = 0, interior_free = 0;
  for (int iy = 0; iy < logodds.size_y(); ++iy) {
    for (int ix = 0; ix < logodds.size_x(); ++ix) {
      const common::Vector2 c = logodds.CenterOf({ix, iy});
      if (c.x() <= 0.0 || c.x() >= 6.0 || c.y() <= 0.0 || c.y() >= 4.0) continue;
      ++interior;
      interior_free += l(ix, iy) < 0.f;
    }
  }
  const double free_fraction = static_cast<double>(interior_free) / interior;

  // The walls, through cairn-map eval's figures on the room's geometry at the laser's height.
  const mapstore::MapEvalReport e = Evaluate(logodds, "room", {3.0, 2.0});
  std::printf("spin: interior free %.1f %%; cairn-map eval %s\n", 100.0 * free_fraction,
              mapstore::MapEvalReportToJson(e).c_str());
  EXPECT_GE(e.occupied_recall_visible, 0.95) << "wall cells occupied";
  EXPECT_GE(free_fraction, 0.95) << "interior cells free";
  EXPECT_DOUBLE_EQ(e.occupied_precision, 1.0) << "an occupied cell more than a cell off a wall";
  // At most a grazing-beam cell or two beside a wall face (one crossing in some runs).
  EXPECT_LE(e.double_wall_length_m, 0.1);
}

// The hall's occupancy grid: x -1..17, y -1..15 at 0.05 m.
constexpr int kHallCellsX = 360, kHallCellsY = 320;
constexpr double kHallX = 8.0, kHallY = 1.0;  // the start: 1 m from the south wall

// Seed 003 test 35: with open floor beyond the laser's reach on one side (the hall's walls but
// the south one are 8 m and more away; the laser reaches 5.6 m), the beams that return nothing
// clear 4.9 m and no farther. After a spin in place every interior cell within 4.6 m of the
// start is free, and every cell beyond 5.3 m is untouched: l exactly 0, which the mapper keeps
// as NaN (never observed; -1 on the bus, 50 in the seed's export). The margins: the laser sits
// off the robot's centre (its 0.2 m circle over the spin), and a cell is 0.05 m.
TEST(ExploreStackTest, Seed003Test35BeamsThatReturnNothingClearUpToFourPointNineMetres) {
  OccupancyRig rig("config/sim/hall_p3dx.yaml", kHallCellsX, kHallCellsY);
  const common::GridMap logodds = rig.SpinOnceAndSnapshot();
  ASSERT_TRUE(logodds.HasLayer(kLogOdds));
  const common::Layer& l = logodds.at(kLogOdds);
  int64_t near = 0, near_free = 0, far = 0, far_untouched = 0;
  double farthest_touched_m = 0.0;
  for (int iy = 0; iy < logodds.size_y(); ++iy) {
    for (int ix = 0; ix < logodds.size_x(); ++ix) {
      const common::Vector2 c = logodds.CenterOf({ix, iy});
      if (c.x() <= 0.1 || c.x() >= 15.9 || c.y() <= 0.1 || c.y() >= 13.9) continue;  // inside
      const double d = std::hypot(c.x() - kHallX, c.y() - kHallY);
      const float v = l(ix, iy);
      if (!std::isnan(v)) farthest_touched_m = std::max(farthest_touched_m, d);
      if (d <= 4.6) {
        ++near;
        near_free += v < 0.f;
      } else if (d >= 5.3) {
        ++far;
        far_untouched += std::isnan(v) || v == 0.f;
      }
    }
  }
  std::printf(
      "no-return clearing: %lld of %lld cells within 4.6 m free, %lld of %lld beyond "
      "5.3 m untouched, the farthest touched %.2f m from the start\n",
      static_cast<long long>(near_free), static_cast<long long>(near),
      static_cast<long long>(far_untouched), static_cast<long long>(far), farthest_touched_m);
  ASSERT_GT(near, 5000);
  EXPECT_GE(near_free, near * 99 / 100) << "the floor within reach was not cleared";
  ASSERT_GT(far, 20000);
  EXPECT_EQ(far_untouched, far) << "a no-return beam cleared beyond 4.9 m";
  EXPECT_GT(farthest_touched_m, 4.7) << "the clearing stopped short of 4.9 m";
}

// Seed 003 test 36 in both modes: a box placed in front of the robot, seen, then removed while
// the robot watches for 50 more scans. With the seed's protection (faithful, the arena's
// config) no miss lowers its cells again (they stay at 2.0 or more); with the
// threshold raised above the clamp (improved) the same cells clear (l < 0).
void ExpectBoxPersistence(bool faithful) {
  OccupancyRig rig("config/sim/hall_p3dx.yaml", kHallCellsX, kHallCellsY,
                   faithful ? "" : "  protect_occupied_logodds: 1000.0\n");
  ASSERT_TRUE(rig.WaitReady());
  // The box's south face 1.8 m ahead of the robot (facing north from (8, 1)).
  const double bx = kHallX, by = kHallY + 2.0, half = 0.2;
  ASSERT_TRUE(
      rig.SimBox(cairn::lcmt_sim_control_request::OP_SPAWN, "box36", bx, by, half, half, 0.4));
  // Seen: cells at its south face are protected (l >= 2.0).
  std::vector<int64_t> face;
  common::GridMap before;
  const bool seen = WaitFor(
      [&] {
        before = rig.Snapshot();
        if (!before.HasLayer(kLogOdds)) return false;
        face.clear();
        const common::Layer& l = before.at(kLogOdds);
        for (double x = bx - half; x <= bx + half; x += 0.025) {
          for (double y = by - half - 0.05; y <= by - half + 0.05; y += 0.025) {
            const auto cell = before.IndexOf({x, y});
            if (!cell || l(cell->ix, cell->iy) < 2.0f) continue;
            const int64_t i = before.geometry().LinearIndex(*cell);
            if (std::find(face.begin(), face.end(), i) == face.end()) face.push_back(i);
          }
        }
        return face.size() >= 5;
      },
      20.0);
  ASSERT_TRUE(seen) << "the box's face never reached l 2.0 (" << face.size() << " cells)";
  ASSERT_TRUE(
      rig.SimBox(cairn::lcmt_sim_control_request::OP_REMOVE, "box36", bx, by, half, half, 0.4));
  const int64_t removed_at = rig.OccupancyVersion();
  ASSERT_TRUE(rig.WaitScans(removed_at, 52, 60.0)) << "the mapper applied fewer than 50 scans";
  const common::GridMap after = rig.Snapshot();
  ASSERT_TRUE(after.HasLayer(kLogOdds));
  int kept = 0, cleared = 0;
  for (const int64_t i : face) {
    const float was = before.at(kLogOdds).data()[i], now = after.at(kLogOdds).data()[i];
    // Protected: no miss lowers it (hits of scans still on their way when the box went may
    // raise it towards the clamp).
    kept += now >= was && now >= 2.0f;
    cleared += now < 0.f;
  }
  std::printf("box persistence (%s): %d face cells, %d kept, %d cleared after 50 scans\n",
              faithful ? "faithful" : "improved", static_cast<int>(face.size()), kept, cleared);
  if (faithful) {
    EXPECT_EQ(kept, static_cast<int>(face.size())) << "a protected cell was lowered";
  } else {
    EXPECT_EQ(cleared, static_cast<int>(face.size())) << "a cell of the removed box stayed";
  }
}

TEST(ExploreStackTest, Seed003Test36ARemovedBoxStaysInTheMapWithTheSeedsProtection) {
  ExpectBoxPersistence(true);
}

TEST(ExploreStackTest, Seed003Test36ARemovedBoxClearsWithTheProtectionRaised) {
  ExpectBoxPersistence(false);
}

}  // namespace
}  // namespace cairn::explore
