// MapServerService over memq:// with the in-memory store and the fake deriver: the served
// layers rebuild exactly on the receiver side (the navigator's LayerAssembler), manifests are
// re-announced, missed tiles are resent, the registry carries the profile's verdicts, and a map
// saved after the server started is served once it appears.

#include "mapstore/lcm/map_server_service.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include <gtest/gtest.h>

#include "cairn/lcmt_obstacle_registry.hpp"

#include "common/channels.h"
#include "mapstore/in_memory_map_store.h"
#include "services/runtime/layer_assembler.h"
#include "services/runtime/tiler.h"
#include "tests/unit/mapstore/fake_deriver.h"
#include "tests/support/memq_node.h"

namespace cairn::mapstore {
namespace {

using testing::FakeDeriver;
using testing::Profile;
using testing::SampleSnapshot;

runtime::NodeOptions MemqOptions() {
  return cairn::testing::MemqNodeOptions("cairn-map-server", "rb");
}

class MapServerServiceTest : public ::testing::Test {
 protected:
  MapServerServiceTest() : node_(MemqOptions()), deriver_(FakeDeriver()) {
    EXPECT_TRUE(store_.PutProfile(Profile("rover", 12.0, 0.08), {"unit", 0, 0}).ok());
    node_.lcm().subscribe("rb.MAP.TILES", &MapServerServiceTest::OnTile, this);
    node_.lcm().subscribe("rb.MAP.MANIFEST", &MapServerServiceTest::OnManifest, this);
    node_.lcm().subscribe("rb.MAP.OBSTACLES", &MapServerServiceTest::OnRegistry, this);
  }
  ~MapServerServiceTest() override { dut_.reset(); }

  void Start(double wait_s, int64_t version = 0) {
    MapServerParams params;
    params.db_path = "unused";
    params.ref = {"lab", "lanes", version};
    params.profile = "rover";
    params.robot = "rb";
    params.wait_s = wait_s;
    params.poll_period_s = 0.05;
    params.follow_period_s = 0.05;
    params.burst_pause_ms = 0.0;
    dut_ = std::make_unique<MapServerService>(
        node_, params, &deriver_, [this]() -> common::Result<const MapStore*> {
          ++opens_;
          return static_cast<const MapStore*>(&store_);
        });
  }
  // Runs the node's loop until `done` or about 5 s passed.
  bool SpinUntil(const std::function<bool()>& done) {
    for (int i = 0; i < 1000 && !done(); ++i) {
      node_.SpinOnce(5);
      dut_->Tick();
    }
    return done();
  }

  void OnTile(const lcm::ReceiveBuffer*, const std::string&, const cairn::lcmt_grid_tile* m) {
    ++tiles_;
    if (m->layer == "cost/rover" && drop_tiles_ > 0) {
      --drop_tiles_;
      return;
    }
    EXPECT_EQ(m->robot, "rb");
    EXPECT_EQ(m->map_name, "lab/lanes");
    assembler_.OnTile(*m);
  }
  void OnManifest(const lcm::ReceiveBuffer*, const std::string&,
                  const cairn::lcmt_grid_manifest* m) {
    ++manifests_[m->layer];
    assembler_.OnManifest(*m);
  }
  void OnRegistry(const lcm::ReceiveBuffer*, const std::string&,
                  const cairn::lcmt_obstacle_registry* m) {
    registry_ = *m;
  }

  InMemoryMapStore store_;
  runtime::Node node_;
  ProfileDeriver deriver_;
  std::unique_ptr<MapServerService> dut_;
  runtime::LayerAssembler assembler_;
  std::map<std::string, int> manifests_;
  std::optional<cairn::lcmt_obstacle_registry> registry_;
  int tiles_{0};
  int drop_tiles_{0};
  std::atomic<int> opens_{0};  // the opener runs on the service's thread
};

TEST_F(MapServerServiceTest, PublishesTheCostLayerAsAMapperWouldAndReannouncesIt) {
  ASSERT_TRUE(store_.SaveMap(SampleSnapshot("lanes", 230, 140), {"unit", 0, 0}).ok());
  Start(0.0);
  ASSERT_TRUE(SpinUntil([&] { return assembler_.Complete("cost/rover"); }));
  ASSERT_TRUE(SpinUntil([&] { return assembler_.Complete("elevation"); }));
  EXPECT_EQ(dut_->state(), MapServerService::State::kServing);
  ASSERT_NE(dut_->served(), nullptr);

  // Cell for cell what the store gives for the profile.
  const common::GridMap& served = dut_->served()->layers;
  for (const char* layer : {"cost/rover", "elevation"}) {
    auto got = assembler_.Layer(layer);
    ASSERT_TRUE(got.has_value()) << layer;
    EXPECT_EQ(got->geometry(), served.geometry());
    const common::Layer& a = got->at(layer);
    const common::Layer& b = served.at(layer);
    for (int iy = 0; iy < b.cols(); ++iy) {
      for (int ix = 0; ix < b.rows(); ++ix) {
        ASSERT_TRUE((std::isnan(a(ix, iy)) && std::isnan(b(ix, iy))) || a(ix, iy) == b(ix, iy))
            << layer << " (" << ix << ", " << iy << ")";
      }
    }
  }
  // Manifests keep coming with the same layer version (the navigator's staleness check).
  const int64_t version = assembler_.version("cost/rover");
  const int before = manifests_["cost/rover"];
  ASSERT_TRUE(SpinUntil([&] { return manifests_["cost/rover"] >= before + 3; }));
  EXPECT_EQ(assembler_.version("cost/rover"), version);
  EXPECT_GE(node_.counter("manifests_sent"), 6);
  EXPECT_GT(node_.counter("tiles_sent"), 0);

  // The registry: the rover's verdicts only.
  ASSERT_TRUE(SpinUntil([&] { return registry_.has_value(); }));
  EXPECT_EQ(registry_->robot, "rb");
  bool ramp_seen = false;
  for (const auto& o : registry_->obstacles) {
    ASSERT_EQ(o.num_verdicts, 1);
    EXPECT_EQ(o.verdicts[0].profile, "rover");
    if (o.id == 7) {
      ramp_seen = true;
      EXPECT_TRUE(o.verdicts[0].crossable);
    }
  }
  EXPECT_TRUE(ramp_seen);
}

TEST_F(MapServerServiceTest, ResendsTilesAReceiverMissed) {
  ASSERT_TRUE(store_.SaveMap(SampleSnapshot("lanes", 230, 140), {"unit", 0, 0}).ok());
  drop_tiles_ = 3;
  Start(0.0);
  ASSERT_TRUE(SpinUntil([&] { return dut_->state() == MapServerService::State::kServing; }));
  ASSERT_TRUE(SpinUntil([&] { return !assembler_.Missing("cost/rover").empty(); }));
  EXPECT_FALSE(assembler_.Complete("cost/rover"));
  auto request = assembler_.MakeResendRequest("cost/rover", "unit", 0);
  ASSERT_TRUE(request.has_value());
  node_.Publish("rb.MAP.TILE_RESEND", *request);
  // A request for another map on the channel (a mapper's) is not answered.
  cairn::lcmt_tile_resend_request foreign = *request;
  foreign.map_name = "live";
  node_.Publish("rb.MAP.TILE_RESEND", foreign);
  ASSERT_TRUE(SpinUntil([&] { return assembler_.Complete("cost/rover"); }));
  EXPECT_EQ(node_.counter("resend_requests"), 1);
  EXPECT_EQ(node_.counter("tiles_resent"), request->num_tiles);
}

TEST_F(MapServerServiceTest, WaitsForAMapSavedLaterThenServesIt) {
  Start(30.0);
  ASSERT_TRUE(SpinUntil([&] { return dut_->state() == MapServerService::State::kWaiting; }));
  EXPECT_EQ(node_.state(), runtime::HealthState::kReady);
  const int opens = opens_;
  ASSERT_TRUE(SpinUntil([&] { return opens_ >= opens + 2; })) << "the store is not polled";
  EXPECT_EQ(manifests_.size(), 0u);
  ASSERT_TRUE(store_.SaveMap(SampleSnapshot("lanes", 120, 80), {"unit", 0, 0}).ok());
  ASSERT_TRUE(SpinUntil([&] { return assembler_.Complete("cost/rover"); }));
  EXPECT_EQ(dut_->state(), MapServerService::State::kServing);
  EXPECT_EQ(dut_->served()->info.version, 1);

  // Following the latest version: a newer save replaces the served map.
  const int64_t layer_version = assembler_.version("cost/rover");
  ASSERT_TRUE(store_.SaveMap(SampleSnapshot("lanes", 120, 80, 1.f), {"unit", 0, 0}).ok());
  ASSERT_TRUE(SpinUntil([&] { return dut_->served()->info.version == 2; }));
  ASSERT_TRUE(SpinUntil([&] {
    return assembler_.version("elevation") > layer_version && assembler_.Complete("elevation");
  }));
  EXPECT_FLOAT_EQ(assembler_.Layer("elevation")->at("elevation")(5, 5), 1.f + 0.005f);
}

TEST_F(MapServerServiceTest, GivesUpWhenTheMapNeverComes) {
  Start(0.2);
  ASSERT_TRUE(SpinUntil([&] { return dut_->state() == MapServerService::State::kFailed; }));
  EXPECT_TRUE(node_.stopping());
  EXPECT_EQ(manifests_.size(), 0u);
}

}  // namespace
}  // namespace cairn::mapstore
