#include "planner/distance_transform.h"

#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace cairn::planner {
namespace {

TEST(DistanceTransformTest, MatchesBruteForce) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const int sx = 5 + static_cast<int>(rng() % 40);
    const int sy = 5 + static_cast<int>(rng() % 40);
    GridMask mask = GridMask::Zero(sx, sy);
    const int n = static_cast<int>(rng() % 12);
    std::vector<std::pair<int, int>> set;
    for (int k = 0; k < n; ++k) {
      const int ix = static_cast<int>(rng() % sx), iy = static_cast<int>(rng() % sy);
      mask(ix, iy) = 1;
      set.push_back({ix, iy});
    }
    const Eigen::MatrixXf d = DistanceTransform(mask);
    for (int iy = 0; iy < sy; ++iy) {
      for (int ix = 0; ix < sx; ++ix) {
        double best = std::numeric_limits<double>::infinity();
        for (const auto& [mx, my] : set) best = std::min(best, std::hypot(ix - mx, iy - my));
        if (std::isinf(best)) {
          EXPECT_TRUE(std::isinf(d(ix, iy)));
        } else {
          ASSERT_NEAR(d(ix, iy), best, 1e-4) << ix << "," << iy;
        }
      }
    }
  }
}

}  // namespace
}  // namespace cairn::planner
