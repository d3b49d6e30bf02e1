#include "services/mapping/obstacle_shape.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "common/layers.h"
#include <Eigen/Eigenvalues>

namespace cairn::mapping::internal {
namespace {

using common::GridMap;
using common::Vector2;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Perpendicular distance of p from the line through a and b.
double LineDistance(const Vector2& p, const Vector2& a, const Vector2& b) {
  const Vector2 ab = b - a;
  const double len = ab.norm();
  if (len < 1e-12) return (p - a).norm();
  return std::fabs(ab.x() * (p.y() - a.y()) - ab.y() * (p.x() - a.x())) / len;
}

void DouglasPeucker(const std::vector<Vector2>& pts, size_t a, size_t b, double tol,
                    std::vector<bool>* keep) {
  if (b <= a + 1) return;
  double best = -1;
  size_t best_i = a;
  for (size_t i = a + 1; i < b; ++i) {
    const double d = LineDistance(pts[i], pts[a], pts[b]);
    if (d > best) {
      best = d;
      best_i = i;
    }
  }
  if (best > tol) {
    (*keep)[best_i] = true;
    DouglasPeucker(pts, a, best_i, tol, keep);
    DouglasPeucker(pts, best_i, b, tol, keep);
  }
}

// A set of cells as a mask over their bounding box with one empty cell of margin on each side.
struct CellMask {
  int x0{0};
  int y0{0};
  int w{0};
  int hgt{0};
  std::vector<uint8_t> mask;
  bool Filled(int x, int y) const { return mask[x + static_cast<size_t>(y) * w] != 0; }
};

CellMask MaskOf(const std::vector<int64_t>& cells, int sx) {
  CellMask m;
  int x0 = std::numeric_limits<int>::max(), y0 = x0, x1 = std::numeric_limits<int>::min(), y1 = x1;
  for (int64_t i : cells) {
    const int x = static_cast<int>(i % sx), y = static_cast<int>(i / sx);
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
  m.x0 = x0;
  m.y0 = y0;
  m.w = x1 - x0 + 3;
  m.hgt = y1 - y0 + 3;
  m.mask.assign(static_cast<size_t>(m.w) * m.hgt, 0);
  for (int64_t i : cells) {
    const int x = static_cast<int>(i % sx) - x0 + 1, y = static_cast<int>(i / sx) - y0 + 1;
    m.mask[x + static_cast<size_t>(y) * m.w] = 1;
  }
  return m;
}

// Directed boundary edges with the region on their left, stored at their start corner as
// direction codes (0 +x, 1 +y, 2 -x, 3 -y); a corner has two when cells touch diagonally.
struct BoundaryEdges {
  int cw{0};  // corners per row
  size_t num_corners{0};
  std::vector<uint8_t> count;
  std::vector<uint8_t> dirs;
};

BoundaryEdges EdgesOf(const CellMask& m) {
  BoundaryEdges e;
  e.cw = m.w + 1;
  e.num_corners = static_cast<size_t>(e.cw) * (m.hgt + 1);
  e.count.assign(e.num_corners, 0);
  e.dirs.assign(2 * e.num_corners, 0);
  auto add = [&](int cx, int cy, uint8_t d) {
    const size_t c = cx + static_cast<size_t>(cy) * e.cw;
    e.dirs[2 * c + e.count[c]++] = d;
  };
  for (int y = 1; y < m.hgt - 1; ++y) {
    for (int x = 1; x < m.w - 1; ++x) {
      if (!m.Filled(x, y)) continue;
      if (!m.Filled(x, y - 1)) add(x, y, 0);
      if (!m.Filled(x + 1, y)) add(x + 1, y, 1);
      if (!m.Filled(x, y + 1)) add(x + 1, y + 1, 2);
      if (!m.Filled(x - 1, y)) add(x, y + 1, 3);
    }
  }
  return e;
}

using Corner = std::pair<int, int>;

// Follows the edges from `start` into one loop (consuming them), turning right at a pinch
// corner.
std::vector<Corner> FollowLoop(BoundaryEdges* e, size_t start) {
  constexpr int kDx[4] = {1, 0, -1, 0}, kDy[4] = {0, 1, 0, -1};
  std::vector<Corner> loop;
  int cx = static_cast<int>(start % e->cw), cy = static_cast<int>(start / e->cw);
  const Corner first{cx, cy};
  uint8_t d = e->dirs[2 * start + --e->count[start]];
  while (true) {
    loop.push_back({cx, cy});
    cx += kDx[d];
    cy += kDy[d];
    if (cx == first.first && cy == first.second) break;
    const size_t c = cx + static_cast<size_t>(cy) * e->cw;
    if (e->count[c] == 0) break;  // cannot happen on a closed boundary
    int pick = e->count[c] - 1;
    if (e->count[c] == 2) {
      const uint8_t right = static_cast<uint8_t>((d + 3) % 4);  // right turn of d
      pick = e->dirs[2 * c] == right ? 0 : 1;
    }
    const uint8_t next = e->dirs[2 * c + pick];
    if (pick == 0 && e->count[c] == 2) e->dirs[2 * c] = e->dirs[2 * c + 1];
    --e->count[c];
    d = next;
  }
  return loop;
}

// The counter-clockwise loops of the edges (outer boundaries, one per piece; holes run
// clockwise), largest first.
std::vector<std::vector<Corner>> OuterLoops(BoundaryEdges* e) {
  std::vector<std::pair<double, std::vector<Corner>>> loops;
  for (size_t start = 0; start < e->num_corners; ++start) {
    while (e->count[start] > 0) {
      std::vector<Corner> loop = FollowLoop(e, start);
      double area = 0;
      for (size_t k = 0; k < loop.size(); ++k) {
        const Corner& a = loop[k];
        const Corner& b = loop[(k + 1) % loop.size()];
        area += double(a.first) * b.second - double(b.first) * a.second;
      }
      if (area > 0) loops.emplace_back(area, std::move(loop));
    }
  }
  std::stable_sort(loops.begin(), loops.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::vector<Corner>> out;
  for (auto& l : loops) out.push_back(std::move(l.second));
  return out;
}

// The convex hull of corners, counter-clockwise, without collinear points (Andrew's monotone
// chain).
std::vector<Corner> ConvexHull(std::vector<Corner> pts) {
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  auto cross = [](const Corner& o, const Corner& a, const Corner& b) {
    return int64_t(a.first - o.first) * (b.second - o.second) -
           int64_t(a.second - o.second) * (b.first - o.first);
  };
  std::vector<Corner> hull(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);
  return hull;
}

// Corner coordinates back to grid cells, dropping collinear corners.
std::vector<Vector2> CornerPoints(const std::vector<Corner>& loop, int x0, int y0) {
  std::vector<Vector2> pts;
  for (size_t k = 0; k < loop.size(); ++k) {
    const Corner& prev = loop[(k + loop.size() - 1) % loop.size()];
    const Corner& cur = loop[k];
    const Corner& next = loop[(k + 1) % loop.size()];
    const int ax = cur.first - prev.first, ay = cur.second - prev.second;
    const int bx = next.first - cur.first, by = next.second - cur.second;
    if (ax * by - ay * bx == 0) continue;
    pts.emplace_back(cur.first + x0 - 1, cur.second + y0 - 1);
  }
  return pts;
}

// Douglas-Peucker on the closed polygon, split at its first point and the point farthest from
// it; the polygon itself when too small to simplify.
std::vector<Vector2> SimplifyClosed(const std::vector<Vector2>& pts, double tol) {
  if (pts.size() <= 4 || tol <= 0) return pts;
  size_t far = 0;
  double far_d = -1;
  for (size_t k = 1; k < pts.size(); ++k) {
    const double d = (pts[k] - pts[0]).norm();
    if (d > far_d) {
      far_d = d;
      far = k;
    }
  }
  std::vector<Vector2> closed = pts;
  closed.push_back(pts[0]);
  std::vector<bool> keep(closed.size(), false);
  keep[0] = keep[far] = keep.back() = true;
  DouglasPeucker(closed, 0, far, tol, &keep);
  DouglasPeucker(closed, far, closed.size() - 1, tol, &keep);
  std::vector<Vector2> simplified;
  for (size_t k = 0; k + 1 < closed.size(); ++k) {
    if (keep[k]) simplified.push_back(closed[k]);
  }
  return simplified.size() >= 3 ? simplified : pts;
}

}  // namespace

std::vector<Vector2> TraceOutline(const std::vector<int64_t>& cells, int sx, double tol) {
  const CellMask mask = MaskOf(cells, sx);
  BoundaryEdges edges = EdgesOf(mask);
  std::vector<std::vector<Corner>> loops = OuterLoops(&edges);
  if (loops.empty()) return {};
  if (loops.size() == 1) return SimplifyClosed(CornerPoints(loops[0], mask.x0, mask.y0), tol);
  // Pieces of one object (faces seen apart, joined): the hull around all of them.
  std::vector<Corner> all;
  for (const auto& l : loops) all.insert(all.end(), l.begin(), l.end());
  return CornerPoints(ConvexHull(std::move(all)), mask.x0, mask.y0);
}

double Median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) {
    m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
  }
  return m;
}

// Linear-interpolated percentile (q in [0, 1]).
double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(pos));
  const double frac = pos - i;
  return i + 1 < v.size() ? v[i] * (1 - frac) + v[i + 1] * frac : v[i];
}

// Slope of the least-squares plane z = a·x + b·y + c through the cells' heights.
double PlaneSlope(const GridMap& map, const std::vector<int64_t>& cells) {
  const int sx = map.size_x();
  const float* h = map.at(layers::kElevation).data();
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  const double res = map.resolution_m();
  const int64_t i0 = cells.front();
  const double x0 = static_cast<double>(i0 % sx), y0 = static_cast<double>(i0 / sx);
  for (int64_t i : cells) {
    if (std::isnan(h[i])) continue;
    const Eigen::Vector3d row((i % sx - x0) * res, (i / sx - y0) * res, 1.0);
    ata += row * row.transpose();
    atb += row * double(h[i]);
  }
  const Eigen::Vector3d sol = ata.ldlt().solve(atb);
  if (!sol.allFinite()) return 0.0;
  return std::atan(std::hypot(sol(0), sol(1)));
}

std::string FormatNumbers(const char* fmt, double a, double b, double c) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), fmt, a, b, c);
  return buf;
}

double HeadingDeg(double heading_rad) {
  double deg = std::fmod(heading_rad * 180.0 / M_PI, 360.0);
  if (deg < 0) deg += 360.0;
  return deg >= 359.5 ? 0.0 : deg;
}

double DownhillHeading(const GridMap& map, const std::vector<int64_t>& cells) {
  const int sx = map.size_x(), sy = map.size_y();
  const float* h = map.at(layers::kElevation).data();
  auto known = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < sx && y < sy && !std::isnan(h[x + static_cast<int64_t>(y) * sx]);
  };
  auto at = [&](int x, int y) { return double(h[x + static_cast<int64_t>(y) * sx]); };
  // The rise per cell along one axis through (x, y): between the farthest known cells up to two
  // cells to either side.
  auto rise = [&](int x, int y, int dx, int dy, double* out) {
    int a = 2, b = 2;
    while (a > 0 && !known(x + a * dx, y + a * dy)) --a;
    while (b > 0 && !known(x - b * dx, y - b * dy)) --b;
    if (a + b == 0) return false;
    *out = (at(x + a * dx, y + a * dy) - at(x - b * dx, y - b * dy)) / (a + b);
    return true;
  };
  Vector2 sum = Vector2::Zero();
  int n = 0;
  for (int64_t i : cells) {
    const int x = static_cast<int>(i % sx), y = static_cast<int>(i / sx);
    double gx = 0, gy = 0;
    const bool has_x = rise(x, y, 1, 0, &gx), has_y = rise(x, y, 0, 1, &gy);
    const Vector2 g(has_x ? gx : 0.0, has_y ? gy : 0.0);
    if (!(g.norm() > 1e-6)) continue;
    sum -= g.normalized();
    ++n;
  }
  if (n == 0 || sum.norm() < 0.7 * n) return std::numeric_limits<double>::quiet_NaN();
  return std::remainder(std::atan2(sum.y(), sum.x()) + map.geometry().origin.yaw_rad, 2 * M_PI);
}

// Measurements shared by every kind: centroid, outline, extents along the principal axes,
// area and cell count.
void MeasureShape(const GridMap& map, const std::vector<int64_t>& cells, const ObstacleParams& p,
                  common::Obstacle* o) {
  const int sx = map.size_x();
  const double res = map.resolution_m();
  const auto& g = map.geometry();
  Vector2 mean = Vector2::Zero();
  std::vector<Vector2> centres;
  centres.reserve(cells.size());
  for (int64_t i : cells) {
    const Vector2 c = g.CenterOf({static_cast<int>(i % sx), static_cast<int>(i / sx)});
    centres.push_back(c);
    mean += c;
  }
  mean /= static_cast<double>(cells.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& c : centres) cov += (c - mean) * (c - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  const Vector2 major = eig.eigenvectors().col(1), minor = eig.eigenvectors().col(0);
  double lo_a = 1e300, hi_a = -1e300, lo_b = 1e300, hi_b = -1e300;
  for (const auto& c : centres) {
    const double a = (c - mean).dot(major), b = (c - mean).dot(minor);
    lo_a = std::min(lo_a, a);
    hi_a = std::max(hi_a, a);
    lo_b = std::min(lo_b, b);
    hi_b = std::max(hi_b, b);
  }
  o->centroid_m = mean;
  o->length_m = hi_a - lo_a + res;
  o->width_m = hi_b - lo_b + res;
  o->area_m2 = cells.size() * res * res;
  o->num_cells = static_cast<int32_t>(cells.size());
  o->outline_m.clear();
  for (const Vector2& corner : TraceOutline(cells, sx, p.outline_tolerance_cells)) {
    o->outline_m.push_back(g.origin.Transform(corner * res));
  }
}

void NumberByCentroid(common::ObstacleRegistry* registry) {
  std::stable_sort(registry->obstacles.begin(), registry->obstacles.end(),
                   [](const common::Obstacle& a, const common::Obstacle& b) {
                     if (a.centroid_m.y() != b.centroid_m.y())
                       return a.centroid_m.y() < b.centroid_m.y();
                     return a.centroid_m.x() < b.centroid_m.x();
                   });
  int32_t id = 1;
  for (auto& o : registry->obstacles) o.id = id++;
}

}  // namespace cairn::mapping::internal
