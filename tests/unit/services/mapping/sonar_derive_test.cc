// Sonar maps shared between profiles: the cost layer of the sonar occupancy, the contacts as
// obstacles of unmeasured height, and DeriveProfileLayers choosing the sonar path for a map
// without an elevation.

#include "services/mapping/sonar_derive.h"

#include <cmath>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "services/mapping/sonar_mapper_layer.h"
#include "tests/unit/services/mapping/terrain_fixtures.h"

namespace cairn::mapping {
namespace {

using common::GridMap;
using testing::ShippedProfile;

// A 20 m x 20 m sonar map at 0.25 m: free water seen round (5, 10), unknown elsewhere.
GridMap SonarMap() {
  common::GridGeometry g;
  g.resolution_m = 0.25;
  g.size_x = 80;
  g.size_y = 80;
  g.origin = {-5.0, 0.0, 0.0};
  GridMap map(g);
  common::Layer& occ = map.AddLayer(kSonarOccupancy);
  occ.setConstant(std::numeric_limits<float>::quiet_NaN());
  occ.block(0, 0, 80, 40).setConstant(10.f);
  return map;
}

void Mark(GridMap* map, double x_m, double y_m, float percent) {
  const auto cell = map->IndexOf({x_m, y_m});
  ASSERT_TRUE(cell.has_value());
  map->at(kSonarOccupancy)(cell->ix, cell->iy) = percent;
}

TEST(SonarCostTest, FreeOccupiedGradedAndUnknown) {
  common::Layer occ(1, 7);
  occ << -1.f, std::numeric_limits<float>::quiet_NaN(), 0.f, 25.f, 40.4f, 65.f, 100.f;
  const common::Layer cost = SonarCost(occ);
  EXPECT_TRUE(std::isnan(cost(0, 0)));  // ROS's -1
  EXPECT_TRUE(std::isnan(cost(0, 1)));
  EXPECT_EQ(cost(0, 2), layers::kCostFree);
  EXPECT_EQ(cost(0, 3), layers::kCostFree);
  EXPECT_EQ(cost(0, 4), 40.f);
  EXPECT_EQ(cost(0, 5), layers::kCostLethal);
  EXPECT_EQ(cost(0, 6), layers::kCostLethal);
}

TEST(SonarContactsTest, AFaceDrawnBeamByBeamIsOneContactAndFarOnesAreTwo) {
  GridMap map = SonarMap();
  // A rock's face: cells every 0.5 m along x = 2 (gaps of one cell), and a second rock 4 m away.
  for (double y = 3.0; y <= 6.0; y += 0.5) Mark(&map, 2.1, y, 90.f);
  Mark(&map, 7.1, 4.1, 80.f);
  Mark(&map, 7.1, 4.4, 80.f);
  // A single stray echo and a weak (graded) cell are no contacts.
  Mark(&map, -3.9, 8.1, 90.f);
  Mark(&map, 0.1, 1.1, 50.f);
  const common::ObstacleRegistry r = ExtractSonarContacts(map, kSonarOccupancy);
  ASSERT_EQ(r.obstacles.size(), 2u);
  const common::Obstacle& face = r.obstacles[0].centroid_m.x() < 5 ? r.obstacles[0] : r.obstacles[1];
  EXPECT_EQ(face.kind, common::ObstacleKind::kWallOrObject);
  EXPECT_EQ(face.num_cells, 7);
  EXPECT_NEAR(face.centroid_m.x(), 2.125, 1e-9);
  EXPECT_NEAR(face.centroid_m.y(), 4.625, 1e-9);
  EXPECT_GT(face.length_m, 3.0);
  EXPECT_TRUE(std::isnan(face.height_m));
  EXPECT_GE(face.outline_m.size(), 3u);
  EXPECT_NE(r.obstacles[0].id, r.obstacles[1].id);
}

TEST(SonarDeriveTest, EveryAuvProfileGetsItsCostLayerAndBlockedContacts) {
  GridMap map = SonarMap();
  for (double y = 3.0; y <= 6.0; y += 0.25) Mark(&map, 2.1, y, 90.f);
  const GridMap before = map;
  for (const char* name : {"sparus2_msis", "girona500"}) {
    SCOPED_TRACE(name);
    // Through the one entry point the map store calls.
    const DerivedLayers d = DeriveProfileLayers(map, ShippedProfile(name));
    EXPECT_TRUE(map == before);
    ASSERT_TRUE(d.layers.HasLayer(layers::CostLayer(name)));
    EXPECT_EQ(d.layers.geometry(), map.geometry());
    const common::Layer& cost = d.layers.at(layers::CostLayer(name));
    const auto rock = *map.IndexOf({2.1, 4.1});
    const auto water = *map.IndexOf({0.0, 2.0});
    const auto unseen = *map.IndexOf({0.0, 15.0});
    EXPECT_EQ(cost(rock.ix, rock.iy), layers::kCostLethal);
    EXPECT_EQ(cost(water.ix, water.iy), layers::kCostFree);
    EXPECT_TRUE(std::isnan(cost(unseen.ix, unseen.iy)));
    // No heading is refused anywhere the cost is known.
    ASSERT_TRUE(d.layers.HasLayer(layers::DirectedLayer(name)));
    const common::Layer& directed = d.layers.at(layers::DirectedLayer(name));
    EXPECT_EQ(directed(rock.ix, rock.iy), 0.f);
    EXPECT_EQ(directed(water.ix, water.iy), 0.f);
    EXPECT_TRUE(std::isnan(directed(unseen.ix, unseen.iy)));
    ASSERT_EQ(d.registry.obstacles.size(), 1u);
    const common::ObstacleVerdict* v = d.registry.obstacles[0].VerdictFor(name);
    ASSERT_NE(v, nullptr);
    EXPECT_FALSE(v->crossable);
    EXPECT_NE(v->reason.find("unmeasured height"), std::string::npos) << v->reason;
  }
}

TEST(SonarDeriveTest, AMapWithNeitherElevationNorSonarIsRefusedNamingBoth) {
  common::GridGeometry g;
  g.resolution_m = 0.5;
  g.size_x = 4;
  g.size_y = 4;
  GridMap map(g);
  map.AddLayer("occupancy").setZero();
  try {
    DeriveProfileLayers(map, ShippedProfile("sparus2_msis"));
    FAIL() << "derived a map without elevation or sonar";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("elevation"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(kSonarOccupancy), std::string::npos) << e.what();
  }
}

TEST(SonarDeriveTest, BadThresholdsAreRefused) {
  SonarDeriveParams p;
  p.free_threshold = 70.0;
  EXPECT_THROW(p.Validate(), std::invalid_argument);
  p = {};
  p.min_cells = 0;
  EXPECT_THROW(p.Validate(), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::mapping
