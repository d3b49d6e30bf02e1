#include "services/explore/scan_features.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "tests/unit/services/explore/scan_test_scenes.h"
#include <Eigen/Geometry>

namespace cairn::explore {
namespace {

using namespace scan_testing;  // NOLINT: the shared scenes

ScanAnalysisParams Theta(double deg) {
  ScanAnalysisParams p;
  p.max_slope_rad = deg * kDeg;
  return p;
}

// Points on `surface` all of whose mesh neighbours are on it too (away from its borders).
std::vector<int> Interior(const CastScan& c, const ScanMesh& mesh, int surface) {
  std::vector<int> out;
  for (int i = 0; i < c.scan.size(); ++i) {
    if (c.id[i] != surface) continue;
    const std::vector<int32_t> nb = NeighboursOf(mesh, i);
    if (nb.size() < 6) continue;
    if (std::all_of(nb.begin(), nb.end(), [&](int32_t q) { return c.id[q] == surface; })) {
      out.push_back(i);
    }
  }
  return out;
}

// Points on which `on` holds, as on all points within `rings` mesh steps of them.
template <typename Pred>
std::vector<int> InteriorWhere(const CastScan& c, const ScanMesh& mesh, int rings, Pred on) {
  std::vector<uint8_t> inside(c.scan.size());
  for (int i = 0; i < c.scan.size(); ++i) inside[i] = c.id[i] >= 0 && on(i);
  for (int r = 0; r < rings; ++r) {
    std::vector<uint8_t> next = inside;
    for (int i = 0; i < c.scan.size(); ++i) {
      if (NeighboursOf(mesh, i).size() < 6) next[i] = 0;
      for (int32_t q : NeighboursOf(mesh, i)) next[i] = next[i] && inside[q];
    }
    inside = std::move(next);
  }
  std::vector<int> out;
  for (int i = 0; i < c.scan.size(); ++i) {
    if (inside[i]) out.push_back(i);
  }
  return out;
}

struct Analysed {
  CastScan cast;
  ScanMesh mesh;
  ScanFeatures features;
};

Analysed Analyse(const Scene& scene, const Fan& fan, const ScanAnalysisParams& params) {
  Analysed a;
  a.cast = Cast(scene, fan);
  a.mesh = BuildScanMesh(a.cast.scan);
  a.features = AnalyseScan(a.cast.scan, a.mesh, params);
  return a;
}

// Seed 002 test 3.
TEST(ScanFeaturesTest, SlopeTermIsOneHalfAtTheClimbingAngle) {
  for (double deg : {5.0, 15.0, 30.0, 45.0, 60.0}) {
    EXPECT_NEAR(SlopeTerm(std::cos(deg * kDeg), deg * kDeg, 10.0), 0.5, 1e-12) << deg;
    EXPECT_NEAR(SlopeTerm(std::cos(deg * kDeg), deg * kDeg, 3.0), 0.5, 1e-12) << deg;
  }
}

TEST(ScanFeaturesTest, SlopeTermIncreasesStrictlyWithTheNormalsZAndStaysPositivePastTheAngle) {
  for (double deg : {5.0, 15.0, 30.0, 45.0, 60.0}) {
    const double theta = deg * kDeg;
    // From 3 (1 - cos θ) below cos θ (S about 1e-13, where doubles still resolve it) to 1.
    const double c = std::cos(theta);
    double previous = -1.0;
    for (int i = 0; i <= 100; ++i) {
      const double n_z = std::min(1.0, c + (-3.0 + 4.0 * i / 100.0) * (1.0 - c));
      const double s = SlopeTerm(n_z, theta, 10.0);
      EXPECT_GT(s, previous) << deg << " deg, n_z " << n_z;
      EXPECT_GT(s, 0.0);
      EXPECT_LT(s, 1.0);
      previous = s;
    }
    // Just past the climbing angle: below one half, but not zero.
    const double steeper = SlopeTerm(std::cos(theta + 1.0 * kDeg), theta, 10.0);
    EXPECT_LT(steeper, 0.5);
    EXPECT_GT(steeper, 0.01);
  }
  EXPECT_GT(SlopeTerm(1.0, 20 * kDeg, 10.0), 0.9999);
}

TEST(ScanFeaturesTest, FlatGroundHasAnUpwardNormalAndASlopeTermNearOne) {
  Scene scene;
  scene.patches = {Floor(0.0)};
  const Analysed a = Analyse(scene, {-10, 10, -40, -10}, ScanAnalysisParams{});
  const std::vector<int> ground = Interior(a.cast, a.mesh, 0);
  ASSERT_GT(ground.size(), 1000u);
  for (int i : ground) {
    EXPECT_GT(a.mesh.normals[i].z(), 0.9999f);
    EXPECT_GT(SlopeTerm(a.mesh.normals[i].z(), 20 * kDeg, 10.0), 0.999);
    // Level ground near the robot's height: H about 1, F = (w_l + w_g) S H.
    EXPECT_GT(a.features.navigability[i], 0.98f);
  }
}

// Seed 002 test 4.
TEST(ScanFeaturesTest, HeightTermIsOneAtTheRobotsHeightAndFallsWithTheHeightDifference) {
  for (double d : {1.0, 2.5, 5.0, 10.0}) {
    for (double deg : {5.0, 15.0, 30.0, 45.0, 60.0}) {
      EXPECT_DOUBLE_EQ(HeightTerm(0.0, d, deg * kDeg), 1.0);
      double previous = 1.0;
      for (int i = 1; i <= 50; ++i) {
        const double dz = 0.1 * i;
        const double h = HeightTerm(dz, d, deg * kDeg);
        EXPECT_LT(h, previous) << d << " m, " << deg << " deg, dz " << dz;
        EXPECT_GT(h, 0.0);
        EXPECT_DOUBLE_EQ(HeightTerm(-dz, d, deg * kDeg), h);  // |P_z|
        previous = h;
      }
    }
  }
  EXPECT_NEAR(HeightTerm(10.0, 10.0, 45 * kDeg), std::exp(-1.0), 1e-12);
  // Straight above the scanner: d_xy is clamped, so H is finite and in (0, 1].
  EXPECT_DOUBLE_EQ(HeightTerm(0.0, 0.0, 30 * kDeg), 1.0);
  EXPECT_GE(HeightTerm(1e-6, 0.0, 30 * kDeg), 0.0);
  EXPECT_LT(HeightTerm(1e-6, 0.0, 30 * kDeg), 1.0);
}

// Seed 002 test 5.
TEST(ScanFeaturesTest, ATwentyDegreeRampIsNavigableForAThirtyDegreeRobot) {
  Scene scene;
  scene.patches = {Floor(0.0), Ramp(20 * kDeg, 3.0, 6.5, -3.0, 3.0)};
  const Analysed a = Analyse(scene, {-10, 10, -40, 0}, Theta(30));
  int ramp = 0;
  for (int i = 0; i < a.cast.scan.size(); ++i) {
    if (a.cast.id[i] != 1 || std::isnan(a.features.navigability[i])) continue;
    EXPECT_GT(a.features.navigability[i], 0.65f) << a.cast.scan.points_m[i].transpose();
    ++ramp;
  }
  EXPECT_GT(ramp, 1000);
}

TEST(ScanFeaturesTest, ARampDownIsNavigableAheadWithTheRobotsDescentAngle) {
  // Level ground to x 1, then a 7 degree ramp down. From 5.5 m on, a 12 degree climber's
  // symmetric H calls the ramp ahead unsafe (H about 0.6, tending to 0.56 far down it); with its
  // 20 degree descent angle below its base it is navigable (about 0.75), and nothing at the
  // base's height changes.
  Scene scene;
  scene.patches = {Floor(0.0, -1e3, 1.0), Ramp(-7 * kDeg, 1.0, 8.0, -3.0, 3.0)};
  const Fan fan{-10, 10, -40, 0};
  ScanAnalysisParams descent = Theta(12);
  descent.max_descent_rad = 20 * kDeg;
  const Analysed sym = Analyse(scene, fan, Theta(12));
  const Analysed asym = Analyse(scene, fan, descent);
  int ramp = 0, navigable_sym = 0, navigable_asym = 0;
  for (int i = 0; i < sym.cast.scan.size(); ++i) {
    if (sym.cast.id[i] != 1 || std::isnan(sym.features.navigability[i])) continue;
    if (sym.cast.scan.points_m[i].x() < 5.5) continue;
    ++ramp;
    navigable_sym += sym.features.navigability[i] > 0.65f;
    navigable_asym += asym.features.navigability[i] > 0.65f;
  }
  ASSERT_GT(ramp, 200);
  EXPECT_LT(navigable_sym, 0.1 * ramp);
  EXPECT_GT(navigable_asym, 0.9 * ramp);
  for (int i = 0; i < sym.cast.scan.size(); ++i) {
    if (sym.cast.id[i] == 0 && !std::isnan(sym.features.navigability[i])) {
      EXPECT_FLOAT_EQ(asym.features.navigability[i], sym.features.navigability[i]);
    }
  }
  ScanAnalysisParams bad = Theta(12);
  bad.max_descent_rad = 2.0;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
}

TEST(ScanFeaturesTest, AFortyFiveDegreeSlopeIsNotNavigableForAThirtyDegreeRobot) {
  Scene scene;
  scene.patches = {Floor(0.0), Ramp(45 * kDeg, 3.0, 4.5, -3.0, 3.0)};
  const Analysed a = Analyse(scene, {-10, 10, -40, 10}, Theta(30));
  const std::vector<int> slope = Interior(a.cast, a.mesh, 1);
  ASSERT_GT(slope.size(), 500u);
  for (int i : slope) EXPECT_LT(a.features.navigability[i], 0.5f);
  int all = 0, below = 0;
  for (int i = 0; i < a.cast.scan.size(); ++i) {
    if (a.cast.id[i] != 1 || std::isnan(a.features.navigability[i])) continue;
    ++all;
    below += a.features.navigability[i] < 0.5f;
  }
  EXPECT_GT(below, 0.95 * all);
}

TEST(ScanFeaturesTest, LevelGroundAboveTheSlopeConeScoresZero) {
  // A 0.5 m platform 1.0-1.3 m out: the cone of a 20 deg robot is 0.36-0.47 m high there, that of
  // a 30 deg robot 0.58-0.75 m.
  Scene scene;
  scene.patches = {Floor(0.0)};
  scene.boxes = {{{1.0, -0.5, 0.0}, {1.3, 0.5, 0.5}}};
  const int top_id = 1;
  for (double deg : {20.0, 30.0}) {
    const Analysed a = Analyse(scene, {-10, 10, -44, -10}, Theta(deg));
    int top = 0;
    for (int i : Interior(a.cast, a.mesh, top_id)) {
      if (std::fabs(a.cast.scan.points_m[i].z() - 0.5f) > 1e-4f) continue;
      ++top;
      if (deg == 20.0) {
        EXPECT_EQ(a.features.navigability[i], 0.f) << a.cast.scan.points_m[i].transpose();
      } else {
        EXPECT_GT(a.features.navigability[i], 0.3f) << a.cast.scan.points_m[i].transpose();
      }
    }
    EXPECT_GT(top, 100) << deg;
  }
}

// Seed 002 test 6: a 0.8 m box 3 m ahead.
TEST(ScanFeaturesTest, TheFacesOfAVerticalBoxAreObstacles) {
  Scene scene;
  scene.patches = {Floor(0.0)};
  scene.boxes = {{{3.0, -0.5, 0.0}, {3.5, 0.5, 0.8}}};
  const Analysed a = Analyse(scene, {-15, 15, -40, 5}, ScanAnalysisParams{});
  const auto on_face = [&](int i) {
    return a.cast.id[i] == 1 && std::fabs(a.cast.scan.points_m[i].x() - 3.f) < 1e-4f;
  };
  // Two mesh steps from the face's edges, where the normals blend with the floor's and top's.
  const std::vector<int> face = InteriorWhere(a.cast, a.mesh, 2, on_face);
  EXPECT_GT(face.size(), 300u);
  for (int i : face) {
    EXPECT_GT(a.features.obstacle[i], 0.83f) << a.cast.scan.points_m[i].transpose();
  }
  for (int i : Interior(a.cast, a.mesh, 0)) EXPECT_LT(a.features.obstacle[i], 0.05f);  // floor
}

TEST(ScanFeaturesTest, PointsMoreThanTheBandAboveTheLocalGroundAreIgnored) {
  Scene scene;
  scene.patches = {Floor(0.0)};
  scene.boxes = {{{3.0, -0.5, 0.0}, {3.5, 0.5, 2.0}}};
  const Analysed a = Analyse(scene, {-15, 15, -40, 25}, ScanAnalysisParams{});
  int high = 0, low = 0;
  const auto on_face = [&](int i) {
    return a.cast.id[i] == 1 && std::fabs(a.cast.scan.points_m[i].x() - 3.f) < 1e-4f;
  };
  for (int i : InteriorWhere(a.cast, a.mesh, 2, on_face)) {
    const float z = a.cast.scan.points_m[i].z();
    if (z > 1.0f) {
      EXPECT_EQ(a.features.obstacle[i], 0.f) << z;
      ++high;
    } else if (z > 0.05f && z < 0.95f) {
      EXPECT_GT(a.features.obstacle[i], 0.83f) << z;
      ++low;
    }
  }
  EXPECT_GT(high, 300);
  EXPECT_GT(low, 300);
}

TEST(ScanFeaturesTest, TheObstacleBandFollowsTheLocalGround) {
  // The robot stands on a platform; 2 m out the ground drops 1.5 m, and a 0.8 m box stands down
  // there 7 m out. Measured from the robot base its face would be 0.7-1.5 m below the ground, out
  // of the band; measured from the ground in front of it, it is an obstacle (H at its foot:
  // exp(-1.5 / (7 tan 20 deg)) = 0.55).
  Scene scene;
  scene.patches = {Floor(0.0, -100, 2.0), Floor(-1.5)};
  scene.boxes = {{{7.0, -0.5, -1.5}, {7.5, 0.5, -0.7}}};
  const Analysed a = Analyse(scene, {-10, 10, -40, 0}, ScanAnalysisParams{});
  const auto on_face = [&](int i) {
    return a.cast.id[i] == 2 && std::fabs(a.cast.scan.points_m[i].x() - 7.f) < 1e-4f;
  };
  const std::vector<int> face = InteriorWhere(a.cast, a.mesh, 2, on_face);
  EXPECT_GT(face.size(), 100u);
  for (int i : face) {
    EXPECT_GT(a.features.obstacle[i], 0.45f) << a.cast.scan.points_m[i].transpose();
  }
}

TEST(ScanFeaturesTest, GrassStubsScoreLowerThanABox) {
  Scene scene;
  scene.patches = {Floor(0.0)};
  const int first_stub = 2;
  scene.boxes = {{{3.0, 1.0, 0.0}, {3.5, 2.0, 0.8}}};  // the box, left of the grass
  for (double x = 2.5; x < 4.0; x += 0.15) {
    for (double y = -1.2; y < 0.0; y += 0.15) {
      scene.boxes.push_back({{x, y, 0.0}, {x + 0.02, y + 0.02, 0.05}});
    }
  }
  const Analysed a = Analyse(scene, {-30, 40, -40, 5}, ScanAnalysisParams{});
  double box_sum = 0, grass_sum = 0, grass_max = 0;
  int box = 0, grass = 0;
  for (int i = 0; i < a.cast.scan.size(); ++i) {
    const float b = a.features.obstacle[i];
    if (std::isnan(b)) continue;
    if (a.cast.id[i] == 1 && std::fabs(a.cast.scan.points_m[i].x() - 3.f) < 1e-4f) {
      box_sum += b;
      ++box;
    } else if (a.cast.id[i] >= first_stub) {
      grass_sum += b;
      grass_max = std::max<double>(grass_max, b);
      ++grass;
    }
  }
  ASSERT_GT(box, 300);
  ASSERT_GT(grass, 100);
  EXPECT_LT(grass_max, 0.83);
  EXPECT_LT(grass_sum / grass, 0.5 * box_sum / box);
  // The neighbourhood term is what filters it: scored on B_l alone the stubs score higher.
  ScanAnalysisParams local_only;
  local_only.w_bl = 1.0;
  local_only.w_bg = 0.0;
  const ScanFeatures unfiltered = AnalyseScan(a.cast.scan, a.mesh, local_only);
  double unfiltered_max = 0;
  for (int i = 0; i < a.cast.scan.size(); ++i) {
    if (a.cast.id[i] >= first_stub && !std::isnan(unfiltered.obstacle[i])) {
      unfiltered_max = std::max<double>(unfiltered_max, unfiltered.obstacle[i]);
    }
  }
  EXPECT_GT(unfiltered_max, grass_max + 0.1);
}

// Seed 002 test 7.
TEST(ScanFeaturesTest, QualityCombinationMatchesTheSeedsValues) {
  EXPECT_NEAR(CombinedQuality(1, 1, 0.93, 0.07), 1.0, 1e-4);
  EXPECT_NEAR(CombinedQuality(1, 0, 0.93, 0.07), 0.9972, 1e-4);
  EXPECT_NEAR(CombinedQuality(0, 1, 0.93, 0.07), 0.0751, 1e-4);
  EXPECT_NEAR(CombinedQuality(0.5, 0.5, 0.93, 0.07), 0.5, 1e-4);
  EXPECT_NEAR(CombinedQuality(0.5, 1, 0.93, 0.07), 0.5042, 1e-4);
  for (double w_a : {0.0, 0.2, 0.5, 0.8, 0.93, 1.0}) {
    for (int i = 0; i <= 10; ++i) {
      for (int j = 0; j <= 10; ++j) {
        const double d = CombinedQuality(i / 10.0, j / 10.0, w_a, 1.0 - w_a);
        EXPECT_GE(d, 0.0);
        EXPECT_LE(d, 1.0);
      }
    }
  }
}

TEST(ScanFeaturesTest, AreaQualityIsOneUpToAmaxThenAmaxOverTheArea) {
  EXPECT_EQ(AreaQuality(0.0019, 0.0025), 1.0);  // 5 m at 0.5 deg
  EXPECT_EQ(AreaQuality(0.0025, 0.0025), 1.0);
  EXPECT_NEAR(AreaQuality(0.0076, 0.0025), 0.0025 / 0.0076, 1e-12);  // 10 m
  EXPECT_NEAR(AreaQuality(0.0305, 0.0025), 0.0025 / 0.0305, 1e-12);  // 20 m
}

TEST(ScanFeaturesTest, PointQualityCombinesAreaPerPointAndIncidence) {
  for (double r : {5.0, 20.0}) {
    Scene scene;
    scene.patches = {WallX(r)};
    const Analysed a = Analyse(scene, {-20, 20, -20, 20}, ScanAnalysisParams{});
    const OrderedScan& s = a.cast.scan;
    for (int i = 0; i < s.size(); ++i) {
      const float par = a.mesh.area_per_point_m2[i];
      if (std::isnan(par)) {
        EXPECT_TRUE(std::isnan(a.features.quality[i]));
        continue;
      }
      const Eigen::Vector3f ray = (s.points_m[i] - s.sensor_origin_m).normalized();
      const double d_i = std::fabs(ray.dot(a.mesh.normals[i]));
      EXPECT_NEAR(a.features.quality[i],
                  CombinedQuality(AreaQuality(par, 0.0025), std::min(1.0, d_i), 0.93, 0.07), 1e-5);
    }
    const int centre = Index(s, s.num_lines / 2, s.beams_per_line / 2);
    if (r == 5.0) {
      EXPECT_GT(a.features.quality[centre], 0.9999f);
    } else {
      EXPECT_NEAR(a.features.quality[centre], 0.111f, 0.005f);
    }
  }
}

// Seed 002 test 8: a 1.5 m box 3 m ahead of a wall 8 m out casts one shadow.
Scene BoxBeforeAWall(double box_half_width_m, double box_height_m) {
  Scene scene;
  scene.patches = {Floor(0.0), WallX(8.0, -20, 20, -1, 10)};  // fills the fan's top
  scene.boxes = {{{3.0, -box_half_width_m, 0.0}, {3.6, box_half_width_m, box_height_m}}};
  return scene;
}

TEST(ScanFeaturesTest, ABoxBeforeAWallLeavesOneOccludedZoneInItsShadow) {
  const Analysed a = Analyse(BoxBeforeAWall(0.5, 1.5), {-25, 25, -40, 25}, ScanAnalysisParams{});
  ASSERT_EQ(a.features.zones.size(), 1u);
  const InterestZone& z = a.features.zones[0];
  // The centre is in the box's shadow: behind its front face, before the wall, and the ray from
  // the sensor to it passes through the face.
  const Eigen::Vector3f o = a.cast.scan.sensor_origin_m;
  EXPECT_GT(z.center_m.x(), 3.0f);
  EXPECT_LT(z.center_m.x(), 8.0f);
  const Eigen::Vector3f at_face =
      o + (z.center_m - o) * ((3.0f - o.x()) / (z.center_m.x() - o.x()));
  EXPECT_LT(std::fabs(at_face.y()), 0.5f);
  EXPECT_GT(at_face.z(), 0.0f);
  EXPECT_LT(at_face.z(), 1.5f);
  // |n| is the area; the open side of a box standing on the floor is above it.
  EXPECT_NEAR(z.normal.norm(), z.area_m2, 1e-4f * z.area_m2);
  EXPECT_GT(z.area_m2, 2.0f);
  EXPECT_GT(z.normal.z(), 0.7f * z.area_m2);
  EXPECT_GE(z.normal.dot(o - z.center_m), 0.f);
  // The area is that of the rejected triangles.
  double rejected = 0.0;
  for (const Eigen::Vector3i& t : a.mesh.rejected_triangles) {
    const Eigen::Vector3f& p = a.cast.scan.points_m[t[0]];
    rejected += 0.5 * (a.cast.scan.points_m[t[1]] - p).cross(a.cast.scan.points_m[t[2]] - p).norm();
  }
  EXPECT_LE(z.area_m2, rejected * (1 + 1e-5));
  EXPECT_GT(z.area_m2, 0.99 * rejected);  // a few small groups stay out
}

TEST(ScanFeaturesTest, AZoneNormalPointsToTheSideTheHoleCanBeSeenFrom) {
  // A box reaching far to the right and above the scan: only its left edge casts a shadow, which
  // is seen by moving left (+y).
  Scene scene;
  scene.patches = {Floor(0.0), WallX(8.0, -20, 20, -1, 10)};
  scene.boxes = {{{3.0, -20.0, 0.0}, {3.6, 0.5, 10.0}}};
  const Analysed a = Analyse(scene, {-25, 25, -40, 25}, ScanAnalysisParams{});
  ASSERT_EQ(a.features.zones.size(), 1u);
  const InterestZone& z = a.features.zones[0];
  EXPECT_GT(z.normal.y(), 0.9f * z.area_m2) << z.normal.transpose();
  EXPECT_GT(z.center_m.y(), 0.4f);  // on the left edge's side of the shadow
}

TEST(ScanFeaturesTest, ALargerHoleGivesALargerZone) {
  const ScanAnalysisParams params;
  // Both tops within the fan (up to 25 deg: 2.4 m at 3 m): the shadow runs around three sides.
  const Analysed low = Analyse(BoxBeforeAWall(0.5, 1.2), {-25, 25, -40, 25}, params);
  const Analysed tall = Analyse(BoxBeforeAWall(0.5, 2.0), {-25, 25, -40, 25}, params);
  ASSERT_EQ(low.features.zones.size(), 1u);
  ASSERT_EQ(tall.features.zones.size(), 1u);
  EXPECT_GT(tall.features.zones[0].area_m2, 1.3f * low.features.zones[0].area_m2);
  EXPECT_GT(tall.features.zones[0].normal.norm(), 1.3f * low.features.zones[0].normal.norm());
  // Above min_zone_area_m2 only.
  ScanAnalysisParams strict = params;
  strict.min_zone_area_m2 = 2.0 * tall.features.zones[0].area_m2;
  EXPECT_TRUE(AnalyseScan(tall.cast.scan, tall.mesh, strict).zones.empty());
}

TEST(ScanFeaturesTest, ZonesJoinTrianglesThroughSharedEdgesOnly) {
  // A 3 x 3 grid on the plane x = 5 with unit spacing; rejected: both halves of quad (0, 0) and
  // one of quad (0, 1), joined by edges, and one half of quad (1, 1), which touches them at one
  // vertex only.
  OrderedScan scan;
  scan.num_lines = 3;
  scan.beams_per_line = 3;
  for (int l = 0; l < 3; ++l) {
    for (int b = 0; b < 3; ++b) scan.points_m.emplace_back(5.f, float(l), float(b));
  }
  ScanMesh mesh = BuildScanMesh(scan);
  mesh.rejected_triangles = {{0, 3, 4}, {0, 4, 1}, {1, 4, 5}, {4, 7, 8}};
  ScanAnalysisParams params;
  params.min_zone_area_m2 = 0.0;
  const ScanFeatures f = AnalyseScan(scan, mesh, params);
  ASSERT_EQ(f.zones.size(), 2u);
  // Largest first: area 1.5, centre the mean of its 5 distinct vertices (points 0, 1, 3, 4, 5;
  // counting shared vertices once per triangle would give (5, 5/9, 7/9)).
  EXPECT_NEAR(f.zones[0].area_m2, 1.5f, 1e-6f);
  EXPECT_TRUE(f.zones[0].center_m.isApprox(Eigen::Vector3f(5.f, 0.6f, 0.8f), 1e-6f))
      << f.zones[0].center_m.transpose();
  EXPECT_TRUE(f.zones[0].normal.isApprox(Eigen::Vector3f(-1.5f, 0.f, 0.f), 1e-6f))
      << f.zones[0].normal.transpose();
  EXPECT_NEAR(f.zones[1].area_m2, 0.5f, 1e-6f);
  EXPECT_TRUE(f.zones[1].center_m.isApprox(Eigen::Vector3f(5.f, 5.f / 3, 4.f / 3), 1e-6f))
      << f.zones[1].center_m.transpose();
  EXPECT_TRUE(f.zones[1].normal.isApprox(Eigen::Vector3f(-0.5f, 0.f, 0.f), 1e-6f));
  // Above a threshold between the two areas only the larger group is kept.
  params.min_zone_area_m2 = 0.75;
  EXPECT_EQ(AnalyseScan(scan, mesh, params).zones.size(), 1u);
}

TEST(ScanFeaturesTest, NavigabilityIsTheWeightedLocalAndNeighbourhoodTerms) {
  Scene scene;
  scene.patches = {Floor(0.0), Ramp(45 * kDeg, 3.0, 4.5, -3.0, 3.0)};
  const ScanAnalysisParams params = Theta(30);
  const Analysed a = Analyse(scene, {-10, 10, -40, 10}, params);
  const OrderedScan& s = a.cast.scan;
  const double theta = params.max_slope_rad;
  std::vector<double> local(s.size(), 0.0);
  for (int i = 0; i < s.size(); ++i) {
    if (std::isnan(a.mesh.normals[i].z())) continue;
    const Eigen::Vector3f& p = s.points_m[i];
    const double d_xy = std::hypot(p.x() - s.sensor_origin_m.x(), p.y() - s.sensor_origin_m.y());
    const double pz = p.z() - s.robot_base_z_m;
    if (pz > d_xy * std::tan(theta)) continue;  // above the cone
    local[i] = SlopeTerm(std::min(1.f, a.mesh.normals[i].z()), theta, params.slope_steepness) *
               HeightTerm(pz, d_xy, theta);
  }
  int mixed = 0;
  for (int i = 0; i < s.size(); ++i) {
    if (std::isnan(a.mesh.normals[i].z())) continue;
    const std::vector<int32_t> nb = NeighboursOf(a.mesh, i);
    double mean = 0.0;
    for (int32_t q : nb) mean += local[q] / nb.size();
    const double want = std::clamp(params.w_l * local[i] + params.w_g * mean, 0.0, 1.0);
    EXPECT_NEAR(a.features.navigability[i], want, 1e-4) << i;
    mixed += std::fabs(want - (params.w_l + params.w_g) * local[i]) > 0.05;
  }
  EXPECT_GT(mixed, 50);  // the neighbourhood term matters along the foot of the slope
}

TEST(ScanFeaturesTest, PointsWithoutAReturnOrATriangleScoreNaN) {
  Scene scene;
  scene.patches = {WallX(5.0, -1.0, 1.0, 0.0, 2.0)};
  const Analysed a = Analyse(scene, {-15, 15, -15, 15}, ScanAnalysisParams{});
  int valid = 0;
  for (int i = 0; i < a.cast.scan.size(); ++i) {
    const bool has_normal = !std::isnan(a.mesh.normals[i].z());
    EXPECT_EQ(std::isnan(a.features.navigability[i]), !has_normal);
    EXPECT_EQ(std::isnan(a.features.obstacle[i]), !has_normal);
    EXPECT_EQ(std::isnan(a.features.quality[i]), !has_normal);
    if (!has_normal) continue;
    ++valid;
    for (float v : {a.features.navigability[i], a.features.obstacle[i], a.features.quality[i]}) {
      EXPECT_GE(v, 0.f);
      EXPECT_LE(v, 1.f);
    }
  }
  EXPECT_GT(valid, 100);
  EXPECT_LT(valid, a.cast.scan.size());
}

TEST(ScanFeaturesTest, BadArgumentsAreRefusedNamingTheField) {
  Scene scene;
  scene.patches = {WallX(5.0)};
  const CastScan c = Cast(scene, {-1, 1, -1, 1});
  const ScanMesh mesh = BuildScanMesh(c.scan);
  EXPECT_NO_THROW(AnalyseScan(c.scan, mesh, ScanAnalysisParams{}));
  const std::vector<std::pair<std::string, void (*)(ScanAnalysisParams*)>> bad{
      {"max_slope_rad", [](ScanAnalysisParams* p) { p->max_slope_rad = M_PI / 2; }},
      {"slope_steepness", [](ScanAnalysisParams* p) { p->slope_steepness = 0.0; }},
      {"w_l", [](ScanAnalysisParams* p) { p->w_l = -0.1; }},
      {"w_bg", [](ScanAnalysisParams* p) { p->w_bg = std::nan(""); }},
      {"obstacle_band_m", [](ScanAnalysisParams* p) { p->obstacle_band_m = 0.0; }},
      {"ground_cell_m", [](ScanAnalysisParams* p) { p->ground_cell_m = 1e-4; }},
      {"a_max_m2", [](ScanAnalysisParams* p) { p->a_max_m2 = -1.0; }},
      {"w_a", [](ScanAnalysisParams* p) { p->w_a = p->w_n = 0.0; }},
      {"min_zone_area_m2", [](ScanAnalysisParams* p) { p->min_zone_area_m2 = -1.0; }},
  };
  for (const auto& [field, spoil] : bad) {
    ScanAnalysisParams p;
    spoil(&p);
    ExpectThrowNaming([&] { p.Validate(); }, field);
    ExpectThrowNaming([&] { AnalyseScan(c.scan, mesh, p); }, field);
  }
  // A mesh of another scan.
  const ScanMesh other = BuildScanMesh(Cast(scene, {-2, 2, -1, 1}).scan);
  ExpectThrowNaming([&] { AnalyseScan(c.scan, other, ScanAnalysisParams{}); }, "ScanMesh");
  ScanMesh broken = mesh;
  broken.neighbours[0] = c.scan.size();
  ExpectThrowNaming([&] { AnalyseScan(c.scan, broken, ScanAnalysisParams{}); }, "neighbours");
  broken = mesh;
  broken.rejected_triangles.push_back({0, 2, 7});  // not neighbouring cells
  ExpectThrowNaming([&] { AnalyseScan(c.scan, broken, ScanAnalysisParams{}); },
                    "rejected_triangles");
  ExpectThrowNaming([] { SlopeTerm(1.5, 0.3, 10.0); }, "n_z");
  ExpectThrowNaming([] { SlopeTerm(1.0, 0.0, 10.0); }, "theta_rad");
  ExpectThrowNaming([] { SlopeTerm(1.0, 0.3, -1.0); }, "k");
  ExpectThrowNaming([] { HeightTerm(0.0, -1.0, 0.3); }, "d_xy_m");
  ExpectThrowNaming([] { AreaQuality(0.001, 0.0); }, "a_max_m2");
  ExpectThrowNaming([] { CombinedQuality(1.1, 0.5, 0.93, 0.07); }, "d_a");
  ExpectThrowNaming([] { CombinedQuality(0.5, 0.5, 0.0, 0.0); }, "w_a");
}

}  // namespace
}  // namespace cairn::explore
