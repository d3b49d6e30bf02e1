#pragma once

#include <cmath>

#include <gtest/gtest.h>

#include "common/grid_map.h"

/// @file
/// Layer comparison shared by unit and integration tests.

namespace cairn::testing {

/// Layers equal cell by cell (NaN equals NaN).
inline ::testing::AssertionResult SameLayer(const common::Layer& a, const common::Layer& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure() << "sizes differ: " << a.rows() << "x" << a.cols()
                                         << " vs " << b.rows() << "x" << b.cols();
  }
  for (int iy = 0; iy < a.cols(); ++iy) {
    for (int ix = 0; ix < a.rows(); ++ix) {
      const float x = a(ix, iy), y = b(ix, iy);
      if (!(std::isnan(x) && std::isnan(y)) && x != y) {
        return ::testing::AssertionFailure()
               << "cell (" << ix << ", " << iy << "): " << x << " != " << y;
      }
    }
  }
  return ::testing::AssertionSuccess();
}

}  // namespace cairn::testing
