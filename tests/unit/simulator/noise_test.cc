#include "simulator/noise.h"

#include <gtest/gtest.h>

namespace cairn::sim {
namespace {

TEST(NoiseSourceTest, GaussianHasUnitVarianceAndDependsOnlyOnIndex) {
  NoiseSource noise(42, 7);
  double sum = 0.0, sum2 = 0.0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = noise.Gaussian(i);
    sum += x;
    sum2 += x * x;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sum2 / n, 1.0, 0.02);
  EXPECT_EQ(noise.Gaussian(12345), NoiseSource(42, 7).Gaussian(12345));
  EXPECT_NE(noise.Gaussian(12345), NoiseSource(43, 7).Gaussian(12345));
  EXPECT_NE(noise.Gaussian(12345), NoiseSource(42, 8).Gaussian(12345));
}

}  // namespace
}  // namespace cairn::sim
