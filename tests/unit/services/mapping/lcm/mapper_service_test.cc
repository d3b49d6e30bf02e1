// The service layer of the mapper over memq:// (no network): the tile publisher's wire
// semantics against runtime::LayerAssembler, the pose buffer, and MapperService end to end.

#include "services/mapping/lcm/mapper_service.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include <gtest/gtest.h>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_mapstore_reply.hpp"
#include "cairn/lcmt_mapstore_request.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"

#include "common/channels.h"
#include "common/layers.h"
#include "services/mapping/pose_buffer.h"
#include "services/mapping/lcm/terrain_publisher.h"
#include "services/runtime/conversions.h"
#include "services/runtime/revolution_assembler.h"
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

common::Pose3 At(double x, double y, double yaw = 0.0) { return SensorAt(x, y, 0.0, yaw); }

TEST(PoseBufferTest, InterpolatesWithinTheGapOnly) {
  PoseBuffer buffer;
  EXPECT_FALSE(buffer.At(0, 1.0).has_value());
  ASSERT_TRUE(buffer.Add(1'000'000, At(0.0, 0.0, 0.0)));
  ASSERT_TRUE(buffer.Add(1'200'000, At(2.0, 0.0, 0.4)));
  const auto mid = buffer.At(1'050'000, 0.2);
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR(mid->position_m.x(), 0.5, 1e-9);
  EXPECT_NEAR(mid->yaw_rad(), 0.1, 1e-9);
  // Outside both samples but near one: that sample.
  EXPECT_NEAR(buffer.At(1'250'000, 0.1)->position_m.x(), 2.0, 1e-12);
  // Between samples farther apart than the gap: the nearer one if it is close enough.
  EXPECT_NEAR(buffer.At(1'090'000, 0.1)->position_m.x(), 0.0, 1e-12);
  EXPECT_FALSE(buffer.At(2'000'000, 0.1).has_value());
  // Out of order, and a non-finite pose refused.
  ASSERT_TRUE(buffer.Add(1'100'000, At(1.0, 1.0)));
  EXPECT_NEAR(buffer.At(1'100'000, 0.01)->position_m.y(), 1.0, 1e-12);
  common::Pose3 bad = At(0, 0);
  bad.position_m.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(buffer.Add(1'300'000, bad));
  EXPECT_EQ(buffer.size(), 3u);
}

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
// MapperService over memq: slices and poses in, tiles, manifests and the registry out.
TEST(MapperServiceTest, MapsSlicesOverMemq) {
  runtime::NodeOptions options;
  options.process_name = "cairn-mapper";
  options.robot = "r1";
  options.lcm_url = "memq://";
  options.install_signal_handlers = false;
  options.follow_sim_clock = false;
  runtime::Node node(options);
  MapperParams params;
  params.robot = "r1";
  params.publish_period_s = 0.05;
  params.registry_period_s = 0.05;
  params.core.octomap_enabled = false;
  params.core.occupancy.resolution_m = 0.1;
  std::map<std::string, int> received;
  std::optional<cairn::lcmt_obstacle_registry> registry;
  node.SubscribeRaw("r1\\.MAP\\..*",
                    [&](const std::string& channel, const void* data, int size, int64_t) {
                      ++received[channel];
                      if (channel == "r1.MAP.OBSTACLES") {
                        cairn::lcmt_obstacle_registry r;
                        if (r.decode(data, 0, size) >= 0) registry = r;
                      }
                    });
  MapperService service(node, params, {ShippedProfile("pioneer3at")},
                        [](const std::string& name) -> common::Result<common::RobotProfile> {
                          return common::NotFoundError("no profile " + name);
                        });
  // A 20 cm block ahead of the sensor.
  auto ground = [](double x, double) { return (x > 3.0 && x < 4.0) ? 0.2 : 0.0; };
  SyntheticLidar lidar;
  lidar.rings = 12;
  lidar.azimuths = 360;
  lidar.max_range_m = 10.0;
  for (int k = 0; k < 3; ++k) {
    const int64_t utime = 1'000'000 + k * 100'000;
    common::LidarSlice slice = SyntheticRevolution(SensorAt(1.0, 0.0, 0.5), ground, lidar, k);
    slice.utime = utime;
    slice.robot = "r1";
    node.Publish("r1.POSE", runtime::ToLcmPose(SensorAt(1.0, 0.0, 0.0), utime, "r1", "world"));
    for (const auto& part : runtime::SplitSlice(slice, 60000)) {
      node.Publish("r1.LIDAR", runtime::ToLcm(part));
    }
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline &&
         !(service.revolutions() == 3 && received["r1.MAP.TILES"] > 0 && registry &&
           !registry->obstacles.empty())) {
    node.SpinOnce(20);
  }
  service.Stop();
  EXPECT_EQ(service.revolutions(), 3);
  EXPECT_GT(received["r1.MAP.TILES"], 0);
  EXPECT_GT(received["r1.MAP.MANIFEST"], 0);
  ASSERT_TRUE(registry.has_value());
  auto step =
      std::find_if(registry->obstacles.begin(), registry->obstacles.end(), [](const auto& o) {
        return o.kind == cairn::lcmt_obstacle::KIND_STEP_UP &&
               std::fabs(o.centroid_m[0] - 3.0) < 0.3;
      });
  ASSERT_NE(step, registry->obstacles.end());
  EXPECT_NEAR(step->height_m, 0.2, 0.03);
  ASSERT_EQ(step->num_verdicts, 1);
  EXPECT_FALSE(step->verdicts[0].crossable);
  EXPECT_EQ(node.counter("bad_points"), 0);
}

// The dynamic layers on a 4 x 3 m extent, with a remembered long-term layer.
MapperParams DynamicParams() {
  MapperParams params;
  params.robot = "r1";
  params.occupancy_period_s = 0.05;
  params.core.occupancy_enabled = false;
  params.core.octomap_enabled = false;
  params.core.dynamic_enabled = true;
  params.core.dynamic_extent.resolution_m = 0.05;
  params.core.dynamic_extent.size_x = 80;
  params.core.dynamic_extent.size_y = 60;
  params.core.dynamic_extent.origin = {-1.0, -1.0, 0.0};
  return params;
}

TEST(MapperCoreTest, RestoresTheLongTermLayerOnlyOnTheSameGrid) {
  MapperCoreParams params = DynamicParams().core;
  common::GridMap stored(params.dynamic_extent);
  stored.AddLayer(layers::kLongTerm, 0.f)(10, 20) = 98.f;
  params.long_term_restore = stored;
  MapperCore restored(params);
  EXPECT_TRUE(restored.long_term_restore_status().ok());
  EXPECT_EQ(restored.dynamic()->LongTermOccupancy({10, 20}), 98);
  // OP_RESET forgets the memory too: back to the static map alone.
  restored.Reset();
  EXPECT_EQ(restored.dynamic()->LongTermOccupancy({10, 20}), -1);

  common::GridGeometry other = params.dynamic_extent;
  other.size_x += 1;
  common::GridMap elsewhere(other);
  elsewhere.AddLayer(layers::kLongTerm, 0.f);
  params.long_term_restore = elsewhere;
  MapperCore ignored(params);
  EXPECT_EQ(ignored.long_term_restore_status().code(), common::StatusCode::kInvalidArgument);
  EXPECT_NE(ignored.long_term_restore_status().message().find("another grid"), std::string::npos);
  EXPECT_EQ(ignored.dynamic()->LongTermOccupancy({10, 20}), -1);
}

TEST(MapperServiceTest, PublishesTheRestoredLongTermLayerAndAsksTheStoreToSaveIt) {
  runtime::NodeOptions options;
  options.process_name = "cairn-mapper";
  options.robot = "r1";
  options.lcm_url = "memq://";
  options.install_signal_handlers = false;
  options.follow_sim_clock = false;
  runtime::Node node(options);
  MapperParams params = DynamicParams();
  common::GridMap stored(params.core.dynamic_extent);
  stored.AddLayer(layers::kLongTerm, 0.f)(10, 20) = 98.f;
  params.core.long_term_restore = stored;
  params.long_term_store = "flat/long_term";
  params.long_term_save_period_s = 0.05;
  runtime::LayerAssembler assembler;
  std::vector<cairn::lcmt_mapstore_request> requests;
  node.Subscribe<cairn::lcmt_occupancy_tile>(
      "r1.MAP.OCCUPANCY", [&](const cairn::lcmt_occupancy_tile& t) { assembler.OnTile(t); });
  node.Subscribe<cairn::lcmt_grid_manifest>(
      "r1.MAP.MANIFEST", [&](const cairn::lcmt_grid_manifest& m) { assembler.OnManifest(m); });
  node.Subscribe<cairn::lcmt_mapstore_request>(
      "MAPSTORE.REQUEST", [&](const cairn::lcmt_mapstore_request& r) { requests.push_back(r); });
  MapperService service(node, params, {ShippedProfile("kobuki")},
                        [](const std::string& name) -> common::Result<common::RobotProfile> {
                          return common::NotFoundError("no profile " + name);
                        });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline &&
         !(assembler.Complete(layers::kLongTerm) && !requests.empty())) {
    node.SpinOnce(20);
  }
  // The first long-term layer on the bus is the restored one (nothing was scanned).
  ASSERT_TRUE(assembler.Complete(layers::kLongTerm));
  const auto layer = assembler.Layer(layers::kLongTerm);
  ASSERT_TRUE(layer.has_value());
  EXPECT_FLOAT_EQ(layer->at(layers::kLongTerm)(10, 20), 98.f);
  EXPECT_FLOAT_EQ(layer->at(layers::kLongTerm)(11, 20), 0.f);
  // A pull save of the long-term layer alone, naming this robot.
  ASSERT_FALSE(requests.empty());
  const cairn::lcmt_mapstore_request& save = requests.front();
  constexpr int kOpSave = cairn::lcmt_mapstore_request::OP_SAVE;  // no odr-use in EXPECT_EQ
  EXPECT_EQ(save.op, kOpSave);
  EXPECT_EQ(save.site, "flat");
  EXPECT_EQ(save.map_name, "long_term");
  EXPECT_EQ(save.robot, "r1");
  ASSERT_EQ(save.num_layers, 1);
  EXPECT_EQ(save.layers[0], layers::kLongTerm);
  // The store's answers are counted; someone else's reply is not.
  cairn::lcmt_mapstore_reply reply{};
  reply.request_id = save.request_id;
  reply.op = save.op;
  reply.status = cairn::lcmt_mapstore_reply::STATUS_OK;
  node.Publish("MAPSTORE.REPLY", reply);
  reply.request_id = 7;  // not one of the mapper's
  node.Publish("MAPSTORE.REPLY", reply);
  for (int i = 0; i < 10; ++i) node.SpinOnce(10);
  service.Stop();
  EXPECT_EQ(node.counter("long_term_saves"), 1);
  EXPECT_GE(node.counter("long_term_save_requests"), 1);
}

TEST(MapperServiceTest, RefusesABadLongTermStore) {
  MapperParams params = DynamicParams();
  params.long_term_store = "no-slash";
  EXPECT_THROW(params.Validate(), std::invalid_argument);
  params.long_term_store = "a/b/c";
  EXPECT_THROW(params.Validate(), std::invalid_argument);
  params.long_term_store = "site/map";
  params.Validate();
  params.core.dynamic_enabled = false;
  EXPECT_THROW(params.Validate(), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::mapping
