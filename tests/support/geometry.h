#pragma once

#include <algorithm>
#include <vector>

#include "common/types.h"

/// @file
/// Geometry for integration tests that check ground truth against a footprint.

namespace cairn::testing {

/// Separating-axis test between two convex polygons; touching (or closer than margin_m)
/// counts as overlapping.
inline bool ConvexOverlap(const std::vector<common::Vector2>& a,
                          const std::vector<common::Vector2>& b, double margin_m = 0.0) {
  for (const auto* poly : {&a, &b}) {
    for (size_t i = 0; i < poly->size(); ++i) {
      const common::Vector2 e = (*poly)[(i + 1) % poly->size()] - (*poly)[i];
      const common::Vector2 axis = common::Vector2(-e.y(), e.x()).normalized();
      double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300;
      for (const common::Vector2& v : a) {
        a0 = std::min(a0, axis.dot(v));
        a1 = std::max(a1, axis.dot(v));
      }
      for (const common::Vector2& v : b) {
        b0 = std::min(b0, axis.dot(v));
        b1 = std::max(b1, axis.dot(v));
      }
      if (a1 + margin_m < b0 || b1 + margin_m < a0) return false;
    }
  }
  return true;
}

}  // namespace cairn::testing
