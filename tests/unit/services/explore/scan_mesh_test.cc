#include "services/explore/scan_mesh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
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

bool SameSurface(const CastScan& c, const Eigen::Vector3i& t) {
  return c.id[t[0]] == c.id[t[1]] && c.id[t[1]] == c.id[t[2]];
}

// Seed 002 test 1: a floor that ends 5 m out and a wall 5 m further back.
TEST(ScanMeshTest, TrianglesAcrossADepthJumpAreRejected) {
  Scene scene;
  scene.patches = {Floor(0.0, -100, 5.0), WallX(10.0)};
  const CastScan c = Cast(scene, {-20, 20, -40, 5});
  // Each bound alone rejects the jump (the side ratio is about 115, the longest side about 115
  // grid spacings); with both off it is meshed.
  MeshParams sines_only, spacing_only, neither;
  sines_only.max_edge_spacing_ratio = 0.0;
  spacing_only.max_side_ratio = 1e4;
  neither.max_side_ratio = 1e4;
  neither.max_edge_spacing_ratio = 0.0;
  for (const MeshParams& p : {sines_only, spacing_only}) {
    const ScanMesh m = BuildScanMesh(c.scan, p);
    EXPECT_GE(m.rejected_triangles.size(), static_cast<size_t>(c.scan.num_lines - 1));
    for (const Eigen::Vector3i& t : m.triangles) EXPECT_TRUE(SameSurface(c, t));
  }
  EXPECT_TRUE(BuildScanMesh(c.scan, neither).rejected_triangles.empty());

  const ScanMesh mesh = BuildScanMesh(c.scan);
  int jumps = 0;
  for (const Eigen::Vector3i& t : mesh.rejected_triangles) {
    EXPECT_FALSE(SameSurface(c, t)) << "a triangle on one surface was rejected";
    ++jumps;
  }
  for (const Eigen::Vector3i& t : mesh.triangles) {
    EXPECT_TRUE(SameSurface(c, t)) << "a triangle across the jump was accepted";
  }
  // Every line pair crosses the floor's edge at least once.
  EXPECT_GE(jumps, c.scan.num_lines - 1);
  // Both surfaces are meshed.
  std::set<int> meshed;
  for (const Eigen::Vector3i& t : mesh.triangles) meshed.insert(c.id[t[0]]);
  EXPECT_EQ(meshed, (std::set<int>{0, 1}));
}

TEST(ScanMeshTest, NoTriangleUsesACellWithoutReturn) {
  Scene scene;
  scene.patches = {WallX(5.0, -1.0, 1.0, 0.0, 2.0)};  // a panel against the sky
  CastScan c = Cast(scene, {-15, 15, -15, 15});
  for (size_t i = 0; i < c.scan.points_m.size(); i += 7) {
    c.scan.points_m[i] = Eigen::Vector3f(kNaNf, 0.f, 0.f);  // a lost return: one NaN is enough
    c.id[i] = -1;
  }
  const ScanMesh mesh = BuildScanMesh(c.scan);
  ASSERT_FALSE(mesh.triangles.empty());
  std::vector<int> in_triangle(c.scan.size(), 0);
  for (const auto* list : {&mesh.triangles, &mesh.rejected_triangles}) {
    for (const Eigen::Vector3i& t : *list) {
      for (int k = 0; k < 3; ++k) {
        ASSERT_GE(c.id[t[k]], 0) << "triangle uses cell " << t[k] << " without return";
        if (list == &mesh.triangles) in_triangle[t[k]] = 1;
      }
    }
  }
  const size_t bound = 2 * static_cast<size_t>(c.scan.num_lines - 1) * (c.scan.beams_per_line - 1);
  EXPECT_LE(mesh.triangles.size() + mesh.rejected_triangles.size(), bound);
  for (int i = 0; i < c.scan.size(); ++i) {
    EXPECT_EQ(std::isnan(mesh.area_per_point_m2[i]), in_triangle[i] == 0) << i;
    EXPECT_EQ(std::isnan(mesh.normals[i].z()), in_triangle[i] == 0) << i;
    EXPECT_EQ(mesh.neighbour_offsets[i + 1] > mesh.neighbour_offsets[i], in_triangle[i] == 1);
  }
}

TEST(ScanMeshTest, AFullPlaneGivesTwoTrianglesPerGridQuad) {
  Scene scene;
  scene.patches = {WallX(5.0)};
  const CastScan c = Cast(scene, {-10, 10, -10, 10});
  const ScanMesh mesh = BuildScanMesh(c.scan);
  EXPECT_EQ(mesh.triangles.size(),
            2 * static_cast<size_t>(c.scan.num_lines - 1) * (c.scan.beams_per_line - 1));
  EXPECT_TRUE(mesh.rejected_triangles.empty());
}

TEST(ScanMeshTest, AGridQuadWithOneLostCornerGivesOneTriangle) {
  Scene scene;
  scene.patches = {WallX(5.0)};
  CastScan c = Cast(scene, {0, 0.5, 0, 0.5});  // 2 x 2 points: one quad
  ASSERT_EQ(c.scan.size(), 4);
  EXPECT_EQ(BuildScanMesh(c.scan).triangles.size(), 2u);
  for (int lost = 0; lost < 4; ++lost) {
    CastScan d = c;
    d.scan.points_m[lost].setConstant(kNaNf);
    const ScanMesh mesh = BuildScanMesh(d.scan);
    ASSERT_EQ(mesh.triangles.size(), 1u) << lost;
    std::set<int> used(mesh.triangles[0].data(), mesh.triangles[0].data() + 3);
    EXPECT_EQ(used.count(lost), 0u);
    EXPECT_EQ(used.size(), 3u);
  }
  CastScan two = c;
  two.scan.points_m[0].setConstant(kNaNf);
  two.scan.points_m[3].setConstant(kNaNf);
  EXPECT_TRUE(BuildScanMesh(two.scan).triangles.empty());
}

// Seed 002 test 2: PAR = r² sin²(0.5 deg) on a plane perpendicular to the beam.
TEST(ScanMeshTest, AreaPerPointIsRangeSquaredTimesTheAngularSteps) {
  const std::vector<std::pair<double, double>> cases{{5.0, 0.0019}, {10.0, 0.0076}, {20.0, 0.0305}};
  for (const auto& [r, seed_value] : cases) {
    Scene scene;
    scene.patches = {WallX(r)};
    const CastScan c = Cast(scene, {-3, 3, -3, 3});
    const ScanMesh mesh = BuildScanMesh(c.scan);
    const int centre = Index(c.scan, c.scan.num_lines / 2, c.scan.beams_per_line / 2);
    ASSERT_NEAR(c.scan.points_m[centre].x(), r, 1e-4);
    ASSERT_NEAR(c.scan.points_m[centre].z(), 1.0, 1e-4);
    const double expected = r * r * std::pow(std::sin(0.5 * kDeg), 2);
    EXPECT_NEAR(mesh.area_per_point_m2[centre], expected, 0.002 * expected) << r;
    EXPECT_NEAR(mesh.area_per_point_m2[centre], seed_value, 0.0001) << r;
    // A border point has fewer triangles; a corner of the grid has only one or two.
    EXPECT_LT(mesh.area_per_point_m2[Index(c.scan, 0, 0)], 0.5 * expected);
  }
}

TEST(ScanMeshTest, AreasPerPointAddUpToTheMeshArea) {
  Scene scene;
  scene.patches = {Floor(0.0)};
  scene.boxes = {{{3, -0.5, 0}, {3.5, 0.5, 0.6}}};
  const CastScan c = Cast(scene, {-15, 15, -40, 0});
  const ScanMesh mesh = BuildScanMesh(c.scan);
  double triangles = 0.0, points = 0.0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3f& a = c.scan.points_m[t[0]];
    triangles += 0.5 * (c.scan.points_m[t[1]] - a).cross(c.scan.points_m[t[2]] - a).norm();
  }
  for (float par : mesh.area_per_point_m2) {
    if (!std::isnan(par)) points += par;
  }
  EXPECT_GT(triangles, 1.0);
  EXPECT_NEAR(points, triangles, 1e-4 * triangles);
}

TEST(ScanMeshTest, NormalsOfFlatGroundPointUpAndThoseOfAWallFaceTheSensor) {
  Scene scene;
  scene.patches = {Floor(0.0), WallX(6.0)};
  const CastScan c = Cast(scene, {-20, 20, -40, 20});
  const ScanMesh mesh = BuildScanMesh(c.scan);
  int floor_points = 0, wall_points = 0;
  for (int i = 0; i < c.scan.size(); ++i) {
    const std::vector<int32_t> nb = NeighboursOf(mesh, i);
    if (nb.size() != 6) continue;  // interior points: away from the floor-wall crease
    if (!std::all_of(nb.begin(), nb.end(), [&](int32_t q) { return c.id[q] == c.id[i]; })) {
      continue;
    }
    const Eigen::Vector3f& n = mesh.normals[i];
    EXPECT_NEAR(n.norm(), 1.f, 1e-5);
    if (c.id[i] == 0) {
      EXPECT_GT(n.z(), 0.9999f) << i;
      ++floor_points;
    } else {
      EXPECT_LT(n.x(), -0.9999f) << i;  // the wall faces -x, towards the sensor
      ++wall_points;
    }
  }
  EXPECT_GT(floor_points, 1000);
  EXPECT_GT(wall_points, 1000);
}

TEST(ScanMeshTest, NormalsFaceTheSensorWhateverTheGridOrder) {
  Scene scene;
  scene.patches = {WallX(5.0)};
  CastScan c = Cast(scene, {-5, 5, -5, 5});
  // Reverse the beams of every line: the triangles' winding flips, the normals must not.
  OrderedScan flipped = c.scan;
  const int beams = c.scan.beams_per_line;
  for (int l = 0; l < c.scan.num_lines; ++l) {
    for (int b = 0; b < beams; ++b) {
      flipped.points_m[Index(flipped, l, b)] = c.scan.points_m[Index(c.scan, l, beams - 1 - b)];
    }
  }
  for (const OrderedScan* s : {&c.scan, &flipped}) {
    const ScanMesh mesh = BuildScanMesh(*s);
    for (int i = 0; i < s->size(); ++i) EXPECT_LT(mesh.normals[i].x(), -0.999f) << i;
  }
}

TEST(ScanMeshTest, NeighboursAreThePointsSharingAnAcceptedTriangle) {
  Scene scene;
  scene.patches = {Floor(0.0, -100, 5.0), WallX(10.0)};
  const CastScan c = Cast(scene, {-10, 10, -40, 5});
  const ScanMesh mesh = BuildScanMesh(c.scan);
  std::vector<std::set<int32_t>> expected(c.scan.size());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        if (a != b) expected[t[a]].insert(t[b]);
      }
    }
  }
  ASSERT_EQ(mesh.neighbour_offsets.size(), static_cast<size_t>(c.scan.size()) + 1);
  for (int i = 0; i < c.scan.size(); ++i) {
    const std::vector<int32_t> nb = NeighboursOf(mesh, i);
    EXPECT_TRUE(std::is_sorted(nb.begin(), nb.end()));
    EXPECT_EQ(std::set<int32_t>(nb.begin(), nb.end()), expected[i]) << i;
    for (int32_t q : nb) EXPECT_EQ(c.id[q], c.id[i]) << "neighbours across the jump";
  }
  // An interior point of a plane: the 6 neighbours of the fixed-diagonal triangulation.
  const int l = 5, b = 10, i = Index(c.scan, l, b);
  ASSERT_EQ(c.id[i], 0);
  const std::vector<int32_t> want{Index(c.scan, l - 1, b - 1), Index(c.scan, l - 1, b),
                                  Index(c.scan, l, b - 1),     Index(c.scan, l, b + 1),
                                  Index(c.scan, l + 1, b),     Index(c.scan, l + 1, b + 1)};
  EXPECT_EQ(NeighboursOf(mesh, i), want);
}

TEST(ScanMeshTest, TheSideRatioBoundDecidesHowFarGrazingGroundIsKept) {
  Scene scene;
  scene.patches = {Floor(0.0)};
  const CastScan c = Cast(scene, {-5, 5, -40, -1});
  // Farthest floor point in any accepted triangle, for two bounds.
  auto farthest = [&](const MeshParams& p) {
    double far = 0.0;
    for (const Eigen::Vector3i& t : BuildScanMesh(c.scan, p).triangles) {
      for (int k = 0; k < 3; ++k) far = std::max(far, double(c.scan.points_m[t[k]].x()));
    }
    return far;
  };
  // Flat ground from a 1 m scanner: side ratio about d / h. The defaults keep it to about 20 m.
  EXPECT_GT(farthest(MeshParams{}), 15.0);
  EXPECT_LT(farthest(MeshParams{}), 25.0);
  MeshParams tight;
  tight.max_side_ratio = 8.0;
  EXPECT_LT(farthest(tight), 10.0);
  EXPECT_GT(farthest(tight), 6.0);
}

TEST(ScanMeshTest, InvalidScansAndParamsAreRefusedNamingTheField) {
  Scene scene;
  scene.patches = {WallX(5.0)};
  const OrderedScan good = Cast(scene, {-1, 1, -1, 1}).scan;
  EXPECT_NO_THROW(BuildScanMesh(good));
  OrderedScan s = good;
  s.points_m.pop_back();
  ExpectThrowNaming([&] { BuildScanMesh(s); }, "points_m");
  s = good;
  s.num_lines = -1;
  ExpectThrowNaming([&] { BuildScanMesh(s); }, "num_lines");
  s = good;
  s.pan_step_rad = 0.0;
  ExpectThrowNaming([&] { BuildScanMesh(s); }, "pan_step_rad");
  s = good;
  s.tilt_step_rad = std::nan("");
  ExpectThrowNaming([&] { BuildScanMesh(s); }, "tilt_step_rad");
  s = good;
  s.sensor_origin_m.x() = kNaNf;
  ExpectThrowNaming([&] { BuildScanMesh(s); }, "sensor_origin_m");
  MeshParams p;
  p.max_side_ratio = 0.5;
  ExpectThrowNaming([&] { BuildScanMesh(good, p); }, "max_side_ratio");
  p = {};
  p.max_edge_spacing_ratio = -1.0;
  ExpectThrowNaming([&] { BuildScanMesh(good, p); }, "max_edge_spacing_ratio");
  // An empty scan is valid and gives an empty mesh.
  const ScanMesh empty = BuildScanMesh(OrderedScan{});
  EXPECT_TRUE(empty.triangles.empty());
  EXPECT_EQ(empty.neighbour_offsets, std::vector<int32_t>{0});
}

}  // namespace
}  // namespace cairn::explore
