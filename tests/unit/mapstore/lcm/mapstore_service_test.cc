// MapstoreService over memq:// in one process, with the in-memory store and the fake deriver.

#include "mapstore/lcm/mapstore_service.h"

#include <cmath>
#include <map>
#include <optional>

#include <gtest/gtest.h>

#include "cairn/lcmt_grid_tile_batch.hpp"
#include "cairn/lcmt_map_control_request.hpp"

#include "common/channels.h"
#include "common/crc32.h"
#include "mapstore/in_memory_map_store.h"
#include "mapstore/lcm/mapstore_conversions.h"
#include "mapstore/lcm/tile_wire.h"
#include "services/runtime/conversions.h"
#include "services/runtime/layer_assembler.h"
#include "services/runtime/tiler.h"
#include "tests/support/memq_node.h"
#include "tests/unit/mapstore/fake_deriver.h"

namespace cairn::mapstore {
namespace {

using Request = cairn::lcmt_mapstore_request;
using Reply = cairn::lcmt_mapstore_reply;
constexpr int8_t kOk = Reply::STATUS_OK;
constexpr int8_t kNotFound = Reply::STATUS_NOT_FOUND;
constexpr int8_t kInvalid = Reply::STATUS_INVALID;
constexpr int8_t kBusy = Reply::STATUS_BUSY;

runtime::NodeOptions MemqOptions() { return cairn::testing::MemqNodeOptions("cairn-mapstore"); }

Request MakeRequest(int8_t op, const std::string& map = "") {
  Request r{};
  r.op = op;
  r.site = "lab";
  r.map_name = map;
  r.requester = "unit";
  r.has_profile = false;
  r.expect_obstacles = false;
  r.expect_octomap = false;
  return r;
}

class MapstoreServiceUnitTest : public ::testing::Test {
 protected:
  explicit MapstoreServiceUnitTest(double poll_period_s = 0.05, bool allow_delete = false)
      : node_(MemqOptions()) {
    MapstoreServiceParams params;
    params.poll_period_s = poll_period_s;
    params.allow_delete = allow_delete;
    params.save_timeout_s = 1.0;
    params.resend_interval_s = 0.05;
    params.pull_settle_s = 0.1;
    params.burst_pause_ms = 0.0;
    dut_ = std::make_unique<MapstoreService>(node_, store_, testing::FakeDeriver(), params);
    node_.lcm().subscribe(channels::kMapstoreReply, &MapstoreServiceUnitTest::OnReply, this);
    node_.lcm().subscribe(channels::kMapstoreTiles, &MapstoreServiceUnitTest::OnTile, this);
    node_.lcm().subscribe(channels::kMapstoreTileBatches, &MapstoreServiceUnitTest::OnTileBatch,
                          this);
    node_.lcm().subscribe(channels::kMapstoreManifest, &MapstoreServiceUnitTest::OnManifest, this);
    node_.lcm().subscribe(channels::kMapstorePushTileResend, &MapstoreServiceUnitTest::OnPushResend,
                          this);
  }

  void OnReply(const lcm::ReceiveBuffer*, const std::string&, const Reply* m) {
    replies_[m->request_id].push_back(*m);
  }
  void OnTileBatch(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                   const cairn::lcmt_grid_tile_batch* m) {
    ++batches_;
    EXPECT_EQ(m->num_tiles, static_cast<int32_t>(m->tiles.size()));
    for (const auto& tile : m->tiles) {
      EXPECT_NE(tile.encoding, +cairn::lcmt_grid_tile::ENCODING_FLOAT32);  // floats go singly
      EXPECT_EQ(tile.map_name, m->map_name);
      OnTile(rbuf, channel, &tile);
    }
  }
  void OnTile(const lcm::ReceiveBuffer*, const std::string&, const cairn::lcmt_grid_tile* m) {
    cairn::lcmt_grid_tile tile = *m;
    if (tile.encoding == cairn::lcmt_grid_tile::ENCODING_ZSTD_BYTES) ++byte_tiles_;
    if (tile.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32) {
      ++compressed_tiles_;
      compressed_bytes_ += tile.num_bytes;
    }
    const common::Status decoded = DecompressTile(&tile);
    EXPECT_TRUE(decoded.ok()) << decoded.ToString();
    assembler_.OnTile(tile);
    ++tiles_;
  }
  void OnManifest(const lcm::ReceiveBuffer*, const std::string&,
                  const cairn::lcmt_grid_manifest* m) {
    assembler_.OnManifest(*m);
  }
  void OnPushResend(const lcm::ReceiveBuffer*, const std::string&,
                    const cairn::lcmt_tile_resend_request* m) {
    push_resends_.push_back(*m);
  }

  // Publishes a request and spins the node until its reply arrives (or 5 s pass).
  Reply Call(Request r) {
    if (r.request_id == 0) r.request_id = ++next_id_;
    r.num_layers = static_cast<int32_t>(r.layers.size());
    r.num_places = static_cast<int32_t>(r.places.size());
    const size_t before = replies_[r.request_id].size();
    node_.Publish(channels::kMapstoreRequest, r);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (replies_[r.request_id].size() == before && std::chrono::steady_clock::now() < deadline) {
      node_.SpinOnce(5);
    }
    EXPECT_GT(replies_[r.request_id].size(), before) << "no reply to op " << int(r.op);
    return replies_[r.request_id].empty() ? Reply{} : replies_[r.request_id].back();
  }

  // Pushes a snapshot's layers (dropping the tiles named in `drop`), then OP_SAVE.
  // Pushes a snapshot's tiles (compressed when `compress`, as MapstoreClient does) without the
  // tiles in `drop`, then OP_SAVE, answering resend requests with float tiles.
  Reply Push(const MapSnapshot& s, std::set<std::pair<int, int>> drop = {}, bool compress = false,
             std::set<std::pair<int, int>> damage = {}) {
    const int64_t id = ++next_id_;
    const std::string map_name = std::to_string(id) + "/" + s.name;
    runtime::LayerTiler tiler(s.provenance.source_robot, map_name, 10);
    for (const std::string& layer : s.base.layer_names()) {
      auto batch = tiler.Update(s.base, layer, runtime::TileEncoding::kFloat, 1, true);
      node_.Publish(channels::kMapstorePushManifest, batch.manifest);
      for (auto t : batch.tiles) {
        if (drop.count({t.tile_ix, t.tile_iy})) continue;
        if (compress) CompressTile(&t);
        if (damage.count({t.tile_ix, t.tile_iy}) && !t.bytes.empty()) t.bytes[0] ^= 0x5a;
        node_.Publish(channels::kMapstorePushTiles, t);
      }
    }
    if (!s.obstacles.obstacles.empty()) {
      node_.Publish(channels::kMapstorePushObstacles,
                    runtime::ToLcm(s.obstacles, 1, s.provenance.source_robot, map_name));
    }
    Request r = MakeRequest(Request::OP_SAVE, s.name);
    r.request_id = id;
    r.site = s.site;
    r.layers = s.base.layer_names();
    r.profile = s.provenance.source_profile;
    r.expect_obstacles = !s.obstacles.obstacles.empty();
    pusher_ = &tiler;
    Reply reply = CallWithResends(r, &tiler);
    pusher_ = nullptr;
    return reply;
  }

  // As Call, answering the store's resend requests from `tiler`.
  Reply CallWithResends(Request r, runtime::LayerTiler* tiler) {
    r.num_layers = static_cast<int32_t>(r.layers.size());
    node_.Publish(channels::kMapstoreRequest, r);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (replies_[r.request_id].empty() && std::chrono::steady_clock::now() < deadline) {
      node_.SpinOnce(5);
      for (const auto& resend : push_resends_) {
        ++resends_answered_;
        if (tiler == nullptr) continue;
        auto batch = tiler->Resend(resend);
        node_.Publish(channels::kMapstorePushManifest, batch.manifest);
        for (const auto& t : batch.tiles) node_.Publish(channels::kMapstorePushTiles, t);
      }
      push_resends_.clear();
    }
    EXPECT_FALSE(replies_[r.request_id].empty());
    return replies_[r.request_id].empty() ? Reply{} : replies_[r.request_id].back();
  }

  runtime::Node node_;
  InMemoryMapStore store_;
  std::unique_ptr<MapstoreService> dut_;
  std::map<int64_t, std::vector<Reply>> replies_;
  runtime::LayerAssembler assembler_;
  std::vector<cairn::lcmt_tile_resend_request> push_resends_;
  runtime::LayerTiler* pusher_{nullptr};
  int tiles_{0};
  int compressed_tiles_{0};
  int batches_{0};
  int byte_tiles_{0};
  int64_t compressed_bytes_{0};
  int resends_answered_{0};
  int64_t next_id_{100};
};

// A service whose periodic check of pending saves never comes in a test's time.
class MapstoreServiceWithoutPollTest : public MapstoreServiceUnitTest {
 protected:
  MapstoreServiceWithoutPollTest() : MapstoreServiceUnitTest(3600.0) {}
};

// The resent tile completes the save the moment it arrives: the save does not wait for the
// periodic check (which never comes here).
TEST_F(MapstoreServiceWithoutPollTest, APushSaveFinishesWhenItsLastTileArrives) {
  const MapSnapshot s = testing::SampleSnapshot("corridor", 37, 23);
  const Reply reply = Push(s, {{1, 1}}, /*compress=*/true);
  ASSERT_EQ(reply.status, kOk) << reply.message;
  EXPECT_EQ(reply.version, 1);
  EXPECT_GE(resends_answered_, 1);
  // Nothing lost: the same push saves without waiting, too.
  const Reply again = Push(testing::SampleSnapshot("corridor", 37, 23, 2.0f));
  ASSERT_EQ(again.status, kOk) << again.message;
  EXPECT_EQ(again.version, 2);
}

TEST_F(MapstoreServiceUnitTest, PushedSaveWithALostTileIsCompletedByResend) {
  const MapSnapshot s = testing::SampleSnapshot("corridor", 37, 23);
  const Reply reply = Push(s, {{1, 1}});
  ASSERT_EQ(reply.status, kOk) << reply.message;
  EXPECT_EQ(reply.version, 1);
  EXPECT_GE(resends_answered_, 1);
  auto stored = store_.LoadLayers({"lab", "corridor", 0}, {});
  ASSERT_TRUE(stored.ok());
  const common::Layer& a = stored->at("elevation");
  const common::Layer& b = s.base.at("elevation");
  for (Eigen::Index i = 0; i < a.size(); ++i) {
    ASSERT_TRUE((std::isnan(a.data()[i]) && std::isnan(b.data()[i])) || a.data()[i] == b.data()[i]);
  }
  EXPECT_EQ(stored->at("observation_count"), s.base.at("observation_count"));
  auto obstacles = store_.LoadObstacles({"lab", "corridor", 0});
  ASSERT_EQ(obstacles->obstacles.size(), 2u);
}

TEST_F(MapstoreServiceUnitTest, CompressedPushIsStoredExactlyAndADamagedTileIsAskedForAgain) {
  const MapSnapshot s = testing::SampleSnapshot("corridor", 37, 23);
  const Reply reply = Push(s, {}, /*compress=*/true, /*damage=*/{{2, 1}});
  ASSERT_EQ(reply.status, kOk) << reply.message;
  EXPECT_GE(resends_answered_, 1);  // the damaged tile was dropped and asked for again
  auto stored = store_.LoadLayers({"lab", "corridor", 0}, {});
  ASSERT_TRUE(stored.ok());
  for (const std::string& name : s.base.layer_names()) {
    const common::Layer& a = stored->at(name);
    const common::Layer& b = s.base.at(name);
    for (Eigen::Index i = 0; i < a.size(); ++i) {
      ASSERT_TRUE((std::isnan(a.data()[i]) && std::isnan(b.data()[i])) ||
                  a.data()[i] == b.data()[i])
          << name << " cell " << i;
    }
  }
}

TEST_F(MapstoreServiceUnitTest, LoadSendsTilesAndAManifestPerLayer) {
  ASSERT_TRUE(store_.SaveMap(testing::SampleSnapshot("corridor", 237, 123), {"unit", 0, 0}).ok());
  Request load = MakeRequest(Request::OP_LOAD, "corridor");
  load.layers = {"elevation"};
  const Reply reply = Call(load);
  ASSERT_EQ(reply.status, kOk) << reply.message;
  EXPECT_EQ(reply.num_tiles, 3 * 2);  // 100-cell reply tiles over 237 x 123 cells
  for (int i = 0; i < 20 && !assembler_.Complete("elevation"); ++i) node_.SpinOnce(5);
  ASSERT_TRUE(assembler_.Complete("elevation"));
  auto layer = assembler_.Layer("elevation");
  ASSERT_TRUE(layer.has_value());
  EXPECT_EQ(layer->size_x(), 237);
  // Every cell comes back exactly, though the tiles travelled compressed.
  const common::Layer stored = store_.LoadLayers({"lab", "corridor", 0}, {})->at("elevation");
  const common::Layer& got = layer->at("elevation");
  ASSERT_EQ(got.size(), stored.size());
  for (Eigen::Index i = 0; i < got.size(); ++i) {
    ASSERT_TRUE((std::isnan(got.data()[i]) && std::isnan(stored.data()[i])) ||
                got.data()[i] == stored.data()[i])
        << "cell " << i;
  }
  EXPECT_EQ(compressed_tiles_, 6);
  EXPECT_LT(compressed_bytes_, 237 * 123 * 4);
}

TEST_F(MapstoreServiceUnitTest, AWholeNumberLayerTravelsAsBytesSeveralTilesToAMessage) {
  // A cost-like layer: whole numbers 0..100 and unknown cells.
  MapSnapshot snapshot = testing::SampleSnapshot("corridor", 237, 123);
  common::Layer& cost = snapshot.base.AddLayer("cost/test");
  for (int iy = 0; iy < 123; ++iy) {
    for (int ix = 0; ix < 237; ++ix) {
      cost(ix, iy) = (ix + iy) % 17 == 0 ? common::kUnknown : static_cast<float>((ix * iy) % 101);
    }
  }
  ASSERT_TRUE(store_.SaveMap(snapshot, {"unit", 0, 0}).ok());
  Request load = MakeRequest(Request::OP_LOAD, "corridor");
  load.layers = {"cost/test"};
  const Reply reply = Call(load);
  ASSERT_EQ(reply.status, kOk) << reply.message;
  for (int i = 0; i < 20 && !assembler_.Complete("cost/test"); ++i) node_.SpinOnce(5);
  ASSERT_TRUE(assembler_.Complete("cost/test"));
  // One byte per cell: the six tiles fit one message.
  EXPECT_EQ(byte_tiles_, 6);
  EXPECT_EQ(batches_, 1);
  EXPECT_LT(compressed_bytes_, 237 * 123);
  const std::optional<common::GridMap> assembled = assembler_.Layer("cost/test");
  ASSERT_TRUE(assembled.has_value());
  const common::Layer& got = assembled->at("cost/test");
  for (Eigen::Index i = 0; i < got.size(); ++i) {
    ASSERT_TRUE((std::isnan(got.data()[i]) && std::isnan(cost.data()[i])) ||
                got.data()[i] == cost.data()[i])
        << "cell " << i;
  }
}

TEST_F(MapstoreServiceUnitTest, ACompressedTileWithADamagedByteIsRefused) {
  cairn::lcmt_grid_tile tile{};
  tile.cells_x = 20;
  tile.cells_y = 10;
  tile.tile_size = 20;
  tile.num_cells = 200;
  for (int i = 0; i < 200; ++i) tile.data.push_back(0.01f * static_cast<float>(i % 37));
  tile.checksum = common::Crc32(tile.data.data(), tile.data.size() * sizeof(float));
  const std::vector<float> sent = tile.data;
  ASSERT_TRUE(CompressTile(&tile));
  EXPECT_EQ(tile.num_cells, 0);
  EXPECT_LT(tile.num_bytes, 800);
  cairn::lcmt_grid_tile damaged = tile;
  damaged.bytes[damaged.bytes.size() / 2] ^= 0x40;
  EXPECT_FALSE(DecompressTile(&damaged).ok());
  cairn::lcmt_grid_tile unknown = tile;
  unknown.encoding = 7;
  EXPECT_EQ(DecompressTile(&unknown).code(), common::StatusCode::kInvalidArgument);
  ASSERT_TRUE(DecompressTile(&tile).ok());
  EXPECT_EQ(tile.data, sent);
  // The assembler, which knows no codec, refuses a compressed tile instead of misreading it.
  runtime::LayerAssembler assembler;
  cairn::lcmt_grid_tile again = tile;
  ASSERT_TRUE(CompressTile(&again));
  EXPECT_FALSE(assembler.OnTile(again));
}

TEST_F(MapstoreServiceUnitTest, ReplayReturnsTheFirstReplyAndSavesOnce) {
  const MapSnapshot s = testing::SampleSnapshot("corridor");
  const Reply first = Push(s);
  ASSERT_EQ(first.status, kOk);
  Request again = MakeRequest(Request::OP_SAVE, "corridor");
  again.request_id = first.request_id;
  again.layers = s.base.layer_names();
  const Reply replayed = Call(again);
  EXPECT_EQ(replayed.version, first.version);
  EXPECT_EQ(replayed.duration_us, first.duration_us);
  EXPECT_EQ(store_.ListMaps({"lab", "corridor", true, true})->size(), 1u);
  EXPECT_EQ(node_.counter("replayed_requests"), 1);
}

TEST_F(MapstoreServiceUnitTest, MissingTilesTimeOutWithAMessage) {
  Request save = MakeRequest(Request::OP_SAVE, "ghost");
  save.request_id = 555;
  save.layers = {"elevation"};
  const Reply reply = CallWithResends(save, nullptr);
  EXPECT_EQ(reply.status, kBusy);
  EXPECT_NE(reply.message.find("elevation"), std::string::npos) << reply.message;
  EXPECT_EQ(node_.counter("save_timeouts"), 1);
}

TEST_F(MapstoreServiceUnitTest, APushWithBadObstaclesFailsAsInvalid) {
  MapSnapshot s = testing::SampleSnapshot("corridor");
  const int64_t id = ++next_id_;
  const std::string map_name = std::to_string(id) + "/corridor";
  runtime::LayerTiler tiler("rover1", map_name, 10);
  for (const std::string& layer : s.base.layer_names()) {
    auto batch = tiler.Update(s.base, layer, runtime::TileEncoding::kFloat, 1, true);
    node_.Publish(channels::kMapstorePushManifest, batch.manifest);
    for (const auto& t : batch.tiles) node_.Publish(channels::kMapstorePushTiles, t);
  }
  auto registry = runtime::ToLcm(s.obstacles, 1, "rover1", map_name);
  registry.obstacles[0].kind = 42;  // no such obstacle kind
  node_.Publish(channels::kMapstorePushObstacles, registry);
  Request r = MakeRequest(Request::OP_SAVE, "corridor");
  r.request_id = id;
  r.layers = s.base.layer_names();
  r.expect_obstacles = true;
  const Reply reply = CallWithResends(r, &tiler);
  EXPECT_EQ(reply.status, kInvalid);
  EXPECT_NE(reply.message.find("obstacle"), std::string::npos) << reply.message;
  EXPECT_FALSE(store_.GetMapInfo({"lab", "corridor", 0}).ok());
}

TEST_F(MapstoreServiceUnitTest, PullSaveFromAMappersLiveMap) {
  const MapSnapshot s = testing::SampleSnapshot("yard", 45, 33);
  common::GridMap live = s.base;
  live.AddLayer("cost/pioneer3at", 0.f);
  runtime::LayerTiler mapper("rover3", "live", 10);
  int publish_all = 0;
  node_.lcm().subscribeFunction<int*>(
      "rover3.MAP.CONTROL",
      [](const lcm::ReceiveBuffer*, const std::string&, int* count) { ++*count; }, &publish_all);
  Request save = MakeRequest(Request::OP_SAVE, "yard");
  save.request_id = 777;
  save.robot = "rover3";
  node_.Publish(channels::kMapstoreRequest, save);
  bool published = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (replies_[777].empty() && std::chrono::steady_clock::now() < deadline) {
    node_.SpinOnce(5);
    if (publish_all > 0 && !published) {
      published = true;
      for (const std::string& layer : live.layer_names()) {
        auto batch = mapper.Update(live, layer, runtime::TileEncoding::kFloat, 1, true);
        node_.Publish("rover3.MAP.MANIFEST", batch.manifest);
        for (const auto& t : batch.tiles) node_.Publish("rover3.MAP.TILES", t);
      }
    }
  }
  ASSERT_FALSE(replies_[777].empty());
  const Reply reply = replies_[777].back();
  ASSERT_EQ(reply.status, kOk) << reply.message;
  EXPECT_EQ(reply.layers, (std::vector<std::string>{"elevation", "observation_count"}));
  EXPECT_EQ(store_.GetMapInfo({"lab", "yard", 0})->provenance.source_robot, "rover3");
}

TEST_F(MapstoreServiceUnitTest, StatusesForUnknownAndInvalidRequests) {
  EXPECT_EQ(Call(MakeRequest(Request::OP_LOAD, "nowhere")).status, kNotFound);
  EXPECT_EQ(Call(MakeRequest(Request::OP_LOAD, "a/b")).status, kInvalid);
  Request no_layers = MakeRequest(Request::OP_SAVE, "x");
  EXPECT_EQ(Call(no_layers).status, kInvalid);
  EXPECT_EQ(Call(MakeRequest(42)).status, kInvalid);
  Request put = MakeRequest(Request::OP_PUT_PROFILE);
  EXPECT_EQ(Call(put).status, kInvalid);  // no profile data
  EXPECT_GE(node_.MakeHealth().dropped_inputs, 4);
}

TEST_F(MapstoreServiceUnitTest, ShareRepliesWithTheVerdictsThatChange) {
  ASSERT_TRUE(store_.SaveMap(testing::SampleSnapshot("corridor"), {"unit", 0, 0}).ok());
  ASSERT_TRUE(store_.PutProfile(testing::Profile("pioneer3at", 8.0, 0.03), {"unit", 0, 0}).ok());
  ASSERT_TRUE(store_.PutProfile(testing::Profile("rover", 12.0, 0.08), {"unit", 0, 0}).ok());
  Request share = MakeRequest(Request::OP_SHARE, "corridor");
  share.profile = "rover";
  const Reply reply = Call(share);
  ASSERT_EQ(reply.status, kOk) << reply.message;
  ASSERT_EQ(reply.num_obstacles, 1);
  EXPECT_EQ(reply.obstacles[0].id, 7);
  EXPECT_TRUE(reply.obstacles[0].verdicts.back().crossable);
  EXPECT_EQ(store_.ListDerived({"lab", "corridor", 0})->size(), 1u);
}

}  // namespace
}  // namespace cairn::mapstore

namespace cairn::mapstore {
namespace {

TEST(TileWireTest, FastEncodingEqualsTheGeneratedOne) {
  for (int n : {0, 1, 7, 10000}) {
    cairn::lcmt_grid_tile t{};
    t.utime = -5;
    t.robot = "rover";
    t.map_name = "42/corridor";
    t.layer = "elevation";
    t.resolution_m = 0.05;
    t.layer_size_x = t.layer_size_y = 1000;
    t.tile_size = 100;
    t.cells_x = n;
    t.cells_y = 1;
    t.checksum = 0xffffffff;
    t.num_cells = n;
    for (int i = 0; i < n; ++i) t.data.push_back(i % 3 == 0 ? NAN : 0.01f * i - 3.f);
    std::vector<uint8_t> fast, generated(t.getEncodedSize());
    EncodeTile(t, &fast);
    t.encode(generated.data(), 0, static_cast<int>(generated.size()));
    EXPECT_EQ(fast, generated) << n << " cells";
  }
}

// Issue 20: OP_DELETE needed no permission. It is off unless the store's configuration allows
// it: refused FORBIDDEN, the map kept, the refusal counted (and logged as an audit line).
TEST_F(MapstoreServiceUnitTest, DeleteIsForbiddenUnlessTheConfigurationAllowsIt) {
  ASSERT_EQ(Push(testing::SampleSnapshot("corridor", 37, 23)).status, kOk);
  const Reply refused = Call(MakeRequest(Request::OP_DELETE, "corridor"));
  EXPECT_EQ(refused.status, +Reply::STATUS_FORBIDDEN);
  EXPECT_NE(refused.message.find("allow_delete"), std::string::npos) << refused.message;
  EXPECT_TRUE(store_.GetMapInfo({"lab", "corridor", 0}).ok());
  EXPECT_EQ(node_.counter("forbidden_requests"), 1);
}

class MapstoreServiceDeleteAllowedTest : public MapstoreServiceUnitTest {
 protected:
  MapstoreServiceDeleteAllowedTest() : MapstoreServiceUnitTest(0.05, /*allow_delete=*/true) {}
};

TEST_F(MapstoreServiceDeleteAllowedTest, DeleteWorksWhenTheConfigurationAllowsIt) {
  ASSERT_EQ(Push(testing::SampleSnapshot("corridor", 37, 23)).status, kOk);
  EXPECT_EQ(Call(MakeRequest(Request::OP_DELETE, "corridor")).status, kOk);
  EXPECT_FALSE(store_.GetMapInfo({"lab", "corridor", 0}).ok());
}

}  // namespace
}  // namespace cairn::mapstore
