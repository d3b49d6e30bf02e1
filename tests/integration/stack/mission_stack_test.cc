// The whole stack under cairn-launch on a private bus: the demo graph (cairn-sim, cairn-mapper,
// cairn-navigator, cairn-mapstore) with cairn-mission driving it, services killed with SIGKILL
// mid-mission, and a recorded run replayed through scripts/replay into a fresh mapper.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include "cairn/lcmt_pose.hpp"

#include "common/layers.h"
#include "mapstore/sqlite_map_store.h"
#include "planner/footprint.h"
#include "services/launch/status.h"
#include "tests/integration/mapstore/mapstore_fixture.h"
#include "tests/support/harness.h"

namespace cairn::testing {
namespace {

constexpr char kRobot[] = "p3at";

std::optional<launch::GraphStatus> ReadStatus(const std::string& run_dir) {
  std::string error;
  return launch::ReadStatusFile(run_dir + "/status.json", &error);
}

const launch::ProcessRow* Row(const launch::GraphStatus& s, const std::string& name) {
  return launch::FindProcess(s, name);
}

struct GraphOptions {
  bool sim{true};
  bool mapper{true};
  bool navigator{true};
  bool sim_after_mapper{false};  // the simulator starts once the mapper listens
  std::string scenario{"config/sim/demo.yaml"};
};

// A graph like config/graphs/demo.yaml, with absolute paths, the test's bus and database.
std::string WriteGraph(const ProcessSet& procs, const std::string& name, const GraphOptions& o) {
  const std::string path = procs.dir() + "/" + name + ".yaml";
  std::ofstream out(path);
  out << "name: " << name << "\n"
      << "lcm_url: " << procs.url() << "\n"
      << "processes:\n"
      << "  mapstore:\n"
      << "    command: " << BinPath("cairn-mapstore") << "\n"
      << "    args: [--db, " << procs.dir() << "/cairn.db]\n"
      << "    restart: on-failure\n"
      << "    backoff_s: 0.2\n";
  if (o.sim) {
    out << "  sim:\n"
        << "    command: " << BinPath("cairn-sim") << "\n"
        << "    args: [--scenario, " << SourcePath(o.scenario) << ", --speed, '1']\n"
        << (o.sim_after_mapper ? "    depends_on: [mapper]\n" : "") << "    restart: on-failure\n"
        << "    backoff_s: 0.2\n";
  }
  if (o.mapper) {
    out << "  mapper:\n"
        << "    command: " << BinPath("cairn-mapper") << "\n"
        << "    args: [--robot, " << kRobot << ", --profiles, pioneer3at, --config, "
        << MapperConfigWithoutOctomap(procs.dir()) << "]\n"
        << "    robot: " << kRobot << "\n"
        << (o.sim && !o.sim_after_mapper ? "    depends_on: [sim]\n" : "")
        << "    restart: on-failure\n"
        << "    backoff_s: 0.2\n";
  }
  if (o.navigator) {
    out << "  navigator:\n"
        << "    command: " << BinPath("cairn-navigator") << "\n"
        << "    args: [--robot, " << kRobot << ", --profile, pioneer3at]\n"
        << "    robot: " << kRobot << "\n"
        << "    depends_on: [mapper]\n"
        << "    restart: on-failure\n"
        << "    backoff_s: 0.2\n";
  }
  return path;
}

ChildProcess& LaunchUp(ProcessSet& procs, const std::string& graph, const std::string& run_dir) {
  procs.AddLogDir(run_dir + "/logs");  // the graph's processes, printed if the test fails
  return procs.StartRaw("cairn-launch",
                        {BinPath("cairn-launch"), "up", graph, "--run-dir", run_dir});
}

bool WaitReady(const std::string& run_dir, double timeout_s) {
  return WaitFor(
      [&] {
        auto s = ReadStatus(run_dir);
        return s && s->state == "ready";
      },
      timeout_s);
}

// SIGKILLs one process of a running graph and waits until cairn-launch has it ready again.
::testing::AssertionResult KillAndWaitForRestart(const std::string& run_dir,
                                                 const std::string& name, double timeout_s) {
  auto before = ReadStatus(run_dir);
  if (!before || Row(*before, name) == nullptr || Row(*before, name)->pid <= 0)
    return ::testing::AssertionFailure() << "no running " << name << " in status.json";
  const int old_pid = Row(*before, name)->pid;
  const int old_restarts = Row(*before, name)->restarts;
  if (kill(old_pid, SIGKILL) != 0)
    return ::testing::AssertionFailure() << "kill(" << old_pid << ") failed";
  const bool back = WaitFor(
      [&] {
        auto s = ReadStatus(run_dir);
        const launch::ProcessRow* row = s ? Row(*s, name) : nullptr;
        return row && row->restarts == old_restarts + 1 && row->pid > 0 && row->pid != old_pid &&
               row->state == "ready";
      },
      timeout_s);
  if (!back) return ::testing::AssertionFailure() << name << " was not restarted and ready";
  return ::testing::AssertionSuccess();
}

double PoseX(Bus& bus) {
  auto p = bus.Last<cairn::lcmt_pose>(std::string(kRobot) + ".POSE");
  return p ? p->position_m[0] : -1e9;
}

TEST(MissionStackTest, MapperAndNavigatorKilledMidMissionAreRestartedAndTheMissionCompletes) {
  ProcessSet procs(PrivateLcmUrl());
  const std::string run_dir = procs.dir() + "/run";
  LaunchUp(procs, WriteGraph(procs, "demo", {}), run_dir);
  ASSERT_TRUE(WaitReady(run_dir, 90.0)) << "the graph never became ready";
  Bus bus(procs.url());
  ChildProcess& mission = procs.Start(
      "cairn-mission", {"--robot", kRobot, "--goal", "21,38", "--site", "tunnel", "--map", "demo",
                        "--share", "rover", "--profiles-dir", SourcePath("config/profiles"),
                        "--out", procs.dir() + "/renders", "--timeout", "200"});
  // While the robot drives, cairn-spy --once --strict against the shipped demo graph's expected
  // rates: every channel decoded by type, none slow or missing.
  ASSERT_TRUE(WaitFor([&] { return PoseX(bus) > 4.5; }, 60.0, [&] { bus.Pump(20); }))
      << "the robot never set off";
  ChildProcess& spy = procs.StartRaw(
      "cairn-spy", {BinPath("cairn-spy"), "--once", "--strict", "--duration", "5", "--graph",
                    SourcePath("config/graphs/demo.yaml"), "--lcm-url", procs.url()});
  const auto spy_status = spy.WaitExit(30.0);
  ASSERT_TRUE(spy_status.has_value()) << "cairn-spy --once did not finish";
  EXPECT_TRUE(WIFEXITED(*spy_status) && WEXITSTATUS(*spy_status) == 0) << spy.Log();
  const std::string table = spy.Log();
  for (const auto& [channel, type] : std::vector<std::pair<std::string, std::string>>{
           {"SIM.CLOCK", "cairn.lcmt_sim_clock"},
           {"HEALTH", "cairn.lcmt_health"},
           {"p3at.LIDAR_RANGES", "cairn.lcmt_lidar_ranges"},
           {"p3at.SCAN", "cairn.lcmt_laser_scan"},
           {"p3at.ODOM", "cairn.lcmt_odometry"},
           {"p3at.POSE", "cairn.lcmt_pose"},
           {"p3at.IMU", "cairn.lcmt_imu"},
           {"p3at.MAP.MANIFEST", "cairn.lcmt_grid_manifest"},
           {"p3at.MAP.TILES", "cairn.lcmt_grid_tile"},
           {"p3at.MAP.OBSTACLES", "cairn.lcmt_obstacle_registry"},
           {"p3at.MAP.OCCUPANCY", "cairn.lcmt_occupancy_tile"},
           {"p3at.CMD_VEL", "cairn.lcmt_velocity_command"},
           {"p3at.NAV_STATUS", "cairn.lcmt_nav_status"}}) {
    const size_t at = table.find("\n" + channel + " ");
    ASSERT_NE(at, std::string::npos) << channel << " is not in the table:\n" << table;
    const std::string row = table.substr(at + 1, table.find('\n', at + 1) - at - 1);
    EXPECT_NE(row.find(type), std::string::npos) << row;
    EXPECT_EQ(row.find("SLOW"), std::string::npos) << row;
  }

  // Mid-mission (demo lane: start x = 4, goal x = 21), first the mapper, then the navigator.
  ASSERT_TRUE(WaitFor([&] { return PoseX(bus) > 8.0; }, 90.0, [&] { bus.Pump(20); }))
      << "the robot never passed x = 8";
  ASSERT_TRUE(KillAndWaitForRestart(run_dir, "mapper", 60.0));
  ASSERT_TRUE(WaitFor([&] { return PoseX(bus) > 12.0; }, 90.0, [&] { bus.Pump(20); }))
      << "the robot did not go on after the mapper's restart";
  ASSERT_TRUE(KillAndWaitForRestart(run_dir, "navigator", 60.0));
  // The mission re-sends its goal to the restarted navigator and completes: reached, saved,
  // shared.
  const auto status = mission.WaitExit(220.0);
  ASSERT_TRUE(status.has_value()) << "the mission did not finish";
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << mission.Log();
  // Ground truth: the robot stands at the goal.
  EXPECT_TRUE(WaitFor(
      [&] {
        auto pose = bus.Last<cairn::lcmt_pose>(std::string(kRobot) + ".POSE");
        return pose && std::hypot(pose->position_m[0] - 21.0, pose->position_m[1] - 38.0) < 0.6;
      },
      10.0, [&] { bus.Pump(20); }));
  const std::string log = mission.Log();
  EXPECT_NE(log.find("sending it again"), std::string::npos)
      << "the mission never had to re-send its goal to the restarted navigator";
  mapstore::SqliteOptions read_only;
  read_only.read_only = true;
  auto store = mapstore::SqliteMapStore::Open(procs.dir() + "/cairn.db", read_only);
  ASSERT_TRUE(store.ok()) << store.status().ToString();
  mapstore::MapFilter filter;
  filter.site = "tunnel";
  filter.name = "demo";
  auto maps = (*store)->ListMaps(filter);
  ASSERT_TRUE(maps.ok());
  EXPECT_EQ(maps->size(), 1u);
}

// The least distance between a vertex of one outline and a vertex of the other: outlines traced
// around the same cells share corners, and a piece split off a feature keeps some of them.
// The distance between two outlines as regions: 0 when they overlap (a vertex of one inside the
// other), else the least distance from a vertex of one to an edge of the other. One object's
// outline and the outline of a larger piece holding it (a wall seen whole in one map and in
// pieces in the other) are 0 apart, however far apart their vertices are.
double PointSegment(const common::Vector2& p, const common::Vector2& a, const common::Vector2& b) {
  const common::Vector2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

double OutlineDistance(const std::vector<common::Vector2>& a,
                       const std::vector<common::Vector2>& b) {
  if (a.empty() || b.empty()) return std::numeric_limits<double>::infinity();
  double best = std::numeric_limits<double>::infinity();
  for (const auto* pair : {&a, &b}) {
    const auto& from = *pair;
    const auto& to = pair == &a ? b : a;
    for (const auto& p : from) {
      if (to.size() >= 3 && planner::PointInPolygon(to, p)) return 0.0;
      for (size_t i = 0; i < to.size(); ++i) {
        best = std::min(best, PointSegment(p, to[i], to[(i + 1) % to.size()]));
      }
    }
  }
  return best;
}

// Cells known in both maps that agree within tol_m, and cells known in only one of them.
struct LayerAgreement {
  int64_t both{0};
  int64_t agree{0};
  int64_t only_one{0};
};

LayerAgreement Compare(const common::GridMap& a, const common::GridMap& b, const std::string& layer,
                       double tol_m) {
  LayerAgreement r;
  const auto& ga = a.geometry();
  const common::Layer& la = a.at(layer);
  for (int iy = 0; iy < ga.size_y; ++iy) {
    for (int ix = 0; ix < ga.size_x; ++ix) {
      const float va = la(ix, iy);
      const float vb = b.ValueAt(layer, a.CenterOf({ix, iy})).value_or(NAN);
      if (std::isnan(va) && std::isnan(vb)) continue;
      if (std::isnan(va) || std::isnan(vb)) {
        ++r.only_one;
        continue;
      }
      ++r.both;
      if (std::abs(va - vb) <= tol_m) ++r.agree;
    }
  }
  return r;
}

TEST(MissionStackTest, ARecordedRunReplaysThroughScriptsReplayIntoTheSameStoredMap) {
  ProcessSet procs(PrivateLcmUrl());
  const std::string log_file = procs.dir() + "/run.lcmlog";

  // Live: sim, mapper and store under cairn-launch, the sensor channels recorded from before
  // the simulator starts (it starts once the mapper listens), so the live mapper and the log
  // see the same messages.
  ChildProcess& recorder = procs.StartRaw(
      "record", {SourcePath("scripts/record"), log_file, "--lcm-url", procs.url(), "--channels",
                 "^(p3at\\.(LIDAR_RANGES|POSE|ODOM|IMU|SCAN)|SIM\\.CLOCK)$"});
  const std::string run_live = procs.dir() + "/live";
  GraphOptions live_graph;
  live_graph.navigator = false;
  live_graph.sim_after_mapper = true;
  ChildProcess& live = LaunchUp(procs, WriteGraph(procs, "live", live_graph), run_live);
  ASSERT_TRUE(WaitReady(run_live, 90.0)) << "the live graph never became ready";
  Bus bus(procs.url());
  // Three seconds of sim time recorded (SIM.CLOCK), then the simulator stops first, so the
  // live mapper and the log hold the same revolutions.
  ASSERT_TRUE(WaitFor([&] { return std::ifstream(log_file).good(); }, 10.0));
  int64_t first_utime = -1;
  ASSERT_TRUE(WaitFor(
      [&] {
        auto p = bus.Last<cairn::lcmt_pose>(std::string(kRobot) + ".POSE");
        if (!p) return false;
        if (first_utime < 0) first_utime = p->utime;
        return p->utime - first_utime > 3'000'000;
      },
      60.0, [&] { bus.Pump(20); }));
  auto status = ReadStatus(run_live);
  ASSERT_TRUE(status && Row(*status, "sim") != nullptr);
  ASSERT_EQ(kill(Row(*status, "sim")->pid, SIGSTOP), 0);  // no further revolutions
  recorder.Signal(SIGINT);
  ASSERT_TRUE(recorder.WaitExit(10.0).has_value());

  lcm::LCM lcm(procs.url());
  mapstore::MapstoreClient client(lcm, "stack-test", mapstore::testing::TestClientOptions(90.0));
  ASSERT_TRUE(mapstore::testing::WaitForStore(client, 30.0));
  auto save = [&](const std::string& map) {
    auto request =
        mapstore::testing::MakeRequest(cairn::lcmt_mapstore_request::OP_SAVE, "tunnel", map);
    request.robot = kRobot;
    request.profile = "pioneer3at";
    return client.Call(request);
  };
  // The live mapper has taken what it will take once its revolution count stops moving.
  auto saved_live = save("live");
  ASSERT_TRUE(saved_live.ok()) << saved_live.status().ToString();
  ASSERT_EQ(saved_live->status, mapstore::testing::kStatusOk) << saved_live->message;
  kill(Row(*status, "sim")->pid, SIGCONT);
  live.Signal(SIGTERM);
  ASSERT_TRUE(live.WaitExit(30.0).has_value());

  // Replayed: a fresh mapper and the same store, fed by scripts/replay.
  const std::string run_replay = procs.dir() + "/replay";
  GraphOptions replay_graph;
  replay_graph.sim = false;
  replay_graph.navigator = false;
  LaunchUp(procs, WriteGraph(procs, "replay", replay_graph), run_replay);
  ASSERT_TRUE(WaitReady(run_replay, 90.0)) << "the replay graph never became ready";
  ChildProcess& player =
      procs.StartRaw("replay", {SourcePath("scripts/replay"), log_file, "--lcm-url", procs.url()});
  const auto played = player.WaitExit(60.0);
  ASSERT_TRUE(played.has_value() && WIFEXITED(*played) && WEXITSTATUS(*played) == 0)
      << player.Log();
  ASSERT_TRUE(mapstore::testing::WaitForStore(client, 30.0));
  auto saved_replay = save("replayed");
  ASSERT_TRUE(saved_replay.ok()) << saved_replay.status().ToString();
  ASSERT_EQ(saved_replay->status, mapstore::testing::kStatusOk) << saved_replay->message;

  mapstore::SqliteOptions read_only;
  read_only.read_only = true;
  auto store = mapstore::SqliteMapStore::Open(procs.dir() + "/cairn.db", read_only);
  ASSERT_TRUE(store.ok()) << store.status().ToString();
  mapstore::LayerQuery query;
  query.layers = {layers::kElevation};
  const mapstore::MapRef live_ref{"tunnel", "live", saved_live->version};
  const mapstore::MapRef replay_ref{"tunnel", "replayed", saved_replay->version};
  auto a = (*store)->LoadLayers(live_ref, query);
  auto b = (*store)->LoadLayers(replay_ref, query);
  ASSERT_TRUE(a.ok() && b.ok());
  const LayerAgreement e = Compare(*a, *b, layers::kElevation, 0.01);
  // A robot standing in a 4 m x 21 m lane for 3 s: most of its floor (about 2100 cells).
  ASSERT_GT(e.both, 800) << "too little of the lane mapped";
  // The same revolutions, poses and parameters give the same elevation: nearly every cell
  // known in either map is known in both and agrees within a centimetre.
  EXPECT_GE(static_cast<double>(e.agree), 0.99 * static_cast<double>(e.both + e.only_one))
      << e.agree << " of " << e.both << " common cells agree, " << e.only_one
      << " known in one map only";
  auto oa = (*store)->LoadObstacles(live_ref);
  auto ob = (*store)->LoadObstacles(replay_ref);
  ASSERT_TRUE(oa.ok() && ob.ok());
  // The registry is derived from the same layers, but a low feature on the edge of a threshold
  // (a few millimetres of step) can split, merge or vanish. Every wall or object taller than
  // 25 cm (the lane's walls, the cube) is in both registries, where the other's outline is.
  auto tall = [](const common::Obstacle& o) {
    return o.kind == common::ObstacleKind::kWallOrObject && o.height_m >= 0.25;
  };
  int tall_live = 0;
  for (const auto* pair : {&*oa, &*ob}) {
    const auto& here = pair->obstacles;
    const auto& there = (pair == &*oa ? ob : oa)->obstacles;
    for (const auto& o : here) {
      if (!tall(o)) continue;
      tall_live += pair == &*oa;
      const bool found = std::any_of(there.begin(), there.end(), [&](const common::Obstacle& p) {
        return p.kind == o.kind && OutlineDistance(o.outline_m, p.outline_m) <= 0.4;
      });
      EXPECT_TRUE(found) << (pair == &*oa ? "live" : "replayed") << " obstacle #" << o.id << " at ("
                         << o.centroid_m.x() << ", " << o.centroid_m.y() << "), " << o.height_m
                         << " m high, is missing from the other registry";
    }
  }
  EXPECT_GE(tall_live, 1) << "the live registry has no wall: nothing was compared";
}

}  // namespace
}  // namespace cairn::testing
