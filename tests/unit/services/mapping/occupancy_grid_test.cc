#include "services/mapping/occupancy_grid.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/layers.h"

namespace cairn::mapping {
namespace {

using common::CellIndex;
using common::Vector2;

// Seed 003's grid: 0.05 m, 800 x 800, world (0, 0) at the corner of centre cell (400, 400).
OccupancyParams SeedParams() {
  OccupancyParams p = OccupancyParams::Seed003();
  p.resolution_m = 0.05;
  p.size_x_cells = 800;
  p.size_y_cells = 800;
  p.origin_x_m = -20.0;
  p.origin_y_m = -20.0;
  return p;
}

OccupancyParams OctomapLikeParams() {
  OccupancyParams p;  // defaults
  p.size_x_cells = 800;
  p.size_y_cells = 800;
  p.origin_x_m = -20.0;
  p.origin_y_m = -20.0;
  return p;
}

common::LaserScan OneBeam(double range_m, double yaw_rad = 0.0, Vector2 at = {0.0, 0.0}) {
  common::LaserScan scan;
  scan.sensor_pose.position_m = {at.x(), at.y(), 0.3};
  scan.sensor_pose.orientation = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ());
  scan.angle_min_rad = 0.0;
  scan.angle_increment_rad = 0.01;
  scan.range_min_m = 0.02;
  scan.range_max_m = 5.0;
  scan.ranges_m = {static_cast<float>(range_m)};
  return scan;
}

PlanarRay Ray(Vector2 from, Vector2 to, bool hit = true) { return PlanarRay{from, to, hit}; }

// A miss ray along y = 0.0125 from x = -1 that crosses cell (ix, 400) and ends beyond it.
PlanarRay MissThrough(int ix) {
  const double x = (ix - 400) * 0.05 + 0.025;
  return Ray({x - 1.0, 0.0125}, {x + 0.5, 0.0125}, /*hit=*/false);
}
// A hit ray along y = 0.0125 that ends in cell (ix, 400).
PlanarRay HitAt(int ix) {
  const double x = (ix - 400) * 0.05 + 0.025;
  return Ray({x - 1.0, 0.0125}, {x, 0.0125}, /*hit=*/true);
}

int SeedExport(float logodds) { return static_cast<int>(OccupancyPercent(logodds)); }

// ---- Seed 003 section 7.1: log-odds arithmetic ------------------------------------------------

TEST(OccupancyLogOddsTest, IdentityAndUnknown) {
  EXPECT_EQ(LogOddsFromProbability(0.5), 0.0f);
  EXPECT_EQ(ProbabilityFromLogOdds(0.0f), 0.5);
  EXPECT_EQ(OccupancyPercent(0.0f), 50.0f);
  // An untouched cell is unknown (NaN), not 50 %.
  OccupancyGrid grid(SeedParams());
  EXPECT_TRUE(std::isnan(grid.LogOdds({400, 400})));
  EXPECT_TRUE(std::isnan(OccupancyPercent(grid.LogOdds({400, 400}))));
}

TEST(OccupancyLogOddsTest, OctomapDefaults) {
  const OccupancyParams p;
  EXPECT_NEAR(p.hit_logodds, LogOddsFromProbability(0.7), 1e-6);
  EXPECT_NEAR(p.hit_logodds, 0.847, 1e-3);
  EXPECT_NEAR(p.miss_logodds, LogOddsFromProbability(0.4), 1e-6);
  EXPECT_NEAR(p.miss_logodds, -0.405, 1e-3);
  EXPECT_EQ(p.clamp_min_logodds, -2.0f);
  EXPECT_EQ(p.clamp_max_logodds, 3.5f);
}

TEST(OccupancyLogOddsTest, Seed003SingleHitAndSingleMiss) {
  OccupancyGrid grid(SeedParams());
  grid.InsertRays({HitAt(420)});
  EXPECT_EQ(grid.LogOdds({420, 400}), 2.0f);
  EXPECT_NEAR(ProbabilityFromLogOdds(2.0f), 0.880797, 1e-6);
  EXPECT_EQ(SeedExport(grid.LogOdds({420, 400})), 88);
  EXPECT_FLOAT_EQ(grid.LogOdds({410, 400}), -0.7f);
  EXPECT_NEAR(ProbabilityFromLogOdds(-0.7f), 0.331812, 1e-6);
  EXPECT_EQ(SeedExport(grid.LogOdds({410, 400})), 33);
}

TEST(OccupancyLogOddsTest, Seed003FreeThenHitThenFree) {
  OccupancyGrid grid(SeedParams());
  const CellIndex c{420, 400};
  grid.InsertRays({MissThrough(420)});
  EXPECT_FLOAT_EQ(grid.LogOdds(c), -0.7f);
  grid.InsertRays({HitAt(420)});
  EXPECT_NEAR(grid.LogOdds(c), 1.3f, 1e-6);
  EXPECT_EQ(SeedExport(grid.LogOdds(c)), 78);
  grid.InsertRays({MissThrough(420)});
  EXPECT_NEAR(grid.LogOdds(c), 0.6f, 1e-6);
  EXPECT_EQ(SeedExport(grid.LogOdds(c)), 64);
  grid.InsertRays({MissThrough(420)});  // two passes after the hit
  EXPECT_NEAR(grid.LogOdds(c), -0.1f, 1e-6);
}

TEST(OccupancyLogOddsTest, Seed003ProtectionIsStrict) {
  OccupancyGrid grid(SeedParams());
  grid.SetLogOdds({420, 400}, 2.0f);
  grid.SetLogOdds({460, 400}, 1.999f);
  for (int i = 0; i < 100; ++i) grid.InsertRays({MissThrough(420)});
  EXPECT_EQ(grid.LogOdds({420, 400}), 2.0f);
  grid.InsertRays({MissThrough(460)});
  EXPECT_NEAR(grid.LogOdds({460, 400}), 1.299f, 1e-5);
}

TEST(OccupancyLogOddsTest, Seed003ClampHighAfterSixHits) {
  OccupancyGrid grid(SeedParams());
  grid.InsertRays(std::vector<PlanarRay>(6, HitAt(420)));
  EXPECT_EQ(grid.LogOdds({420, 400}), 10.0f);           // not 12.0
  EXPECT_EQ(SeedExport(grid.LogOdds({420, 400})), 99);  // never 100
}

TEST(OccupancyLogOddsTest, Seed003ClampLowAfterTwentyMisses) {
  OccupancyGrid grid(SeedParams());
  for (int i = 0; i < 20; ++i) grid.InsertRays({MissThrough(420)});
  EXPECT_EQ(grid.LogOdds({420, 400}), -10.0f);
  EXPECT_EQ(SeedExport(grid.LogOdds({420, 400})), 0);
}

TEST(OccupancyLogOddsTest, Seed003ClampsOnlyAtTheEndOfAScan) {
  // Protection off so that misses reach a cell above 2.0. Six hits then three misses in ONE
  // scan: 12.0 - 2.1 = 9.9 when clamping after the scan; per-update clamping would give
  // 10.0 - 2.1 = 7.9.
  OccupancyParams p = SeedParams();
  p.protect_occupied_logodds = INFINITY;
  std::vector<PlanarRay> scan(6, HitAt(420));
  for (int i = 0; i < 3; ++i) scan.push_back(MissThrough(420));
  OccupancyGrid after_scan(p);
  after_scan.InsertRays(scan);
  EXPECT_NEAR(after_scan.LogOdds({420, 400}), 9.9f, 1e-5);
  p.clamp_after_scan = false;
  OccupancyGrid per_update(p);
  per_update.InsertRays(scan);
  EXPECT_NEAR(per_update.LogOdds({420, 400}), 7.9f, 1e-5);
}

TEST(OccupancyLogOddsTest, ProbabilityFormulasAgree) {
  for (double l = -10.0; l <= 10.0; l += 0.01) {
    const double p = ProbabilityFromLogOdds(static_cast<float>(l));
    EXPECT_NEAR(p, 1.0 - 1.0 / (1.0 + std::exp(static_cast<float>(l))), 1e-6);
    EXPECT_NEAR(LogOddsFromProbability(p), static_cast<float>(l), 1e-4);
  }
}

// ---- Seed 003 section 7.2: inverse sensor model and grid geometry -----------------------------

TEST(OccupancyGridTest, Seed003GridIndexingUsesFloor) {
  OccupancyGrid grid(SeedParams());
  EXPECT_EQ(grid.CellAt({0.0, 0.0}), (CellIndex{400, 400}));
  EXPECT_EQ(grid.CellAt({1.0, -2.0}), (CellIndex{420, 360}));   // row 360, col 420
  EXPECT_EQ(grid.CellAt({-0.03, 0.0}), (CellIndex{399, 400}));  // truncation would give 400
  EXPECT_FALSE(grid.CellAt({20.0, 0.0}).has_value());
  EXPECT_FALSE(grid.CellAt({-20.001, 0.0}).has_value());
  EXPECT_TRUE(grid.CellAt({-20.0, 0.0}).has_value());
}

TEST(OccupancyGridTest, Seed003HitBeam) {
  OccupancyGrid grid(SeedParams());
  const OccupancyInsertStats stats = grid.InsertScan(OneBeam(1.0));
  EXPECT_EQ(stats.beams_used, 1);
  for (int ix = 400; ix <= 419; ++ix) {
    EXPECT_FLOAT_EQ(grid.LogOdds({ix, 400}), -0.7f) << ix;
  }
  EXPECT_EQ(grid.LogOdds({420, 400}), 2.0f);
  EXPECT_TRUE(std::isnan(grid.LogOdds({421, 400})));
  EXPECT_TRUE(std::isnan(grid.LogOdds({399, 400})));
  EXPECT_TRUE(std::isnan(grid.LogOdds({410, 399})));
  EXPECT_TRUE(std::isnan(grid.LogOdds({410, 401})));
  EXPECT_EQ(stats.hits, 1);
  EXPECT_EQ(stats.misses, 20);
}

TEST(OccupancyGridTest, Seed003NoHitBeam) {
  // The sensor sits at the centre of cell (400, 400): from the cell corner the seed uses, the
  // 4.9 m end falls exactly on the border of cells 497 and 498, where rounding alone decides.
  for (double r : {5.0, 4.95, static_cast<double>(INFINITY)}) {
    OccupancyGrid grid(SeedParams());
    const OccupancyInsertStats stats = grid.InsertScan(OneBeam(r, 0.0, {0.025, 0.025}));
    EXPECT_EQ(stats.hits, 0) << r;
    for (int ix = 400; ix <= 498; ++ix) {
      ASSERT_FLOAT_EQ(grid.LogOdds({ix, 400}), -0.7f) << "r " << r << " ix " << ix;
    }
    EXPECT_TRUE(std::isnan(grid.LogOdds({499, 400}))) << r;
    EXPECT_EQ(stats.misses, 99) << r;
  }
}

TEST(OccupancyGridTest, NoReturnClearsNoFartherThanTheLaserReaches) {
  // Default params clear 30 m for a no-return, but a 5 m laser's no-return proves 5 m only.
  OccupancyGrid grid(OctomapLikeParams());
  common::LaserScan scan = OneBeam(INFINITY, 0.0, {0.025, 0.025});
  scan.range_max_m = 5.0;
  const OccupancyInsertStats stats = grid.InsertScan(scan);
  EXPECT_EQ(stats.hits, 0);
  EXPECT_EQ(stats.misses, 101);  // cells 400..500 (5.025 m lies in cell 500)
  EXPECT_TRUE(std::isnan(grid.LogOdds({501, 400})));
}

TEST(OccupancyGridTest, Seed003NearReading) {
  OccupancyGrid grid(SeedParams());
  OccupancyInsertStats stats = grid.InsertScan(OneBeam(0.09));
  EXPECT_EQ(stats.beams_used, 0);
  EXPECT_EQ(grid.num_tiles(), 0u);
  EXPECT_EQ(grid.version(), 0);
  stats = grid.InsertScan(OneBeam(0.10));
  EXPECT_EQ(stats.beams_used, 1);
  EXPECT_EQ(grid.LogOdds({402, 400}), 2.0f);
}

TEST(OccupancyGridTest, Seed003BeamDecimation) {
  OccupancyGrid grid(SeedParams());
  common::LaserScan scan = OneBeam(3.0);
  scan.angle_min_rad = -2.0944;
  scan.angle_increment_rad = 4.18879 / 683;
  scan.ranges_m.assign(684, 3.0f);
  const OccupancyInsertStats stats = grid.InsertScan(scan);
  EXPECT_EQ(stats.beams_used, 342);
  EXPECT_EQ(stats.beams_skipped, 342);
}

TEST(OccupancyGridTest, Seed003OutOfMapEndpointIsNeverAHit) {
  // Robot in column 795, beam +x of 1 m: the end lies 0.8 m beyond the map edge. The seed
  // marked column 799 as a hit; here the crossed cells are free and nothing is occupied.
  OccupancyGrid grid(SeedParams());
  const double x = 795 * 0.05 - 20.0 + 0.025;
  const OccupancyInsertStats stats = grid.InsertScan(OneBeam(1.0, 0.0, {x, 0.0125}));
  EXPECT_EQ(stats.hits, 0);
  EXPECT_EQ(stats.hits_outside, 1);
  for (int ix = 795; ix <= 799; ++ix) EXPECT_FLOAT_EQ(grid.LogOdds({ix, 400}), -0.7f) << ix;
  // Same in the per-scan mode.
  OccupancyParams p = SeedParams();
  p.one_update_per_scan = true;
  OccupancyGrid once(p);
  EXPECT_EQ(once.InsertScan(OneBeam(1.0, 0.0, {x, 0.0125})).hits, 0);
  EXPECT_FLOAT_EQ(once.LogOdds({799, 400}), -0.7f);
}

TEST(OccupancyGridTest, Seed003BeamAngleUsesYaw) {
  // Yaw 90 deg, angle_min -120 deg: beam 0 points at world -30 deg.
  OccupancyGrid grid(SeedParams());
  common::LaserScan scan = OneBeam(2.0, M_PI / 2);
  scan.angle_min_rad = -120.0 * M_PI / 180.0;
  grid.InsertScan(scan);
  const Vector2 end(2.0 * std::cos(-M_PI / 6), 2.0 * std::sin(-M_PI / 6));
  const auto cell = grid.CellAt(end);
  ASSERT_TRUE(cell.has_value());
  EXPECT_EQ(grid.LogOdds(*cell), 2.0f);
}

TEST(OccupancyGridTest, NegativeSideCellsAreDistinct) {
  // A hit at x = -0.03 lands in column 399 and one at x = +0.03 in 400 (truncation would merge
  // them into one 10 cm wide cell).
  OccupancyGrid grid(SeedParams());
  grid.InsertRays({Ray({-1.0, 0.0125}, {-0.03, 0.0125}), Ray({1.0, 0.0125}, {0.03, 0.0125})});
  EXPECT_EQ(grid.LogOdds({399, 400}), 2.0f);
  EXPECT_EQ(grid.LogOdds({400, 400}), 2.0f);
}

TEST(OccupancyGridTest, TiltedLaserLandsWhereItHits) {
  // A laser pitched 45 deg down from 1 m: a 1.4142 m reading ends 1 m ahead on the ground.
  OccupancyGrid grid(OctomapLikeParams());
  common::LaserScan scan = OneBeam(std::sqrt(2.0));
  scan.sensor_pose.position_m = {0.0125, 0.0125, 1.0};
  scan.sensor_pose.orientation = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitY());
  grid.InsertScan(scan);
  EXPECT_GT(grid.LogOddsAt({1.0125, 0.0125}), 0.0f);
  EXPECT_LT(grid.LogOddsAt({0.5, 0.0125}), 0.0f);
}

// A robot pitched nose down (a bump, a hard stop) puts its planar laser on the floor: from
// 0.3 m at 6 deg, 2.87 m ahead. With seed 003's protected-occupied rule one such hit is a wall
// for good; beyond max_scan_tilt the scan is skipped whole, and counted.
TEST(OccupancyGridTest, AScanTiltedBeyondTheLimitIsSkippedAndCounted) {
  OccupancyParams p = SeedParams();
  p.max_scan_tilt_rad = 3.0 * M_PI / 180.0;
  auto pitched = [](double pitch_deg) {
    common::LaserScan scan = OneBeam(0.3 / std::sin(pitch_deg * M_PI / 180.0));
    scan.sensor_pose.orientation =
        Eigen::AngleAxisd(pitch_deg * M_PI / 180.0, Eigen::Vector3d::UnitY());
    return scan;
  };
  OccupancyGrid grid(p);
  const OccupancyInsertStats skipped = grid.InsertScan(pitched(6.0));
  EXPECT_EQ(skipped.scans_tilted, 1);
  EXPECT_EQ(skipped.beams_used, 0);
  EXPECT_TRUE(std::isnan(grid.LogOddsAt({2.85, 0.0125})));
  EXPECT_TRUE(std::isnan(grid.LogOddsAt({1.0, 0.0125})));
  // Rolled as far: skipped too (the tilt is the sensor's z axis against the vertical).
  common::LaserScan rolled = OneBeam(2.0);
  rolled.sensor_pose.orientation = Eigen::AngleAxisd(6.0 * M_PI / 180.0, Eigen::Vector3d::UnitX());
  EXPECT_EQ(grid.InsertScan(rolled).scans_tilted, 1);
  // Within the limit, and with no limit (the default), the scan counts.
  const OccupancyInsertStats kept = grid.InsertScan(pitched(2.0));
  EXPECT_EQ(kept.scans_tilted, 0);
  EXPECT_GT(kept.beams_used, 0);
  OccupancyGrid unlimited(SeedParams());
  EXPECT_EQ(unlimited.InsertScan(pitched(6.0)).scans_tilted, 0);
  EXPECT_EQ(unlimited.LogOddsAt({0.3 / std::tan(6.0 * M_PI / 180.0), 0.0125}), 2.0f);
  // A limit must be positive.
  p.max_scan_tilt_rad = 0.0;
  EXPECT_THROW(OccupancyGrid{p}, std::invalid_argument);
  p.max_scan_tilt_rad = std::nan("");
  EXPECT_THROW(OccupancyGrid{p}, std::invalid_argument);
}

// ---- OctoMap-like default mode ----------------------------------------------------------------

TEST(OccupancyGridTest, DefaultValuesPerHitAndMissAndClamps) {
  OccupancyGrid grid(OctomapLikeParams());
  grid.InsertRays({HitAt(420)});
  EXPECT_NEAR(grid.LogOdds({420, 400}), 0.847298f, 1e-5);
  EXPECT_NEAR(grid.LogOdds({410, 400}), -0.405465f, 1e-5);
  for (int i = 0; i < 9; ++i) grid.InsertRays({HitAt(420)});
  EXPECT_EQ(grid.LogOdds({420, 400}), 3.5f);
  EXPECT_EQ(grid.LogOdds({410, 400}), -2.0f);
  // Clamped per update: one miss after saturation moves it right away.
  grid.InsertRays({MissThrough(420)});
  EXPECT_NEAR(grid.LogOdds({420, 400}), 3.5f - 0.405465f, 1e-5);
}

TEST(OccupancyGridTest, DefaultOneUpdatePerScanAndHitWins) {
  OccupancyGrid grid(OctomapLikeParams());
  // Ray A ends in cell 420; ray B crosses 420 in the same scan; ray C repeats B.
  grid.InsertRays({HitAt(420), MissThrough(420), MissThrough(420), HitAt(420)});
  EXPECT_NEAR(grid.LogOdds({420, 400}), 0.847298f, 1e-5);   // one hit, no miss
  EXPECT_NEAR(grid.LogOdds({419, 400}), -0.405465f, 1e-5);  // one miss, not four
  // The seed's per-beam mode applies everything.
  OccupancyParams p = OctomapLikeParams();
  p.one_update_per_scan = false;
  OccupancyGrid per_beam(p);
  per_beam.InsertRays({HitAt(420), MissThrough(420), MissThrough(420), HitAt(420)});
  EXPECT_NEAR(per_beam.LogOdds({419, 400}), -4 * 0.405465f, 1e-5);
  EXPECT_NEAR(per_beam.LogOdds({420, 400}), 2 * 0.847298f - 2 * 0.405465f, 1e-5);
}

TEST(OccupancyGridTest, BresenhamTraversalOption) {
  OccupancyParams p = SeedParams();
  p.traversal = OccupancyTraversal::kBresenham;
  OccupancyGrid grid(p);
  // From cell (400,400) to (403,407) centre to centre: 8 cells, the last a hit.
  grid.InsertRays({Ray({0.025, 0.025}, {3 * 0.05 + 0.025, 7 * 0.05 + 0.025})});
  int known = 0;
  for (int ix = 398; ix < 406; ++ix) {
    for (int iy = 398; iy < 410; ++iy) known += std::isnan(grid.LogOdds({ix, iy})) ? 0 : 1;
  }
  EXPECT_EQ(known, 8);
  EXPECT_EQ(grid.LogOdds({403, 407}), 2.0f);
}

TEST(OccupancyGridTest, InvalidInputIsCountedOrRefused) {
  OccupancyGrid grid(OctomapLikeParams());
  common::LaserScan scan = OneBeam(1.0);
  scan.ranges_m = {1.0f, NAN, -1.0f, 2.0f};
  const OccupancyInsertStats stats = grid.InsertScan(scan);
  EXPECT_EQ(stats.beams_used, 2);
  EXPECT_EQ(stats.beams_invalid, 2);
  common::LaserScan bad = OneBeam(1.0);
  bad.sensor_pose.position_m.x() = NAN;
  EXPECT_THROW(grid.InsertScan(bad), std::invalid_argument);
  bad = OneBeam(1.0);
  bad.angle_increment_rad = INFINITY;
  EXPECT_THROW(grid.InsertScan(bad), std::invalid_argument);
  EXPECT_EQ(grid.InsertRays({Ray({0, 0}, {NAN, 1.0})}).beams_invalid, 1);
  OccupancyParams p;
  p.tile_size_cells = 100;
  EXPECT_THROW(OccupancyGrid{p}, std::invalid_argument);
  p = OccupancyParams();
  p.miss_logodds = 0.4f;
  EXPECT_THROW(OccupancyGrid{p}, std::invalid_argument);
}

// ---- Extent, export, import -------------------------------------------------------------------

TEST(OccupancyGridTest, TilesAreAllocatedWhereRaysGo) {
  OccupancyParams p;  // 2 km x 2 km at 0.05 m, 128-cell tiles (6.4 m)
  OccupancyGrid grid(p);
  EXPECT_EQ(grid.num_tiles(), 0u);
  EXPECT_EQ(grid.ObservedBounds().size_x, 0);
  // A robot 700 m from the origin: the grid covers it without moving.
  grid.InsertRays({Ray({700.0, -650.0}, {703.0, -650.0})});
  EXPECT_EQ(grid.LogOddsAt({703.0, -650.0}), p.hit_logodds);
  EXPECT_LE(grid.num_tiles(), 2u);
  const common::GridGeometry bounds = grid.ObservedBounds();
  EXPECT_EQ(bounds.size_x % 128, 0);
  EXPECT_EQ(bounds.size_y, 128);
  EXPECT_LE(bounds.origin.x_m, 700.0);
  EXPECT_GE(bounds.origin.x_m + bounds.length_x_m(), 703.0);
  // Far outside the extent: nothing happens.
  const OccupancyInsertStats stats = grid.InsertRays({Ray({1500.0, 0.0}, {1503.0, 0.0})});
  EXPECT_EQ(stats.hits, 0);
  EXPECT_EQ(stats.hits_outside, 1);
  EXPECT_LE(grid.num_tiles(), 2u);
}

TEST(OccupancyGridTest, ExportAlignedCopyAndCoarseMax) {
  OccupancyGrid grid(OctomapLikeParams());
  grid.InsertRays({HitAt(420)});
  const common::GridMap fine = grid.ExportObserved();
  ASSERT_TRUE(fine.HasLayer(layers::kOccupancy));
  ASSERT_TRUE(fine.HasLayer(layers::kOccupancyLogOdds));
  EXPECT_NEAR(*fine.ValueAt(layers::kOccupancy, {1.025, 0.0125}), 70.0f, 1e-3);
  EXPECT_NEAR(*fine.ValueAt(layers::kOccupancy, {0.5, 0.0125}), 40.0f, 1e-3);
  EXPECT_FALSE(fine.ValueAt(layers::kOccupancy, {0.5, 0.5}).has_value());  // unknown
  // A 0.2 m window: the cell holding the hit keeps the hit.
  common::GridGeometry coarse;
  coarse.resolution_m = 0.2;
  coarse.size_x = 20;
  coarse.size_y = 20;
  coarse.origin = {-2.0, -2.0, 0.0};
  const common::GridMap map = grid.Export(coarse);
  EXPECT_NEAR(*map.ValueAt(layers::kOccupancy, {1.025, 0.0125}), 70.0f, 1e-3);
  EXPECT_NEAR(*map.ValueAt(layers::kOccupancy, {0.5, 0.0125}), 40.0f, 1e-3);
}

TEST(OccupancyGridTest, ImportRestoresExport) {
  OccupancyGrid grid(OctomapLikeParams());
  grid.InsertScan(OneBeam(1.0));
  grid.InsertScan(OneBeam(2.0, 0.7));
  OccupancyGrid restored(OctomapLikeParams());
  restored.Import(grid.ExportObserved());
  for (int ix = 380; ix < 460; ++ix) {
    for (int iy = 380; iy < 440; ++iy) {
      const float a = grid.LogOdds({ix, iy}), b = restored.LogOdds({ix, iy});
      ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << ix << ", " << iy;
    }
  }
  common::GridMap no_layer(grid.ObservedBounds());
  EXPECT_THROW(restored.Import(no_layer), std::out_of_range);
}

TEST(OccupancyGridTest, CopyIsDeep) {
  OccupancyGrid grid(OctomapLikeParams());
  grid.InsertRays({HitAt(420)});
  OccupancyGrid copy = grid;
  copy.InsertRays({HitAt(420)});
  EXPECT_NEAR(grid.LogOdds({420, 400}), 0.847298f, 1e-5);
  EXPECT_NEAR(copy.LogOdds({420, 400}), 2 * 0.847298f, 1e-5);
}

}  // namespace
}  // namespace cairn::mapping
