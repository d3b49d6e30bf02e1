// The whole chain with real processes: cairn-sim drives a Pioneer 3-AT in the tunnel world,
// cairn-mapper maps the 10 degree ramp lane for pioneer3at only, cairn-mapstore pulls the
// mapper's live map, and sharing the stored map with the rover relabels the ramp while the base
// blobs stay byte-identical.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_velocity_command.hpp"

#include "mapstore/sqlite_map_store.h"
#include "tests/integration/mapstore/mapstore_fixture.h"

namespace cairn::mapstore::testing {
namespace {

constexpr char kRobot[] = "p1";

// Drives the robot along y = lane_y towards +x (heading control on the ground-truth pose) until
// x >= x_end, as an operator would to look at the lane.
bool DriveTo(cairn::testing::Bus& bus, double lane_y, double x_end, double timeout_s) {
  const std::string pose_channel = std::string(kRobot) + ".POSE";
  auto command = [&](double v, double w) {
    cairn::lcmt_velocity_command cmd{};
    cmd.robot = kRobot;
    cmd.source = "mapstore_stack_test";
    cmd.linear_mps = v;
    cmd.angular_radps = w;
    bus.Publish(std::string(kRobot) + ".CMD_VEL", cmd);
  };
  auto last = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  const bool reached = WaitFor(
      [&] {
        auto pose = bus.Last<cairn::lcmt_pose>(pose_channel);
        if (!pose) return false;
        if (pose->position_m[0] >= x_end) return true;
        if (std::chrono::steady_clock::now() - last > std::chrono::milliseconds(50)) {
          const double* q = pose->orientation_wxyz;
          const double yaw = std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]),
                                        1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
          command(0.3, std::clamp(-0.8 * (pose->position_m[1] - lane_y) - 1.5 * yaw, -0.5, 0.5));
          last = std::chrono::steady_clock::now();
        }
        return false;
      },
      timeout_s, [&] { bus.Pump(5); });
  command(0.0, 0.0);
  return reached;
}

// The ramp of the tunnel's lane 2 (simulator/worlds: 10 deg from x = 8 around y = 10), as the
// mapper labels it seen from a robot standing at its foot.
bool IsLaneRamp(const cairn::lcmt_obstacle& o) {
  return o.kind == static_cast<int8_t>(common::ObstacleKind::kRamp) && o.centroid_m[0] > 7.5 &&
         o.centroid_m[0] < 10.5 && o.centroid_m[1] > 8.1 && o.centroid_m[1] < 11.9;
}

TEST(MapstoreStackTest, PulledMapOfTheRampIsSharedWithTheRover) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  procs.Start("cairn-sim",
              {"--world", "tunnel", "--robot", std::string(kRobot) + ":pioneer3at:pioneer3at:5,10",
               "--speed", "1", "--seed", "3"});
  procs.Start("cairn-mapper", {"--robot", kRobot, "--config",
                               cairn::testing::MapperConfigWithoutOctomap(procs.dir()),
                               "--profiles", "pioneer3at"});
  const std::string db = procs.dir() + "/site.db";
  procs.Start("cairn-mapstore", {"--db", db});
  cairn::testing::Bus bus(procs.url());
  lcm::LCM lcm(procs.url());
  MapstoreClient client(lcm, "stack-test", TestClientOptions(90.0));
  ASSERT_TRUE(WaitForStore(client, 30.0));
  ASSERT_EQ(client.Call(PutProfileRequest(ShippedProfile("pioneer3at")))->status, kStatusOk);
  ASSERT_EQ(client.Call(PutProfileRequest(ShippedProfile("rover")))->status, kStatusOk);

  // Drive up to the ramp lane; the mapper sees the ramp and judges it for pioneer3at alone.
  ASSERT_TRUE(DriveTo(bus, 10.0, 6.9, 40.0)) << "the robot did not reach x = 6.9";
  const std::string obstacles_channel = std::string(kRobot) + ".MAP.OBSTACLES";
  bool ramp_seen = WaitFor(
      [&] {
        auto r = bus.Last<cairn::lcmt_obstacle_registry>(obstacles_channel);
        if (!r) return false;
        // Judged lethal for pioneer3at (a ramp seen only at its foot measures flatter).
        for (const auto& o : r->obstacles) {
          if (IsLaneRamp(o) && o.num_verdicts == 1 && !o.verdicts[0].crossable) return true;
        }
        return false;
      },
      60.0, [&] { bus.Pump(20); });
  if (!ramp_seen) {
    auto r = bus.Last<cairn::lcmt_obstacle_registry>(obstacles_channel);
    std::ostringstream seen;
    if (r) {
      for (const auto& o : r->obstacles) {
        seen << "  kind " << int(o.kind) << " at (" << o.centroid_m[0] << ", " << o.centroid_m[1]
             << ") slope " << o.slope_rad * 180 / M_PI << " deg\n";
      }
    }
    FAIL() << "the mapper never reported the lane's ramp; "
           << (r ? "its registry:\n" + seen.str() : "no registry arrived");
  }

  // Pull save: the store takes the mapper's robot-agnostic layers and its registry.
  Request save = MakeRequest(Request::OP_SAVE, "tunnel", "lanes");
  save.robot = kRobot;
  save.profile = "pioneer3at";
  auto saved = client.Call(save);
  ASSERT_TRUE(saved.ok()) << saved.status().ToString();
  ASSERT_EQ(saved->status, kStatusOk) << saved->message;
  bool has_elevation = false;
  for (const std::string& layer : saved->layers) {
    EXPECT_FALSE(layers::IsCostLayer(layer)) << layer << " is a profile layer";
    has_elevation |= layer == layers::kElevation;
  }
  EXPECT_TRUE(has_elevation);
  ASSERT_GE(saved->num_maps, 1);  // the 2-D occupancy, on its own grid, is a companion map
  EXPECT_GT(saved->maps[0].num_obstacles, 0);
  EXPECT_EQ(saved->maps[0].source_robot, kRobot);
  const MapRef ref{"tunnel", "lanes", saved->version};

  SqliteOptions read_only;
  read_only.read_only = true;
  auto reader = SqliteMapStore::Open(db, read_only);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  const auto blobs_before = (*reader)->BaseBlobBytes(ref);
  ASSERT_TRUE(blobs_before.ok());

  // Shared with the rover, the ramp changes verdict.
  Request share = MakeRequest(Request::OP_SHARE, "tunnel", "lanes", saved->version);
  share.profile = "rover";
  auto shared = client.Call(share);
  ASSERT_TRUE(shared.ok());
  ASSERT_EQ(shared->status, kStatusOk) << shared->message;
  const cairn::lcmt_obstacle* ramp = nullptr;
  for (const auto& o : shared->obstacles) {
    if (IsLaneRamp(o)) ramp = &o;
  }
  if (ramp == nullptr) {
    std::ostringstream text;
    const auto stored = (*reader)->LoadObstacles(ref);
    for (const auto& o : stored.value().obstacles) {
      text << "  stored kind " << static_cast<int>(o.kind) << " at (" << o.centroid_m.x() << ", "
           << o.centroid_m.y() << ") slope " << o.slope_rad * 180 / M_PI << " deg height "
           << o.height_m;
      for (const auto& v : o.verdicts) text << " " << v.profile << ":" << v.crossable;
      text << "\n";
    }
    for (const auto& o : shared->obstacles) {
      text << "  changed kind " << static_cast<int>(o.kind) << " at (" << o.centroid_m[0] << ", "
           << o.centroid_m[1] << ")\n";
    }
    FAIL() << shared->message << "\n" << text.str();
  }
  ASSERT_EQ(ramp->num_verdicts, 2);
  EXPECT_EQ(ramp->verdicts[0].profile, "pioneer3at");
  EXPECT_FALSE(ramp->verdicts[0].crossable);
  EXPECT_EQ(ramp->verdicts[1].profile, "rover");
  EXPECT_TRUE(ramp->verdicts[1].crossable);

  // Cost layers: on the ramp, cells lethal for pioneer3at are passable for the rover.
  auto p = client.Load("tunnel", "lanes", saved->version, "pioneer3at", {"cost/pioneer3at"});
  auto r = client.Load("tunnel", "lanes", saved->version, "rover", {"cost/rover"});
  ASSERT_TRUE(p.ok()) << p.status().ToString();
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  double x0 = ramp->centroid_m[0], x1 = x0, y0 = ramp->centroid_m[1], y1 = y0;
  for (int i = 0; i < ramp->num_outline; ++i) {
    x0 = std::min(x0, ramp->outline_x_m[i]);
    x1 = std::max(x1, ramp->outline_x_m[i]);
    y0 = std::min(y0, ramp->outline_y_m[i]);
    y1 = std::max(y1, ramp->outline_y_m[i]);
  }
  int relabelled = 0, lethal_for_pioneer = 0;
  const common::GridMap& grid = p->layers;
  for (int iy = 0; iy < grid.size_y(); ++iy) {
    for (int ix = 0; ix < grid.size_x(); ++ix) {
      const common::Vector2 c = grid.CenterOf({ix, iy});
      if (c.x() < x0 || c.x() > x1 || c.y() < y0 || c.y() > y1) continue;
      const float cp = grid.at("cost/pioneer3at")(ix, iy);
      const float cr = r->layers.at("cost/rover")(ix, iy);
      if (cp != layers::kCostLethal) continue;
      ++lethal_for_pioneer;
      relabelled += std::isfinite(cr) && cr < layers::kCostLethal;
    }
  }
  EXPECT_GT(lethal_for_pioneer, 10);
  EXPECT_GT(relabelled, lethal_for_pioneer / 2)
      << relabelled << " of " << lethal_for_pioneer << " ramp cells lethal for pioneer3at are "
      << "passable for the rover";

  const auto blobs_after = (*reader)->BaseBlobBytes(ref);
  ASSERT_TRUE(blobs_after.ok());
  EXPECT_TRUE(*blobs_after == *blobs_before);
}

}  // namespace
}  // namespace cairn::mapstore::testing
