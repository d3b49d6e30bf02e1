// TerrainPublisher: the terrain layers' wire semantics against runtime::LayerAssembler (only
// changed tiles, growth, resend, reset, a successor's larger version base).

#include "services/mapping/lcm/terrain_publisher.h"

#include <cmath>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "services/runtime/layer_assembler.h"
#include "services/runtime/tiler.h"
#include "tests/unit/services/mapping/synthetic_scan.h"
#include "tests/unit/services/mapping/terrain_fixtures.h"

namespace cairn::mapping {
namespace {

using testing::SensorAt;
using testing::ShippedProfile;
using testing::SyntheticLidar;
using testing::SyntheticRevolution;

// A terrain map with some flat ground observed around (x, y).
void Observe(TerrainMap* map, double x, double y, int64_t scan) {
  SyntheticLidar lidar;
  lidar.rings = 8;
  lidar.azimuths = 180;
  lidar.max_range_m = 8.0;
  const common::LidarSlice s = SyntheticRevolution(
      SensorAt(x, y, 0.5), [](double, double) { return 0.0; }, lidar, scan);
  map->Integrate(s.points, s.sensor_pose, scan, scan * 0.1);
  map->UpdateDerived({});
}

// What a receiver rebuilds from the publisher's tiles and manifests equals the map's export.
TEST(TerrainPublisherTest, ReceiverRebuildsTheLayersAndOnlyChangesAreSent) {
  TerrainMap map;
  map.AddProfile(ShippedProfile("rover"));
  Observe(&map, 1.0, 1.0, 0);
  TerrainPublisher publisher("r1", "live");
  const std::vector<std::string> names{layers::kElevation, layers::CostLayer("rover")};
  auto first = publisher.Update(map, names, 10);
  EXPECT_TRUE(first.geometry_changed);
  ASSERT_EQ(first.manifests.size(), 2u);
  EXPECT_GT(first.tiles.size(), 0u);

  runtime::LayerAssembler receiver;
  for (const auto& t : first.tiles) ASSERT_TRUE(receiver.OnTile(t));
  for (const auto& m : first.manifests) receiver.OnManifest(m);
  for (const auto& name : names) {
    ASSERT_TRUE(receiver.Complete(name)) << name;
    const common::GridMap got = *receiver.Layer(name);
    const common::GridMap expected = map.Export({name}, got.geometry());
    const common::Layer& a = got.at(name);
    const common::Layer& b = expected.at(name);
    for (int64_t i = 0; i < a.size(); ++i) {
      ASSERT_TRUE((std::isnan(a.data()[i]) && std::isnan(b.data()[i])) ||
                  a.data()[i] == b.data()[i])
          << name << " cell " << i;
    }
  }
  // Nothing changed: nothing sent.
  auto idle = publisher.Update(map, names, 20);
  EXPECT_TRUE(idle.tiles.empty());
  EXPECT_TRUE(idle.manifests.empty());
  // The same ground seen again changes next to nothing; new ground elsewhere in the same tiles
  // sends only those tiles, with a new layer version.
  Observe(&map, 3.0, 1.0, 1);
  auto second = publisher.Update(map, names, 30);
  EXPECT_FALSE(second.geometry_changed);
  EXPECT_LE(second.tiles.size(), first.tiles.size());
  for (const auto& m : second.manifests) EXPECT_GT(m.layer_version, 1);
  // Growing past the published extent resends everything (receivers reset on new geometry).
  Observe(&map, 100.0, 1.0, 2);
  auto grown = publisher.Update(map, names, 40);
  EXPECT_TRUE(grown.geometry_changed);
  EXPECT_GT(grown.tiles.size(), first.tiles.size());
  // A resend of everything, and of one named tile.
  cairn::lcmt_tile_resend_request all{};
  all.layer = layers::kElevation;
  const auto resent = publisher.Resend(all);
  EXPECT_FALSE(resent.tiles.empty());
  cairn::lcmt_tile_resend_request one{};
  one.layer = layers::kElevation;
  one.num_tiles = 1;
  one.tile_ix = {resent.tiles[0].tile_ix};
  one.tile_iy = {resent.tiles[0].tile_iy};
  EXPECT_EQ(publisher.Resend(one).tiles.size(), 1u);
  cairn::lcmt_tile_resend_request unknown{};
  unknown.layer = "no_such_layer";
  EXPECT_TRUE(publisher.Resend(unknown).tiles.empty());
  // A reset announces empty layers with newer versions.
  const auto reset = publisher.Reset(50);
  ASSERT_EQ(reset.manifests.size(), 2u);
  for (const auto& m : reset.manifests) {
    EXPECT_EQ(m.num_tiles, 0);
    EXPECT_GT(m.layer_version, grown.manifests[0].layer_version - 1);
  }
}

// A restarted mapper (a new publisher with a larger version base) mapping the same ground into
// the same grid replaces what a receiver holds from its predecessor, tile by tile; without the
// base its first versions would be older and ignored.
TEST(TerrainPublisherTest, ASuccessorWithALargerVersionBaseSupersedesItsPredecessor) {
  const std::vector<std::string> names{layers::kElevation};
  TerrainMap before;
  Observe(&before, 1.0, 1.0, 0);
  Observe(&before, 3.0, 1.0, 1);  // several versions on the predecessor's side
  TerrainPublisher predecessor("r1", "live", 4, /*version_base=*/1000);
  runtime::LayerAssembler receiver;
  for (int64_t scan = 0; scan < 3; ++scan) {
    Observe(&before, 1.0 + scan, 2.0, 2 + scan);
    auto batch = predecessor.Update(before, names, 10 + scan);
    for (const auto& t : batch.tiles) ASSERT_TRUE(receiver.OnTile(t));
    for (const auto& m : batch.manifests) receiver.OnManifest(m);
  }
  const int64_t held = receiver.version(layers::kElevation);
  ASSERT_GT(held, 1000);

  TerrainMap after;  // the successor starts from nothing and sees the same first ground
  Observe(&after, 1.0, 1.0, 0);
  TerrainPublisher successor("r1", "live", 4, /*version_base=*/2000);
  auto first = successor.Update(after, names, 100);
  ASSERT_EQ(first.manifests.size(), 1u);
  EXPECT_GT(first.manifests[0].layer_version, held);
  for (const auto& t : first.tiles) ASSERT_TRUE(receiver.OnTile(t));
  for (const auto& m : first.manifests) receiver.OnManifest(m);
  EXPECT_EQ(receiver.version(layers::kElevation), first.manifests[0].layer_version);
  ASSERT_TRUE(receiver.Complete(layers::kElevation));
  const common::GridMap got = *receiver.Layer(layers::kElevation);
  const common::GridMap expected = after.Export({layers::kElevation}, got.geometry());
  const common::Layer& a = got.at(layers::kElevation);
  const common::Layer& b = expected.at(layers::kElevation);
  for (int64_t i = 0; i < a.size(); ++i) {
    ASSERT_TRUE((std::isnan(a.data()[i]) && std::isnan(b.data()[i])) || a.data()[i] == b.data()[i])
        << "cell " << i;
  }
}

}  // namespace
}  // namespace cairn::mapping
