// The height filter of the elevation map (seed 000, elevation_mapping): Kalman fusion, gating,
// variance limits, the laser noise model.

#include "services/mapping/elevation_filter.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace cairn::mapping {
namespace {

// Seed 000 test 12, the fusion arithmetic.
TEST(ElevationFilterTest, KalmanFusionOfTwoMeasurements) {
  const ElevationFilterParams p;
  float h = NAN, var = NAN;
  EXPECT_EQ(FuseHeight(&h, &var, 0.10, 1e-4, false, p), FuseOutcome::kInitialized);
  EXPECT_FLOAT_EQ(h, 0.10f);
  EXPECT_FLOAT_EQ(var, 1e-4f);
  // m = 0.02 / 0.01 = 2 < 2.5: fused.
  EXPECT_EQ(FuseHeight(&h, &var, 0.12, 1e-4, false, p), FuseOutcome::kFused);
  EXPECT_NEAR(h, 0.11, 1e-7);
  EXPECT_NEAR(var, 5e-5, 1e-11);
}

TEST(ElevationFilterTest, GatingSameScanAndLaterScan) {
  const ElevationFilterParams p;
  // Cell at 0.11 with variance 5e-5; a point 5 cm lower with variance 1e-4:
  // m = 0.05 / sqrt(1.5e-4) = 4.1 >= 2.5.
  float h = 0.11f, var = 5e-5f;
  EXPECT_EQ(FuseHeight(&h, &var, 0.06, 1e-4, /*same_scan=*/true, p), FuseOutcome::kIgnoredLower);
  EXPECT_FLOAT_EQ(h, 0.11f);
  EXPECT_FLOAT_EQ(var, 5e-5f);
  EXPECT_EQ(FuseHeight(&h, &var, 0.06, 1e-4, /*same_scan=*/false, p), FuseOutcome::kMultiHeight);
  EXPECT_FLOAT_EQ(h, 0.11f);
  EXPECT_NEAR(var, 5e-5 + 9e-7, 1e-11);
  // Higher, same scan: the higher point wins (increase_height_alpha 0).
  EXPECT_EQ(FuseHeight(&h, &var, 0.20, 2e-5, true, p), FuseOutcome::kRaised);
  // The gate counts the measurement's variance too: 2 cm off with sigma 1 cm each is fused
  // (the cell alone, at the 3 mm clamp, would call it another height).
  float h4 = 0.0f, var4 = 9e-6f;
  EXPECT_EQ(FuseHeight(&h4, &var4, 0.02, 1e-4, false, p), FuseOutcome::kFused);
  EXPECT_FLOAT_EQ(h, 0.20f);
  EXPECT_FLOAT_EQ(var, 2e-5f);
}

TEST(ElevationFilterTest, VarianceLimits) {
  const ElevationFilterParams p;
  float h = 0.0f, var = 1e-5f;
  // Fusing 1e-5 with 1e-5 gives 5e-6 < 9e-6: clamped up.
  EXPECT_EQ(FuseHeight(&h, &var, 0.0, 1e-5, false, p), FuseOutcome::kFused);
  EXPECT_FLOAT_EQ(var, 9e-6f);
  // Above 0.01 the cell becomes unknown.
  float h2 = 0.5f, var2 = 0.0099999f;
  EXPECT_EQ(FuseHeight(&h2, &var2, 5.0, 1e-4, false, p), FuseOutcome::kMultiHeight);
  EXPECT_TRUE(std::isnan(h2));
  EXPECT_TRUE(std::isnan(var2));
  // ... and the next point starts it again.
  EXPECT_EQ(FuseHeight(&h2, &var2, 0.3, 1e-4, false, p), FuseOutcome::kInitialized);
  EXPECT_FLOAT_EQ(h2, 0.3f);
  // A first measurement with a huge variance is unknown at once.
  float h3 = NAN, var3 = NAN;
  FuseHeight(&h3, &var3, 0.3, 0.02, false, p);
  EXPECT_TRUE(std::isnan(h3));
}

TEST(ElevationFilterTest, LaserNoiseFollowsTheBeam) {
  const ElevationFilterParams p;
  // Straight down: the range sigma (1.8 cm).
  EXPECT_NEAR(PointHeightVariance({0, 0, 1}, {0, 0, 0}, p), 0.018 * 0.018, 1e-12);
  // Horizontal at 5 m: only the lateral sigma, 1.5 mm + 0.6 mrad x 5 m = 4.5 mm.
  EXPECT_NEAR(PointHeightVariance({0, 0, 0}, {5, 0, 0}, p), 0.0045 * 0.0045, 1e-12);
  // Grazing the ground at 45 deg: half of each.
  const double lat = 0.0015 + 0.0006 * std::sqrt(2.0);
  EXPECT_NEAR(PointHeightVariance({0, 0, 1}, {1, 0, 0}, p), 0.5 * 0.018 * 0.018 + 0.5 * lat * lat,
              1e-12);
}

}  // namespace
}  // namespace cairn::mapping
