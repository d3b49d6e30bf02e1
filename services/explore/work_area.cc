#include "services/explore/work_area.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace cairn::explore {
namespace {

double Cross(const common::Vector2& a, const common::Vector2& b, const common::Vector2& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

bool OnSegment(const common::Vector2& a, const common::Vector2& b, const common::Vector2& p) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}

// Closed segments ab and cd share a point.
bool SegmentsTouch(const common::Vector2& a, const common::Vector2& b, const common::Vector2& c,
                   const common::Vector2& d) {
  const double d1 = Cross(c, d, a), d2 = Cross(c, d, b);
  const double d3 = Cross(a, b, c), d4 = Cross(a, b, d);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) {
    return true;
  }
  return (d1 == 0 && OnSegment(c, d, a)) || (d2 == 0 && OnSegment(c, d, b)) ||
         (d3 == 0 && OnSegment(a, b, c)) || (d4 == 0 && OnSegment(a, b, d));
}

double SignedArea(const std::vector<common::Vector2>& v) {
  double twice = 0.0;
  for (size_t i = 0; i < v.size(); ++i) {
    const auto& a = v[i];
    const auto& b = v[(i + 1) % v.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * twice;
}

}  // namespace

void WorkArea::Validate() const {
  const size_t n = vertices_m.size();
  if (n < 3) {
    throw std::invalid_argument("work area: a polygon needs at least 3 vertices, got " +
                                std::to_string(n));
  }
  for (size_t i = 0; i < n; ++i) {
    if (!vertices_m[i].allFinite()) {
      throw std::invalid_argument("work area: vertex " + std::to_string(i) + " is not finite");
    }
    if (vertices_m[i] == vertices_m[(i + 1) % n]) {
      throw std::invalid_argument("work area: vertex " + std::to_string(i) +
                                  " repeats the next one");
    }
  }
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
      if (adjacent) continue;
      if (SegmentsTouch(vertices_m[i], vertices_m[(i + 1) % n], vertices_m[j],
                        vertices_m[(j + 1) % n])) {
        throw std::invalid_argument("work area: edge " + std::to_string(i) + " crosses edge " +
                                    std::to_string(j) + " (the outline intersects itself)");
      }
    }
  }
  if (std::abs(SignedArea(vertices_m)) < 1e-9) {
    throw std::invalid_argument("work area: the polygon has no area");
  }
}

bool WorkArea::Contains(const common::Vector2& p) const {
  bool inside = false;
  const size_t n = vertices_m.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const auto& a = vertices_m[i];
    const auto& b = vertices_m[j];
    if (Cross(a, b, p) == 0.0 && OnSegment(a, b, p)) return true;
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

double WorkArea::AreaM2() const { return std::abs(SignedArea(vertices_m)); }

common::Vector2 WorkArea::MinCorner() const {
  common::Vector2 m = vertices_m.front();
  for (const auto& v : vertices_m) m = m.cwiseMin(v);
  return m;
}

common::Vector2 WorkArea::MaxCorner() const {
  common::Vector2 m = vertices_m.front();
  for (const auto& v : vertices_m) m = m.cwiseMax(v);
  return m;
}

WorkArea RectangleWorkArea(const common::Vector2& min_m, const common::Vector2& max_m) {
  return WorkArea{{min_m, {max_m.x(), min_m.y()}, max_m, {min_m.x(), max_m.y()}}};
}

WorkArea ParseWorkArea(const std::string& text) {
  WorkArea area;
  std::istringstream in(text);
  std::string token;
  while (in >> token) {
    const size_t comma = token.find(',');
    if (comma == std::string::npos) {
      throw std::invalid_argument("work area: '" + token + "' is not a vertex 'x,y'");
    }
    try {
      size_t used_x = 0, used_y = 0;
      const std::string xs = token.substr(0, comma), ys = token.substr(comma + 1);
      const double x = std::stod(xs, &used_x);
      const double y = std::stod(ys, &used_y);
      if (used_x != xs.size() || used_y != ys.size()) throw std::invalid_argument(token);
      area.vertices_m.emplace_back(x, y);
    } catch (const std::exception&) {
      throw std::invalid_argument("work area: '" + token + "' is not a vertex 'x,y'");
    }
  }
  return area;
}

}  // namespace cairn::explore
