// DeriveProfileLayers: a profile's layers and registry from stored base layers, the base never
// touched.

#include "services/mapping/derive.h"

#include <cmath>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "tests/unit/services/mapping/terrain_fixtures.h"

namespace cairn::mapping {
namespace {

using common::GridMap;
using common::ObstacleKind;
using testing::Corridor;
using testing::kDeg;
using testing::ShippedProfile;

// Seed 000 scenario 17: deriving never touches the stored base layers, and two profiles differ
// only where the terrain matters to them.
TEST(DeriveTest, BaseMapUntouchedAndProfilesDifferOnlyOnTheRamp) {
  const double t = std::tan(10 * kDeg);
  const GridMap base =
      Corridor([t](double x) { return x < 4.0 ? 0.0 : (x < 7.0 ? (x - 4.0) * t : 3.0 * t); });
  const GridMap before = base;
  const DerivedLayers a = DeriveProfileLayers(base, ShippedProfile("pioneer3at"));
  const DerivedLayers b = DeriveProfileLayers(base, ShippedProfile("rover"));
  EXPECT_TRUE(base == before);
  EXPECT_EQ(base.layer_names(), before.layer_names());
  ASSERT_TRUE(a.layers.HasLayer(layers::CostLayer("pioneer3at")));
  ASSERT_TRUE(b.layers.HasLayer(layers::CostLayer("rover")));
  for (const char* name : {layers::kSlope, layers::kStepMax, layers::kRoughness}) {
    EXPECT_TRUE(a.layers.HasLayer(name)) << name;
  }
  EXPECT_EQ(a.layers.geometry(), base.geometry());
  const common::Layer& ca = a.layers.at(layers::CostLayer("pioneer3at"));
  const common::Layer& cb = b.layers.at(layers::CostLayer("rover"));
  int differ = 0;
  for (int iy = 1; iy < base.size_y() - 1; ++iy) {
    for (int ix = 1; ix < base.size_x() - 1; ++ix) {
      const bool a_lethal = ca(ix, iy) == layers::kCostLethal;
      const bool b_lethal = cb(ix, iy) == layers::kCostLethal;
      if (a_lethal != b_lethal) {
        ++differ;
        const double x = base.CenterOf({ix, iy}).x();
        EXPECT_GT(x, 3.7) << ix;  // on the ramp (with its foot and top)
        EXPECT_LT(x, 7.3) << ix;
      }
    }
  }
  EXPECT_GT(differ, 100);
  ASSERT_EQ(a.registry.obstacles.size(), 1u);
  EXPECT_FALSE(a.registry.obstacles[0].VerdictFor("pioneer3at")->crossable);
  EXPECT_TRUE(b.registry.obstacles[0].VerdictFor("rover")->crossable);
  EXPECT_EQ(a.registry.obstacles[0].VerdictFor("rover"), nullptr);
  // The same input gives the same output, bit for bit.
  const DerivedLayers again = DeriveProfileLayers(base, ShippedProfile("pioneer3at"));
  EXPECT_TRUE(again.layers == a.layers);
  EXPECT_STRNE(kMappingCodeVersion, "");
}

TEST(DeriveTest, ProfileChangeChangesTheVerdict) {
  // Seed 000 scenario 18: the rover edited to 9 deg no longer crosses the 10 deg ramp.
  const double t = std::tan(10 * kDeg);
  const GridMap base =
      Corridor([t](double x) { return x < 4.0 ? 0.0 : (x < 7.0 ? (x - 4.0) * t : 3.0 * t); });
  common::RobotProfile rover = ShippedProfile("rover");
  const std::string hash_before = rover.ContentHash();
  rover.max_slope_up_rad = 9 * kDeg;
  EXPECT_NE(rover.ContentHash(), hash_before);
  const DerivedLayers d = DeriveProfileLayers(base, rover);
  ASSERT_EQ(d.registry.obstacles.size(), 1u);
  EXPECT_FALSE(d.registry.obstacles[0].VerdictFor("rover")->crossable);
  EXPECT_EQ(d.registry.obstacles[0].VerdictFor("rover")->profile_hash, rover.ContentHash());
}

TEST(DeriveTest, MissingElevationThrows) {
  common::GridGeometry g;
  g.size_x = 3;
  g.size_y = 3;
  EXPECT_THROW(DeriveProfileLayers(GridMap(g), ShippedProfile("rover")), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::mapping
