// SaveAssembler against the in-memory store (and, where the stored bytes matter, SQLite in
// memory): push and pull saves put together from pieces, with time passed in.

#include "mapstore/save_assembler.h"

#include <gtest/gtest.h>

#include "common/layers.h"
#include "mapstore/in_memory_map_store.h"
#include "mapstore/sqlite_map_store.h"
#include "tests/unit/mapstore/core_tiles.h"
#include "tests/unit/mapstore/fake_deriver.h"

namespace cairn::mapstore {
namespace {

using Clock = SaveAssembler::Clock;
using Intake = SaveAssembler::Intake;
using testing::CutLayer;
using testing::SameLayer;

Clock::time_point T(double s) {
  return Clock::time_point() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1000.0 + s));
}

SaveAssemblerParams Params() {
  SaveAssemblerParams p;
  p.save_timeout_s = 2.0;
  p.resend_interval_s = 0.1;
  p.staging_timeout_s = 5.0;
  p.pull_settle_s = 0.5;
  return p;
}

SaveRequest PushRequest(const MapSnapshot& s, int64_t id = 11) {
  SaveRequest r;
  r.requester = "unit";
  r.request_id = id;
  r.site = s.site;
  r.map_name = s.name;
  r.layers = s.base.layer_names();
  r.profile = s.provenance.source_profile;
  r.code_version = s.provenance.code_version;
  return r;
}

SaveRequest PullRequest(int64_t id, const std::string& map, const std::string& robot) {
  SaveRequest r;
  r.requester = "unit";
  r.request_id = id;
  r.site = "lab";
  r.map_name = map;
  r.robot = robot;
  return r;
}

class SaveAssemblerTest : public ::testing::Test {
 protected:
  SaveAssemblerTest() : snapshot_(testing::SampleSnapshot("corridor", 37, 23)) {}

  // Stages every layer of the snapshot under the push name of request `id` (dropping tile
  // `skip` of the first layer when >= 0), compressed when `compress`.
  void Stage(SaveAssembler& dut, int64_t id, bool compress = false, int skip = -1,
             double at = 0.0) {
    const std::string name = std::to_string(id) + "/" + snapshot_.name;
    bool first = true;
    for (const std::string& layer : snapshot_.base.layer_names()) {
      const auto cut = CutLayer(snapshot_.base, layer, 10, name);
      EXPECT_EQ(dut.StageManifest(cut.manifest, T(at)), Intake::kHeld);
      for (size_t i = 0; i < cut.tiles.size(); ++i) {
        if (first && static_cast<int>(i) == skip) continue;
        StageTile(dut, cut.tiles[i], compress, at);
      }
      first = false;
    }
  }
  Intake StageTile(SaveAssembler& dut, const testing::OwnedTile& t, bool compress, double at) {
    if (!compress) return dut.StageTile(t.As(), std::nullopt, "", T(at));
    const EncodedBlob blob = t.Compressed();
    return dut.StageTile(t.As(), static_cast<int>(blob.codec), blob.data, T(at));
  }

  MapSnapshot snapshot_;
  InMemoryMapStore store_;
};

TEST_F(SaveAssemblerTest, APushSaveFinishesTheMomentItsLastTileArrives) {
  SaveAssembler dut(store_, Params());
  Stage(dut, 11, false, /*skip=*/2);
  SaveProgress started = dut.Start(PushRequest(snapshot_), T(0.0));
  EXPECT_TRUE(started.finished.empty());
  EXPECT_TRUE(dut.IsPending("unit#11"));
  // The missing tile is asked for at once, on the push channel.
  ASSERT_EQ(started.resends.size(), 1u);
  EXPECT_TRUE(started.resends[0].pull_robot.empty());
  EXPECT_EQ(started.resends[0].tiles.map_name, "11/corridor");
  const auto cut = CutLayer(snapshot_.base, snapshot_.base.layer_names()[0], 10, "11/corridor");
  const std::pair<int, int> missing{cut.tiles[2].header.tile_ix, cut.tiles[2].header.tile_iy};
  EXPECT_EQ(started.resends[0].tiles.tiles, (std::vector<std::pair<int, int>>{missing}));

  EXPECT_TRUE(dut.OnPushed("11/other", T(0.01)).finished.empty());  // another push: no change
  EXPECT_EQ(StageTile(dut, cut.tiles[2], false, 0.01), Intake::kHeld);
  SaveProgress done = dut.OnPushed("11/corridor", T(0.01));
  ASSERT_EQ(done.finished.size(), 1u);
  const SaveOutcome& outcome = done.finished[0];
  ASSERT_TRUE(outcome.status.ok()) << outcome.status.ToString();
  EXPECT_EQ(outcome.version, 1);
  EXPECT_EQ(outcome.message, "saved version 1");
  EXPECT_EQ(outcome.saved_maps, 1);
  EXPECT_EQ(outcome.key, "unit#11");
  ASSERT_EQ(outcome.events.size(), 1u);
  EXPECT_NE(outcome.events[0].find("saved lab/corridor v1 from a push"), std::string::npos);
  EXPECT_FALSE(dut.IsPending("unit#11"));
  EXPECT_EQ(dut.staged_bytes(), 0);  // the staging went with the save

  auto stored = store_.LoadLayers({"lab", "corridor", 1}, {});
  ASSERT_TRUE(stored.ok());
  for (const std::string& layer : snapshot_.base.layer_names()) {
    EXPECT_TRUE(SameLayer(stored->at(layer), snapshot_.base.at(layer))) << layer;
  }
  auto info = store_.GetMapInfo({"lab", "corridor", 1});
  EXPECT_EQ(info->provenance.source_robot, "rover1");  // the pushed tiles' robot
  EXPECT_EQ(info->provenance.code_version, "mapping-7");
}

TEST_F(SaveAssemblerTest, ResendsArePacedAndASaveStillIncompleteTimesOutNamingWhatIsMissing) {
  SaveAssembler dut(store_, Params());
  Stage(dut, 11, false, /*skip=*/0);
  SaveRequest request = PushRequest(snapshot_);
  request.expect_obstacles = true;
  EXPECT_EQ(dut.Start(request, T(0.0)).resends.size(), 2u);  // the tile and "#obstacles"
  EXPECT_TRUE(dut.Poll(T(0.05)).resends.empty());            // within the resend interval
  SaveProgress again = dut.Poll(T(0.1));
  ASSERT_EQ(again.resends.size(), 2u);
  EXPECT_EQ(again.resends[1].tiles.layer, kResendObstacles);
  EXPECT_TRUE(again.resends[1].tiles.tiles.empty());  // "send it all"
  EXPECT_TRUE(dut.Poll(T(1.9)).finished.empty());
  SaveProgress late = dut.Poll(T(2.01));
  ASSERT_EQ(late.finished.size(), 1u);
  EXPECT_TRUE(late.finished[0].timed_out);
  EXPECT_EQ(late.finished[0].status.code(), common::StatusCode::kUnavailable);
  EXPECT_EQ(late.finished[0].status.message(),
            "timed out after 2 s waiting for: elevation, #obstacles");
  EXPECT_FALSE(dut.IsPending("unit#11"));
  EXPECT_FALSE(store_.GetMapInfo({"lab", "corridor", 0}).ok());
}

TEST_F(SaveAssemblerTest, PushedCompressedTilesAreStoredAsTheyCame) {
  auto sqlite = SqliteMapStore::Open(":memory:", [] {
    SqliteOptions o;
    o.tile_size_cells = 10;
    return o;
  }());
  ASSERT_TRUE(sqlite.ok());
  SaveAssembler dut(**sqlite, Params());
  Stage(dut, 11, /*compress=*/true);
  SaveProgress done = dut.Start(PushRequest(snapshot_), T(0.0));  // everything is there
  ASSERT_EQ(done.finished.size(), 1u);
  ASSERT_TRUE(done.finished[0].status.ok()) << done.finished[0].status.ToString();
  auto blobs = (*sqlite)->BaseBlobBytes({"lab", "corridor", 1});
  ASSERT_TRUE(blobs.ok());
  size_t compared = 0;
  for (const std::string& layer : snapshot_.base.layer_names()) {
    for (const auto& t : CutLayer(snapshot_.base, layer, 10, "x").tiles) {
      const std::string key =
          layer + "/" + std::to_string(t.header.tile_ix) + "/" + std::to_string(t.header.tile_iy);
      ASSERT_TRUE(blobs->count(key)) << key;
      EXPECT_EQ(blobs->at(key), t.Compressed().data) << key;
      ++compared;
    }
  }
  EXPECT_EQ(compared, blobs->size());
  auto loaded = (*sqlite)->LoadLayers({"lab", "corridor", 1}, {});
  ASSERT_TRUE(loaded.ok());
  EXPECT_TRUE(SameLayer(loaded->at(layers::kElevation), snapshot_.base.at(layers::kElevation)));
}

TEST_F(SaveAssemblerTest, BadRequestsAndBadObstaclesFailAsInvalid) {
  SaveAssembler dut(store_, Params());
  SaveRequest no_layers = PushRequest(snapshot_);
  no_layers.layers.clear();
  SaveProgress p = dut.Start(no_layers, T(0.0));
  ASSERT_EQ(p.finished.size(), 1u);
  EXPECT_EQ(p.finished[0].status.code(), common::StatusCode::kInvalidArgument);
  EXPECT_EQ(p.finished[0].status.message(), "a pushed save must name its layers");
  SaveRequest bad_name = PushRequest(snapshot_);
  bad_name.map_name = "../etc";
  EXPECT_EQ(dut.Start(bad_name, T(0.0)).finished.at(0).status.code(),
            common::StatusCode::kInvalidArgument);

  Stage(dut, 12);
  EXPECT_EQ(dut.StageObstacles("12/corridor", common::InvalidArgumentError("kind 9"), T(0.0)),
            Intake::kRefused);
  SaveProgress refused = dut.Start(PushRequest(snapshot_, 12), T(0.0));
  ASSERT_EQ(refused.finished.size(), 1u);
  EXPECT_EQ(refused.finished[0].status.code(), common::StatusCode::kInvalidArgument);
  EXPECT_EQ(refused.finished[0].status.message(), "pushed obstacles: kind 9");
  EXPECT_EQ(dut.staged_bytes(), 0);
  // Data without a push name ("<request_id>/<map>") are refused.
  EXPECT_EQ(
      dut.StageManifest(CutLayer(snapshot_.base, layers::kElevation, 10, "live").manifest, T(0.0)),
      Intake::kRefused);
}

TEST_F(SaveAssemblerTest, ASaveReplayedAfterARestartAnswersWithTheVersionItMade) {
  {
    SaveAssembler first(store_, Params());
    Stage(first, 11);
    ASSERT_TRUE(first.Start(PushRequest(snapshot_), T(0.0)).finished.at(0).status.ok());
  }
  SaveAssembler restarted(store_, Params());
  SaveProgress replay = restarted.Start(PushRequest(snapshot_), T(0.0));
  ASSERT_EQ(replay.finished.size(), 1u);
  EXPECT_EQ(replay.finished[0].version, 1);
  EXPECT_EQ(replay.finished[0].message, "already saved as version 1");
  EXPECT_FALSE(store_.GetMapInfo({"lab", "corridor", 2}).ok());  // saved once
}

TEST_F(SaveAssemblerTest, StagedCellsAreBoundedAndAbandonedPushesDropped) {
  SaveAssemblerParams params = Params();
  const int64_t layer_bytes = snapshot_.base.geometry().num_cells() * 4;
  params.max_staged_bytes = layer_bytes + 2048;  // one layer's canvas and a bit
  SaveAssembler dut(store_, params);
  const auto elevation = CutLayer(snapshot_.base, layers::kElevation, 10, "11/corridor");
  int full = 0;
  for (const std::string& layer : snapshot_.base.layer_names()) {
    for (const auto& t : CutLayer(snapshot_.base, layer, 10, "11/corridor").tiles) {
      full += StageTile(dut, t, false, 0.0) == Intake::kStagingFull ? 1 : 0;
    }
  }
  EXPECT_GT(full, 0);
  EXPECT_LE(dut.staged_bytes(), params.max_staged_bytes);
  // Nobody asks to save it: dropped after staging_timeout_s without news.
  EXPECT_EQ(dut.Poll(T(4.9)).abandoned_pushes, 0);
  EXPECT_EQ(dut.Poll(T(5.1)).abandoned_pushes, 1);
  EXPECT_EQ(dut.staged_bytes(), 0);
  EXPECT_EQ(StageTile(dut, elevation.tiles[0], false, 5.2), Intake::kHeld);  // room again
}

// Issue 20: the staging cap counted the cells of tiles only. A small tile of a layer whose grid
// is 1000 x 1000 allocated the whole layer (4 MB here; 256 MB at the layer cap), and manifests,
// obstacles, OctoMaps and push names were not counted at all.
TEST_F(SaveAssemblerTest, StagingCountsCanvasesManifestsOctomapsAndPushNames) {
  SaveAssemblerParams params = Params();
  params.max_staged_bytes = 18'000'000;
  params.max_pushes = 8;
  SaveAssembler dut(store_, params);
  common::GridMap wide = testing::SampleSnapshot("corridor", 1000, 1000).base;
  const auto cut = CutLayer(wide, layers::kElevation, 10, "1/corridor");
  int held = 0, full = 0;
  for (int push = 1; push <= 8; ++push) {
    testing::OwnedTile t = cut.tiles.front();
    t.header.map_name = std::to_string(push) + "/corridor";
    const Intake intake = StageTile(dut, t, false, 0.0);
    held += intake == Intake::kHeld ? 1 : 0;
    full += intake == Intake::kStagingFull ? 1 : 0;
  }
  EXPECT_EQ(held, 4);  // four 4 MB canvases fit in 18 MB, the fifth does not
  EXPECT_EQ(full, 4);
  EXPECT_LE(dut.staged_bytes(), params.max_staged_bytes);
  // Push names beyond max_pushes are refused whatever they carry.
  int names_full = 0;
  for (int push = 100; push < 120; ++push) {
    TileManifest m = CutLayer(snapshot_.base, layers::kElevation, 10,
                              std::to_string(push) + "/corridor")
                         .manifest;
    names_full += dut.StageManifest(m, T(0.0)) == Intake::kStagingFull ? 1 : 0;
  }
  EXPECT_EQ(names_full, 16);  // 4 names held tiles, 4 more take manifests
  // An OctoMap chunk counts as its bytes: a tree that does not fit is refused.
  const std::string bytes(6 << 20, 'z');
  OctomapChunk chunk;
  chunk.chunk_count = 1;
  chunk.total_bytes = static_cast<int64_t>(bytes.size());
  chunk.data = bytes.data();
  chunk.size = bytes.size();
  EXPECT_EQ(dut.StageOctomapChunk("1/corridor", chunk, T(0.0)), Intake::kStagingFull);
  EXPECT_LE(dut.staged_bytes(), params.max_staged_bytes);
  // Everything goes after the staging timeout, and room comes back.
  dut.Poll(T(6.0));
  EXPECT_EQ(dut.staged_bytes(), 0);
  EXPECT_EQ(StageTile(dut, cut.tiles.front(), false, 6.1), Intake::kHeld);
}

TEST_F(SaveAssemblerTest, APushWaitsForItsOctomapAndObstacles) {
  SaveAssembler dut(store_, Params());
  Stage(dut, 11);
  SaveRequest request = PushRequest(snapshot_);
  request.expect_obstacles = true;
  request.expect_octomap = true;
  EXPECT_TRUE(dut.Start(request, T(0.0)).finished.empty());
  EXPECT_EQ(dut.StageObstacles("11/corridor", snapshot_.obstacles, T(0.01)), Intake::kHeld);
  EXPECT_TRUE(dut.OnPushed("11/corridor", T(0.01)).finished.empty());
  OctomapData tree;
  tree.binary = true;
  tree.resolution_m = 0.1;
  tree.bytes = std::string(1000, 'o');
  for (const OctomapChunk& c : SplitOctomap(tree, 400)) {
    EXPECT_EQ(dut.StageOctomapChunk("11/corridor", c, T(0.02)), Intake::kHeld);
  }
  SaveProgress done = dut.OnPushed("11/corridor", T(0.02));
  ASSERT_EQ(done.finished.size(), 1u);
  ASSERT_TRUE(done.finished[0].status.ok());
  EXPECT_EQ(store_.LoadOctomap({"lab", "corridor", 1}).value(), tree);
  EXPECT_EQ(store_.LoadObstacles({"lab", "corridor", 1}).value().obstacles.size(), 2u);
}

// A mapper's live map: the store asks for everything, follows the manifests and tiles that
// come after the request and saves the robot-agnostic layers; a layer of another grid becomes a
// companion map.
TEST_F(SaveAssemblerTest, APullSaveTakesTheLiveMapsRobotAgnosticLayers) {
  SaveAssembler dut(store_, Params());
  const SaveRequest request = PullRequest(21, "tunnel", "rover1");
  SaveProgress started = dut.Start(request, T(0.0));
  EXPECT_EQ(started.new_robots, std::vector<std::string>{"rover1"});
  ASSERT_EQ(started.publish_all.size(), 1u);
  EXPECT_EQ(started.publish_all[0].robot, "rover1");
  EXPECT_TRUE(started.finished.empty());

  common::GridMap live = snapshot_.base;
  live.AddLayer("cost/rover", 0.f);  // a profile layer: left out
  common::GridGeometry fine = live.geometry();
  fine.resolution_m = 0.05;
  fine.size_x *= 4;
  fine.size_y *= 4;
  common::GridMap occupancy(fine);
  occupancy.AddLayer("occupancy", 50.f);
  std::vector<testing::TiledLayer> cuts;
  for (const std::string& layer : live.layer_names()) {
    cuts.push_back(CutLayer(live, layer, 10, "live"));
  }
  cuts.push_back(CutLayer(occupancy, "occupancy", 50, "live"));
  for (const auto& cut : cuts) {
    dut.MirrorManifest("rover1", cut.manifest, T(0.1));
    for (const auto& t : cut.tiles) EXPECT_TRUE(dut.MirrorTile("rover1", t.As()));
  }
  // The mapper's answer lists what it published, its profile layer too.
  MapperLayers reply{started.publish_all[0].request_id, true, live.layer_names()};
  reply.layers.push_back("occupancy");
  EXPECT_TRUE(dut.OnMapperLayers("rover1", reply, T(0.2)).finished.empty());
  EXPECT_TRUE(dut.Poll(T(0.3)).finished.empty());
  SaveProgress later = dut.Poll(T(0.6));  // no obstacles yet: still waiting
  EXPECT_TRUE(later.finished.empty());
  for (const ResendAsk& ask : later.resends) EXPECT_EQ(ask.pull_robot, "rover1");
  dut.MirrorObstacles("rover1", snapshot_.obstacles, T(0.7));
  SaveProgress done = dut.Poll(T(0.8));
  ASSERT_EQ(done.finished.size(), 1u);
  const SaveOutcome& outcome = done.finished[0];
  ASSERT_TRUE(outcome.status.ok()) << outcome.status.ToString();
  EXPECT_EQ(outcome.saved_maps, 2);
  EXPECT_EQ(outcome.layers,
            (std::vector<std::string>{layers::kElevation, layers::kObservationCount}));
  ASSERT_EQ(outcome.maps.size(), 2u);
  EXPECT_EQ(outcome.maps[1].name, "tunnel-occupancy");
  EXPECT_EQ(outcome.message,
            "saved version 1; also tunnel-occupancy v1 (1 layers of another grid)");
  auto info = store_.GetMapInfo({"lab", "tunnel", 1});
  EXPECT_EQ(info->provenance.source_robot, "rover1");
  EXPECT_EQ(info->num_obstacles, 2);
  EXPECT_TRUE(store_.GetMapInfo({"lab", "tunnel-occupancy", 1}).ok());
}

// Issue 21 (found by the bus-fault test under 5 % loss): a pull naming no layers took every
// robot-agnostic layer announced within pull_settle_s of its request. A manifest lost in that
// window left its layer out of the save, which replied OK. Now the save waits for the mapper's
// list of its layers and asks for each one missing, like a named layer.
TEST_F(SaveAssemblerTest, APullWaitsForEveryLayerTheMapperListsAndAsksForALostManifest) {
  SaveAssembler dut(store_, Params());
  SaveProgress started = dut.Start(PullRequest(61, "tunnel", "rover1"), T(0.0));
  ASSERT_EQ(started.publish_all.size(), 1u);
  const int64_t id = started.publish_all[0].request_id;
  const std::vector<std::string> names = snapshot_.base.layer_names();
  ASSERT_EQ(names.size(), 2u);
  const auto kept = CutLayer(snapshot_.base, names[0], 10, "live");
  const auto lost = CutLayer(snapshot_.base, names[1], 10, "live");
  dut.MirrorManifest("rover1", kept.manifest, T(0.1));
  for (const auto& t : kept.tiles) dut.MirrorTile("rover1", t.As());
  dut.MirrorObstacles("rover1", snapshot_.obstacles, T(0.1));
  // The second layer's manifest is lost on the link (its tiles came).
  for (const auto& t : lost.tiles) dut.MirrorTile("rover1", t.As());
  // Answers to other requests (or another robot's) are not the save's.
  EXPECT_TRUE(dut.OnMapperLayers("rover1", {id + 1, true, {names[0]}}, T(0.15)).finished.empty());
  EXPECT_TRUE(dut.OnMapperLayers("rover2", {id, true, {names[0]}}, T(0.15)).finished.empty());
  EXPECT_TRUE(dut.OnMapperLayers("rover1", {id, true, {names[0], names[1], "cost/rover"}}, T(0.2))
                  .finished.empty());
  // Past the settle window the save still waits (it saved one layer of two before), asking for
  // the lost layer whole: its manifest comes with it.
  bool asked = false;
  for (double t = 0.6; t < 1.5; t += 0.1) {
    SaveProgress p = dut.Poll(T(t));
    EXPECT_TRUE(p.finished.empty()) << "saved at " << t << " s without " << names[1];
    EXPECT_TRUE(p.publish_all.empty());  // the answer came: no need to ask again
    for (const ResendAsk& ask : p.resends) {
      EXPECT_NE(ask.tiles.layer, names[0]);
      EXPECT_NE(ask.tiles.layer, "cost/rover");  // a profile layer is never waited for
      if (ask.tiles.layer != names[1]) continue;
      asked = true;
      EXPECT_EQ(ask.pull_robot, "rover1");
      EXPECT_EQ(ask.tiles.map_name, "live");
      EXPECT_TRUE(ask.tiles.tiles.empty());
    }
  }
  EXPECT_TRUE(asked) << names[1] << " was never asked for";
  dut.MirrorManifest("rover1", lost.manifest, T(1.5));  // the mapper answers with the layer
  for (const auto& t : lost.tiles) dut.MirrorTile("rover1", t.As());
  SaveProgress done = dut.Poll(T(1.6));
  ASSERT_EQ(done.finished.size(), 1u);
  ASSERT_TRUE(done.finished[0].status.ok()) << done.finished[0].status.ToString();
  EXPECT_EQ(done.finished[0].layers, names);
  auto stored = store_.LoadLayers({"lab", "tunnel", 1}, {});
  ASSERT_TRUE(stored.ok());
  for (const std::string& layer : names) {
    EXPECT_TRUE(SameLayer(stored->at(layer), snapshot_.base.at(layer))) << layer;
  }
}

// Until the mapper answers, the save sends the same request again every resend round (a mapper
// answers a replay from its cache, without publishing again). A mapper that never answers (one
// older than the list) gets 4 x pull_settle_s; then the layers announced are taken.
TEST_F(SaveAssemblerTest, APullWithoutTheMappersAnswerAsksAgainThenTakesTheLayersAnnounced) {
  SaveAssemblerParams params = Params();
  params.save_timeout_s = 5.0;
  SaveAssembler dut(store_, params);
  SaveProgress started = dut.Start(PullRequest(71, "tunnel", "rover1"), T(0.0));
  ASSERT_EQ(started.publish_all.size(), 1u);
  const int64_t id = started.publish_all[0].request_id;
  for (const std::string& layer : snapshot_.base.layer_names()) {
    const auto cut = CutLayer(snapshot_.base, layer, 10, "live");
    dut.MirrorManifest("rover1", cut.manifest, T(0.1));
    for (const auto& t : cut.tiles) dut.MirrorTile("rover1", t.As());
  }
  dut.MirrorObstacles("rover1", snapshot_.obstacles, T(0.1));
  int asks = 0;
  for (double t = 0.3; t < 1.95; t += 0.05) {
    SaveProgress p = dut.Poll(T(t));
    EXPECT_TRUE(p.finished.empty()) << "saved at " << t << " s before the mapper answered";
    for (const PublishAllAsk& ask : p.publish_all) {
      EXPECT_EQ(ask.robot, "rover1");
      EXPECT_EQ(ask.request_id, id);  // the same request: not a second publication
      ++asks;
    }
  }
  EXPECT_GE(asks, 10);  // every resend round (0.1 s) from pull_settle_s on
  EXPECT_LE(asks, 16);
  SaveProgress done = dut.Poll(T(2.05));
  ASSERT_EQ(done.finished.size(), 1u);
  ASSERT_TRUE(done.finished[0].status.ok()) << done.finished[0].status.ToString();
  EXPECT_EQ(done.finished[0].layers, snapshot_.base.layer_names());
  // Request ids differ between saves and start above the base a process gives.
  dut.set_publish_all_id_base(1000);
  SaveProgress second = dut.Start(PullRequest(72, "tunnel", "rover1"), T(3.0));
  ASSERT_EQ(second.publish_all.size(), 1u);
  EXPECT_EQ(second.publish_all[0].request_id, 1001);
}

TEST_F(SaveAssemblerTest, APullSaveOnlyTakesManifestsNewerThanItsRequest) {
  SaveAssembler dut(store_, Params());
  SaveRequest request = PullRequest(21, "tunnel", "rover1");
  request.layers = {layers::kElevation};
  dut.Start(request, T(0.0));  // follows rover1 from now on
  const auto cut = CutLayer(snapshot_.base, layers::kElevation, 10, "live");
  dut.MirrorManifest("rover1", cut.manifest, T(0.1));
  for (const auto& t : cut.tiles) dut.MirrorTile("rover1", t.As());
  dut.MirrorObstacles("rover1", {}, T(0.1));
  ASSERT_EQ(dut.Poll(T(0.2)).finished.size(), 1u);
  // A second pull: the manifest it has is older than the request, so it asks for the layer.
  request.request_id = 22;
  SaveProgress second = dut.Start(request, T(1.0));
  EXPECT_TRUE(second.new_robots.empty());  // followed already
  SaveProgress waiting = dut.Poll(T(1.6));
  EXPECT_TRUE(waiting.finished.empty());
  ASSERT_FALSE(waiting.resends.empty());
  EXPECT_EQ(waiting.resends[0].tiles.layer, layers::kElevation);
  EXPECT_EQ(waiting.resends[0].tiles.map_name, "live");
  EXPECT_TRUE(waiting.resends[0].tiles.tiles.empty());  // the whole layer
  dut.MirrorManifest("rover1", cut.manifest, T(1.7));
  dut.MirrorObstacles("rover1", {}, T(1.7));
  SaveProgress done = dut.Poll(T(1.8));
  ASSERT_EQ(done.finished.size(), 1u);
  EXPECT_EQ(done.finished[0].version, 2);
}

// Issue 20 (found by the bus-fault test): the registry travels as one message. Lost on a
// lossy link, a pull save waited 4 x pull_settle_s and then saved the map without its
// obstacles, replying OK. Now it asks the mapper for the registry again ("#obstacles") every
// round, and a mapper known to keep one is waited for: the save stores the obstacles when they
// come, or fails naming them when they never do.
TEST_F(SaveAssemblerTest, APullSaveAsksForALostRegistryAndNeverSavesWithoutIt) {
  SaveAssembler dut(store_, Params());
  SaveRequest request = PullRequest(41, "tunnel", "rover1");
  request.layers = {layers::kElevation};
  const auto cut = CutLayer(snapshot_.base, layers::kElevation, 10, "live");
  auto send_layer = [&](double t) {
    dut.MirrorManifest("rover1", cut.manifest, T(t));
    for (const auto& tile : cut.tiles) dut.MirrorTile("rover1", tile.As());
  };
  dut.Start(request, T(0.0));
  send_layer(0.1);
  dut.MirrorObstacles("rover1", snapshot_.obstacles, T(0.1));
  ASSERT_EQ(dut.Poll(T(0.2)).finished.size(), 1u);  // the mapper keeps a registry
  // A second pull whose registry is lost: the layer arrives, the obstacles do not.
  request.request_id = 42;
  dut.Start(request, T(1.0));
  send_layer(1.1);
  bool asked = false;
  for (double t = 1.2; t < 2.9; t += 0.1) {
    SaveProgress p = dut.Poll(T(t));
    EXPECT_TRUE(p.finished.empty()) << "saved at " << t << " s without its obstacles";
    for (const ResendAsk& ask : p.resends) {
      if (ask.tiles.layer == kResendObstacles) {
        asked = true;
        EXPECT_EQ(ask.pull_robot, "rover1");
        EXPECT_EQ(ask.tiles.map_name, "live");
      }
    }
  }
  EXPECT_TRUE(asked) << "the registry was never asked for again";
  dut.MirrorObstacles("rover1", snapshot_.obstacles, T(2.9));
  SaveProgress done = dut.Poll(T(2.95));
  ASSERT_EQ(done.finished.size(), 1u);
  ASSERT_TRUE(done.finished[0].status.ok()) << done.finished[0].status.ToString();
  EXPECT_EQ(store_.LoadObstacles({"lab", "tunnel", 2}).value().obstacles.size(), 2u);
  // A third whose registry never comes: it fails, naming what it waited for.
  request.request_id = 43;
  dut.Start(request, T(5.0));
  send_layer(5.1);
  SaveProgress failed = dut.Poll(T(7.5));
  ASSERT_EQ(failed.finished.size(), 1u);
  EXPECT_FALSE(failed.finished[0].status.ok());
  EXPECT_NE(failed.finished[0].status.message().find("obstacles"), std::string::npos)
      << failed.finished[0].status.message();
  EXPECT_FALSE(store_.GetMapInfo({"lab", "tunnel", 3}).ok());
}

// A mapper never heard to keep a registry (no terrain layer): asked, then saved without one.
TEST_F(SaveAssemblerTest, APullFromAMapperWithoutARegistrySavesAfterAWhile) {
  SaveAssembler dut(store_, Params());
  SaveRequest request = PullRequest(51, "sonar", "auv");
  request.layers = {layers::kElevation};
  dut.Start(request, T(0.0));
  const auto cut = CutLayer(snapshot_.base, layers::kElevation, 10, "live");
  dut.MirrorManifest("auv", cut.manifest, T(0.1));
  for (const auto& tile : cut.tiles) dut.MirrorTile("auv", tile.As());
  SaveProgress waiting = dut.Poll(T(0.6));
  EXPECT_TRUE(waiting.finished.empty());
  ASSERT_FALSE(waiting.resends.empty());
  EXPECT_EQ(waiting.resends.back().tiles.layer, kResendObstacles);
  SaveProgress done = dut.Poll(T(2.1));  // past 4 x pull_settle_s
  ASSERT_EQ(done.finished.size(), 1u);
  EXPECT_TRUE(done.finished[0].status.ok());
}

TEST_F(SaveAssemblerTest, APullFromARobotWithoutAMapperTimesOut) {
  SaveAssembler dut(store_, Params());
  dut.Start(PullRequest(31, "nothing", "ghost"), T(0.0));
  SaveProgress p = dut.Poll(T(2.5));
  ASSERT_EQ(p.finished.size(), 1u);
  EXPECT_EQ(p.finished[0].status.message(),
            "timed out after 2 s waiting for: any layer (is the mapper of 'ghost' running?)");
}

}  // namespace
}  // namespace cairn::mapstore
