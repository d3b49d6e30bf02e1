// One stored map, two robot profiles: a 10 degree ramp is lethal for pioneer3at (8 degrees,
// 3 cm steps) and traversable for the rover (12 degrees, 8 cm steps), while the stored base
// blobs stay byte-identical. The derivation is the real cairn::mapping one.

#include <cmath>

#include <gtest/gtest.h>

#include "mapstore/sqlite_map_store.h"
#include "services/mapping/derive.h"
#include "tests/integration/mapstore/mapstore_fixture.h"

namespace cairn::mapstore::testing {
namespace {

constexpr int kSizeX = 80;
constexpr int kSizeY = 50;
constexpr int kRampStart = 25;  // cells
constexpr int kRampCells = 30;

// Flat ground, a 10 degree ramp across the whole width, a plateau on top.
MapSnapshot RampSnapshot() {
  MapSnapshot s;
  s.site = "test-site";
  s.name = "ramp";
  s.provenance.source_robot = "p3at1";
  s.provenance.source_profile = "pioneer3at";
  s.provenance.code_version = mapping::kMappingCodeVersion;
  common::GridGeometry g;
  g.resolution_m = 0.2;
  g.size_x = kSizeX;
  g.size_y = kSizeY;
  g.origin = {0.0, 0.0, 0.0};
  s.base = common::GridMap(g);
  common::Layer& e = s.base.AddLayer(layers::kElevation);
  common::Layer& v = s.base.AddLayer(layers::kElevationVariance, 1e-4f);
  (void)v;
  const double rise = std::tan(10.0 * M_PI / 180.0) * g.resolution_m;
  for (int iy = 0; iy < kSizeY; ++iy) {
    for (int ix = 0; ix < kSizeX; ++ix) {
      e(ix, iy) = static_cast<float>(std::clamp(ix - kRampStart, 0, kRampCells) * rise);
    }
  }
  // The mapper records the obstacles it found with its own profile's verdicts.
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  s.provenance.source_profile_hash = pioneer.ContentHash();
  s.obstacles = mapping::DeriveProfileLayers(s.base, pioneer).registry;
  return s;
}

TEST(MapstoreSharingTest, RampIsLethalForPioneerAndTraversableForRoverBaseUntouched) {
  ProcessSet procs(cairn::testing::PrivateLcmUrl());
  const std::string db = procs.dir() + "/site.db";
  procs.Start("cairn-mapstore", {"--db", db});
  lcm::LCM lcm(procs.url());
  MapstoreClient client(lcm, "sharing-test", TestClientOptions(60.0));
  ASSERT_TRUE(WaitForStore(client));
  ASSERT_EQ(client.Call(PutProfileRequest(ShippedProfile("pioneer3at")))->status, kStatusOk);
  ASSERT_EQ(client.Call(PutProfileRequest(ShippedProfile("rover")))->status, kStatusOk);

  const MapSnapshot s = RampSnapshot();
  ASSERT_EQ(s.obstacles.obstacles.size(), 1u);
  ASSERT_EQ(s.obstacles.obstacles[0].kind, common::ObstacleKind::kRamp);
  auto saved = client.Save(s);
  ASSERT_TRUE(saved.ok() && saved->status == kStatusOk);
  const MapRef ref{"test-site", "ramp", saved->version};

  // The stored base blobs, read from the file by another reader.
  SqliteOptions read_only;
  read_only.read_only = true;
  auto reader = SqliteMapStore::Open(db, read_only);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  const auto blobs_before = (*reader)->BaseBlobBytes(ref);
  ASSERT_TRUE(blobs_before.ok());
  ASSERT_FALSE(blobs_before->empty());

  // Share with both profiles.
  Request share = MakeRequest(Request::OP_SHARE, "test-site", "ramp");
  share.profile = "pioneer3at";
  auto same = client.Call(share);
  ASSERT_TRUE(same.ok());
  ASSERT_EQ(same->status, kStatusOk) << same->message;
  EXPECT_EQ(same->num_obstacles, 0) << "the source profile keeps its own verdicts";
  share.profile = "rover";
  auto rover = client.Call(share);
  ASSERT_TRUE(rover.ok());
  ASSERT_EQ(rover->status, kStatusOk) << rover->message;
  ASSERT_EQ(rover->num_obstacles, 1) << rover->message;
  const auto& changed = rover->obstacles[0];
  EXPECT_EQ(changed.kind, static_cast<int8_t>(common::ObstacleKind::kRamp));
  EXPECT_NEAR(changed.slope_rad, 10.0 * M_PI / 180.0, 0.5 * M_PI / 180.0);
  ASSERT_EQ(changed.num_verdicts, 2);
  EXPECT_EQ(changed.verdicts[0].profile, "pioneer3at");
  EXPECT_FALSE(changed.verdicts[0].crossable);
  EXPECT_FALSE(changed.verdicts[0].reason.empty());
  EXPECT_EQ(changed.verdicts[1].profile, "rover");
  EXPECT_TRUE(changed.verdicts[1].crossable);

  // The cost layers differ on the ramp and agree on the flat ground.
  auto p = client.Load("test-site", "ramp", 0, "pioneer3at", {"cost/pioneer3at"});
  auto r = client.Load("test-site", "ramp", 0, "rover", {"cost/rover"});
  ASSERT_TRUE(p.ok()) << p.status().ToString();
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_NE(p->reply.message.find("cache"), std::string::npos) << p->reply.message;
  const common::Layer& cost_p = p->layers.at("cost/pioneer3at");
  const common::Layer& cost_r = r->layers.at("cost/rover");
  int ramp_cells = 0;
  for (int iy = 5; iy < kSizeY - 5; ++iy) {
    for (int ix = kRampStart + 3; ix < kRampStart + kRampCells - 3; ++ix) {
      ++ramp_cells;
      EXPECT_EQ(cost_p(ix, iy), layers::kCostLethal) << ix << "," << iy;
      EXPECT_TRUE(std::isfinite(cost_r(ix, iy)) && cost_r(ix, iy) < layers::kCostLethal)
          << ix << "," << iy << ": " << cost_r(ix, iy);
    }
    for (int ix = 3; ix < kRampStart - 3; ++ix) {
      EXPECT_EQ(cost_p(ix, iy), layers::kCostFree);
      EXPECT_EQ(cost_r(ix, iy), layers::kCostFree);
    }
  }
  EXPECT_GT(ramp_cells, 400);
  // Each profile's verdict on the stored obstacle.
  Request verdicts = MakeRequest(Request::OP_LOAD_OBSTACLES, "test-site", "ramp");
  verdicts.profile = "pioneer3at";
  auto vp = client.Call(verdicts);
  verdicts.profile = "rover";
  auto vr = client.Call(verdicts);
  ASSERT_EQ(vp->num_obstacles, 1);
  ASSERT_EQ(vr->num_obstacles, 1);
  EXPECT_FALSE(vp->obstacles[0].verdicts[0].crossable);
  EXPECT_TRUE(vr->obstacles[0].verdicts[0].crossable);

  // The base blobs did not change by a single byte, and the base still loads as saved.
  const auto blobs_after = (*reader)->BaseBlobBytes(ref);
  ASSERT_TRUE(blobs_after.ok());
  EXPECT_TRUE(*blobs_after == *blobs_before);
  auto base = client.Load("test-site", "ramp", 0, "", {"elevation"});
  ASSERT_TRUE(base.ok());
  EXPECT_TRUE(SameLayer(base->layers.at("elevation"), s.base.at("elevation")));
  EXPECT_EQ((*reader)->ListDerived(ref)->size(), 2u);

  // A rover limited to 9 degrees is another profile content: not the cached layers, and the
  // ramp is lethal for it.
  common::RobotProfile cautious = ShippedProfile("rover");
  cautious.max_slope_up_rad = 9.0 * M_PI / 180.0;
  ASSERT_EQ(client.Call(PutProfileRequest(cautious))->status, kStatusOk);
  auto c = client.Load("test-site", "ramp", 0, "rover", {"cost/rover"});
  ASSERT_TRUE(c.ok());
  EXPECT_NE(c->reply.message.find("derived now"), std::string::npos) << c->reply.message;
  EXPECT_EQ(c->layers.at("cost/rover")(kRampStart + 15, kSizeY / 2), layers::kCostLethal);
}

}  // namespace
}  // namespace cairn::mapstore::testing
