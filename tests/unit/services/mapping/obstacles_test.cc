#include "services/mapping/obstacles.h"

#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "services/mapping/feature_classes.h"
#include "services/mapping/traversability.h"
#include "tests/unit/services/mapping/terrain_fixtures.h"

namespace cairn::mapping {
namespace {

using common::GridMap;
using common::Obstacle;
using common::ObstacleKind;
using testing::Corridor;
using testing::kDeg;
using testing::MakeTerrain;
using testing::ShippedProfile;

constexpr double kRes = 0.2;

common::ObstacleRegistry Extract(GridMap map) {
  ComputeGeometricLayers(&map, {});
  common::ObstacleRegistry r = ExtractObstacles(map, {});
  LabelObstacles(&r, {ShippedProfile("pioneer3at"), ShippedProfile("rover")});
  return r;
}

common::ObstacleRegistry ExtractWith(GridMap map, const ObstacleParams& params) {
  ComputeGeometricLayers(&map, {});
  return ExtractObstacles(map, params);
}

std::vector<const Obstacle*> OfKind(const common::ObstacleRegistry& r, ObstacleKind kind) {
  std::vector<const Obstacle*> out;
  for (const auto& o : r.obstacles) {
    if (o.kind == kind) out.push_back(&o);
  }
  return out;
}

bool Crossable(const Obstacle& o, const std::string& profile) {
  const common::ObstacleVerdict* v = o.VerdictFor(profile);
  EXPECT_NE(v, nullptr) << profile;
  return v != nullptr && v->crossable;
}

// Point-in-polygon (even-odd) for the outline checks.
bool Inside(const std::vector<common::Vector2>& poly, const common::Vector2& p) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    if ((poly[i].y() > p.y()) != (poly[j].y() > p.y()) &&
        p.x() < (poly[j].x() - poly[i].x()) * (p.y() - poly[i].y()) / (poly[j].y() - poly[i].y()) +
                    poly[i].x()) {
      in = !in;
    }
  }
  return in;
}

// A small rock far off: two cells of ground and one of the rock's face seen at the end of a
// lidar ring, nothing around. Fewer cells than min_cells (4) are noise unless they stand
// min_small_feature_height_m (0.1 m) high.
TEST(ObstaclesTest, ASmallFeatureIsListedOnlyWhenItStandsHigh) {
  auto patch = [](double rock_m) {
    return MakeTerrain(30, 30, kRes, [rock_m](double x, double y) {
      if (y < 3.0 || y >= 3.2 || x < 2.0 || x >= 2.6) return std::nan("");
      return x >= 2.4 ? rock_m : 0.0;
    });
  };
  const common::ObstacleRegistry high = ExtractWith(patch(0.12), {});
  ASSERT_EQ(high.obstacles.size(), 1u);
  EXPECT_LT(high.obstacles[0].num_cells, ObstacleParams{}.min_cells);
  EXPECT_NEAR(high.obstacles[0].height_m, 0.12, 1e-4);
  EXPECT_TRUE(ExtractWith(patch(0.06), {}).obstacles.empty());
  ObstacleParams min_cells_alone;
  min_cells_alone.min_small_feature_height_m = 0.0;
  EXPECT_TRUE(ExtractWith(patch(0.12), min_cells_alone).obstacles.empty());
}

// Seed 000 scenario 13: a 10 deg ramp (3 m long, then a platform) is a ramp; not crossable for
// the P3-AT (8 deg), crossable for the rover (12 deg).
TEST(ObstaclesTest, TenDegreeRampSplitsThePioneerAndTheRover) {
  const double t = std::tan(10 * kDeg);
  const common::ObstacleRegistry r = Extract(
      Corridor([t](double x) { return x < 4.0 ? 0.0 : (x < 7.0 ? (x - 4.0) * t : 3.0 * t); }));
  const auto ramps = OfKind(r, ObstacleKind::kRamp);
  ASSERT_EQ(ramps.size(), 1u);
  const Obstacle& ramp = *ramps[0];
  EXPECT_NEAR(ramp.slope_rad / kDeg, 10.0, 0.3);
  EXPECT_NEAR(ramp.height_m, 3.0 * t, 0.1);
  EXPECT_NEAR(ramp.centroid_m.x(), 5.5, 0.3);
  EXPECT_NEAR(ramp.centroid_m.y(), 2.0, 0.2);
  EXPECT_NEAR(ramp.width_m, 3.0, 0.45);   // along the slope, the shorter extent here
  EXPECT_NEAR(ramp.length_m, 4.0, 0.45);  // across the corridor
  EXPECT_FALSE(Crossable(ramp, "pioneer3at"));
  EXPECT_TRUE(Crossable(ramp, "rover"));
  EXPECT_NE(ramp.VerdictFor("pioneer3at")->reason.find("slope"), std::string::npos);
  // It rises eastwards: down it is west, and the Pioneer (no downhill limit) may drive it that way.
  EXPECT_NEAR(std::fabs(std::remainder(ramp.downhill_heading_rad, 2 * M_PI)) / kDeg, 180.0, 5.0);
  EXPECT_NE(ramp.VerdictFor("pioneer3at")->reason.find("crossable downhill only, heading 180 deg"),
            std::string::npos)
      << ramp.VerdictFor("pioneer3at")->reason;
  EXPECT_TRUE(Inside(ramp.outline_m, ramp.centroid_m));
  EXPECT_TRUE(OfKind(r, ObstacleKind::kStepUp).empty());
  EXPECT_TRUE(OfKind(r, ObstacleKind::kWallOrObject).empty());
}

TEST(ObstaclesTest, FiveDegreeRampIsCrossableForBoth) {
  const double t = std::tan(5 * kDeg);
  const common::ObstacleRegistry r = Extract(
      Corridor([t](double x) { return x < 4.0 ? 0.0 : (x < 7.0 ? (x - 4.0) * t : 3.0 * t); }));
  const auto ramps = OfKind(r, ObstacleKind::kRamp);
  ASSERT_EQ(ramps.size(), 1u);
  EXPECT_NEAR(ramps[0]->slope_rad / kDeg, 5.0, 0.3);
  EXPECT_TRUE(Crossable(*ramps[0], "pioneer3at"));
  EXPECT_TRUE(Crossable(*ramps[0], "rover"));
}

// A block across the corridor, 0.2 m high and 1 m deep: a slab with its faces, one terrace whose
// two faces are steps up of 0.2 m (the ground around it is at the low level), blocked for both
// profiles with no way onto it. With terraces off, the faces are two steps up.
TEST(ObstaclesTest, TwentyCentimetreStepIsAStepUpForNeither) {
  const GridMap block = Corridor([](double x) { return (x > 6.0 && x < 7.0) ? 0.2 : 0.0; });
  const common::ObstacleRegistry r = Extract(block);
  ASSERT_EQ(r.obstacles.size(), 1u);
  const Obstacle& slab = r.obstacles[0];
  ASSERT_EQ(slab.kind, ObstacleKind::kTerrace);
  ASSERT_EQ(slab.parts.size(), 2u);
  for (const auto& face : slab.parts) {
    EXPECT_EQ(face.kind, ObstacleKind::kStepUp);
    EXPECT_NEAR(face.height_m, 0.2, 1e-4);
    EXPECT_NEAR(face.length_m, 4.0, 0.05);
    EXPECT_FALSE(face.VerdictFor("pioneer3at")->crossable);
  }
  EXPECT_NEAR(std::min(slab.parts[0].centroid_m.x(), slab.parts[1].centroid_m.x()), 6.0, 0.25);
  EXPECT_NEAR(std::max(slab.parts[0].centroid_m.x(), slab.parts[1].centroid_m.x()), 7.0, 0.25);
  EXPECT_FALSE(Crossable(slab, "pioneer3at"));
  EXPECT_FALSE(Crossable(slab, "rover"));
  EXPECT_EQ(slab.VerdictFor("rover")->reason.rfind("no way onto the platform: ", 0), 0u)
      << slab.VerdictFor("rover")->reason;

  ObstacleParams no_terraces;
  no_terraces.max_terrace_area_m2 = 0.0;
  common::ObstacleRegistry pieces = ExtractWith(block, no_terraces);
  LabelObstacles(&pieces, {ShippedProfile("pioneer3at"), ShippedProfile("rover")});
  const auto steps = OfKind(pieces, ObstacleKind::kStepUp);
  ASSERT_EQ(steps.size(), 2u);
  for (const Obstacle* s : steps) {
    EXPECT_NEAR(s->height_m, 0.2, 1e-4);
    EXPECT_NEAR(s->length_m, 4.0, 0.05);
    EXPECT_FALSE(Crossable(*s, "pioneer3at"));
    EXPECT_FALSE(Crossable(*s, "rover"));
  }
  EXPECT_NEAR(steps[0]->centroid_m.x(), 6.0, 0.25);
  EXPECT_NEAR(steps[1]->centroid_m.x(), 7.0, 0.25);
  EXPECT_TRUE(OfKind(pieces, ObstacleKind::kRamp).empty());
  EXPECT_TRUE(OfKind(pieces, ObstacleKind::kWallOrObject).empty());
}

// A 1 cm slab across the corridor in noisy ground: its faces are listed (a terrace's parts, or
// steps), 1 cm high and crossable both ways for both profiles, and so is the whole.
TEST(ObstaclesTest, OneCentimetreStepIsCrossable) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.0015);
  const common::ObstacleRegistry r =
      Extract(Corridor([&](double x) { return ((x > 6.0 && x < 7.0) ? 0.01 : 0.0) + noise(rng); }));
  struct Face {
    double height_m, length_m;
    int32_t num_cells;
    const std::vector<common::ObstacleVerdict>* verdicts;
  };
  std::vector<Face> faces;
  for (const auto& o : r.obstacles) {
    if (o.kind == ObstacleKind::kStepUp) {
      faces.push_back({o.height_m, o.length_m, o.num_cells, &o.verdicts});
    }
    for (const auto& p : o.parts) {
      if (p.kind == ObstacleKind::kStepUp) {
        faces.push_back({p.height_m, p.length_m, p.num_cells, &p.verdicts});
      }
    }
    EXPECT_TRUE(Crossable(o, "pioneer3at")) << common::ObstacleKindName(o.kind);
    EXPECT_TRUE(Crossable(o, "rover"));
  }
  ASSERT_GE(faces.size(), 1u);
  const Face* longest = &faces[0];
  for (const Face& f : faces) {
    if (f.num_cells > longest->num_cells) longest = &f;
  }
  EXPECT_NEAR(longest->height_m, 0.01, 0.003);
  EXPECT_GT(longest->length_m, 3.0);
  for (const Face& f : faces) {
    for (const auto& v : *f.verdicts) EXPECT_TRUE(v.crossable) << v.profile << ": " << v.reason;
  }
}

// A platform reached by ground on one side, seen falling away on the other: the far edge is a
// step down (the ground around it is at the high level).
TEST(ObstaclesTest, StepDownOfALowerArea) {
  const common::ObstacleRegistry r =
      Extract(Corridor([](double x) { return (x > 12.0) ? -0.2 : 0.0; }, 70));
  const auto downs = OfKind(r, ObstacleKind::kStepDown);
  ASSERT_EQ(downs.size(), 1u);
  EXPECT_NEAR(downs[0]->height_m, 0.2, 1e-4);
  EXPECT_NEAR(std::remainder(downs[0]->downhill_heading_rad, 2 * M_PI) / kDeg, 0.0, 5.0);
  EXPECT_FALSE(Crossable(*downs[0], "pioneer3at"));  // 0.20 > 0.10
  EXPECT_FALSE(Crossable(*downs[0], "rover"));       // 0.20 > 0.15
}

TEST(ObstaclesTest, UnseenTrenchIsADitchForBoth) {
  GridMap map = Corridor([](double x) { return (x > 6.0 && x < 6.6) ? std::nan("") : 0.0; });
  common::Layer& b = map.AddLayer(layers::kGroundBound);
  for (int ix = 30; ix < 33; ++ix) {
    for (int iy = 0; iy < 20; ++iy) b(ix, iy) = -0.12f;
  }
  const common::ObstacleRegistry r = Extract(map);
  const auto ditches = OfKind(r, ObstacleKind::kDitch);
  ASSERT_EQ(ditches.size(), 1u);
  const Obstacle& d = *ditches[0];
  EXPECT_NEAR(d.width_m, 0.6, 1e-4);
  EXPECT_TRUE(std::isnan(d.depth_m));  // never saw the bottom
  EXPECT_NEAR(d.centroid_m.x(), 6.3, 0.15);
  EXPECT_FALSE(Crossable(d, "pioneer3at"));
  EXPECT_FALSE(Crossable(d, "rover"));
  EXPECT_TRUE(OfKind(r, ObstacleKind::kStepUp).empty());
  EXPECT_TRUE(OfKind(r, ObstacleKind::kStepDown).empty());
}

// The trench of the terraces world seen whole: 0.6 m wide, 0.25 m deep, its floor known. One
// ditch with its width and depth (no steps down and up at its faces); the rover (0.30 m ditches,
// 0.08 m steps up) can neither bridge it nor drive through it.
TEST(ObstaclesTest, ASeenTrenchIsOneDitchWithItsWidthAndDepth) {
  const common::ObstacleRegistry r =
      Extract(Corridor([](double x) { return (x > 6.0 && x < 6.6) ? -0.25 : 0.0; }));
  const auto ditches = OfKind(r, ObstacleKind::kDitch);
  ASSERT_EQ(ditches.size(), 1u);
  const Obstacle& d = *ditches[0];
  EXPECT_NEAR(d.width_m, 0.6, 1e-4);
  EXPECT_NEAR(d.depth_m, 0.25, 1e-4);
  EXPECT_NEAR(d.centroid_m.x(), 6.3, 0.15);
  EXPECT_FALSE(Crossable(d, "pioneer3at"));
  EXPECT_FALSE(Crossable(d, "rover"));
  EXPECT_TRUE(OfKind(r, ObstacleKind::kStepUp).empty());
  EXPECT_TRUE(OfKind(r, ObstacleKind::kStepDown).empty());
  // Off: the faces are steps again.
  ObstacleParams off;
  off.seen_ditch_max_width_m = 0;
  EXPECT_TRUE(
      OfKind(
          ExtractWith(Corridor([](double x) { return (x > 6.0 && x < 6.6) ? -0.25 : 0.0; }), off),
          ObstacleKind::kDitch)
          .empty());
}

// A seen slot narrower than the rover's ditch width is bridged; 6 cm deep and 1 m wide, the
// rover drives through it (both steps within its limits) but the Pioneer (3 cm up) cannot.
TEST(ObstaclesTest, SeenDitchesAreJudgedByWidthAndDepth) {
  const common::ObstacleRegistry slot =
      Extract(Corridor([](double x) { return (x > 6.0 && x < 6.2) ? -0.25 : 0.0; }));
  const auto narrow = OfKind(slot, ObstacleKind::kDitch);
  ASSERT_EQ(narrow.size(), 1u);
  EXPECT_NEAR(narrow[0]->width_m, 0.2, 1e-4);
  EXPECT_TRUE(Crossable(*narrow[0], "rover"));        // 0.20 <= 0.30
  EXPECT_FALSE(Crossable(*narrow[0], "pioneer3at"));  // 0.20 > 0.10, 0.25 deep
  const common::ObstacleRegistry dip =
      Extract(Corridor([](double x) { return (x > 6.0 && x < 7.0) ? -0.06 : 0.0; }));
  const auto shallow = OfKind(dip, ObstacleKind::kDitch);
  ASSERT_EQ(shallow.size(), 1u);
  EXPECT_NEAR(shallow[0]->depth_m, 0.06, 1e-4);
  EXPECT_TRUE(Crossable(*shallow[0], "rover"));
  EXPECT_FALSE(Crossable(*shallow[0], "pioneer3at"));
}

// Floor between two raised slabs further apart than seen_ditch_max_width_m (1.2 m) is floor, and a
// valley between two slopes is no ditch either.
TEST(ObstaclesTest, WideFloorsAndValleysAreNoDitches) {
  const auto between =
      Extract(Corridor([](double x) { return (x > 4.0 && x < 6.0) || x > 8.0 ? 0.2 : 0.0; }));
  for (const Obstacle* d : OfKind(between, ObstacleKind::kDitch)) {
    ADD_FAILURE() << "a ditch at " << d->centroid_m.transpose() << ", " << d->width_m << " m wide";
  }
  // 1 m apart, the same floor is a ditch between the slabs.
  const auto trench =
      Extract(Corridor([](double x) { return (x > 4.0 && x < 6.0) || x > 7.0 ? 0.2 : 0.0; }));
  const auto ditches = OfKind(trench, ObstacleKind::kDitch);
  ASSERT_EQ(ditches.size(), 1u);
  EXPECT_NEAR(ditches[0]->width_m, 1.0, 1e-4);
  // Nor is a dip in the top of a wall (1 m high, 0.2 m thick, 6 cm lower over 0.4 m): its cells
  // are the wall's.
  const auto wall_top = Extract(MakeTerrain(40, 30, kRes, [](double x, double y) {
    if (y > 3.0 && y < 3.2) return (x > 3.0 && x < 3.4) ? 0.94 : 1.0;
    return 0.0;
  }));
  EXPECT_TRUE(OfKind(wall_top, ObstacleKind::kDitch).empty());
  // The top of a 1.3 m wall, 0.4 m thick, seen from afar (as the mapper kept it in the terraces
  // world): 13 cm lower over 0.6 m, nothing seen west of it, the floor east of it seen only beside
  // the dip, and the wall's edges unclassified. Still no ditch.
  GridMap far_wall = MakeTerrain(40, 30, kRes, [](double x, double y) {
    if (x > 3.0 && x < 3.4) return (y > 3.0 && y < 3.6) ? 1.17 : 1.3;
    return (x > 3.4 && x < 3.6 && y > 2.8 && y < 3.8) ? 0.0 : std::nan("");
  });
  ComputeGeometricLayers(&far_wall, {});
  ComputeFeatureLayers(&far_wall, {}, CellRect::All(far_wall));
  for (int iy = 0; iy < far_wall.size_y(); ++iy) {
    for (int ix : {15, 16}) {
      far_wall.at(kFeatureClassLayer)(ix, iy) = static_cast<float>(internal::kNone);
    }
  }
  EXPECT_TRUE(OfKind(AssembleObstacles(far_wall, {}), ObstacleKind::kDitch).empty());
  const auto valley = Extract(Corridor([](double x) { return 0.05 * std::fabs(x - 6.0); }));
  EXPECT_TRUE(OfKind(valley, ObstacleKind::kDitch).empty());
}

TEST(ObstaclesTest, CubeIsAWallOrObject) {
  const common::ObstacleRegistry r = Extract(MakeTerrain(40, 40, kRes, [](double x, double y) {
    return (x > 3.0 && x < 4.0 && y > 4.0 && y < 5.0) ? 1.0 : 0.0;
  }));
  const auto walls = OfKind(r, ObstacleKind::kWallOrObject);
  ASSERT_EQ(walls.size(), 1u);
  EXPECT_NEAR(walls[0]->height_m, 1.0, 1e-4);
  EXPECT_NEAR(walls[0]->centroid_m.x(), 3.5, 0.05);
  EXPECT_NEAR(walls[0]->centroid_m.y(), 4.5, 0.05);
  EXPECT_TRUE(Inside(walls[0]->outline_m, {3.5, 4.5}));
  EXPECT_FALSE(Inside(walls[0]->outline_m, {6.0, 6.0}));
  EXPECT_FALSE(Crossable(*walls[0], "rover"));
  EXPECT_EQ(r.obstacles.size(), 1u);
}

// Two pieces of one 1 m high wall. With nothing seen in the 0.4 m between them (the object's
// unseen middle, its shadow) they come within object_join_gap_m (0.6 m, off by default) of each
// other: one object, outlined around both pieces. With floor seen between them, a doorway 1.2 m
// wide (the floor cells at its sides are edges of the wall: 0.8 m between the pieces' cells),
// they stay two; with nothing seen over 2 m, too.
TEST(ObstaclesTest, WallPiecesWithNothingSeenBetweenThemAreOneObject) {
  const double kNaNHeight = std::numeric_limits<double>::quiet_NaN();
  auto wall = [&](double gap_m, bool seen_between) {
    return MakeTerrain(60, 40, kRes, [=](double x, double y) {
      const bool in_y = y > 4.0 && y < 4.2;
      const bool in_gap = x > 4.0 && x < 4.0 + gap_m;
      if (!seen_between && in_gap && y > 3.6 && y < 4.6) return kNaNHeight;
      return in_y && ((x > 2.0 && x < 4.0) || (x > 4.0 + gap_m && x < 6.0 + gap_m)) ? 1.0 : 0.0;
    });
  };
  ObstacleParams joined;
  joined.object_join_gap_m = 0.6;
  const auto one = OfKind(ExtractWith(wall(0.4, false), joined), ObstacleKind::kWallOrObject);
  ASSERT_EQ(one.size(), 1u);
  for (const common::Vector2& p :
       {common::Vector2(2.5, 4.1), common::Vector2(4.2, 4.1), common::Vector2(6.1, 4.1)}) {
    EXPECT_TRUE(Inside(one[0]->outline_m, p)) << p.transpose();
  }
  EXPECT_FALSE(Inside(one[0]->outline_m, {4.2, 5.0}));
  EXPECT_EQ(OfKind(ExtractWith(wall(0.4, false), {}), ObstacleKind::kWallOrObject).size(),
            2u);  // off
  EXPECT_EQ(OfKind(ExtractWith(wall(1.2, true), joined), ObstacleKind::kWallOrObject).size(),
            2u);  // a doorway
  EXPECT_EQ(OfKind(ExtractWith(wall(2.0, false), joined), ObstacleKind::kWallOrObject).size(), 2u);
}

// A straight wall with a 1.2 m doorway (floor seen through it) is one wall when openings up to
// 1.5 m join pieces in line; two walls 1.2 m apart side by side (a corridor) stay two, and so
// does a wall whose pieces are offset sideways.
TEST(ObstaclesTest, AWallWithADoorwayIsOneWall) {
  auto terrain = [](std::function<bool(double, double)> wall) {
    return MakeTerrain(60, 40, kRes, [wall](double x, double y) { return wall(x, y) ? 1.0 : 0.0; });
  };
  const GridMap doorway = terrain([](double x, double y) {
    return y > 4.0 && y < 4.2 && ((x > 2.0 && x < 4.0) || (x > 5.2 && x < 7.2));
  });
  const GridMap corridor = terrain([](double x, double y) {
    return x > 2.0 && x < 7.0 && ((y > 2.0 && y < 2.2) || (y > 3.4 && y < 3.6));
  });
  const GridMap offset = terrain([](double x, double y) {
    return (y > 4.0 && y < 4.2 && x > 2.0 && x < 4.0) || (y > 5.0 && y < 5.2 && x > 5.2 && x < 7.2);
  });
  ObstacleParams openings;
  openings.object_opening_max_m = 1.5;
  const auto one = OfKind(ExtractWith(doorway, openings), ObstacleKind::kWallOrObject);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_TRUE(Inside(one[0]->outline_m, {3.0, 4.1}));
  EXPECT_TRUE(Inside(one[0]->outline_m, {6.0, 4.1}));
  EXPECT_EQ(OfKind(ExtractWith(doorway, {}), ObstacleKind::kWallOrObject).size(), 2u);  // off
  EXPECT_EQ(OfKind(ExtractWith(corridor, openings), ObstacleKind::kWallOrObject).size(), 2u);
  EXPECT_EQ(OfKind(ExtractWith(offset, openings), ObstacleKind::kWallOrObject).size(), 2u);
}

TEST(ObstaclesTest, FlatNoisyGroundHoldsNoFeatures) {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.001);
  const common::ObstacleRegistry r =
      Extract(MakeTerrain(50, 50, kRes, [&](double, double) { return noise(rng); }));
  EXPECT_TRUE(r.obstacles.empty());
}

// A smooth hill (a Gaussian bump 1 m high, 2.5 m wide: up to 13 deg) fades out into the plain
// around it: terrain the cost layer judges by its slope, not a ramp. The same cells with the
// crease rule off come out as ramps.
TEST(ObstaclesTest, AHillsideIsTerrainNotARamp) {
  const GridMap hill = MakeTerrain(60, 60, kRes, [](double x, double y) {
    return std::exp(-((x - 6.0) * (x - 6.0) + (y - 6.0) * (y - 6.0)) / (2.0 * 2.5 * 2.5));
  });
  ObstacleParams every_incline;
  every_incline.min_ramp_crease_fraction = 0.0;
  EXPECT_FALSE(OfKind(ExtractWith(hill, every_incline), ObstacleKind::kRamp).empty());
  EXPECT_TRUE(ExtractWith(hill, {}).obstacles.empty());
}

// A 1.2 cm step across a corridor is a step where both sides were observed to a millimetre, and
// noise where their heights are known to a centimetre only (3 sigma of the difference: 4 cm).
TEST(ObstaclesTest, AStepMustStandOutOfTheNoiseOfItsHeights) {
  GridMap step = Corridor([](double x) { return x < 5.0 ? 0.0 : 0.012; });
  common::Layer& variance = step.AddLayer(layers::kElevationVariance);
  variance.setConstant(1e-6f);
  EXPECT_EQ(OfKind(ExtractWith(step, {}), ObstacleKind::kStepUp).size(), 1u);
  variance.setConstant(1e-4f);
  EXPECT_TRUE(ExtractWith(step, {}).obstacles.empty());
  ObstacleParams no_noise_test;
  no_noise_test.step_noise_sigmas = 0.0;
  EXPECT_EQ(OfKind(ExtractWith(step, no_noise_test), ObstacleKind::kStepUp).size(), 1u);
}

// A hillside seen from afar: a lidar ring crosses each cell along one contour, so a cell's
// height is the ground's where its points lay, up to half a cell's rise off its centre's. Cells
// seen in pairs with nothing known to either side differ by the slope's rise plus twice that
// offset; the normals' rise (here from the true heights) is all there is to take the slope from,
// and against it the difference is noise. The same difference on level ground is a step.
TEST(ObstaclesTest, CellsSeenInPairsOnAHillsideHoldNoStep) {
  const double offset_m = 0.012;
  for (const double slope_deg : {8.0, 0.0}) {
    SCOPED_TRACE(slope_deg);
    const double t = std::tan(slope_deg * kDeg);
    // Pairs of columns (x = 0.4 k to 0.4 k + 0.4 m), every other pair unknown.
    GridMap map = MakeTerrain(40, 40, kRes, [t](double x, double) {
      const int ix = static_cast<int>(std::floor(x / kRes));
      return ix % 4 >= 2 ? std::numeric_limits<double>::quiet_NaN() : t * x;
    });
    map.AddLayer(layers::kElevationVariance).setConstant(0.004f * 0.004f);
    ComputeGeometricLayers(&map, {});
    // The normals stand; each cell's height moves to where its points lay, the lower cell of a
    // pair down the slope, the upper one up it (on level ground: as far, for the same difference).
    const double rise_m = slope_deg > 0 ? 0.0 : kRes * std::tan(8.0 * kDeg);
    common::Layer& h = map.at(layers::kElevation);
    for (int iy = 0; iy < map.size_y(); ++iy) {
      for (int ix = 0; ix < map.size_x(); ++ix) {
        if (ix % 4 == 0) h(ix, iy) -= static_cast<float>(offset_m);
        if (ix % 4 == 1) h(ix, iy) += static_cast<float>(offset_m + rise_m);
      }
    }
    const common::ObstacleRegistry r = ExtractObstacles(map, {});
    const size_t steps = OfKind(r, ObstacleKind::kStepUp).size() +
                         OfKind(r, ObstacleKind::kStepDown).size() +
                         OfKind(r, ObstacleKind::kTerrace).size();
    if (slope_deg > 0) {
      EXPECT_EQ(steps, 0u);
    } else {
      EXPECT_GT(steps, 0u);
    }
  }
}

common::Obstacle Make(ObstacleKind kind) {
  common::Obstacle o;
  o.kind = kind;
  return o;
}

// Terraces: lane 0 of the terraces world in a 4 m corridor. A 5 deg ramp rises from x 8.0 to the
// platform at `drop_m`, which runs to x 12.0 and drops back to the ground there. North of
// `ramp_down_from_y_m` the far end is a 5 deg ramp down instead of the drop (lane 4).
GridMap Terrace(double drop_m, double ramp_down_from_y_m = 1e9) {
  const double t = std::tan(5 * kDeg);
  const double up_end = 8.0 + drop_m / t;
  return MakeTerrain(80, 20, kRes, [=](double x, double y) {
    if (x < 8.0) return 0.0;
    if (x < up_end) return (x - 8.0) * t;
    if (x < 12.0) return drop_m;
    if (y >= ramp_down_from_y_m && x < 12.0 + drop_m / t) return drop_m - (x - 12.0) * t;
    return 0.0;
  });
}

const common::ObstaclePart* PartOfKind(const Obstacle& o, ObstacleKind kind, double x_m) {
  const common::ObstaclePart* best = nullptr;
  for (const auto& p : o.parts) {
    if (p.kind == kind && (best == nullptr || std::fabs(p.centroid_m.x() - x_m) <
                                                  std::fabs(best->centroid_m.x() - x_m))) {
      best = &p;
    }
  }
  return best;
}

double HeadingDeg(double rad) { return std::remainder(rad, 2 * M_PI) / kDeg; }

// The lane: a ramp up and an 8 cm drop at the far end of the platform are one entry, a
// terrace with its two parts, and its verdict is what the planner does: the Pioneer 3-AT (3 cm
// up, 10 cm down) may cross it eastwards only, up the ramp and off the drop; the rover (8 cm up)
// both ways. Each part says which way it may be driven.
TEST(ObstaclesTest, ARampItsPlatformAndItsDropAreOneTerrace) {
  const common::ObstacleRegistry r = Extract(Terrace(0.08));
  ASSERT_EQ(r.obstacles.size(), 1u);
  const Obstacle& t = r.obstacles[0];
  ASSERT_EQ(t.kind, ObstacleKind::kTerrace);
  ASSERT_EQ(t.parts.size(), 2u);
  const common::ObstaclePart* ramp = PartOfKind(t, ObstacleKind::kRamp, 8.5);
  const common::ObstaclePart* face = PartOfKind(t, ObstacleKind::kStepUp, 12.0);
  ASSERT_NE(ramp, nullptr);
  ASSERT_NE(face, nullptr);
  EXPECT_NEAR(ramp->slope_rad / kDeg, 5.0, 0.5);
  EXPECT_NEAR(face->height_m, 0.08, 0.005);
  EXPECT_NEAR(face->centroid_m.x(), 12.0, 0.3);
  EXPECT_NEAR(HeadingDeg(ramp->heading_in_rad), 0.0, 10.0);               // onto it eastwards
  EXPECT_NEAR(std::fabs(HeadingDeg(face->heading_in_rad)), 180.0, 10.0);  // westwards
  EXPECT_NEAR(t.height_m, 0.08, 0.01);
  EXPECT_TRUE(Inside(t.outline_m, {10.5, 2.0}));  // the platform is in the entry
  EXPECT_TRUE(Inside(t.outline_m, ramp->centroid_m));

  const common::ObstacleVerdict* pioneer = t.VerdictFor("pioneer3at");
  ASSERT_NE(pioneer, nullptr);
  EXPECT_TRUE(common::IsOneWay(*pioneer)) << pioneer->reason;
  EXPECT_NE(pioneer->reason.find("crossable heading 0 deg only"), std::string::npos)
      << pioneer->reason;
  EXPECT_NE(pioneer->reason.find("step up 0.080 m > 0.030 m"), std::string::npos)
      << pioneer->reason;
  EXPECT_TRUE(Crossable(t, "rover"));
  ASSERT_NE(ramp->VerdictFor("pioneer3at"), nullptr);
  EXPECT_TRUE(ramp->VerdictFor("pioneer3at")->crossable);
  ASSERT_NE(face->VerdictFor("pioneer3at"), nullptr);
  EXPECT_TRUE(common::IsOneWay(*face->VerdictFor("pioneer3at")));
  EXPECT_NE(face->VerdictFor("pioneer3at")->reason.find("off the platform only, heading 0 deg"),
            std::string::npos)
      << face->VerdictFor("pioneer3at")->reason;
  EXPECT_TRUE(face->VerdictFor("rover")->crossable);
}

// A 12 cm drop: the Pioneer may drive up the ramp and back, but not across (12 cm is over both
// of its step limits); the rover (8 cm up, 15 cm down) eastwards only.
TEST(ObstaclesTest, ATerraceWhoseDropIsTooHighIsBlockedWithTheReason) {
  const common::ObstacleRegistry r = Extract(Terrace(0.12));
  const auto terraces = OfKind(r, ObstacleKind::kTerrace);
  ASSERT_EQ(terraces.size(), 1u);
  EXPECT_EQ(r.obstacles.size(), 1u);
  const common::ObstacleVerdict* pioneer = terraces[0]->VerdictFor("pioneer3at");
  ASSERT_NE(pioneer, nullptr);
  EXPECT_FALSE(pioneer->crossable);
  EXPECT_FALSE(common::IsOneWay(*pioneer)) << pioneer->reason;
  EXPECT_NE(pioneer->reason.find("(ramp) only"), std::string::npos) << pioneer->reason;
  EXPECT_NE(pioneer->reason.find("step 0.120 m > 0.030 m up and > 0.100 m down"), std::string::npos)
      << pioneer->reason;
  const common::ObstacleVerdict* rover = terraces[0]->VerdictFor("rover");
  EXPECT_TRUE(common::IsOneWay(*rover)) << rover->reason;
}

// Lane 4: the far end is half drop, half ramp down. The terrace is crossable both ways (over the
// two ramps); its drop is one-way, off the platform only.
TEST(ObstaclesTest, ATerraceWithTwoRampsIsCrossableAndItsDropOneWay) {
  const common::ObstacleRegistry r = Extract(Terrace(0.08, 2.0));
  const auto terraces = OfKind(r, ObstacleKind::kTerrace);
  ASSERT_EQ(terraces.size(), 1u);
  EXPECT_EQ(r.obstacles.size(), 1u);
  const Obstacle& t = *terraces[0];
  EXPECT_TRUE(Crossable(t, "pioneer3at")) << t.VerdictFor("pioneer3at")->reason;
  int ramps = 0, one_way_faces = 0;
  for (const auto& p : t.parts) {
    if (p.kind == ObstacleKind::kRamp) {
      ++ramps;
      EXPECT_TRUE(p.VerdictFor("pioneer3at")->crossable);
    } else if (common::IsOneWay(*p.VerdictFor("pioneer3at"))) {
      ++one_way_faces;
    }
  }
  EXPECT_EQ(ramps, 2);
  EXPECT_GE(one_way_faces, 1);
}

// A slab the height of a step stays level ground's business when it is as large as the ground:
// terraces are platforms no larger than max_terrace_area_m2, and 0 turns them off.
TEST(ObstaclesTest, TerracesCanBeTurnedOff) {
  ObstacleParams off;
  off.max_terrace_area_m2 = 0.0;
  const common::ObstacleRegistry r = ExtractWith(Terrace(0.08), off);
  EXPECT_TRUE(OfKind(r, ObstacleKind::kTerrace).empty());
  EXPECT_EQ(OfKind(r, ObstacleKind::kRamp).size(), 1u);
  ObstacleParams small;
  small.max_terrace_area_m2 = 5.0;  // the platform is about 3 m by 4 m
  EXPECT_TRUE(OfKind(ExtractWith(Terrace(0.08), small), ObstacleKind::kTerrace).empty());
}

TEST(JudgeObstacleTest, BoundariesPerKind) {
  const common::RobotProfile pioneer = ShippedProfile("pioneer3at");
  Obstacle ramp = Make(ObstacleKind::kRamp);
  ramp.slope_rad = 7.9 * kDeg;
  EXPECT_TRUE(JudgeObstacle(ramp, pioneer).crossable);
  ramp.slope_rad = 8.0 * kDeg;
  EXPECT_FALSE(JudgeObstacle(ramp, pioneer).crossable);
  // No downhill limit (seed 000): one-way.
  EXPECT_EQ(JudgeObstacle(ramp, pioneer).reason,
            "slope 8.0 deg >= 8.0 deg; one-way: crossable downhill only");
  Obstacle up = Make(ObstacleKind::kStepUp);
  up.height_m = 0.03;
  EXPECT_TRUE(JudgeObstacle(up, pioneer).crossable);
  up.height_m = 0.031;
  const common::ObstacleVerdict v = JudgeObstacle(up, pioneer);
  EXPECT_FALSE(v.crossable);
  // Within the 10 cm step down: the directed layer lets the Pioneer drive down it.
  EXPECT_EQ(v.reason,
            "step up 0.031 m > 0.030 m; one-way: crossable downwards only (<= 0.100 m step down)");
  EXPECT_TRUE(common::IsOneWay(v));
  EXPECT_STREQ(common::VerdictWord(v), "one-way");
  up.downhill_heading_rad = M_PI / 2;  // the way down, when the registry knows it
  EXPECT_EQ(JudgeObstacle(up, pioneer).reason,
            "step up 0.031 m > 0.030 m; one-way: crossable downwards only (<= 0.100 m step down), "
            "heading 90 deg +- 45 deg");
  up.height_m = 0.12;  // over both limits: no way across
  EXPECT_EQ(JudgeObstacle(up, pioneer).reason, "step up 0.120 m > 0.030 m");
  EXPECT_FALSE(common::IsOneWay(JudgeObstacle(up, pioneer)));
  EXPECT_STREQ(common::VerdictWord(JudgeObstacle(up, pioneer)), "blocked");
  EXPECT_EQ(v.profile, "pioneer3at");
  EXPECT_EQ(v.profile_hash, pioneer.ContentHash());
  Obstacle down = Make(ObstacleKind::kStepDown);
  down.height_m = 0.10;
  EXPECT_TRUE(JudgeObstacle(down, pioneer).crossable);
  down.height_m = 0.101;
  EXPECT_FALSE(JudgeObstacle(down, pioneer).crossable);
  Obstacle ditch = Make(ObstacleKind::kDitch);
  ditch.width_m = 0.1;
  ditch.depth_m = NAN;
  EXPECT_TRUE(JudgeObstacle(ditch, pioneer).crossable);  // bridged
  ditch.width_m = 0.6;
  EXPECT_FALSE(JudgeObstacle(ditch, pioneer).crossable);
  ditch.depth_m = 0.02;  // a shallow groove the robot drives through
  EXPECT_TRUE(JudgeObstacle(ditch, pioneer).crossable);
  Obstacle wall = Make(ObstacleKind::kWallOrObject);
  wall.height_m = 1.0;
  EXPECT_FALSE(JudgeObstacle(wall, pioneer).crossable);
  EXPECT_TRUE(JudgeObstacle(ramp, ShippedProfile("rover")).crossable);
}

TEST(JudgeObstacleTest, LabelReplacesOnlyTheGivenProfiles) {
  common::ObstacleRegistry r;
  Obstacle up = Make(ObstacleKind::kStepUp);
  up.height_m = 0.05;
  common::ObstacleVerdict stale;
  stale.profile = "pioneer3at";
  stale.crossable = true;
  common::ObstacleVerdict other;
  other.profile = "kobuki";
  other.crossable = false;
  up.verdicts = {stale, other};
  r.obstacles.push_back(up);
  LabelObstacles(&r, {ShippedProfile("pioneer3at"), ShippedProfile("rover")});
  ASSERT_EQ(r.obstacles[0].verdicts.size(), 3u);
  EXPECT_FALSE(r.obstacles[0].VerdictFor("pioneer3at")->crossable);
  EXPECT_TRUE(r.obstacles[0].VerdictFor("rover")->crossable);
  EXPECT_FALSE(r.obstacles[0].VerdictFor("kobuki")->crossable);  // kept as it was
}

// Issue 20 (found by fuzz_bus_mapper under UBSan): the registry cast the class layer's floats
// to integers, NaN included (a cell never classified): undefined behaviour. ClassOf reads NaN,
// and any value that is no class, as kNone.
TEST(ObstaclesTest, AClassLayerValueThatIsNoClassReadsAsNone) {
  EXPECT_EQ(internal::ClassOf(std::numeric_limits<float>::quiet_NaN()), internal::kNone);
  EXPECT_EQ(internal::ClassOf(-3.f), internal::kNone);
  EXPECT_EQ(internal::ClassOf(1e9f), internal::kNone);
  EXPECT_EQ(internal::ClassOf(0.f), internal::kNone);
  EXPECT_EQ(internal::ClassOf(static_cast<float>(internal::kStep)), internal::kStep);
  EXPECT_EQ(internal::ClassOf(static_cast<float>(internal::kRamp)), internal::kRamp);
}

}  // namespace
}  // namespace cairn::mapping
