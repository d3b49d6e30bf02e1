#pragma once

#include <vector>

#include "common/types.h"

/// @file
/// Footprint rasterisation: which grid cells a robot footprint covers at a pose.

namespace cairn::planner {

/// Cells [ix_min, ix_max] (inclusive) of grid row iy.
struct RowSpan {
  int iy{0};
  int ix_min{0};
  int ix_max{0};
};

/// Rasterises a footprint polygon onto a grid, one x-span per row.
///
/// The polygon is replaced by its convex hull (robot footprints are convex; a concave one is
/// covered conservatively). A cell counts as covered when the hull touches it, boundary
/// included, so the result never misses a cell the robot overlaps. Coordinates are in cells of
/// the grid frame: x along the grid's x axis from the minimum corner of cell (0, 0).
class FootprintRasterizer {
 public:
  /// @param polygon_m footprint in the base frame (x forward, y left), metres, >= 3 vertices.
  /// @throws std::invalid_argument for fewer than 3 vertices, non-finite vertices or a hull of
  /// zero area.
  explicit FootprintRasterizer(const std::vector<common::Vector2>& polygon_m);
  FootprintRasterizer(const FootprintRasterizer&) = default;
  FootprintRasterizer& operator=(const FootprintRasterizer&) = default;
  FootprintRasterizer(FootprintRasterizer&&) = default;
  FootprintRasterizer& operator=(FootprintRasterizer&&) = default;

  /// Covered cells with the base origin at (x_cells, y_cells) and heading yaw_rad in the grid
  /// frame, on a grid of `resolution_m`. Rows come out in increasing iy; `spans` is cleared.
  /// Cells may lie outside the grid (negative or too large indices); callers clip.
  void Rasterize(double x_cells, double y_cells, double yaw_rad, double resolution_m,
                 std::vector<RowSpan>* spans) const;

  /// Convex hull of the footprint, counter-clockwise, metres.
  const std::vector<common::Vector2>& hull_m() const { return hull_m_; }
  /// Largest distance from the base origin to the hull (metres).
  double circumscribed_radius_m() const { return circumscribed_radius_m_; }
  /// Radius of the largest origin-centred disc inside the hull; 0 if the origin lies outside.
  double inscribed_radius_m() const { return inscribed_radius_m_; }

 private:
  std::vector<common::Vector2> hull_m_;
  double circumscribed_radius_m_{0.0};
  double inscribed_radius_m_{0.0};
};

/// A convex polygon (counter-clockwise) grown outward by `margin_m`: every edge moves out by
/// the margin and neighbouring edges meet at mitred corners.
std::vector<common::Vector2> GrowConvexPolygon(const std::vector<common::Vector2>& ccw_polygon,
                                               double margin_m);

/// Convex hull (Andrew's monotone chain), counter-clockwise, without collinear points.
std::vector<common::Vector2> ConvexHull(std::vector<common::Vector2> points);

/// True when `p` lies inside the polygon (even-odd rule; boundary points may go either way).
bool PointInPolygon(const std::vector<common::Vector2>& polygon, const common::Vector2& p);

}  // namespace cairn::planner
