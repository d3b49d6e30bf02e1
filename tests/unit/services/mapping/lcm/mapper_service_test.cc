// MapperService over memq:// (no network): slices and poses in, tiles, manifests, the registry
// and the dynamic layers out; the long-term store's saves; a layer added through the seam is
// published without the service knowing it.

#include "services/mapping/lcm/mapper_service.h"

#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_map_control_reply.hpp"
#include "cairn/lcmt_map_control_request.hpp"
#include "cairn/lcmt_mapstore_reply.hpp"
#include "cairn/lcmt_mapstore_request.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/channels.h"
#include "common/layers.h"
#include "services/runtime/conversions.h"
#include "services/runtime/layer_assembler.h"
#include "services/runtime/revolution_assembler.h"
#include "services/runtime/tiler.h"
#include "tests/support/memq_node.h"
#include "tests/unit/services/mapping/synthetic_scan.h"
#include "tests/unit/services/mapping/terrain_fixtures.h"

namespace cairn::mapping {
namespace {

using cairn::lcmt_map_control_reply;
using cairn::lcmt_map_control_request;
using testing::SensorAt;
using testing::ShippedProfile;
using testing::SyntheticLidar;
using testing::SyntheticRevolution;

// The mapper's node on memq:// (no network, no signal handlers, no simulator clock).
runtime::NodeOptions MemqOptions() { return cairn::testing::MemqNodeOptions("cairn-mapper", "r1"); }

// Publishes revolution k of `lidar` over `ground`, seen from (1, 0, 0.5), with its pose, as r1.
template <typename Ground>
void PublishRevolution(runtime::Node& node, const SyntheticLidar& lidar, Ground ground, int k,
                       int64_t utime) {
  common::LidarSlice slice = SyntheticRevolution(SensorAt(1.0, 0.0, 0.5), ground, lidar, k);
  slice.utime = utime;
  slice.robot = "r1";
  node.Publish("r1.POSE", runtime::ToLcmPose(SensorAt(1.0, 0.0, 0.0), utime, "r1", "world"));
  for (const auto& part : runtime::SplitSlice(slice, 60000)) {
    node.Publish("r1.LIDAR", runtime::ToLcm(part));
  }
}

// The profile resolver of a mapper with no profiles folder: every name is unknown.
common::Result<common::RobotProfile> NoProfileFolder(const std::string& name) {
  return common::NotFoundError("no profile " + name);
}

// Robot r1 with the terrain layer only (no OctoMap, no occupancy), publishing every period_s.
MapperParams TerrainOnly(double period_s) {
  MapperParams params;
  params.robot = "r1";
  params.core.terrain.publish_period_s = period_s;
  params.core.SetListed(kOctomapLayerName, false);
  params.core.SetListed(kOccupancyLayerName, false);
  return params;
}

// Spins `node` until `done` or `bound_s` wall seconds; returns done().
bool SpinUntil(runtime::Node& node, const std::function<bool()>& done, double bound_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(bound_s);
  while (!done() && std::chrono::steady_clock::now() < deadline) node.SpinOnce(5);
  return done();
}

// MapperService over memq: slices and poses in, tiles, manifests and the registry out.
TEST(MapperServiceTest, MapsSlicesOverMemq) {
  runtime::Node node(MemqOptions());
  MapperParams params;
  params.robot = "r1";
  params.core.terrain.publish_period_s = 0.05;
  params.core.terrain.registry_period_s = 0.05;
  params.core.SetListed(kOctomapLayerName, false);
  params.core.occupancy.grid.resolution_m = 0.1;
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
                        NoProfileFolder);
  // A 20 cm block ahead of the sensor.
  auto ground = [](double x, double) { return (x > 3.0 && x < 4.0) ? 0.2 : 0.0; };
  SyntheticLidar lidar;
  lidar.rings = 12;
  lidar.azimuths = 360;
  lidar.max_range_m = 10.0;
  for (int k = 0; k < 3; ++k) PublishRevolution(node, lidar, ground, k, 1'000'000 + k * 100'000);
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

// Issue 20 (found by the bus-fault test): a mapper starved of lidar (fragments lost on a lossy
// link) kept announcing its cost layer as current every period, so the navigator's stale-map
// stop never fired and the robot drove on a map frozen since its first seconds. The fast
// layers' manifests now stop once no revolution has been integrated for
// max_announce_without_data_s, and resume with the next one; a forced publication (a pull
// save's OP_PUBLISH_ALL) still goes out.
TEST(MapperServiceTest, ACostLayerIsAnnouncedAsCurrentOnlyWhileRevolutionsComeIn) {
  runtime::Node node(MemqOptions());
  MapperParams params = TerrainOnly(0.02);
  params.core.terrain.max_announce_without_data_s = 0.2;
  const std::string cost = layers::CostLayer("pioneer3at");
  int cost_manifests = 0;
  node.Subscribe<cairn::lcmt_grid_manifest>("r1.MAP.MANIFEST",
                                            [&](const cairn::lcmt_grid_manifest& m) {
                                              if (m.layer == cost) ++cost_manifests;
                                            });
  MapperService service(node, params, {ShippedProfile("pioneer3at")},
                        NoProfileFolder);
  SyntheticLidar lidar;
  lidar.rings = 8;
  lidar.azimuths = 180;
  lidar.max_range_m = 8.0;
  auto flat = [](double, double) { return 0.0; };
  int sent = 0;
  auto send_revolution = [&] {
    PublishRevolution(node, lidar, flat, sent, 1'000'000 + sent * 100'000);
    ++sent;
  };
  auto spin_until = [&](const std::function<bool()>& done, double bound_s) {
    return SpinUntil(node, done, bound_s);
  };
  auto spin_for = [&](double s) { SpinUntil(node, [] { return false; }, s); };
  // Revolutions coming in: announced every period.
  for (int i = 0; i < 3; ++i) send_revolution();
  ASSERT_TRUE(spin_until([&] { return service.revolutions() == 3 && cost_manifests >= 3; }, 20.0));
  // The lidar goes quiet: within 0.2 s (and a period) the announcements stop...
  spin_for(0.4);
  const int when_quiet = cost_manifests;
  spin_for(0.5);
  EXPECT_EQ(cost_manifests, when_quiet) << "a starved mapper still says its layer is current";
  // ...a forced publication still goes out...
  lcmt_map_control_request publish_all{};
  publish_all.request_id = 7;
  publish_all.requester = "store";
  publish_all.op = lcmt_map_control_request::OP_PUBLISH_ALL;
  node.Publish("r1.MAP.CONTROL", publish_all);
  EXPECT_TRUE(spin_until([&] { return cost_manifests > when_quiet; }, 10.0));
  // ...and the next revolution brings them back.
  const int before = cost_manifests;
  send_revolution();
  EXPECT_TRUE(spin_until([&] { return cost_manifests >= before + 3; }, 10.0));
  service.Stop();
}

// Issue 20 (found by the bus-fault test): the registry is one message, lost whole on a lossy
// link, and could not be asked for again. A resend request for "#obstacles" publishes it again
// (and counts as one tile against the resend rate).
TEST(MapperServiceTest, AResendRequestForObstaclesPublishesTheRegistryAgain) {
  runtime::Node node(MemqOptions());
  MapperParams params = TerrainOnly(0.02);
  params.core.terrain.registry_period_s = 0.02;
  int registries = 0;
  node.Subscribe<cairn::lcmt_obstacle_registry>(
      "r1.MAP.OBSTACLES", [&](const cairn::lcmt_obstacle_registry&) { ++registries; });
  MapperService service(node, params, {ShippedProfile("pioneer3at")},
                        NoProfileFolder);
  SyntheticLidar lidar;
  lidar.rings = 8;
  lidar.azimuths = 180;
  lidar.max_range_m = 8.0;
  PublishRevolution(node, lidar, [](double, double) { return 0.0; }, 0, 1'000'000);
  auto spin_until = [&](const std::function<bool()>& done, double bound_s) {
    return SpinUntil(node, done, bound_s);
  };
  ASSERT_TRUE(spin_until([&] { return registries >= 1; }, 20.0));
  // Unchanged: not published again on its own.
  spin_until([] { return false; }, 0.3);
  const int before = registries;
  for (int i = 0; i < 20; ++i) {  // far beyond a whole layer's budget, were it counted as one
    cairn::lcmt_tile_resend_request ask{};
    ask.requester = "store";
    ask.robot = "r1";
    ask.map_name = params.map_name;
    ask.layer = layers::kResendObstacles;
    node.Publish("r1.MAP.TILE_RESEND", ask);
  }
  EXPECT_TRUE(spin_until([&] { return registries >= before + 20; }, 10.0))
      << registries - before << " of 20 asked for";
  EXPECT_EQ(node.counter("resend_rate_limited"), 0);
  service.Stop();
}

// Issue 20 (found by the bus-fault test): a pull save naming no layers took what was announced
// within pull_settle_s, so a manifest lost on the link left its layer out. The reply to
// OP_PUBLISH_ALL now lists every layer whose manifest the publication sent; a replay of the
// request id gets the same list from the reply cache, without a second publication.
TEST(MapperServiceTest, TheReplyToPublishAllListsTheLayersPublished) {
  runtime::Node node(MemqOptions());
  // No publication on its own during the test: only the forced one.
  MapperParams params = TerrainOnly(100.0);
  params.core.terrain.slow_publish_period_s = 100.0;
  params.core.terrain.registry_period_s = 100.0;
  std::vector<std::string> manifests;
  node.Subscribe<cairn::lcmt_grid_manifest>(
      "r1.MAP.MANIFEST", [&](const cairn::lcmt_grid_manifest& m) { manifests.push_back(m.layer); });
  std::vector<lcmt_map_control_reply> replies;
  node.Subscribe<lcmt_map_control_reply>(
      "r1.MAP.CONTROL_REPLY", [&](const lcmt_map_control_reply& r) { replies.push_back(r); });
  MapperService service(node, params, {ShippedProfile("pioneer3at")},
                        NoProfileFolder);
  SyntheticLidar lidar;
  lidar.rings = 8;
  lidar.azimuths = 180;
  lidar.max_range_m = 8.0;
  common::LidarSlice slice = SyntheticRevolution(
      SensorAt(1.0, 0.0, 0.5), [](double, double) { return 0.0; }, lidar, 0);
  slice.utime = 1'000'000;
  slice.robot = "r1";
  node.Publish("r1.POSE", runtime::ToLcmPose(SensorAt(1.0, 0.0, 0.0), slice.utime, "r1", "world"));
  for (const auto& part : runtime::SplitSlice(slice, 60000)) {
    node.Publish("r1.LIDAR", runtime::ToLcm(part));
  }
  auto spin_until = [&](const std::function<bool()>& done, double bound_s) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(bound_s);
    while (!done() && std::chrono::steady_clock::now() < deadline) node.SpinOnce(5);
    return done();
  };
  ASSERT_TRUE(spin_until([&] { return service.revolutions() == 1; }, 20.0));
  manifests.clear();
  lcmt_map_control_request publish_all{};
  publish_all.request_id = 9;
  publish_all.requester = "store";
  publish_all.op = lcmt_map_control_request::OP_PUBLISH_ALL;
  node.Publish("r1.MAP.CONTROL", publish_all);
  ASSERT_TRUE(spin_until([&] { return replies.size() == 1; }, 10.0));
  const lcmt_map_control_reply& reply = replies[0];
  EXPECT_EQ(reply.request_id, 9);
  EXPECT_EQ(reply.status, +lcmt_map_control_reply::STATUS_OK) << reply.message;
  ASSERT_EQ(reply.num_layers, static_cast<int32_t>(reply.layers.size()));
  // Every layer the publication announced, and only those.
  std::set<std::string> announced(manifests.begin(), manifests.end());
  EXPECT_EQ(std::set<std::string>(reply.layers.begin(), reply.layers.end()), announced);
  EXPECT_EQ(announced.size(), reply.layers.size());  // each listed once
  for (const std::string& layer :
       {std::string(layers::kElevation), std::string(layers::kElevationVariance),
        std::string(layers::kObservationCount), layers::CostLayer("pioneer3at")}) {
    EXPECT_TRUE(announced.count(layer)) << layer << " not listed";
  }
  // A replay: the same list, nothing published again.
  const size_t published = manifests.size();
  node.Publish("r1.MAP.CONTROL", publish_all);
  ASSERT_TRUE(spin_until([&] { return replies.size() == 2; }, 10.0));
  EXPECT_EQ(replies[1].layers, replies[0].layers);
  spin_until([] { return false; }, 0.2);
  EXPECT_EQ(manifests.size(), published) << "a replayed request published everything again";
  // Another op lists nothing.
  lcmt_map_control_request clear{};
  clear.request_id = 10;
  clear.requester = "store";
  clear.op = lcmt_map_control_request::OP_CLEAR_SHORT_TERM;
  node.Publish("r1.MAP.CONTROL", clear);
  ASSERT_TRUE(spin_until([&] { return replies.size() == 3; }, 10.0));
  EXPECT_EQ(replies[2].num_layers, 0);
  service.Stop();
}

// A reading of a stream the mapper has no fixed input for: here made from lcmt_pose messages
// on r1.TEST_MARK (its x is what the layer keeps).
struct MarkReading : SensorReading {
  double x_m{0.0};
};

StreamConverter MarkConverter() {
  StreamConverter c;
  c.stream = "TEST_MARK";
  c.convert = [](const void* data, int size) -> common::Result<std::unique_ptr<SensorReading>> {
    cairn::lcmt_pose m;
    if (m.decode(data, 0, size) < 0) return common::InvalidArgumentError("does not decode");
    auto pose = runtime::FromLcm(m);
    if (!pose.ok()) return pose.status();
    auto reading = std::make_unique<MarkReading>();
    reading->utime = m.utime;
    reading->sensor_pose = *pose;
    reading->x_m = m.position_m[0];
    return std::unique_ptr<SensorReading>(std::move(reading));
  };
  return c;
}

// A layer the service has never heard of, added through the seam: it counts the scans and keeps
// the last mark in a float grid and an occupancy grid, and the service publishes both
// generically.
class ScanCountLayer : public MapperLayer {
 public:
  ScanCountLayer() {
    common::GridGeometry g;
    g.resolution_m = 0.5;
    g.size_x = g.size_y = 4;
    grid_ = common::GridMap(g);
    grid_.AddLayer("test/scans", 0.f);
    grid_.AddLayer("test/seen", NAN);
  }
  const std::string& name() const override { return name_; }
  uint32_t inputs() const override { return kPlanarScans | kSensorReadings; }
  LayerSchedule schedule() const override {
    LayerSchedule s;
    s.publish_period_s = 0.05;
    return s;
  }
  std::vector<std::string> OwnedLayers() const override { return {"test/scans", "test/seen"}; }
  void OnScan(const common::LaserScan&) override {
    grid_.at("test/scans")(1, 1) += 1.f;
    grid_.at("test/seen")(2, 2) = 100.f;
    ++version_;
  }
  std::vector<std::string> ReadingStreams() const override { return {"TEST_MARK"}; }
  void OnReading(const SensorReading& reading) override {
    grid_.at("test/scans")(3, 3) =
        static_cast<float>(dynamic_cast<const MarkReading&>(reading).x_m);
    ++version_;
  }
  void Reset() override {}
  std::vector<GridOutput> GridOutputs() const override {
    return {{"test/scans", GridEncoding::kFloat, true, true},
            {"test/seen", GridEncoding::kOccupancy, true, true}};
  }
  std::optional<common::GridMap> ExportGrids() const override { return grid_; }
  int64_t version() const override { return version_; }

 private:
  std::string name_ = "scan_count";
  common::GridMap grid_;
  int64_t version_{0};
};

TEST(MapperServiceTest, PublishesALayerAddedThroughTheSeam) {
  runtime::Node node(MemqOptions());
  MapperParams params;
  params.robot = "r1";
  params.core.layers = {kTerrainLayerName};
  runtime::LayerAssembler assembler;
  node.Subscribe<cairn::lcmt_grid_tile>(
      "r1.MAP.TILES", [&](const cairn::lcmt_grid_tile& t) { assembler.OnTile(t); });
  node.Subscribe<cairn::lcmt_occupancy_tile>(
      "r1.MAP.OCCUPANCY", [&](const cairn::lcmt_occupancy_tile& t) { assembler.OnTile(t); });
  node.Subscribe<cairn::lcmt_grid_manifest>(
      "r1.MAP.MANIFEST", [&](const cairn::lcmt_grid_manifest& m) { assembler.OnManifest(m); });
  // A layer taking a stream without a converter is refused.
  {
    std::vector<std::unique_ptr<MapperLayer>> extra;
    extra.push_back(std::make_unique<ScanCountLayer>());
    EXPECT_THROW(
        MapperService(node, params, {}, nullptr, MapperService::Mode::kReplay, std::move(extra)),
        std::invalid_argument);
  }
  std::vector<std::unique_ptr<MapperLayer>> extra;
  extra.push_back(std::make_unique<ScanCountLayer>());
  MapperService service(node, params, {}, nullptr, MapperService::Mode::kLive, std::move(extra),
                        {MarkConverter()});
  common::LaserScan scan;
  scan.range_min_m = 0.1;
  scan.range_max_m = 5.0;
  scan.angle_increment_rad = 0.1;
  scan.ranges_m.assign(5, 1.0f);
  scan.robot = "r1";
  for (int k = 0; k < 3; ++k) {
    scan.utime = 1'000'000 + k * 100'000;
    node.Publish("r1.POSE", runtime::ToLcmPose(SensorAt(0.0, 0.0, 0.0), scan.utime, "r1", "world"));
    node.Publish("r1.SCAN", runtime::ToLcm(scan));
  }
  node.Publish("r1.TEST_MARK", runtime::ToLcmPose(SensorAt(1.5, 0.0, 0.0), 1'200'000, "r1", "w"));
  const std::string garbage = "not a pose";
  node.lcm().publish("r1.TEST_MARK", garbage.data(), static_cast<unsigned>(garbage.size()));
  auto cell = [&](const char* layer, int x, int y) -> float {
    auto grid = assembler.Layer(layer);
    return grid ? grid->at(layer)(x, y) : NAN;
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline &&
         !(cell("test/scans", 1, 1) == 3.f && cell("test/scans", 3, 3) == 1.5f &&
           assembler.Complete("test/seen"))) {
    node.SpinOnce(20);
  }
  service.Stop();
  EXPECT_EQ(cell("test/scans", 1, 1), 3.f);
  EXPECT_EQ(cell("test/scans", 3, 3), 1.5f);  // the reading came through its stream
  EXPECT_EQ(node.counter("bad_test_mark"), 1);
  ASSERT_TRUE(assembler.Complete("test/seen"));
  EXPECT_FLOAT_EQ(cell("test/seen", 2, 2), 100.f);
  EXPECT_TRUE(std::isnan(cell("test/seen", 0, 0)));
}

// The dynamic layers on a 4 x 3 m extent, with a remembered long-term layer.
MapperParams DynamicParams() {
  MapperParams params;
  params.robot = "r1";
  params.core.occupancy.publish_period_s = params.core.dynamic.publish_period_s = 0.05;
  params.core.layers = {kTerrainLayerName, kDynamicLayerName};
  params.core.dynamic.extent.resolution_m = 0.05;
  params.core.dynamic.extent.size_x = 80;
  params.core.dynamic.extent.size_y = 60;
  params.core.dynamic.extent.origin = {-1.0, -1.0, 0.0};
  return params;
}

TEST(MapperServiceTest, PublishesTheRestoredLongTermLayerAndAsksTheStoreToSaveIt) {
  runtime::Node node(MemqOptions());
  MapperParams params = DynamicParams();
  common::GridMap stored(params.core.dynamic.extent);
  stored.AddLayer(layers::kLongTerm, 0.f)(10, 20) = 98.f;
  params.core.dynamic.long_term_restore = stored;
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
                        NoProfileFolder);
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
  params.core.SetListed(kDynamicLayerName, false);
  EXPECT_THROW(params.Validate(), std::invalid_argument);
}

// Issue 20: OP_RESET (forgets every map) and OP_SNAPSHOT (writes files) needed no permission.
// They are off unless the mapper's configuration allows them: refused FORBIDDEN, counted.
TEST(MapperServiceTest, ResetAndSnapshotAreForbiddenUnlessTheConfigurationAllowsThem) {
  for (const bool allowed : {false, true}) {
    runtime::Node node(MemqOptions());
    MapperParams params;
    params.robot = "r1";
    params.core.SetListed(kOctomapLayerName, false);
    params.snapshot_dir = ::testing::TempDir() + "/mapper-snapshots";
    params.allow_reset = allowed;
    params.allow_snapshot = allowed;
    std::map<int64_t, lcmt_map_control_reply> replies;
    node.Subscribe<lcmt_map_control_reply>(
        "r1.MAP.CONTROL_REPLY",
        [&](const lcmt_map_control_reply& r) { replies[r.request_id] = r; });
    MapperService service(node, params, {ShippedProfile("pioneer3at")}, nullptr);
    for (const int8_t op :
         {lcmt_map_control_request::OP_RESET, lcmt_map_control_request::OP_SNAPSHOT}) {
      lcmt_map_control_request request{};
      request.requester = "unit";
      request.request_id = op;
      request.op = op;
      node.Publish("r1.MAP.CONTROL", request);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (replies.size() < 2 && std::chrono::steady_clock::now() < deadline) node.SpinOnce(10);
    service.Stop();
    ASSERT_EQ(replies.size(), 2u);
    for (const auto& [id, reply] : replies) {
      if (allowed) {
        EXPECT_EQ(reply.status, +lcmt_map_control_reply::STATUS_OK) << reply.message;
      } else {
        EXPECT_EQ(reply.status, +lcmt_map_control_reply::STATUS_FORBIDDEN);
        EXPECT_NE(reply.message.find(id == lcmt_map_control_request::OP_RESET ? "allow_reset"
                                                                              : "allow_snapshot"),
                  std::string::npos)
            << reply.message;
      }
    }
    EXPECT_EQ(node.counter("forbidden_requests"), allowed ? 0 : 2);
  }
}

// Issue 20: resend requests were not rate-limited: a peer asking for every tile of every layer
// as fast as it could made the mapper send without limit. A requester gets its burst, then its
// rate; the rest are dropped and counted.
TEST(MapperServiceTest, ResendRequestsBeyondTheRateAreDropped) {
  runtime::Node node(MemqOptions());
  MapperParams params;
  params.robot = "r1";
  params.core.SetListed(kOctomapLayerName, false);
  params.resend_limits.rate_per_s = 1.0;  // a test's whole run gains almost nothing
  params.resend_limits.burst = 10 * kWholeLayerResendTiles;
  MapperService service(node, params, {ShippedProfile("pioneer3at")}, nullptr);
  for (int i = 0; i < 100; ++i) {
    cairn::lcmt_tile_resend_request request{};
    request.requester = "flood";
    request.robot = "r1";
    request.map_name = "live";
    request.layer = "elevation";
    node.Publish("r1.MAP.TILE_RESEND", request);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (node.counter("resend_rate_limited") < 90 && std::chrono::steady_clock::now() < deadline) {
    node.SpinOnce(10);
  }
  service.Stop();
  EXPECT_EQ(node.counter("resend_rate_limited"), 90);
}

}  // namespace
}  // namespace cairn::mapping
