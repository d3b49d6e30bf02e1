#include "planner/places.h"

#include <gtest/gtest.h>

#include "common/yaml_reader.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Vector2;
using testing::PioneerFootprint;
using testing::TestLayer;

std::string ErrorOf(const std::string& yaml) {
  try {
    LoadPlacesString(yaml, "places.yaml");
  } catch (const common::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(PlacesTest, LoadsAListOrAPlacesMap) {
  const auto list = LoadPlacesString(
      "- name: kitchen\n"
      "  polygon: [[0, 0], [4, 0], [4, 3], [0, 3]]\n"
      "- name: hall\n"
      "  polygon: [[4, 0], [6, 0], [5, 2]]\n");
  ASSERT_EQ(list.size(), 2u);
  EXPECT_EQ(list[0].name, "kitchen");
  EXPECT_EQ(list[0].polygon_m.size(), 4u);
  EXPECT_EQ(list[1].polygon_m[2], Vector2(5, 2));
  const auto map = LoadPlacesString("places:\n  - {name: a, polygon: [[0, 0], [1, 0], [1, 1]]}\n");
  ASSERT_EQ(map.size(), 1u);
  EXPECT_NE(FindPlace(map, "a"), nullptr);
  EXPECT_EQ(FindPlace(map, "b"), nullptr);
}

TEST(PlacesTest, LoadsTheApartmentPlaces) {
  const auto places =
      LoadPlacesFile(std::string(CAIRN_SOURCE_DIR) + "/simulator/worlds/apartment_places.yaml");
  const Place* kitchen = FindPlace(places, "kitchen");
  ASSERT_NE(kitchen, nullptr);
  EXPECT_EQ(kitchen->label_value, 60);
  EXPECT_GE(kitchen->polygon_m.size(), 3u);
}

TEST(PlacesTest, ErrorsNameTheFileAndLine) {
  EXPECT_NE(ErrorOf("- name: a\n  polygon: [[0, 0], [1, 0]]\n").find("places.yaml:2"),
            std::string::npos);
  EXPECT_NE(ErrorOf("- name: a\n  polygon: [[0, 0], [1, 0], [1, 1]]\n  colour: red\n")
                .find("unknown key 'places[0].colour'"),
            std::string::npos);
  EXPECT_NE(ErrorOf("- name: a\n  polygon: [[0, 0], [1, 0], [1, 1]]\n"
                    "- name: a\n  polygon: [[0, 0], [1, 0], [1, 1]]\n")
                .find("duplicate place 'a'"),
            std::string::npos);
  EXPECT_NE(ErrorOf("- name: a\n  polygon: [[0, 0], [1, x], [1, 1]]\n").find("places.yaml:2"),
            std::string::npos);
  EXPECT_NE(ErrorOf("- polygon: [[0, 0], [1, 0], [1, 1]]\n")
                .find("missing required key 'places[0].name'"),
            std::string::npos);
  EXPECT_NE(ErrorOf("rooms: []\n").find("places.yaml:1: missing key 'places'"), std::string::npos);
  EXPECT_NE(ErrorOf("places: []\nrooms: []\n").find("unknown key 'rooms'"), std::string::npos);
  EXPECT_THROW(LoadPlacesFile("/nonexistent/places.yaml"), common::ConfigError);
}

TEST(PlacesTest, ResolvesToTheFreeCellFarthestFromWalls) {
  // Two rooms side by side: [0, 6] × [0, 4] and [6, 10] × [0, 4], walls 0.2 m thick all
  // around, a door in the middle wall at y in [1.5, 2.5]. A cabinet stands in the left room.
  TestLayer layer(100, 40, 0.1);
  layer.Rect(0.0, 0.0, 10.0, 0.2, 100.0f).Rect(0.0, 3.8, 10.0, 4.0, 100.0f);
  layer.Rect(0.0, 0.0, 0.2, 4.0, 100.0f).Rect(9.8, 0.0, 10.0, 4.0, 100.0f);
  layer.Rect(5.9, 0.0, 6.1, 1.5, 100.0f).Rect(5.9, 2.5, 6.1, 4.0, 100.0f);
  layer.Rect(0.2, 0.2, 2.5, 3.8, 100.0f);  // the cabinet fills the left part of the left room
  const auto map = layer.Build(PioneerFootprint());
  const std::vector<Place> places = LoadPlacesString(
      "- {name: left, polygon: [[0, 0], [6, 0], [6, 4], [0, 4]]}\n"
      "- {name: right, polygon: [[6, 0], [10, 0], [10, 4], [6, 4]]}\n"
      "- {name: closet, polygon: [[0.5, 0.5], [2, 0.5], [2, 2]]}\n");
  const PlaceGoal left = ResolvePlace(*FindPlace(places, "left"), *map);
  ASSERT_TRUE(left.found) << left.message;
  // Midway between the cabinet (x = 2.5) and the middle wall (x = 5.9), and between the outer
  // walls in y.
  EXPECT_NEAR(left.pose.x_m, 4.2, 0.15);
  EXPECT_NEAR(left.pose.y_m, 2.0, 0.15);
  EXPECT_GT(left.clearance_m, 1.5);
  EXPECT_TRUE(map->IsValid(left.pose));
  const PlaceGoal right = ResolvePlace(*FindPlace(places, "right"), *map);
  ASSERT_TRUE(right.found);
  EXPECT_NEAR(right.pose.x_m, 7.9, 0.15);
  EXPECT_NEAR(right.pose.y_m, 2.0, 0.15);
  // No free cell in the closet (it is all cabinet).
  const PlaceGoal closet = ResolvePlace(*FindPlace(places, "closet"), *map);
  EXPECT_FALSE(closet.found);
  EXPECT_NE(closet.message.find("no known free cell"), std::string::npos);
}

TEST(PlacesTest, UnknownCellsCountAsObstaclesForClearance) {
  TestLayer layer(60, 60, 0.1);
  layer.Rect(3.0, 0.0, 6.0, 6.0, NAN);  // the right half is unexplored
  const auto map = layer.Build(PioneerFootprint());
  const Place room{"room", {{0, 0}, {6, 0}, {6, 6}, {0, 6}}};
  const PlaceGoal g = ResolvePlace(room, *map);
  ASSERT_TRUE(g.found);
  EXPECT_LT(g.pose.x_m, 3.0);
  EXPECT_NEAR(g.pose.x_m, 1.5, 0.15);  // equally far from the map edge and the unknown half
  EXPECT_NEAR(g.pose.y_m, 3.0, 0.5);
}

}  // namespace
}  // namespace cairn::planner
