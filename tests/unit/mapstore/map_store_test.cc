// One behavioural suite, run on both MapStore implementations.

#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "mapstore/blob_codec.h"
#include "mapstore/in_memory_map_store.h"
#include "mapstore/map_operations.h"
#include "mapstore/sqlite_map_store.h"
#include "tests/support/sample_obstacles.h"
#include "tests/unit/mapstore/fake_deriver.h"

namespace cairn::mapstore {
namespace {

using common::StatusCode;
using testing::FakeDeriver;
using testing::Profile;
using testing::SameLayer;
using testing::SampleSnapshot;

// Builds the store under test.
template <typename T>
std::unique_ptr<MapStore> MakeStore();

template <>
std::unique_ptr<MapStore> MakeStore<InMemoryMapStore>() {
  return std::make_unique<InMemoryMapStore>();
}

template <>
std::unique_ptr<MapStore> MakeStore<SqliteMapStore>() {
  SqliteOptions options;
  options.tile_size_cells = 16;  // several tiles, including partial edge tiles
  auto store = SqliteMapStore::Open(":memory:", options);
  if (!store.ok()) throw std::runtime_error(store.status().ToString());
  return std::move(store).value();
}

template <typename T>
class MapStoreTest : public ::testing::Test {
 protected:
  void SetUp() override { dut_ = MakeStore<T>(); }

  MapInfo Save(const MapSnapshot& s) {
    auto info = dut_->SaveMap(s, ctx_);
    EXPECT_TRUE(info.ok()) << info.status().ToString();
    return info.ok() ? *info : MapInfo{};
  }

  std::unique_ptr<MapStore> dut_;
  WriteContext ctx_{"unit-test", 0, 0};
};

using StoreTypes = ::testing::Types<InMemoryMapStore, SqliteMapStore>;
TYPED_TEST_SUITE(MapStoreTest, StoreTypes);

TYPED_TEST(MapStoreTest, SaveThenLoadReturnsWhatWasSaved) {
  MapSnapshot s = SampleSnapshot("corridor");
  s.octomap = OctomapData{true, 0.1, std::string("\x01\x02\x00\x03octree", 10)};
  const MapInfo info = this->Save(s);
  EXPECT_EQ(info.version, 1);
  EXPECT_EQ(info.site, "lab");
  EXPECT_EQ(info.name, "corridor");
  EXPECT_EQ(info.provenance, s.provenance);
  EXPECT_EQ(info.geometry, s.base.geometry());
  EXPECT_EQ(info.layers, (std::vector<std::string>{"elevation", "observation_count"}));
  EXPECT_EQ(info.num_obstacles, 2);
  EXPECT_TRUE(info.has_octomap);

  auto map = this->dut_->LoadLayers({"lab", "corridor", 0}, {});
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  EXPECT_EQ(map->geometry(), s.base.geometry());
  EXPECT_TRUE(SameLayer(map->at("elevation"), s.base.at("elevation")));
  EXPECT_TRUE(SameLayer(map->at("observation_count"), s.base.at("observation_count")));
  EXPECT_TRUE(std::isnan(map->at("elevation")(0, 0)));

  auto obstacles = this->dut_->LoadObstacles({"lab", "corridor", 1});
  ASSERT_TRUE(obstacles.ok()) << obstacles.status().ToString();
  ASSERT_EQ(obstacles->obstacles.size(), 2u);
  EXPECT_EQ(obstacles->map_version, 1);
  // Sorted by id; measurements, outlines and verdicts kept exactly.
  const common::Obstacle& step = obstacles->obstacles[0];
  const common::Obstacle& ramp = obstacles->obstacles[1];
  EXPECT_EQ(step.id, 3);
  EXPECT_EQ(step.kind, common::ObstacleKind::kStepUp);
  EXPECT_EQ(step.outline_m, s.obstacles.obstacles[1].outline_m);
  EXPECT_EQ(ramp.id, 7);
  EXPECT_DOUBLE_EQ(ramp.slope_rad, 10.0 * M_PI / 180.0);
  EXPECT_TRUE(std::isnan(ramp.depth_m));
  ASSERT_EQ(ramp.verdicts.size(), 1u);
  EXPECT_EQ(ramp.verdicts[0], s.obstacles.obstacles[0].verdicts[0]);

  auto octomap = this->dut_->LoadOctomap({"lab", "corridor", 0});
  ASSERT_TRUE(octomap.ok()) << octomap.status().ToString();
  EXPECT_EQ(*octomap, *s.octomap);
}

TYPED_TEST(MapStoreTest, EverySaveIsANewImmutableVersion) {
  this->Save(SampleSnapshot("corridor", 37, 23, 0.f));
  const MapInfo v2 = this->Save(SampleSnapshot("corridor", 37, 23, 5.f));
  EXPECT_EQ(v2.version, 2);
  auto latest = this->dut_->LoadLayers({"lab", "corridor", 0}, {{"elevation"}, std::nullopt});
  auto first = this->dut_->LoadLayers({"lab", "corridor", 1}, {{"elevation"}, std::nullopt});
  ASSERT_TRUE(latest.ok() && first.ok());
  EXPECT_FLOAT_EQ(latest->at("elevation")(5, 5), 5.f + 0.005f);
  EXPECT_FLOAT_EQ(first->at("elevation")(5, 5), 0.005f);
  auto list = this->dut_->ListMaps({"lab", "", true, false});
  ASSERT_TRUE(list.ok());
  ASSERT_EQ(list->size(), 2u);
  EXPECT_EQ((*list)[0].version, 1);
  EXPECT_EQ((*list)[1].version, 2);
}

TYPED_TEST(MapStoreTest, SoftDeleteHidesVersionsButKeepsNumbering) {
  this->Save(SampleSnapshot("corridor"));
  this->Save(SampleSnapshot("corridor", 37, 23, 1.f));
  ASSERT_TRUE(this->dut_->DeleteMap({"lab", "corridor", 2}, this->ctx_).ok());
  auto latest = this->dut_->GetMapInfo({"lab", "corridor", 0});
  ASSERT_TRUE(latest.ok());
  EXPECT_EQ(latest->version, 1);
  auto deleted = this->dut_->GetMapInfo({"lab", "corridor", 2});
  EXPECT_EQ(deleted.status().code(), StatusCode::kNotFound);
  EXPECT_NE(deleted.status().message().find("deleted"), std::string::npos);

  ASSERT_TRUE(this->dut_->DeleteMap({"lab", "corridor", 0}, this->ctx_).ok());
  auto gone = this->dut_->GetMapInfo({"lab", "corridor", 0});
  EXPECT_EQ(gone.status().code(), StatusCode::kNotFound);
  EXPECT_NE(gone.status().message().find("is deleted"), std::string::npos);
  EXPECT_TRUE(this->dut_->ListMaps({}).value().empty());
  auto with_deleted = this->dut_->ListMaps({"", "", true, true});
  ASSERT_TRUE(with_deleted.ok());
  ASSERT_EQ(with_deleted->size(), 2u);
  EXPECT_TRUE((*with_deleted)[0].deleted);
  // Numbering continues after deleted versions.
  EXPECT_EQ(this->Save(SampleSnapshot("corridor")).version, 3);
}

TYPED_TEST(MapStoreTest, UnknownThingsAreNotFoundWithAMessage) {
  this->Save(SampleSnapshot("corridor"));
  auto map = this->dut_->GetMapInfo({"lab", "nowhere", 0});
  EXPECT_EQ(map.status().code(), StatusCode::kNotFound);
  EXPECT_NE(map.status().message().find("nowhere"), std::string::npos);
  auto site = this->dut_->GetMapInfo({"moon", "corridor", 0});
  EXPECT_EQ(site.status().code(), StatusCode::kNotFound);
  auto version = this->dut_->GetMapInfo({"lab", "corridor", 9});
  EXPECT_EQ(version.status().code(), StatusCode::kNotFound);
  EXPECT_NE(version.status().message().find("no version 9"), std::string::npos);
  auto layer = this->dut_->LoadLayers({"lab", "corridor", 0}, {{"colour"}, std::nullopt});
  EXPECT_EQ(layer.status().code(), StatusCode::kNotFound);
  EXPECT_NE(layer.status().message().find("colour"), std::string::npos);
  EXPECT_NE(layer.status().message().find("elevation"), std::string::npos);
  auto profile = this->dut_->GetProfile("hovercraft");
  EXPECT_EQ(profile.status().code(), StatusCode::kNotFound);
  EXPECT_NE(profile.status().message().find("hovercraft"), std::string::npos);
  auto hash = this->dut_->GetProfileHash("hovercraft");
  EXPECT_EQ(hash.status().code(), StatusCode::kNotFound);
  EXPECT_NE(hash.status().message().find("hovercraft"), std::string::npos);
  auto octomap = this->dut_->LoadOctomap({"lab", "corridor", 0});
  EXPECT_EQ(octomap.status().code(), StatusCode::kNotFound);
  auto places = this->dut_->ListPlaces("moon");
  EXPECT_EQ(places.status().code(), StatusCode::kNotFound);
}

TYPED_TEST(MapStoreTest, BadNamesAndBadMapsAreRefused) {
  for (const std::string& bad :
       std::vector<std::string>{"", "../etc", "a/b", "semi;colon", "-dash", "x'y", "sp ace",
                                std::string(65, 'a'), std::string("nul\0x", 5)}) {
    MapSnapshot s = SampleSnapshot(bad);
    auto r = this->dut_->SaveMap(s, this->ctx_);
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument) << "name '" << bad << "'";
    EXPECT_EQ(this->dut_->GetMapInfo({"lab", bad, 0}).status().code(),
              StatusCode::kInvalidArgument);
  }
  MapSnapshot bad_site = SampleSnapshot("ok");
  bad_site.site = "lab/../../x";
  EXPECT_EQ(this->dut_->SaveMap(bad_site, this->ctx_).status().code(),
            StatusCode::kInvalidArgument);
  MapSnapshot bad_layer = SampleSnapshot("ok");
  bad_layer.base.AddLayer("Bad Layer!");
  EXPECT_EQ(this->dut_->SaveMap(bad_layer, this->ctx_).status().code(),
            StatusCode::kInvalidArgument);
  MapSnapshot no_layers = SampleSnapshot("ok");
  no_layers.base = common::GridMap(no_layers.base.geometry());
  EXPECT_EQ(this->dut_->SaveMap(no_layers, this->ctx_).status().code(),
            StatusCode::kInvalidArgument);
  MapSnapshot dup = SampleSnapshot("ok");
  dup.obstacles.obstacles[1].id = dup.obstacles.obstacles[0].id;
  EXPECT_EQ(this->dut_->SaveMap(dup, this->ctx_).status().code(), StatusCode::kInvalidArgument);
  MapSnapshot bad_kind = SampleSnapshot("ok");
  bad_kind.obstacles.obstacles[0].kind = static_cast<common::ObstacleKind>(9);
  EXPECT_EQ(this->dut_->SaveMap(bad_kind, this->ctx_).status().code(),
            StatusCode::kInvalidArgument);
  // Nothing above was stored.
  EXPECT_TRUE(this->dut_->ListMaps({}).value().empty());
  // Layer names with a profile part are fine.
  MapSnapshot cost = SampleSnapshot("ok");
  cost.base.AddLayer("cost/pioneer3at", 0.f);
  EXPECT_TRUE(this->dut_->SaveMap(cost, this->ctx_).ok());
}

// A load reply sends stored tiles as they are: they must hold exactly the loaded layers.
TYPED_TEST(MapStoreTest, StoredTilesHoldExactlyTheLoadedLayers) {
  MapSnapshot s = SampleSnapshot("corridor", 53, 41);
  for (int iy = 0; iy < 16; ++iy) {
    for (int ix = 0; ix < 16; ++ix) s.base.at(layers::kElevation)(ix, iy) = common::kUnknown;
  }
  this->Save(s);
  auto stored = this->dut_->LoadStoredTiles({"lab", "corridor", 0}, {}, 16);
  ASSERT_TRUE(stored.ok()) << stored.status().ToString();
  ASSERT_EQ(stored->size(), 2u);
  for (const StoredLayer& layer : *stored) {
    SCOPED_TRACE(layer.name);
    ASSERT_EQ(layer.tile_size, 16);
    common::Layer rebuilt = common::Layer::Constant(53, 41, common::kUnknown);
    std::pair<int, int> previous{-1, -1};
    bool has_first_tile = false;
    for (const StoredTile& t : layer.tiles) {
      EXPECT_LT(previous, std::make_pair(t.tile_iy, t.tile_ix)) << "tiles go row by row";
      previous = {t.tile_iy, t.tile_ix};
      has_first_tile |= t.tile_ix == 0 && t.tile_iy == 0;
      EXPECT_EQ(t.cells_x, std::min(16, 53 - 16 * t.tile_ix));
      EXPECT_EQ(t.cells_y, std::min(16, 41 - 16 * t.tile_iy));
      std::vector<float> cells(static_cast<size_t>(t.cells_x) * t.cells_y);
      ASSERT_TRUE(DecodeBlobTo(static_cast<Codec>(t.codec), t.data.data(), t.data.size(),
                               static_cast<int64_t>(cells.size() * sizeof(float)), t.raw_crc32,
                               reinterpret_cast<uint8_t*>(cells.data()), /*verify_crc=*/true)
                      .ok());
      PasteTile({t.tile_ix, t.tile_iy, t.tile_ix * 16, t.tile_iy * 16, t.cells_x, t.cells_y},
                cells.data(), 0, 0, &rebuilt);
    }
    EXPECT_TRUE(SameLayer(rebuilt, s.base.at(layer.name)));
    // An all-unknown tile is not stored (absent = unknown); the other layer has that tile.
    EXPECT_EQ(has_first_tile, layer.name != layers::kElevation);
  }
  auto one = this->dut_->LoadStoredTiles({"lab", "corridor", 0}, {layers::kElevation}, 16);
  ASSERT_TRUE(one.ok());
  ASSERT_EQ(one->size(), 1u);
  EXPECT_EQ(one->front().name, layers::kElevation);
  EXPECT_EQ(this->dut_->LoadStoredTiles({"lab", "corridor", 0}, {"nope"}, 16).status().code(),
            StatusCode::kNotFound);
  EXPECT_EQ(this->dut_->LoadStoredTiles({"lab", "hall", 0}, {}, 16).status().code(),
            StatusCode::kNotFound);
}

TYPED_TEST(MapStoreTest, RegionLoadsMatchTheFullMap) {
  MapSnapshot s = SampleSnapshot("corridor", 53, 41);
  this->Save(s);
  const CellBox box{17, 5, 40, 33};
  auto part = this->dut_->LoadLayers({"lab", "corridor", 0}, {{"elevation"}, box});
  ASSERT_TRUE(part.ok()) << part.status().ToString();
  EXPECT_EQ(part->size_x(), 23);
  EXPECT_EQ(part->size_y(), 28);
  EXPECT_EQ(part->layer_names(), std::vector<std::string>{"elevation"});
  for (int iy = 0; iy < part->size_y(); ++iy) {
    for (int ix = 0; ix < part->size_x(); ++ix) {
      ASSERT_EQ(part->at("elevation")(ix, iy), s.base.at("elevation")(ix + 17, iy + 5));
    }
  }
  // The cropped grid sits where the box is in the world.
  const common::Vector2 centre = part->CenterOf({0, 0});
  const common::Vector2 expected = s.base.CenterOf({17, 5});
  EXPECT_NEAR(centre.x(), expected.x(), 1e-9);
  EXPECT_NEAR(centre.y(), expected.y(), 1e-9);
  // A box partly outside is clipped; one fully outside is refused.
  auto clipped = this->dut_->LoadLayers({"lab", "corridor", 0}, {{}, CellBox{-5, -5, 3, 2}});
  ASSERT_TRUE(clipped.ok());
  EXPECT_EQ(clipped->size_x(), 3);
  EXPECT_EQ(clipped->size_y(), 2);
  auto outside = this->dut_->LoadLayers({"lab", "corridor", 0}, {{}, CellBox{100, 100, 120, 120}});
  EXPECT_EQ(outside.status().code(), StatusCode::kInvalidArgument);
}

TYPED_TEST(MapStoreTest, ProfilesKeepTheirNewestContent) {
  common::RobotProfile p = Profile("pioneer3at", 8.0, 0.03);
  ASSERT_TRUE(this->dut_->PutProfile(p, this->ctx_).ok());
  ASSERT_TRUE(this->dut_->PutProfile(p, this->ctx_).ok());  // same content: no change
  auto audit = this->dut_->ListAudit(10);
  ASSERT_TRUE(audit.ok());
  EXPECT_EQ(audit->size(), 1u);
  auto got = this->dut_->GetProfile("pioneer3at");
  ASSERT_TRUE(got.ok());
  EXPECT_EQ(got->profile, p);
  EXPECT_EQ(got->content_hash, p.ContentHash());

  common::RobotProfile changed = p;
  changed.max_step_up_m = 0.05;
  ASSERT_TRUE(this->dut_->PutProfile(changed, this->ctx_).ok());
  EXPECT_EQ(this->dut_->GetProfile("pioneer3at")->content_hash, changed.ContentHash());
  EXPECT_EQ(this->dut_->GetProfileHash("pioneer3at").value(), changed.ContentHash());
  ASSERT_TRUE(this->dut_->PutProfile(p, this->ctx_).ok());  // back to the first content
  EXPECT_EQ(this->dut_->GetProfile("pioneer3at")->content_hash, p.ContentHash());
  EXPECT_EQ(this->dut_->GetProfileHash("pioneer3at").value(), p.ContentHash());

  ASSERT_TRUE(this->dut_->PutProfile(Profile("rover", 12.0, 0.08), this->ctx_).ok());
  auto list = this->dut_->ListProfiles();
  ASSERT_TRUE(list.ok());
  ASSERT_EQ(list->size(), 2u);
  EXPECT_EQ((*list)[0].profile.name, "pioneer3at");
  EXPECT_EQ((*list)[1].profile.name, "rover");

  common::RobotProfile invalid = p;
  invalid.name = "bad name";
  EXPECT_EQ(this->dut_->PutProfile(invalid, this->ctx_).code(), StatusCode::kInvalidArgument);
  common::RobotProfile negative = p;
  negative.name = "negative";
  negative.max_step_up_m = -1.0;
  EXPECT_EQ(this->dut_->PutProfile(negative, this->ctx_).code(), StatusCode::kInvalidArgument);
}

TYPED_TEST(MapStoreTest, PlacesAreAddedAndReplacedByName) {
  const Place kitchen{"kitchen", {{0, 0}, {4, 0}, {4, 3}, {0, 3}}};
  const Place living{"living room", {{4, 0}, {9, 0}, {9, 5}}};
  ASSERT_TRUE(this->dut_->PutPlaces("flat", {kitchen, living}, this->ctx_).ok());
  Place bigger_kitchen = kitchen;
  bigger_kitchen.polygon_m.push_back({-1, 1.5});
  ASSERT_TRUE(this->dut_->PutPlaces("flat", {bigger_kitchen}, this->ctx_).ok());
  auto places = this->dut_->ListPlaces("flat");
  ASSERT_TRUE(places.ok());
  ASSERT_EQ(places->size(), 2u);
  EXPECT_EQ((*places)[0], bigger_kitchen);
  EXPECT_EQ((*places)[1], living);
  EXPECT_EQ(this->dut_->PutPlaces("flat", {{"x", {{0, 0}, {1, 1}}}}, this->ctx_).code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(this->dut_->PutPlaces("flat", {{"", {{0, 0}, {1, 1}, {1, 0}}}}, this->ctx_).code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(this->dut_->ListSites().value(), std::vector<std::string>{"flat"});
}

// A load of cached derived layers sends the cache's tiles as they are: they must rebuild
// exactly the cached layer and come with the cached verdicts.
TYPED_TEST(MapStoreTest, CachedDerivedTilesRebuildTheCachedLayer) {
  MapSnapshot s = SampleSnapshot("corridor", 53, 41);
  this->Save(s);
  const MapRef ref{"lab", "corridor", 1};
  DerivedProfile d = testing::RoverDerivation(s.base.geometry());
  common::Layer& cost = d.layers.at("cost/rover");
  for (int iy = 0; iy < 41; ++iy) {
    for (int ix = 0; ix < 53; ++ix) cost(ix, iy) = ix < 10 ? common::kUnknown : (ix * 7 + iy) % 101;
  }
  d.layers.AddLayer("slope", 0.1f);
  d.registry.obstacles = {s.obstacles.obstacles[1]};
  ASSERT_TRUE(this->dut_->PutDerived(ref, d, this->ctx_).ok());

  auto hit = this->dut_->FindDerivedTiles(ref, "h1", "c1", {"cost/rover"}, 16);
  ASSERT_TRUE(hit.ok()) << hit.status().ToString();
  ASSERT_TRUE(hit->has_value());
  EXPECT_EQ((*hit)->profile_name, "rover");
  ASSERT_EQ((*hit)->registry.obstacles.size(), 1u);
  EXPECT_EQ((*hit)->registry.obstacles[0].id, s.obstacles.obstacles[1].id);
  ASSERT_EQ((*hit)->layers.size(), 1u);
  const StoredLayer& layer = (*hit)->layers.front();
  EXPECT_EQ(layer.name, "cost/rover");
  ASSERT_GT(layer.tile_size, 0);
  const int ts = layer.tile_size;
  common::Layer rebuilt = common::Layer::Constant(53, 41, common::kUnknown);
  for (const StoredTile& t : layer.tiles) {
    EXPECT_EQ(t.cells_x, std::min(ts, 53 - ts * t.tile_ix));
    EXPECT_EQ(t.cells_y, std::min(ts, 41 - ts * t.tile_iy));
    std::vector<float> cells(static_cast<size_t>(t.cells_x) * t.cells_y);
    ASSERT_TRUE(DecodeBlobTo(static_cast<Codec>(t.codec), t.data.data(), t.data.size(),
                             static_cast<int64_t>(cells.size() * sizeof(float)), t.raw_crc32,
                             reinterpret_cast<uint8_t*>(cells.data()), /*verify_crc=*/true)
                    .ok());
    PasteTile({t.tile_ix, t.tile_iy, t.tile_ix * ts, t.tile_iy * ts, t.cells_x, t.cells_y},
              cells.data(), 0, 0, &rebuilt);
  }
  EXPECT_TRUE(SameLayer(rebuilt, cost));
  auto both = this->dut_->FindDerivedTiles(ref, "h1", "c1", {}, 16);
  ASSERT_TRUE(both.ok() && both->has_value());
  EXPECT_EQ((*both)->layers.size(), 2u);

  EXPECT_FALSE(this->dut_->FindDerivedTiles(ref, "h2", "c1", {}, 16)->has_value());
  EXPECT_FALSE(this->dut_->FindDerivedTiles(ref, "h1", "c2", {}, 16)->has_value());
  EXPECT_EQ(this->dut_->FindDerivedTiles(ref, "h1", "c1", {"cost/pioneer3at"}, 16).status().code(),
            StatusCode::kNotFound);
  EXPECT_EQ(this->dut_->FindDerivedTiles({"lab", "hall", 0}, "h1", "c1", {}, 16).status().code(),
            StatusCode::kNotFound);
}

TYPED_TEST(MapStoreTest, DerivedCacheIsKeyedByVersionProfileHashAndCodeVersion) {
  MapSnapshot s = SampleSnapshot("corridor");
  this->Save(s);
  const MapRef ref{"lab", "corridor", 1};
  DerivedProfile d = testing::RoverDerivation(s.base.geometry());
  d.layers.at("cost/rover")(3, 4) = 100.f;
  d.registry.obstacles = {s.obstacles.obstacles[1]};
  ASSERT_TRUE(this->dut_->PutDerived(ref, d, this->ctx_).ok());
  auto hit = this->dut_->FindDerived(ref, "h1", "c1", {});
  ASSERT_TRUE(hit.ok()) << hit.status().ToString();
  ASSERT_TRUE(hit->has_value());
  EXPECT_EQ((*hit)->profile_name, "rover");
  EXPECT_TRUE(SameLayer((*hit)->layers.at("cost/rover"), d.layers.at("cost/rover")));
  ASSERT_EQ((*hit)->registry.obstacles.size(), 1u);
  EXPECT_EQ((*hit)->registry.obstacles[0].id, 3);
  EXPECT_FALSE(this->dut_->FindDerived(ref, "h2", "c1", {})->has_value());
  EXPECT_FALSE(this->dut_->FindDerived(ref, "h1", "c2", {})->has_value());
  // A second put of the same key keeps the first.
  DerivedProfile other = d;
  other.layers.at("cost/rover").setConstant(50.f);
  ASSERT_TRUE(this->dut_->PutDerived(ref, other, this->ctx_).ok());
  EXPECT_EQ((**this->dut_->FindDerived(ref, "h1", "c1", {})).layers.at("cost/rover")(3, 4), 100.f);
  // Regions work on cached layers too.
  auto part = this->dut_->FindDerived(ref, "h1", "c1", {{"cost/rover"}, CellBox{2, 3, 6, 8}});
  ASSERT_TRUE(part.ok() && part->has_value());
  EXPECT_EQ((*part)->layers.size_x(), 4);
  EXPECT_EQ((*part)->layers.at("cost/rover")(1, 1), 100.f);
  auto listed = this->dut_->ListDerived(ref);
  ASSERT_TRUE(listed.ok());
  ASSERT_EQ(listed->size(), 1u);
  EXPECT_EQ((*listed)[0].profile_name, "rover");
  EXPECT_EQ((*listed)[0].code_version, "c1");
  EXPECT_EQ((*listed)[0].layers, std::vector<std::string>{"cost/rover"});
  // A derivation of another geometry is refused.
  DerivedProfile wrong = d;
  wrong.profile_hash = "h3";
  common::GridGeometry g = s.base.geometry();
  g.size_x += 1;
  wrong.layers = common::GridMap(g);
  wrong.layers.AddLayer("cost/rover", 0.f);
  EXPECT_EQ(this->dut_->PutDerived(ref, wrong, this->ctx_).code(), StatusCode::kInvalidArgument);
}

// A feature blocked for the source profile and crossable one way for the target (the directed
// layer lets it drive down a drop) is a verdict change, though neither verdict is "crossable".
TYPED_TEST(MapStoreTest, SharingCountsAOneWayVerdictAsAChange) {
  ProfileDeriver deriver = FakeDeriver();
  deriver.judge = [](const common::Obstacle&, const common::RobotProfile& profile) {
    common::ObstacleVerdict v;
    v.profile = profile.name;
    v.profile_hash = profile.ContentHash();
    v.crossable = false;
    v.reason = "step up 0.080 m > 0.030 m";
    if (profile.name == "oneway") v.reason += std::string(common::kOneWayMarker) + "downwards";
    return v;
  };
  this->Save(SampleSnapshot("corridor"));
  ASSERT_TRUE(this->dut_->PutProfile(Profile("pioneer3at", 8.0, 0.03), this->ctx_).ok());
  ASSERT_TRUE(this->dut_->PutProfile(Profile("oneway", 8.0, 0.03), this->ctx_).ok());
  auto shared = ShareMap(*this->dut_, deriver, {"lab", "corridor", 0}, "oneway", this->ctx_);
  ASSERT_TRUE(shared.ok()) << shared.status().ToString();
  ASSERT_EQ(shared->changed.size(), 2u);  // the ramp (stored verdict) and the step (judged)
  for (const auto& o : shared->changed) {
    ASSERT_EQ(o.verdicts.size(), 2u);
    EXPECT_FALSE(common::IsOneWay(o.verdicts[0])) << o.id;
    EXPECT_TRUE(common::IsOneWay(o.verdicts[1])) << o.id;
    EXPECT_STREQ(common::VerdictWord(o.verdicts[1]), "one-way");
  }
}

// A stored terrace shared with another profile: the whole and each part are judged for it (the
// parts' stored verdicts are the source profile's and are not carried over).
TYPED_TEST(MapStoreTest, SharingJudgesATerracesPartsForTheTargetProfile) {
  ProfileDeriver deriver = FakeDeriver();
  deriver.judge_parts = [](const common::Obstacle& o, const common::RobotProfile& profile) {
    std::vector<common::ObstacleVerdict> out;
    for (const auto& p : o.parts) {
      common::ObstacleVerdict v;
      v.crossable = p.height_m <= profile.max_step_up_m;
      if (!v.crossable) v.reason = "step up";
      out.push_back(v);
    }
    return out;
  };
  MapSnapshot s = SampleSnapshot("corridor");
  s.obstacles.obstacles.push_back(cairn::testing::SampleTerrace());
  s.obstacles.obstacles.back().id = 1000;
  this->Save(s);
  ASSERT_TRUE(this->dut_->PutProfile(Profile("pioneer3at", 8.0, 0.03), this->ctx_).ok());
  ASSERT_TRUE(this->dut_->PutProfile(Profile("rover", 12.0, 0.08), this->ctx_).ok());
  auto shared = ShareMap(*this->dut_, deriver, {"lab", "corridor", 0}, "rover", this->ctx_);
  ASSERT_TRUE(shared.ok()) << shared.status().ToString();
  const common::Obstacle* terrace = nullptr;
  for (const auto& o : shared->derived.registry.obstacles) {
    if (o.id == 1000) terrace = &o;
  }
  ASSERT_NE(terrace, nullptr);
  ASSERT_EQ(terrace->parts.size(), 2u);
  for (const auto& p : terrace->parts) {
    ASSERT_EQ(p.verdicts.size(), 1u);
    EXPECT_EQ(p.verdicts[0].profile, "rover");
    EXPECT_TRUE(p.verdicts[0].crossable);  // 0.08 m <= the rover's 0.08 m step up
    EXPECT_FALSE(p.verdicts[0].profile_hash.empty());
  }
}

TYPED_TEST(MapStoreTest, SharingDerivesCachesAndReportsVerdictChanges) {
  const ProfileDeriver deriver = FakeDeriver();
  MapSnapshot s = SampleSnapshot("corridor");
  this->Save(s);
  const common::RobotProfile pioneer = Profile("pioneer3at", 8.0, 0.03);
  const common::RobotProfile rover = Profile("rover", 12.0, 0.08);
  ASSERT_TRUE(this->dut_->PutProfile(pioneer, this->ctx_).ok());
  ASSERT_TRUE(this->dut_->PutProfile(rover, this->ctx_).ok());
  auto before = this->dut_->LoadLayers({"lab", "corridor", 0}, {});
  ASSERT_TRUE(before.ok());

  auto shared = ShareMap(*this->dut_, deriver, {"lab", "corridor", 0}, "rover", this->ctx_);
  ASSERT_TRUE(shared.ok()) << shared.status().ToString();
  EXPECT_FALSE(shared->was_cached);
  EXPECT_EQ(shared->source_profile, "pioneer3at");
  EXPECT_TRUE(shared->derived.layers.HasLayer("cost/rover"));
  // The 10 degree ramp: stored verdict blocked for pioneer3at, crossable for the rover. The 20 cm
  // step blocks both (no stored verdict: judged with the stored pioneer3at profile).
  ASSERT_EQ(shared->changed.size(), 1u);
  EXPECT_EQ(shared->changed[0].id, 7);
  ASSERT_EQ(shared->changed[0].verdicts.size(), 2u);
  EXPECT_EQ(shared->changed[0].verdicts[0].profile, "pioneer3at");
  EXPECT_FALSE(shared->changed[0].verdicts[0].crossable);
  EXPECT_EQ(shared->changed[0].verdicts[1].profile, "rover");
  EXPECT_TRUE(shared->changed[0].verdicts[1].crossable);

  // Cached now; the base layers did not change.
  auto again = ShareMap(*this->dut_, deriver, {"lab", "corridor", 0}, "rover", this->ctx_);
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE(again->was_cached);
  EXPECT_TRUE(
      SameLayer(again->derived.layers.at("cost/rover"), shared->derived.layers.at("cost/rover")));
  auto after = this->dut_->LoadLayers({"lab", "corridor", 0}, {});
  ASSERT_TRUE(after.ok());
  EXPECT_TRUE(SameLayer(before->at("elevation"), after->at("elevation")));
  EXPECT_EQ(this->dut_->GetMapInfo({"lab", "corridor", 0})->version, 1);

  // A new code version is a cache miss.
  auto other_code =
      ShareMap(*this->dut_, FakeDeriver("fake-2"), {"lab", "corridor", 0}, "rover", this->ctx_);
  ASSERT_TRUE(other_code.ok());
  EXPECT_FALSE(other_code->was_cached);
  // Unknown profile or map.
  EXPECT_EQ(
      ShareMap(*this->dut_, deriver, {"lab", "corridor", 0}, "tank", this->ctx_).status().code(),
      StatusCode::kNotFound);
  EXPECT_EQ(ShareMap(*this->dut_, deriver, {"lab", "nope", 0}, "rover", this->ctx_).status().code(),
            StatusCode::kNotFound);
}

TYPED_TEST(MapStoreTest, LoadForAProfileDerivesOnAMissWithoutWriting) {
  const ProfileDeriver deriver = FakeDeriver();
  MapSnapshot s = SampleSnapshot("corridor");
  this->Save(s);
  ASSERT_TRUE(this->dut_->PutProfile(Profile("rover", 12.0, 0.08), this->ctx_).ok());
  ASSERT_TRUE(this->dut_->PutProfile(Profile("tiny", 3.0, 0.01), this->ctx_).ok());
  const size_t audit_before = this->dut_->ListAudit(100)->size();

  auto miss = LoadForProfile(*this->dut_, &deriver, {"lab", "corridor", 0}, "tiny");
  ASSERT_TRUE(miss.ok()) << miss.status().ToString();
  EXPECT_FALSE(miss->from_cache);
  EXPECT_TRUE(miss->layers.HasLayer("elevation"));
  ASSERT_TRUE(miss->layers.HasLayer("cost/tiny"));
  // Ramp cells step 5 cm > 1 cm: lethal; flat cells free; unknown stays unknown.
  EXPECT_EQ(miss->layers.at("cost/tiny")(20, 10), 100.f);
  EXPECT_EQ(miss->layers.at("cost/tiny")(5, 10), 0.f);
  EXPECT_TRUE(std::isnan(miss->layers.at("cost/tiny")(1, 1)));
  ASSERT_EQ(miss->obstacles.obstacles.size(), 2u);
  EXPECT_EQ(miss->obstacles.obstacles[0].verdicts.size(), 1u);
  EXPECT_EQ(miss->obstacles.obstacles[0].verdicts[0].profile, "tiny");
  EXPECT_EQ(this->dut_->ListAudit(100)->size(), audit_before);  // nothing written

  ASSERT_TRUE(ShareMap(*this->dut_, deriver, {"lab", "corridor", 0}, "tiny", this->ctx_).ok());
  auto hit = LoadForProfile(*this->dut_, &deriver, {"lab", "corridor", 0}, "tiny",
                            {{"cost/tiny"}, CellBox{15, 5, 25, 15}});
  ASSERT_TRUE(hit.ok()) << hit.status().ToString();
  EXPECT_TRUE(hit->from_cache);
  EXPECT_EQ(hit->layers.layer_names(), std::vector<std::string>{"cost/tiny"});
  EXPECT_EQ(hit->layers.at("cost/tiny")(5, 5), 100.f);

  // Without a profile: base only; asking for a derived layer then is NOT_FOUND.
  auto base = LoadForProfile(*this->dut_, nullptr, {"lab", "corridor", 0}, "");
  ASSERT_TRUE(base.ok());
  EXPECT_FALSE(base->layers.HasLayer("cost/tiny"));
  EXPECT_EQ(LoadForProfile(*this->dut_, nullptr, {"lab", "corridor", 0}, "", {{"cost/tiny"}, {}})
                .status()
                .code(),
            StatusCode::kNotFound);
  EXPECT_EQ(LoadForProfile(*this->dut_, &deriver, {"lab", "corridor", 0}, "ghost").status().code(),
            StatusCode::kNotFound);
  EXPECT_EQ(LoadForProfile(*this->dut_, nullptr, {"lab", "corridor", 0}, "rover").status().code(),
            StatusCode::kUnavailable);
}

TYPED_TEST(MapStoreTest, AuditLogRecordsChangesAndRequests) {
  WriteContext ctx{"rover1-mapper", 4242, 123456};
  ASSERT_TRUE(this->dut_->SaveMap(SampleSnapshot("corridor"), ctx).ok());
  ASSERT_TRUE(this->dut_->DeleteMap({"lab", "corridor", 0}, {"cairn-map", 0, 0}).ok());
  auto audit = this->dut_->ListAudit(10);
  ASSERT_TRUE(audit.ok());
  ASSERT_EQ(audit->size(), 2u);
  EXPECT_EQ((*audit)[0].op, "delete");
  EXPECT_EQ((*audit)[1].op, "save");
  EXPECT_EQ((*audit)[1].actor, "rover1-mapper");
  EXPECT_EQ((*audit)[1].utime, 123456);
  EXPECT_EQ((*audit)[1].version, 1);
  auto found = this->dut_->FindRequest("rover1-mapper", 4242);
  ASSERT_TRUE(found.ok() && found->has_value());
  EXPECT_EQ((*found)->op, "save");
  EXPECT_EQ((*found)->map, "corridor");
  EXPECT_FALSE(this->dut_->FindRequest("rover1-mapper", 4243)->has_value());
  EXPECT_TRUE(this->dut_->Check().value().ok);
}

TYPED_TEST(MapStoreTest, DiffFindsChangedCellsAndObstacles) {
  const ProfileDeriver deriver = FakeDeriver();
  MapSnapshot a = SampleSnapshot("corridor");
  this->Save(a);
  MapSnapshot b = a;
  b.base.at("elevation")(30, 20) += 1.f;
  b.base.at("elevation")(0, 0) = 0.f;  // unknown -> known counts
  b.obstacles.obstacles[0].height_m = 0.04;
  b.obstacles.obstacles.pop_back();
  this->Save(b);
  auto diff = DiffVersions(*this->dut_, {"lab", "corridor", 1}, {"lab", "corridor", 2});
  ASSERT_TRUE(diff.ok()) << diff.status().ToString();
  EXPECT_FALSE(diff->identical());
  ASSERT_EQ(diff->layers.size(), 2u);
  EXPECT_EQ(diff->layers[0].layer_a, "elevation");
  EXPECT_EQ(diff->layers[0].cells_different, 2);
  EXPECT_EQ(diff->layers[1].cells_different, 0);
  ASSERT_EQ(diff->obstacles.size(), 2u);
  EXPECT_EQ(diff->obstacles[0].id, 3);
  EXPECT_EQ(diff->obstacles[0].what, "only in A");
  EXPECT_EQ(diff->obstacles[1].id, 7);
  EXPECT_NE(diff->obstacles[1].what.find("height_m"), std::string::npos);
  auto same = DiffVersions(*this->dut_, {"lab", "corridor", 1}, {"lab", "corridor", 1});
  ASSERT_TRUE(same.ok());
  EXPECT_TRUE(same->identical());

  ASSERT_TRUE(this->dut_->PutProfile(Profile("pioneer3at", 8.0, 0.03), this->ctx_).ok());
  ASSERT_TRUE(this->dut_->PutProfile(Profile("rover", 12.0, 0.08), this->ctx_).ok());
  auto profiles =
      DiffProfiles(*this->dut_, &deriver, {"lab", "corridor", 1}, "pioneer3at", "rover");
  ASSERT_TRUE(profiles.ok()) << profiles.status().ToString();
  ASSERT_EQ(profiles->layers.size(), 1u);
  // Ramp cells (5 cm steps) are lethal for pioneer3at and free for the rover.
  EXPECT_EQ(profiles->layers[0].cells_different, (37 - 10 - 1) * 23);
  ASSERT_EQ(profiles->obstacles.size(), 1u);
  EXPECT_EQ(profiles->obstacles[0].id, 7);
}

}  // namespace
}  // namespace cairn::mapstore
