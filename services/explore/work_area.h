#pragma once

#include <string>
#include <vector>

#include "common/types.h"

/// @file
/// The work area of an exploration mission: a simple polygon in world metres (seed 002's red
/// rectangle, or any outline the user gives). Cells outside it count for neither gain nor
/// coverage.

namespace cairn::explore {

struct WorkArea {
  std::vector<common::Vector2> vertices_m;  ///< in order, either winding; not closed

  /// @throws std::invalid_argument when the polygon has fewer than 3 vertices, a non-finite
  /// coordinate, a repeated vertex, no area, or edges that cross (a self-intersecting outline),
  /// naming the problem and the edges.
  void Validate() const;

  /// Even-odd rule; points on an edge count as inside.
  bool Contains(const common::Vector2& point_m) const;

  double AreaM2() const;  ///< unsigned
  common::Vector2 MinCorner() const;
  common::Vector2 MaxCorner() const;
};

/// An axis-aligned rectangle as a work area.
WorkArea RectangleWorkArea(const common::Vector2& min_m, const common::Vector2& max_m);

/// "x0,y0 x1,y1 ..." (the form the command line and the mission request take).
/// @throws std::invalid_argument naming the bad token.
WorkArea ParseWorkArea(const std::string& text);

}  // namespace cairn::explore
