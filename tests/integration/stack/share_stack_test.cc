// Map sharing between robots (issue 7) with real processes under cairn-launch on a private bus:
// the tunnel world of config/sim/share.yaml, a Pioneer 3-AT with a lidar (p3at) and a rover-
// profile robot without one (rover).
//
// Phase 1: p3at maps lane 2 (the 10 deg ramp up to a 0.3 m platform) and the map store pull-
// saves its map; the stored verdict of pioneer3at on the ramp is "not traversable".
// Phase 2: the rover, which has no mapper, is served the stored map for its own profile by
// cairn-map-server (started at the beginning and waiting for the map) and its navigator drives
// it up the ramp onto the platform, on that map alone.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_nav_status.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sim_control_reply.hpp"
#include "cairn/lcmt_sim_control_request.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "common/channels.h"
#include "common/layers.h"
#include "common/robot_profile.h"
#include "mapstore/lcm/mapstore_client.h"
#include "mapstore/sqlite_map_store.h"
#include "services/runtime/conversions.h"
#include "tests/support/harness.h"

namespace cairn::testing {
namespace {

namespace ch = cairn::channels;
namespace fs = std::filesystem;
using Request = cairn::lcmt_mapstore_request;

constexpr char kScout[] = "p3at";   // pioneer3at, lidar, mapper
constexpr char kRover[] = "rover";  // rover profile, no lidar, served
constexpr char kSite[] = "tunnel";
constexpr char kMap[] = "share";
constexpr int kStateReached = cairn::lcmt_nav_status::STATE_REACHED;
constexpr int kReasonStaleMap = cairn::lcmt_nav_status::REASON_STALE_MAP;
// A copy (gtest takes arguments by reference; the generated class only declares it).
constexpr int8_t kStoreOk = cairn::lcmt_mapstore_reply::STATUS_OK;

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The shipped mapper configuration for pioneer3at only, cost layers every 0.2 s, no OctoMap
// (not under test, and the costliest part on a shared machine).
std::string MapperConfig(const std::string& dir) {
  std::string yaml = ReadFile(SourcePath("config/mapping/mapper.yaml"));
  yaml = std::regex_replace(yaml, std::regex("\\npublish_period_s: [0-9.]+"),
                            "\npublish_period_s: 0.2");
  yaml = std::regex_replace(yaml, std::regex("\\nprofiles: \\[[^\\]]*\\]"),
                            "\nprofiles: [pioneer3at]");
  yaml = std::regex_replace(yaml, std::regex("octomap:\\n  enabled: true"),
                            "octomap:\n  enabled: false");
  const std::string path = dir + "/mapper.yaml";
  std::ofstream(path) << yaml;
  return path;
}

// The graph of config/graphs/share.yaml with absolute paths, the test's bus, no navigator for
// the scout (the test drives it) and the map server polling faster.
std::string WriteGraph(const std::string& dir, const std::string& url, const std::string& db) {
  const std::string config = SourcePath("config");
  const std::string path = dir + "/share.yaml";
  std::ofstream out(path);
  out << "name: share_test\n"
      << "lcm_url: " << url << "\n"
      << "run_dir: " << dir << "/run\n"
      << "processes:\n"
      << "  mapstore:\n"
      << "    command: " << BinPath("cairn-mapstore") << "\n"
      << "    args: [--db, " << db << "]\n"
      << "    restart: never\n"
      << "  sim:\n"
      << "    command: " << BinPath("cairn-sim") << "\n"
      << "    args: [--scenario, " << config << "/sim/share.yaml, --speed, '1']\n"
      << "    restart: never\n"
      << "  mapper:\n"
      << "    command: " << BinPath("cairn-mapper") << "\n"
      << "    args: [--robot, " << kScout << ", --config, " << MapperConfig(dir) << "]\n"
      << "    robot: " << kScout << "\n"
      << "    depends_on: [sim]\n"
      << "    restart: never\n"
      << "  map_server:\n"
      << "    command: " << BinPath("cairn-map-server") << "\n"
      << "    args: [--db, " << db << ", --site, " << kSite << ", --map, " << kMap
      << ", --profile, rover, --robot, " << kRover << ", --wait-s, '170', --poll-s, '0.5']\n"
      << "    robot: " << kRover << "\n"
      << "    restart: never\n"
      << "  rover_navigator:\n"
      << "    command: " << BinPath("cairn-navigator") << "\n"
      << "    args: [--robot, " << kRover << ", --profile, rover, --config-dir, " << config << "]\n"
      << "    robot: " << kRover << "\n"
      << "    depends_on: [sim]\n"
      << "    restart: never\n";
  return path;
}

// The ramp of lane 2 (10 deg from x = 8 to 9.7 around y = 10, up to the 0.3 m platform). The
// mapper labels it a ramp or, seen with the platform's edge, a step up; pieces along the lane
// walls (y = 8.1 and 11.9) are the walls' edges.
bool IsLaneRamp(common::ObstacleKind kind, double x, double y) {
  return (kind == common::ObstacleKind::kRamp || kind == common::ObstacleKind::kStepUp) &&
         x > 7.5 && x < 10.5 && y > 8.5 && y < 11.5;
}

// The ramp-like obstacles of the lane in a registry, one line each (for failure messages).
std::string LaneObstacles(const std::optional<cairn::lcmt_obstacle_registry>& registry) {
  if (!registry) return "  (no registry)\n";
  std::ostringstream out;
  for (const auto& o : registry->obstacles) {
    if (o.centroid_m[1] < 8.1 || o.centroid_m[1] > 11.9) continue;
    out << "  kind " << static_cast<int>(o.kind) << " at (" << o.centroid_m[0] << ", "
        << o.centroid_m[1] << ") slope " << o.slope_rad * 180 / M_PI << " deg";
    for (int i = 0; i < o.num_verdicts; ++i) {
      out << " " << o.verdicts[i].profile << ":" << static_cast<int>(o.verdicts[i].crossable);
    }
    out << "\n";
  }
  return out.str();
}

double Yaw(const cairn::lcmt_pose& pose) {
  const double* q = pose.orientation_wxyz;
  return std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
}

class ShareStackTest : public ::testing::Test {
 protected:
  ShareStackTest() : procs_(PrivateLcmUrl()), bus_(procs_.url()) {
    for (const char* stream : {ch::kMapTiles, ch::kMapManifest}) {
      bus_.Keep(ch::ForRobot(kRover, stream));
    }
    bus_.Keep(ch::ForRobot(kRover, ch::kNavStatus));
    bus_.Keep(ch::ForRobot(kRover, ch::kPose));
  }
  ~ShareStackTest() override {
    if (launcher_ != nullptr) launcher_->Stop(15.0);  // cairn-launch stops the graph
    if (::testing::Test::HasFailure()) PrintGraphLogs();
  }

  void PrintGraphLogs() const {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(procs_.dir() + "/run/logs", ec)) {
      std::string log = ReadFile(entry.path().string());
      if (log.size() > 6000) log = "...\n" + log.substr(log.size() - 6000);
      std::printf("----- %s -----\n%s\n", entry.path().filename().c_str(), log.c_str());
    }
  }

  void Pump() { bus_.Pump(10); }

  std::optional<cairn::lcmt_pose> Pose(const char* robot) {
    return bus_.Last<cairn::lcmt_pose>(ch::ForRobot(robot, ch::kPose));
  }

  // Drives the scout along y = lane_y towards +x (heading control on ground truth) until
  // x >= x_end, as an operator would to look at the lane.
  bool DriveScoutTo(double lane_y, double x_end, double timeout_s) {
    auto command = [&](double v, double w) {
      cairn::lcmt_velocity_command cmd{};
      cmd.robot = kScout;
      cmd.source = "share_stack_test";
      cmd.linear_mps = v;
      cmd.angular_radps = w;
      bus_.Publish(ch::ForRobot(kScout, ch::kCmdVel), cmd);
    };
    auto last = std::chrono::steady_clock::now() - std::chrono::seconds(1);
    const bool reached = WaitFor(
        [&] {
          auto pose = Pose(kScout);
          if (!pose) return false;
          if (pose->position_m[0] >= x_end) return true;
          if (std::chrono::steady_clock::now() - last > std::chrono::milliseconds(50)) {
            command(0.3, std::clamp(-0.8 * (pose->position_m[1] - lane_y) - 1.5 * Yaw(*pose), -0.5,
                                    0.5));
            last = std::chrono::steady_clock::now();
          }
          return false;
        },
        timeout_s, [&] { Pump(); });
    command(0.0, 0.0);
    return reached;
  }

  // Puts a robot at rest at (x, y) on the surface below, through SIM.CONTROL. The request is
  // repeated until its reply arrives (a replayed request id gets the first reply again): this
  // bus carries lidar and map bursts, and a small reply can be lost in a full receive buffer.
  bool ResetRobot(const char* robot, double x, double y, double yaw_rad) {
    cairn::lcmt_sim_control_request r{};
    r.request_id = ++request_id_;
    r.requester = "share_stack_test";
    r.op = cairn::lcmt_sim_control_request::OP_RESET_ROBOT;
    r.name = robot;
    r.position_m[0] = x;
    r.position_m[1] = y;
    r.yaw_rad = yaw_rad;
    std::optional<cairn::lcmt_sim_control_reply> reply;
    auto last_sent = std::chrono::steady_clock::now() - std::chrono::seconds(1);
    WaitFor(
        [&] {
          auto m = bus_.Last<cairn::lcmt_sim_control_reply>(ch::kSimControlReply);
          if (m && m->request_id == r.request_id) reply = m;
          if (!reply &&
              std::chrono::steady_clock::now() - last_sent > std::chrono::milliseconds(500)) {
            bus_.Publish(ch::kSimControl, r);
            last_sent = std::chrono::steady_clock::now();
          }
          return reply.has_value();
        },
        10.0, [&] { Pump(); });
    EXPECT_TRUE(reply.has_value()) << "no reply to resetting " << robot;
    if (reply) {
      EXPECT_EQ(reply->status, 0) << reply->message;
    }
    // Ground truth confirms it.
    return reply && reply->status == 0 &&
           WaitFor(
               [&] {
                 auto pose = Pose(robot);
                 return pose && std::hypot(pose->position_m[0] - x, pose->position_m[1] - y) < 0.3;
               },
               10.0, [&] { Pump(); });
  }

  std::string HealthMessage(const std::string& process, const std::string& robot) {
    auto h = bus_.Health(process, robot);
    return h ? h->message : "";
  }

  // Decoded messages kept on a channel.
  template <typename Msg>
  std::vector<Msg> Kept(const std::string& channel) {
    std::vector<Msg> out;
    for (const auto& bytes : bus_.Kept(channel)) {
      Msg m;
      if (m.decode(bytes.data(), 0, static_cast<int>(bytes.size())) >= 0) out.push_back(m);
    }
    return out;
  }

  ProcessSet procs_;
  Bus bus_;
  ChildProcess* launcher_{nullptr};
  int64_t request_id_{0};
};

TEST_F(ShareStackTest, ARoverWithoutLidarClimbsTheRampOnTheMapAPioneerLeft) {
  const auto t_start = std::chrono::steady_clock::now();
  const std::string db = procs_.dir() + "/site.db";
  const std::string graph = WriteGraph(procs_.dir(), procs_.url(), db);
  procs_.AddLogDir(procs_.dir() + "/run/logs");  // the graph's run_dir
  launcher_ = &procs_.StartRaw("cairn-launch", {BinPath("cairn-launch"), "up", graph});

  // The store answers; the profiles it derives for are stored (as cairn-mission would).
  lcm::LCM lcm(procs_.url());
  mapstore::MapstoreClientOptions client_options;
  client_options.reply_timeout_s = 1.0;
  client_options.total_timeout_s = 60.0;
  mapstore::MapstoreClient client(lcm, "share_stack_test", client_options);
  for (const char* profile : {"pioneer3at", "rover"}) {
    Request put{};
    put.op = Request::OP_PUT_PROFILE;
    put.has_profile = true;
    put.profile_data = runtime::ToLcm(common::LoadRobotProfileFile(
        SourcePath(std::string("config/profiles/") + profile + ".yaml")));
    auto reply = client.Call(put);
    ASSERT_TRUE(reply.ok()) << reply.status().ToString();
    ASSERT_EQ(reply->status, kStoreOk) << reply->message;
  }

  // The rover's map server is up and waiting for a map nobody saved yet.
  ASSERT_TRUE(WaitFor(
      [&] {
        return HealthMessage("cairn-map-server", kRover).find("waiting") != std::string::npos &&
               Pose(kScout).has_value() && Pose(kRover).has_value();
      },
      60.0, [&] { Pump(); }))
      << "map server: '" << HealthMessage("cairn-map-server", kRover) << "'";
  EXPECT_FALSE(bus_.Seen(ch::ForRobot(kRover, ch::kMapManifest)));

  // ---- Phase 1: the Pioneer maps the ramp lane; the store pull-saves its map. ----
  ASSERT_TRUE(DriveScoutTo(10.0, 6.9, 40.0)) << "the scout did not reach x = 6.9";
  // The mapper has measured the whole ramp and judged it for pioneer3at (a ramp seen only in
  // part can measure flatter than it is).
  const std::string obstacles = ch::ForRobot(kScout, ch::kMapObstacles);
  ASSERT_TRUE(WaitFor(
      [&] {
        auto r = bus_.Last<cairn::lcmt_obstacle_registry>(obstacles);
        if (!r) return false;
        return std::any_of(r->obstacles.begin(), r->obstacles.end(), [](const auto& o) {
          return IsLaneRamp(static_cast<common::ObstacleKind>(o.kind), o.centroid_m[0],
                            o.centroid_m[1]) &&
                 o.num_verdicts > 0 && !o.verdicts[0].crossable;
        });
      },
      60.0, [&] { Pump(); }))
      << "the mapper never judged the lane's ramp lethal for pioneer3at; its registry:\n"
      << LaneObstacles(bus_.Last<cairn::lcmt_obstacle_registry>(obstacles));

  Request save{};
  save.op = Request::OP_SAVE;
  save.site = kSite;
  save.map_name = kMap;
  save.robot = kScout;
  save.profile = "pioneer3at";
  auto saved = client.Call(save);
  ASSERT_TRUE(saved.ok()) << saved.status().ToString();
  ASSERT_EQ(saved->status, kStoreOk) << saved->message;
  const mapstore::MapRef ref{kSite, kMap, saved->version};

  // The stored verdict of pioneer3at on the 10 deg ramp: not traversable.
  mapstore::SqliteOptions read_only;
  read_only.read_only = true;
  auto reader = mapstore::SqliteMapStore::Open(db, read_only);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  auto stored = (*reader)->LoadObstacles(ref);
  ASSERT_TRUE(stored.ok()) << stored.status().ToString();
  // The ramp is the largest ramp-like feature of the lane (its edges may form small ones).
  const common::Obstacle* ramp = nullptr;
  std::ostringstream candidates;
  for (const auto& o : stored->obstacles) {
    if (!IsLaneRamp(o.kind, o.centroid_m.x(), o.centroid_m.y())) continue;
    candidates << "  (" << o.centroid_m.x() << ", " << o.centroid_m.y() << ") " << o.num_cells
               << " cells, slope " << o.slope_rad * 180 / M_PI << " deg, height " << o.height_m;
    for (const auto& v : o.verdicts) candidates << " " << v.profile << ":" << v.crossable;
    candidates << "\n";
    if (ramp == nullptr || o.num_cells > ramp->num_cells) ramp = &o;
  }
  ASSERT_NE(ramp, nullptr) << "no ramp in the stored registry";
  const common::ObstacleVerdict* pioneer = ramp->VerdictFor("pioneer3at");
  ASSERT_NE(pioneer, nullptr) << "the stored ramp has no pioneer3at verdict";
  EXPECT_FALSE(pioneer->crossable) << "stored lane ramps:\n" << candidates.str();
  const auto phase1_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start);

  // ---- Phase 2: the rover, served the stored map, climbs to the platform. ----
  // The scout leaves the lane (to lane 9) and the rover comes in from the corridor.
  ASSERT_TRUE(ResetRobot(kScout, 4.0, 38.0, 0.0));
  ASSERT_TRUE(ResetRobot(kRover, 4.0, 10.0, 0.0));

  // The server found the saved version and serves the rover's cost layer.
  ASSERT_TRUE(WaitFor(
      [&] {
        for (const auto& m :
             Kept<cairn::lcmt_grid_manifest>(ch::ForRobot(kRover, ch::kMapManifest))) {
          if (m.layer == layers::CostLayer("rover") && m.num_tiles > 0) return true;
        }
        return false;
      },
      60.0, [&] { Pump(); }))
      << "map server: '" << HealthMessage("cairn-map-server", kRover) << "'";
  // Its registry carries the stored obstacles, each with the rover's verdict only.
  ASSERT_TRUE(WaitFor([&] { return bus_.Seen(ch::ForRobot(kRover, ch::kMapObstacles)); }, 10.0,
                      [&] { Pump(); }));
  {
    auto r = bus_.Last<cairn::lcmt_obstacle_registry>(ch::ForRobot(kRover, ch::kMapObstacles));
    ASSERT_TRUE(r.has_value());
    EXPECT_EQ(r->obstacles.size(), stored->obstacles.size());
    for (const auto& o : r->obstacles) {
      ASSERT_EQ(o.num_verdicts, 1);
      EXPECT_EQ(o.verdicts[0].profile, "rover");
    }
    std::printf("served to the rover:\n%s", LaneObstacles(r).c_str());
  }

  // The rover stands at the lane start (ground truth) before it is sent.
  std::optional<cairn::lcmt_pose> start;
  ASSERT_TRUE(WaitFor(
      [&] {
        start = Pose(kRover);
        return start && std::hypot(start->position_m[0] - 4.0, start->position_m[1] - 10.0) < 0.3;
      },
      10.0, [&] { Pump(); }));
  const size_t statuses_before = bus_.Kept(ch::ForRobot(kRover, ch::kNavStatus)).size();
  cairn::lcmt_goal goal{};
  goal.robot = kRover;
  goal.goal_id = 1;
  goal.kind = cairn::lcmt_goal::KIND_POSE;
  goal.x_m = 14.0;
  goal.y_m = 10.0;
  bus_.Publish(ch::ForRobot(kRover, ch::kGoal), goal);
  std::optional<cairn::lcmt_nav_status> status;
  auto sent = std::chrono::steady_clock::now();
  const bool reached = WaitFor(
      [&] {
        status = bus_.Last<cairn::lcmt_nav_status>(ch::ForRobot(kRover, ch::kNavStatus));
        return status && status->goal_id == 1 && status->state == kStateReached;
      },
      90.0,
      [&] {
        Pump();
        // A goal is one UDP datagram: until the navigator reports on it, send it again (the
        // navigator takes a repeated goal id as the same goal).
        if ((!status || status->goal_id != 1) &&
            std::chrono::steady_clock::now() - sent > std::chrono::seconds(1)) {
          bus_.Publish(ch::ForRobot(kRover, ch::kGoal), goal);
          sent = std::chrono::steady_clock::now();
        }
      });
  if (!reached) {
    const auto pose = Pose(kRover);
    const auto cmd = bus_.Last<cairn::lcmt_velocity_command>(ch::ForRobot(kRover, ch::kCmdVel));
    char where[160] = "no pose";
    if (pose) {
      std::snprintf(where, sizeof(where), "at (%.2f, %.2f, z %.3f)", pose->position_m[0],
                    pose->position_m[1], pose->position_m[2]);
    }
    FAIL() << "rover " << where
           << (cmd ? ", last command v " + std::to_string(cmd->linear_mps) + " m/s, w " +
                         std::to_string(cmd->angular_radps) + " rad/s"
                   : ", no command")
           << ": "
           << (status ? "state " + std::to_string(status->state) + " reason " +
                            std::to_string(status->reason) + ": " + status->message
                      : "no status");
  }

  // Ground truth: on the platform, 0.3 m above the lane floor.
  auto last = Pose(kRover);
  ASSERT_TRUE(last.has_value());
  EXPECT_LT(std::hypot(last->position_m[0] - 14.0, last->position_m[1] - 10.0), 0.5);
  EXPECT_NEAR(last->position_m[2] - start->position_m[2], 0.3, 0.05);

  // The map never went stale on the way (the server re-announces it every 0.2 s).
  const auto statuses = Kept<cairn::lcmt_nav_status>(ch::ForRobot(kRover, ch::kNavStatus));
  for (size_t i = statuses_before; i < statuses.size(); ++i) {
    EXPECT_NE(statuses[i].reason, kReasonStaleMap) << statuses[i].message;
  }

  // Everything the rover's navigator received as a map came from the map server: the stored
  // map's name on every tile and manifest, and no mapper ever ran for the rover.
  const auto tiles = Kept<cairn::lcmt_grid_tile>(ch::ForRobot(kRover, ch::kMapTiles));
  const auto manifests = Kept<cairn::lcmt_grid_manifest>(ch::ForRobot(kRover, ch::kMapManifest));
  EXPECT_FALSE(tiles.empty());
  for (const auto& t : tiles) ASSERT_EQ(t.map_name, "tunnel/share") << t.layer;
  for (const auto& m : manifests) ASSERT_EQ(m.map_name, "tunnel/share") << m.layer;
  EXPECT_FALSE(bus_.Health("cairn-mapper", kRover).has_value());
  ASSERT_TRUE(bus_.Health("cairn-map-server", kRover).has_value());

  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  std::printf("share stack: phase 1 %.1f s, total %.1f s\n", phase1_s.count(), total_s);
}

}  // namespace
}  // namespace cairn::testing
