#include "planner/footprint.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "common/check.h"

namespace cairn::planner {

using common::Vector2;

namespace {

constexpr size_t kMaxHullVertices = 32;

double Cross(const Vector2& o, const Vector2& a, const Vector2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

}  // namespace

std::vector<Vector2> ConvexHull(std::vector<Vector2> points) {
  std::sort(points.begin(), points.end(), [](const Vector2& a, const Vector2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) return points;
  std::vector<Vector2> hull(2 * points.size());
  size_t k = 0;
  // Lower hull, then upper hull; strict turns drop collinear points.
  for (const Vector2& p : points) {
    while (k >= 2 && Cross(hull[k - 2], hull[k - 1], p) <= 0.0) --k;
    hull[k++] = p;
  }
  for (size_t i = points.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && Cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);
  return hull;
}

std::vector<Vector2> GrowConvexPolygon(const std::vector<Vector2>& poly, double margin_m) {
  const size_t n = poly.size();
  if (n < 3 || margin_m == 0.0) return poly;
  std::vector<Vector2> out(n);
  for (size_t i = 0; i < n; ++i) {
    const Vector2 d_prev = (poly[i] - poly[(i + n - 1) % n]).normalized();
    const Vector2 d_next = (poly[(i + 1) % n] - poly[i]).normalized();
    // Outward normals of a counter-clockwise polygon's edges.
    const Vector2 n_prev(d_prev.y(), -d_prev.x());
    const Vector2 n_next(d_next.y(), -d_next.x());
    out[i] = poly[i] + margin_m * (n_prev + n_next) / (1.0 + n_prev.dot(n_next));
  }
  return out;
}

bool PointInPolygon(const std::vector<Vector2>& polygon, const Vector2& p) {
  bool inside = false;
  const size_t n = polygon.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vector2& a = polygon[i];
    const Vector2& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (p.x() < x) inside = !inside;
    }
  }
  return inside;
}

FootprintRasterizer::FootprintRasterizer(const std::vector<Vector2>& polygon_m) {
  CAIRN_THROW_UNLESS(polygon_m.size() >= 3,
                     "a footprint needs at least 3 vertices, got " << polygon_m.size());
  for (const Vector2& v : polygon_m) {
    CAIRN_THROW_UNLESS(v.allFinite(), "footprint vertex is not finite");
  }
  hull_m_ = ConvexHull(polygon_m);
  CAIRN_THROW_UNLESS(hull_m_.size() >= 3, "footprint has zero area");
  CAIRN_THROW_UNLESS(hull_m_.size() <= kMaxHullVertices,
                     "footprint hull has " << hull_m_.size() << " vertices, at most "
                                           << kMaxHullVertices << " are supported");
  for (const Vector2& v : hull_m_)
    circumscribed_radius_m_ = std::max(circumscribed_radius_m_, v.norm());
  // Inscribed radius: distance from the origin to the nearest hull edge, if the origin is inside.
  double inscribed = std::numeric_limits<double>::infinity();
  bool inside = true;
  for (size_t i = 0; i < hull_m_.size(); ++i) {
    const Vector2& a = hull_m_[i];
    const Vector2& b = hull_m_[(i + 1) % hull_m_.size()];
    const double cross = Cross(a, b, Vector2::Zero());
    if (cross < 0.0) inside = false;
    inscribed = std::min(inscribed, std::abs(cross) / (b - a).norm());
  }
  inscribed_radius_m_ = inside ? inscribed : 0.0;
}

void FootprintRasterizer::Rasterize(double x_cells, double y_cells, double yaw_rad,
                                    double resolution_m, std::vector<RowSpan>* spans) const {
  spans->clear();
  const size_t n = hull_m_.size();
  std::array<double, kMaxHullVertices> vx, vy;
  const double c = std::cos(yaw_rad) / resolution_m;
  const double s = std::sin(yaw_rad) / resolution_m;
  double y_min = std::numeric_limits<double>::infinity();
  double y_max = -y_min;
  for (size_t i = 0; i < n; ++i) {
    const Vector2& p = hull_m_[i];
    vx[i] = x_cells + c * p.x() - s * p.y();
    vy[i] = y_cells + s * p.x() + c * p.y();
    y_min = std::min(y_min, vy[i]);
    y_max = std::max(y_max, vy[i]);
  }
  if (!std::isfinite(y_min) || !std::isfinite(y_max)) return;
  const int row_lo = static_cast<int>(std::floor(y_min));
  const int row_hi = static_cast<int>(std::floor(y_max));
  for (int iy = row_lo; iy <= row_hi; ++iy) {
    // The hull restricted to this row's strip is convex: its x extent is reached at a vertex
    // inside the strip or where an edge crosses the strip's lower or upper line.
    const double y0 = std::max(static_cast<double>(iy), y_min);
    const double y1 = std::min(static_cast<double>(iy + 1), y_max);
    double x_lo = std::numeric_limits<double>::infinity();
    double x_hi = -x_lo;
    for (size_t i = 0; i < n; ++i) {
      const size_t j = (i + 1 == n) ? 0 : i + 1;
      const double ay = vy[i], by = vy[j];
      if (ay >= y0 && ay <= y1) {
        x_lo = std::min(x_lo, vx[i]);
        x_hi = std::max(x_hi, vx[i]);
      }
      if (ay == by) continue;
      const double inv = (vx[j] - vx[i]) / (by - ay);
      for (const double yl : {y0, y1}) {
        if ((ay - yl) * (by - yl) <= 0.0) {
          const double x = vx[i] + (yl - ay) * inv;
          x_lo = std::min(x_lo, x);
          x_hi = std::max(x_hi, x);
        }
      }
    }
    if (x_lo > x_hi) continue;
    spans->push_back({iy, static_cast<int>(std::floor(x_lo)), static_cast<int>(std::floor(x_hi))});
  }
}

}  // namespace cairn::planner
