// cairn-mapstore as a real process on a private bus: push and pull saves, loads, lists, errors,
// replays, bad input, read-only use, export and import.

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <signal.h>
#include <sys/stat.h>

#include "cairn/lcmt_map_control_reply.hpp"
#include "cairn/lcmt_map_control_request.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"

#include "common/channels.h"
#include "services/runtime/tiler.h"
#include "tests/integration/mapstore/mapstore_fixture.h"

namespace cairn::mapstore::testing {
namespace {

namespace fs = std::filesystem;

MapSnapshot WithObstaclesAndOctomap(MapSnapshot s) {
  common::Obstacle ramp;
  ramp.id = 4;
  ramp.kind = common::ObstacleKind::kRamp;
  ramp.centroid_m = {1.0, 0.5};
  ramp.outline_m = {{0.5, 0.0}, {1.5, 0.0}, {1.5, 1.0}, {0.5, 1.0}};
  ramp.slope_rad = 0.1745;
  ramp.height_m = 0.17;
  ramp.depth_m = std::nan("");
  ramp.verdicts = {{"pioneer3at", "x", false, "slope 10.0 deg > 8.0 deg"}};
  common::Obstacle wall;
  wall.id = 9;
  wall.kind = common::ObstacleKind::kWallOrObject;
  wall.centroid_m = {-1.0, 2.0};
  wall.height_m = 1.2;
  s.obstacles.obstacles = {ramp, wall};
  octomap::OcTree tree(0.1);
  for (int i = 0; i < 50; ++i) tree.updateNode(octomap::point3d(i * 0.1f, 0.2f, 0.5f), true);
  std::ostringstream bytes;
  tree.writeBinary(bytes);
  s.octomap = OctomapData{true, 0.1, bytes.str()};
  return s;
}

int64_t Counter(const cairn::lcmt_health& h, const std::string& name) {
  for (int i = 0; i < h.num_counters; ++i) {
    if (h.counter_names[i] == name) return h.counter_values[i];
  }
  return 0;
}

class MapstoreServiceTest : public ::testing::Test {
 protected:
  MapstoreServiceTest()
      : procs_(cairn::testing::PrivateLcmUrl()),
        lcm_(procs_.url()),
        client_(lcm_, "test-client", TestClientOptions()) {}

  // The store on the shipped configuration (OP_DELETE off), or on a copy that allows deletes.
  ChildProcess& StartStore(bool allow_delete = false) {
    db_ = procs_.dir() + "/site.db";
    std::string config = SourcePath("config/mapstore/mapstore.yaml");
    if (allow_delete) {
      std::ifstream in(config);
      std::stringstream text;
      text << in.rdbuf();
      std::string yaml = text.str();
      const std::string off = "allow_delete: false";
      EXPECT_NE(yaml.find(off), std::string::npos) << "the shipped store no longer says " << off;
      if (yaml.find(off) != std::string::npos)
        yaml.replace(yaml.find(off), off.size(), "allow_delete: true");
      config = procs_.dir() + "/mapstore.yaml";
      std::ofstream(config) << yaml;
    }
    ChildProcess& p = procs_.Start("cairn-mapstore", {"--db", db_, "--config", config,
                                                      "--files-root", procs_.dir() + "/files"});
    EXPECT_TRUE(WaitForStore(client_)) << "cairn-mapstore did not answer";
    return p;
  }

  ProcessSet procs_;
  lcm::LCM lcm_;
  MapstoreClient client_;
  std::string db_;
};

TEST_F(MapstoreServiceTest, PushSaveThenLoadGivesBackEverything) {
  StartStore();
  const MapSnapshot s = WithObstaclesAndOctomap(TerrainSnapshot("lab", "corridor", 230, 150, 0.f));
  auto saved = client_.Save(s);
  ASSERT_TRUE(saved.ok()) << saved.status().ToString();
  ASSERT_EQ(saved->status, kStatusOk) << saved->message;
  EXPECT_EQ(saved->version, 1);
  EXPECT_EQ(saved->layers, (std::vector<std::string>{"elevation", "elevation_variance"}));

  auto loaded =
      client_.Load("lab", "corridor", 0, "", {"elevation", "elevation_variance", "octomap"});
  ASSERT_TRUE(loaded.ok()) << loaded.status().ToString();
  EXPECT_EQ(loaded->reply.version, 1);
  EXPECT_EQ(loaded->layers.geometry(), s.base.geometry());
  EXPECT_TRUE(SameLayer(loaded->layers.at("elevation"), s.base.at("elevation")));
  EXPECT_TRUE(SameLayer(loaded->layers.at("elevation_variance"), s.base.at("elevation_variance")));
  ASSERT_TRUE(loaded->octomap.has_value());
  EXPECT_EQ(*loaded->octomap, *s.octomap);
  ASSERT_EQ(loaded->obstacles.obstacles.size(), 2u);
  EXPECT_EQ(loaded->obstacles.obstacles[0].id, 4);
  EXPECT_EQ(loaded->obstacles.obstacles[0].outline_m, s.obstacles.obstacles[0].outline_m);
  EXPECT_EQ(loaded->obstacles.obstacles[0].verdicts, s.obstacles.obstacles[0].verdicts);

  auto list = client_.Call(MakeRequest(Request::OP_LIST_MAPS, "lab"));
  ASSERT_TRUE(list.ok());
  ASSERT_EQ(list->num_maps, 1);
  EXPECT_EQ(list->maps[0].name, "corridor");
  EXPECT_EQ(list->maps[0].source_robot, "rover1");
  EXPECT_EQ(list->maps[0].num_obstacles, 2);

  // Places and profiles round-trip too.
  Request place = MakeRequest(Request::OP_PUT_PLACE, "lab");
  cairn::lcmt_place kitchen{};
  kitchen.name = "kitchen";
  kitchen.num_vertices = 3;
  kitchen.x_m = {0, 4, 4};
  kitchen.y_m = {0, 0, 3};
  place.places = {kitchen};
  ASSERT_EQ(client_.Call(place)->status, kStatusOk);
  auto places = client_.Call(MakeRequest(Request::OP_LIST_PLACES, "lab"));
  ASSERT_EQ(places->num_places, 1);
  EXPECT_EQ(places->places[0].name, "kitchen");
  ASSERT_EQ(client_.Call(PutProfileRequest(ShippedProfile("rover")))->status, kStatusOk);
  Request get = MakeRequest(Request::OP_GET_PROFILE);
  get.profile = "rover";
  auto profile = client_.Call(get);
  ASSERT_EQ(profile->num_profiles, 1);
  EXPECT_EQ(profile->profiles[0].content_hash, ShippedProfile("rover").ContentHash());
}

TEST_F(MapstoreServiceTest, UnknownThingsAreNotFoundAndBadNamesInvalid) {
  ChildProcess& store = StartStore();
  ASSERT_EQ(client_.Save(TerrainSnapshot("lab", "corridor", 40, 30, 0.f))->status, kStatusOk);
  auto no_map = client_.Load("lab", "attic", 0, "");
  EXPECT_EQ(no_map.status().code(), common::StatusCode::kNotFound);
  EXPECT_NE(no_map.status().message().find("attic"), std::string::npos);
  auto no_version = client_.Load("lab", "corridor", 7, "");
  EXPECT_EQ(no_version.status().code(), common::StatusCode::kNotFound);
  auto no_profile = client_.Load("lab", "corridor", 0, "hovercraft");
  EXPECT_EQ(no_profile.status().code(), common::StatusCode::kNotFound);
  EXPECT_NE(no_profile.status().message().find("hovercraft"), std::string::npos);
  Request get = MakeRequest(Request::OP_GET_PROFILE);
  get.profile = "hovercraft";
  EXPECT_EQ(client_.Call(get)->status, kStatusNotFound);
  Request share = MakeRequest(Request::OP_SHARE, "lab", "corridor");
  share.profile = "hovercraft";
  EXPECT_EQ(client_.Call(share)->status, kStatusNotFound);
  auto bad = client_.Call(MakeRequest(Request::OP_LOAD, "lab", "../../etc/passwd"));
  ASSERT_TRUE(bad.ok());
  EXPECT_EQ(bad->status, kStatusInvalid);
  EXPECT_NE(bad->message.find("map name"), std::string::npos);
  // Issue 20: OP_DELETE is off in the shipped configuration: refused, with an audit line, and
  // the map is kept. A store configured to allow it deletes.
  Request del = MakeRequest(Request::OP_DELETE, "lab", "corridor");
  auto refused = client_.Call(del);
  ASSERT_TRUE(refused.ok());
  EXPECT_EQ(refused->status, +Reply::STATUS_FORBIDDEN);
  EXPECT_NE(refused->message.find("allow_delete"), std::string::npos) << refused->message;
  EXPECT_TRUE(client_.Load("lab", "corridor", 0, "").ok());
  EXPECT_TRUE(
      WaitFor([&] { return store.Log().find("refused OP_DELETE") != std::string::npos; }, 5.0))
      << store.Log();
  store.Stop();
  StartStore(/*allow_delete=*/true);
  del.request_id += 1000;
  EXPECT_EQ(client_.Call(del)->status, kStatusOk);
  auto deleted = client_.Load("lab", "corridor", 0, "");
  EXPECT_EQ(deleted.status().code(), common::StatusCode::kNotFound);
  EXPECT_NE(deleted.status().message().find("deleted"), std::string::npos);
}

TEST_F(MapstoreServiceTest, ReplayedRequestsReturnTheFirstReplyEvenAfterARestart) {
  ChildProcess& first_store = StartStore();
  auto first = client_.Save(TerrainSnapshot("lab", "corridor", 60, 40, 0.f));
  ASSERT_TRUE(first.ok() && first->status == kStatusOk);
  // The same save request again: same reply, no new version.
  Request replay = MakeRequest(Request::OP_SAVE, "lab", "corridor");
  replay.request_id = first->request_id;
  replay.requester = "test-client";
  replay.layers = {"elevation", "elevation_variance"};
  auto again = client_.Call(replay);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->status, kStatusOk);
  EXPECT_EQ(again->version, first->version);
  EXPECT_EQ(again->duration_us, first->duration_us);  // the very first reply
  // After a restart the audit log still knows the request.
  first_store.Stop();
  StartStore();
  auto after = client_.Call(replay);
  ASSERT_TRUE(after.ok());
  EXPECT_EQ(after->status, kStatusOk) << after->message;
  EXPECT_EQ(after->version, first->version);
  auto list = client_.Call(MakeRequest(Request::OP_LIST_MAPS, "lab", "corridor"));
  EXPECT_EQ(list->num_maps, 1);  // every version of corridor: still only one
}

TEST_F(MapstoreServiceTest, BadInputIsCountedAndNeverCrashesTheService) {
  ChildProcess& store = StartStore();
  cairn::testing::Bus bus(procs_.url());
  // Garbage and truncated messages on every input channel.
  const std::string junk(300, '\x5a');
  for (const char* channel : {channels::kMapstoreRequest, channels::kMapstorePushTiles,
                              channels::kMapstorePushManifest, channels::kMapstoreTileResend}) {
    lcm_.publish(channel, junk.data(), static_cast<unsigned>(junk.size()));
  }
  Request valid = MakeRequest(Request::OP_LIST_MAPS);
  valid.request_id = 77;
  std::vector<uint8_t> buf(valid.getEncodedSize());
  valid.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm_.publish(channels::kMapstoreRequest, buf.data(), static_cast<unsigned>(buf.size() / 2));
  // Well-formed requests carrying bad values.
  common::RobotProfile nan_profile = ShippedProfile("rover");
  nan_profile.name = "nanbot";
  Request put = PutProfileRequest(nan_profile);
  put.profile_data.max_step_up_m = std::nan("");
  auto refused = client_.Call(put);
  ASSERT_TRUE(refused.ok());
  EXPECT_EQ(refused->status, kStatusInvalid);
  EXPECT_EQ(client_.Call(MakeRequest(99))->status, kStatusInvalid);
  Request place = MakeRequest(Request::OP_PUT_PLACE, "lab");
  cairn::lcmt_place inf_place{};
  inf_place.name = "void";
  inf_place.num_vertices = 3;
  inf_place.x_m = {0, INFINITY, 1};
  inf_place.y_m = {0, 0, 1};
  place.places = {inf_place};
  EXPECT_EQ(client_.Call(place)->status, kStatusInvalid);
  MapSnapshot infinite = TerrainSnapshot("lab", "bad", 30, 20, 0.f);
  infinite.base.at("elevation")(3, 3) = INFINITY;
  EXPECT_EQ(client_.Save(infinite)->status, kStatusInvalid);
  // A pushed tile whose checksum is wrong.
  cairn::lcmt_grid_tile tile{};
  tile.map_name = "5/x";
  tile.layer = "elevation";
  tile.resolution_m = 0.2;
  tile.layer_size_x = tile.layer_size_y = tile.tile_size = tile.cells_x = tile.cells_y = 2;
  tile.num_cells = 4;
  tile.data = {1, 2, 3, 4};
  tile.checksum = 12345;
  lcm_.publish(channels::kMapstorePushTiles, &tile);

  // Still answering, and HEALTH says what it refused.
  ASSERT_EQ(client_.Call(MakeRequest(Request::OP_LIST_MAPS))->status, kStatusOk);
  ASSERT_TRUE(WaitFor(
      [&] {
        auto h = bus.Health("cairn-mapstore");
        return h && h->decode_errors >= 5 && h->dropped_inputs >= 5;
      },
      10.0, [&] { bus.Pump(50); }))
      << "decode_errors/dropped_inputs not reported";
  const auto health = bus.Health("cairn-mapstore");
  EXPECT_GE(Counter(*health, "invalid_requests"), 4);
  EXPECT_TRUE(store.Running());
}

TEST_F(MapstoreServiceTest, ReadOnlyUseNeverChangesTheDatabase) {
  {
    ChildProcess& writer = StartStore();
    ASSERT_EQ(client_.Call(PutProfileRequest(ShippedProfile("pioneer3at")))->status, kStatusOk);
    ASSERT_EQ(client_.Call(PutProfileRequest(ShippedProfile("rover")))->status, kStatusOk);
    ASSERT_EQ(
        client_.Save(WithObstaclesAndOctomap(TerrainSnapshot("lab", "corridor", 80, 60, 0.f)))
            ->status,
        kStatusOk);
    // A clean stop (SIGTERM) exits 0.
    const int status = writer.Stop();
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "exit status " << status;
  }
  const std::string before = ReadAll(db_);
  struct stat st_before {};
  ASSERT_EQ(stat(db_.c_str(), &st_before), 0);

  ChildProcess& store = StartStore();
  auto maps = client_.Call(MakeRequest(Request::OP_LIST_MAPS));
  ASSERT_EQ(maps->num_maps, 1);
  ASSERT_EQ(client_.Call(MakeRequest(Request::OP_LIST_PROFILES))->num_profiles, 2);
  EXPECT_EQ(client_.Call(MakeRequest(Request::OP_LIST_PLACES, "lab"))->status, kStatusOk);
  ASSERT_TRUE(client_.Load("lab", "corridor", 0, "", {"elevation", "octomap"}).ok());
  Request obstacles = MakeRequest(Request::OP_LOAD_OBSTACLES, "lab", "corridor");
  ASSERT_EQ(client_.Call(obstacles)->num_obstacles, 2);
  Request get = MakeRequest(Request::OP_GET_PROFILE);
  get.profile = "rover";
  ASSERT_EQ(client_.Call(get)->status, kStatusOk);
  // A load for a profile that was never shared derives without writing.
  auto derived = client_.Load("lab", "corridor", 0, "rover");
  ASSERT_TRUE(derived.ok()) << derived.status().ToString();
  EXPECT_TRUE(derived->layers.HasLayer("cost/rover"));
  store.Signal(SIGTERM);
  auto status = store.WaitExit(15.0);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0);
  struct stat st_after {};
  ASSERT_EQ(stat(db_.c_str(), &st_after), 0);
  EXPECT_EQ(st_after.st_mtim.tv_sec, st_before.st_mtim.tv_sec);
  EXPECT_EQ(st_after.st_mtim.tv_nsec, st_before.st_mtim.tv_nsec);
  EXPECT_TRUE(ReadAll(db_) == before) << "the database file changed";
}

// Plays a mapper: publishes its live map on <robot>.MAP.*, republishes everything on
// OP_PUBLISH_ALL (once per request id, as cairn-mapper: a replay is answered from its cache)
// with a reply listing the layers, and answers resend requests.
class FakeMapper {
 public:
  FakeMapper(lcm::LCM& lcm, std::string robot, common::GridMap map,
             common::ObstacleRegistry obstacles)
      : lcm_(lcm),
        robot_(std::move(robot)),
        map_(std::move(map)),
        obstacles_(std::move(obstacles)),
        tiler_(robot_, "live") {
    subs_.push_back(lcm_.subscribe(channels::ForRobot(robot_, channels::kMapControl),
                                   &FakeMapper::OnControl, this));
    subs_.push_back(lcm_.subscribe(channels::ForRobot(robot_, channels::kMapTileResend),
                                   &FakeMapper::OnResend, this));
  }
  ~FakeMapper() {
    for (auto* s : subs_) lcm_.unsubscribe(s);
  }
  void PublishAll() {
    for (const std::string& layer : map_.layer_names()) {
      const bool occupancy = layer == layers::kOccupancy;
      auto batch = tiler_.Update(
          map_, layer,
          occupancy ? runtime::TileEncoding::kOccupancy : runtime::TileEncoding::kFloat, 1, true);
      lcm_.publish(channels::ForRobot(robot_, channels::kMapManifest), &batch.manifest);
      for (const auto& t : batch.tiles) {
        // The first round loses a tile of the elevation, as UDP may.
        if (!dropped_ && layer == layers::kElevation) {
          dropped_ = true;
          continue;
        }
        lcm_.publish(channels::ForRobot(robot_, channels::kMapTiles), &t);
      }
      for (const auto& t : batch.occupancy_tiles) {
        lcm_.publish(channels::ForRobot(robot_, channels::kMapOccupancy), &t);
      }
    }
    const auto registry = runtime::ToLcm(obstacles_, 1, robot_, "live");
    lcm_.publish(channels::ForRobot(robot_, channels::kMapObstacles), &registry);
  }
  int resends() const { return resends_; }
  int publish_all() const { return publish_all_; }

 private:
  void OnControl(const lcm::ReceiveBuffer*, const std::string&,
                 const cairn::lcmt_map_control_request* m) {
    if (m->op != cairn::lcmt_map_control_request::OP_PUBLISH_ALL) return;
    if (answered_.insert(m->request_id).second) {
      ++publish_all_;
      PublishAll();
    }
    cairn::lcmt_map_control_reply reply{};
    reply.request_id = m->request_id;
    reply.status = cairn::lcmt_map_control_reply::STATUS_OK;
    reply.layers = map_.layer_names();
    reply.num_layers = static_cast<int32_t>(reply.layers.size());
    lcm_.publish(channels::ForRobot(robot_, channels::kMapControlReply), &reply);
  }
  void OnResend(const lcm::ReceiveBuffer*, const std::string&,
                const cairn::lcmt_tile_resend_request* m) {
    ++resends_;
    auto batch = tiler_.Resend(*m);
    lcm_.publish(channels::ForRobot(robot_, channels::kMapManifest), &batch.manifest);
    for (const auto& t : batch.tiles)
      lcm_.publish(channels::ForRobot(robot_, channels::kMapTiles), &t);
    for (const auto& t : batch.occupancy_tiles) {
      lcm_.publish(channels::ForRobot(robot_, channels::kMapOccupancy), &t);
    }
  }

  lcm::LCM& lcm_;
  std::string robot_;
  common::GridMap map_;
  common::ObstacleRegistry obstacles_;
  runtime::LayerTiler tiler_;
  std::vector<lcm::Subscription*> subs_;
  bool dropped_{false};
  int resends_{0};
  int publish_all_{0};
  std::set<int64_t> answered_;
};

TEST_F(MapstoreServiceTest, PullSaveTakesTheMappersRobotAgnosticLayers) {
  StartStore();
  MapSnapshot s = WithObstaclesAndOctomap(TerrainSnapshot("lab", "yard", 250, 120, 0.f));
  common::GridMap live = s.base;
  live.AddLayer(layers::CostLayer("pioneer3at"), 0.f);  // profile layers are not saved
  common::Layer& occ = live.AddLayer(layers::kOccupancy, 0.f);
  occ.block(10, 10, 5, 50).setConstant(100.f);
  occ(0, 0) = common::kUnknown;
  FakeMapper mapper(lcm_, "rover7", live, s.obstacles);

  Request save = MakeRequest(Request::OP_SAVE, "lab", "yard");
  save.robot = "rover7";
  save.profile = "pioneer3at";
  save.code_version = "mapping-test";
  auto reply = client_.Call(save);
  ASSERT_TRUE(reply.ok()) << reply.status().ToString();
  ASSERT_EQ(reply->status, kStatusOk) << reply->message;
  EXPECT_EQ(mapper.publish_all(), 1);  // asked again only with the same request id
  EXPECT_GE(mapper.resends(), 1);      // the dropped tile was asked for again
  EXPECT_EQ(reply->layers,
            (std::vector<std::string>{"elevation", "elevation_variance", "occupancy"}));
  auto loaded = client_.Load("lab", "yard", reply->version, "");
  ASSERT_TRUE(loaded.ok()) << loaded.status().ToString();
  EXPECT_TRUE(SameLayer(loaded->layers.at("elevation"), s.base.at("elevation")));
  EXPECT_TRUE(SameLayer(loaded->layers.at("occupancy"), occ));
  EXPECT_EQ(loaded->obstacles.obstacles.size(), 2u);
  auto list = client_.Call(MakeRequest(Request::OP_LIST_MAPS, "lab", "yard"));
  ASSERT_EQ(list->num_maps, 1);
  EXPECT_EQ(list->maps[0].source_robot, "rover7");
  EXPECT_EQ(list->maps[0].code_version, "mapping-test");
}

TEST_F(MapstoreServiceTest, ExportAndImportStayInTheFilesFolder) {
  StartStore();
  MapSnapshot s = TerrainSnapshot("lab", "flat", 64, 48, 0.f);
  common::Layer& stat = s.base.AddLayer(layers::kStaticMap, 0.f);
  stat.row(20).setConstant(100.f);
  stat(5, 5) = 37.f;
  stat(6, 6) = common::kUnknown;
  ASSERT_EQ(client_.Save(s)->status, kStatusOk);

  Request exp = MakeRequest(Request::OP_EXPORT, "lab", "flat");
  exp.format = "ros-raw";
  exp.path = "exports";
  exp.layers = {"static"};
  auto exported = client_.Call(exp);
  ASSERT_EQ(exported->status, kStatusOk) << exported->message;
  EXPECT_TRUE(fs::exists(procs_.dir() + "/files/exports/flat_v1_static.pgm"));
  Request imp = MakeRequest(Request::OP_IMPORT, "lab", "copy");
  imp.path = "exports/flat_v1_static.yaml";
  auto imported = client_.Call(imp);
  ASSERT_EQ(imported->status, kStatusOk) << imported->message;
  auto copy = client_.Load("lab", "copy", 0, "");
  ASSERT_TRUE(copy.ok());
  EXPECT_TRUE(SameLayer(copy->layers.at("static"), stat));  // raw mode keeps every value

  Request escape = exp;
  escape.path = "../../outside";
  EXPECT_EQ(client_.Call(escape)->status, kStatusInvalid);
  EXPECT_FALSE(fs::exists(procs_.dir() + "/../outside"));
  Request absolute = imp;
  absolute.path = "/etc/passwd";
  EXPECT_EQ(client_.Call(absolute)->status, kStatusInvalid);
}

TEST_F(MapstoreServiceTest, ABadConfigIsRefusedNamingFileAndLine) {
  const std::string config = procs_.dir() + "/bad.yaml";
  std::ofstream(config) << "service:\n  save_timeout_s: 3\n  tiles_per_bust: 4\n";
  ChildProcess& p =
      procs_.Start("cairn-mapstore", {"--db", procs_.dir() + "/x.db", "--config", config});
  auto status = p.WaitExit(10.0);
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(WEXITSTATUS(*status), 2);
  EXPECT_NE(p.Log().find("bad.yaml:3"), std::string::npos) << p.Log();
  EXPECT_NE(p.Log().find("tiles_per_bust"), std::string::npos) << p.Log();
  EXPECT_FALSE(fs::exists(procs_.dir() + "/x.db"));
}

}  // namespace
}  // namespace cairn::mapstore::testing
