#include "mapstore/load_answers.h"

#include <gtest/gtest.h>

#include "common/layers.h"
#include "mapstore/in_memory_map_store.h"
#include "mapstore/map_operations.h"
#include "tests/unit/mapstore/fake_deriver.h"

namespace cairn::mapstore {
namespace {

using testing::SameLayer;

class LoadAnswersTest : public ::testing::Test {
 protected:
  LoadAnswersTest()
      : snapshot_(testing::SampleSnapshot("corridor")), deriver_(testing::FakeDeriver()) {
    OctomapData tree;
    tree.bytes = "tree";
    tree.resolution_m = 0.1;
    snapshot_.octomap = tree;
    EXPECT_TRUE(store_.SaveMap(snapshot_, {"unit", 0, 0}).ok());
    EXPECT_TRUE(store_.PutProfile(testing::Profile("rover", 20.0, 0.1), {"unit", 0, 0}).ok());
  }
  LoadRequest Request(std::vector<std::string> layers, std::string profile = "") const {
    LoadRequest r;
    r.ref = {"lab", "corridor", 0};
    r.profile = std::move(profile);
    r.layers = std::move(layers);
    r.tile_size = 10;
    return r;
  }

  MapSnapshot snapshot_;
  ProfileDeriver deriver_;
  InMemoryMapStore store_{10};
};

TEST_F(LoadAnswersTest, BaseLayersWithoutAProfileAreTheStoredTilesAsTheyAre) {
  auto answer = AnswerLoad(store_, deriver_, Request({layers::kElevation}));
  ASSERT_TRUE(answer.ok()) << answer.status().ToString();
  EXPECT_TRUE(answer->stored);
  EXPECT_EQ(answer->view.info.version, 1);
  ASSERT_EQ(answer->stored_layers.size(), 1u);
  EXPECT_EQ(answer->stored_layers[0].name, layers::kElevation);
  EXPECT_FALSE(answer->stored_layers[0].tiles.empty());
  EXPECT_EQ(answer->view.obstacles.obstacles.size(), 2u);
  EXPECT_EQ(answer->layer_names(), std::vector<std::string>{layers::kElevation});
  EXPECT_EQ(answer->Summary(false), "1 layers");
  EXPECT_FALSE(answer->octomap.has_value());
}

TEST_F(LoadAnswersTest, WithoutStoredTilesTheLayersAreDecoded) {
  LoadRequest request = Request({});
  request.may_send_stored = false;
  auto answer = AnswerLoad(store_, deriver_, request);
  ASSERT_TRUE(answer.ok());
  EXPECT_FALSE(answer->stored);
  EXPECT_EQ(answer->layer_names(), snapshot_.base.layer_names());
  EXPECT_TRUE(
      SameLayer(answer->view.layers.at(layers::kElevation), snapshot_.base.at(layers::kElevation)));
}

TEST_F(LoadAnswersTest, DerivedLayersComeFromTheCacheAsStoredOrAreDerivedNow) {
  const std::vector<std::string> cost = {layers::CostLayer("rover")};
  auto derived_now = AnswerLoad(store_, deriver_, Request(cost, "rover"));
  ASSERT_TRUE(derived_now.ok()) << derived_now.status().ToString();
  EXPECT_FALSE(derived_now->stored);
  EXPECT_FALSE(derived_now->view.from_cache);
  EXPECT_EQ(derived_now->Summary(true), "1 layers, derived now (not cached)");
  ASSERT_TRUE(ShareMap(store_, deriver_, {"lab", "corridor", 0}, "rover", {"unit", 0, 0}).ok());
  auto cached = AnswerLoad(store_, deriver_, Request(cost, "rover"));
  ASSERT_TRUE(cached.ok());
  EXPECT_TRUE(cached->stored);
  EXPECT_TRUE(cached->view.from_cache);
  EXPECT_EQ(cached->layer_names(), cost);
  EXPECT_EQ(cached->Summary(true), "1 layers, derived layers from the cache");
  // A base layer beside a derived one: decoded (the cache holds only derived layers).
  auto mixed = AnswerLoad(store_, deriver_, Request({layers::kElevation, cost[0]}, "rover"));
  ASSERT_TRUE(mixed.ok());
  EXPECT_FALSE(mixed->stored);
  EXPECT_EQ(mixed->layer_names().size(), 2u);
}

TEST_F(LoadAnswersTest, TheOctomapAloneOrBesideLayers) {
  auto alone = AnswerLoad(store_, deriver_, Request({"octomap"}));
  ASSERT_TRUE(alone.ok());
  EXPECT_TRUE(alone->only_octomap);
  EXPECT_TRUE(alone->layer_names().empty());
  ASSERT_TRUE(alone->octomap.has_value());
  EXPECT_EQ(alone->octomap->bytes, "tree");
  EXPECT_EQ(alone->Summary(false), "0 layers, OctoMap follows");
  auto beside = AnswerLoad(store_, deriver_, Request({layers::kElevation, "octomap"}));
  ASSERT_TRUE(beside.ok());
  EXPECT_EQ(beside->layer_names(), std::vector<std::string>{layers::kElevation});
  EXPECT_TRUE(beside->octomap.has_value());
}

TEST_F(LoadAnswersTest, UnknownMapsLayersAndProfilesAreNotFound) {
  LoadRequest unknown_map = Request({});
  unknown_map.ref.name = "nowhere";
  EXPECT_EQ(AnswerLoad(store_, deriver_, unknown_map).status().code(),
            common::StatusCode::kNotFound);
  EXPECT_EQ(AnswerLoad(store_, deriver_, Request({"no_such_layer"})).status().code(),
            common::StatusCode::kNotFound);
  EXPECT_EQ(AnswerLoad(store_, deriver_, Request({"cost/ghost"}, "ghost")).status().code(),
            common::StatusCode::kNotFound);
}

TEST_F(LoadAnswersTest, ObstaclesAsStoredOrWithAProfilesVerdicts) {
  auto stored = AnswerObstacles(store_, deriver_, {"lab", "corridor", 0}, "");
  ASSERT_TRUE(stored.ok());
  EXPECT_EQ(stored->info.version, 1);
  ASSERT_EQ(stored->registry.obstacles.size(), 2u);
  auto judged = AnswerObstacles(store_, deriver_, {"lab", "corridor", 0}, "rover");
  ASSERT_TRUE(judged.ok()) << judged.status().ToString();
  for (const auto& o : judged->registry.obstacles) {
    EXPECT_NE(o.VerdictFor("rover"), nullptr) << o.id;
  }
}

}  // namespace
}  // namespace cairn::mapstore
