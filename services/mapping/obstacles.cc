#include "services/mapping/obstacles.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"
#include "services/mapping/traversability.h"
#include <Eigen/Eigenvalues>

namespace cairn::mapping {
namespace {

using common::GridMap;
using common::Obstacle;
using common::ObstacleKind;
using common::Vector2;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kRadToDeg = 180.0 / M_PI;
constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

// Per-cell feature class, in priority order (a cell takes the first that applies).
enum CellClass : uint8_t { kNone = 0, kDitch, kWall, kStep, kDrop, kRamp };

constexpr std::array<std::array<int, 2>, 4> kNeighbours4{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};
constexpr std::array<std::array<int, 2>, 8> kNeighbours8{
    {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {1, -1}, {-1, 1}, {-1, -1}}};

// The classified grid: per cell its class and, for edges, the largest discontinuity.
struct Cells {
  int sx{0};
  int sy{0};
  const float* cls{nullptr};   // CellClass as float
  const float* edge{nullptr};  // height of the largest step/wall/drop at the cell
  const float* low{nullptr};   // lower side of that edge
  const float* high{nullptr};  // higher side of that edge
  int64_t Index(int x, int y) const { return x + static_cast<int64_t>(y) * sx; }
  bool Inside(int x, int y) const { return x >= 0 && y >= 0 && x < sx && y < sy; }
  uint8_t Class(int64_t i) const { return static_cast<uint8_t>(cls[i]); }
};

// Rise per cell along direction d of the plane with the cell's normal (0 where unknown).
double Rise(const float* nx, const float* ny, int x, int y, int sx, const std::array<int, 2>& d,
            double res) {
  const int64_t i = x + static_cast<int64_t>(y) * sx;
  const double a = nx[i], b = ny[i];
  if (std::isnan(a) || std::isnan(b)) return 0.0;
  const double nz = std::sqrt(std::max(1e-6, 1.0 - a * a - b * b));
  return res * std::fabs(a * d[0] + b * d[1]) / nz;
}

// Classification of the window W = rect grown by one cell (the ramp rule looks at the classes
// of the 8-neighbours); written back for rect only.
void Classify(GridMap* map, const ObstacleParams& p, const CellRect& rect) {
  const int sx = map->size_x(), sy = map->size_y();
  const CellRect w{std::max(0, rect.x0 - 1), std::max(0, rect.y0 - 1), std::min(sx, rect.x1 + 1),
                   std::min(sy, rect.y1 + 1)};
  const int ww = w.x1 - w.x0, wh = w.y1 - w.y0;
  const size_t n = static_cast<size_t>(ww) * wh;
  std::vector<uint8_t> cls(n, kNone);
  std::vector<float> edge(n, kNaNf), low(n, kNaNf), high(n, kNaNf);
  auto wi = [&](int x, int y) { return (x - w.x0) + static_cast<size_t>(y - w.y0) * ww; };
  auto in_w = [&](int x, int y) { return x >= w.x0 && y >= w.y0 && x < w.x1 && y < w.y1; };
  auto inside = [&](int x, int y) { return x >= 0 && y >= 0 && x < sx && y < sy; };
  auto note = [&](int x, int y, float height, float lo, float hi) {
    if (!in_w(x, y)) return;
    const size_t i = wi(x, y);
    if (!(height <= edge[i])) {
      edge[i] = height;
      low[i] = lo;
      high[i] = hi;
    }
  };
  const float* h = map->at(layers::kElevation).data();
  const float* slope = map->at(layers::kSlope).data();
  const float* ddepth = map->at(layers::kDitchDepth).data();
  const float* nxl = map->at(kNormalXLayer).data();
  const float* nyl = map->at(kNormalYLayer).data();
  const double res = map->resolution_m();
  const float* bound =
      map->HasLayer(layers::kGroundBound) ? map->at(layers::kGroundBound).data() : nullptr;
  auto H = [&](int x, int y) { return h[x + static_cast<int64_t>(y) * sx]; };

  // Discontinuities along x and y that stand out from the same-direction differences just
  // before and after them (a ramp rises evenly; a spike rises and falls). A step spans one
  // cell pair, or two when a vertical face left an intermediate height in the cell it cuts
  // (then the rise is compared with twice the outer differences, as a ramp would rise that
  // much over two cells). Spans start up to two cells before the window.
  auto same_sign_abs = [](double v, double ref) {
    return (v > 0) == (ref > 0) ? std::fabs(v) : 0.0;
  };
  auto known = [&](int x, int y) { return inside(x, y) && !std::isnan(H(x, y)); };
  for (int y = std::max(0, w.y0 - 2); y < w.y1; ++y) {
    for (int x = std::max(0, w.x0 - 2); x < w.x1; ++x) {
      const float hc = H(x, y);
      if (std::isnan(hc)) continue;
      for (const auto& d : {std::array<int, 2>{1, 0}, std::array<int, 2>{0, 1}}) {
        for (int span = 1; span <= 2; ++span) {
          const int nx = x + span * d[0], ny = y + span * d[1];
          if (!known(nx, ny)) continue;
          const int mx = x + d[0], my = y + d[1];  // the intermediate cell of a two-cell span
          if (!in_w(x, y) && !in_w(nx, ny) && !(span == 2 && in_w(mx, my))) continue;
          const float hn = H(nx, ny);
          const double delta = double(hn) - hc;
          if (std::fabs(delta) < p.min_step_height_m) continue;
          if (span == 2) {
            if (!known(mx, my)) continue;
            const double hm = H(mx, my);
            if ((hm - hc) * delta < 0 || (hn - hm) * delta < 0) continue;  // not monotonic
          }
          double before = 0, after = 0;
          if (known(x - d[0], y - d[1]))
            before = same_sign_abs(double(hc) - H(x - d[0], y - d[1]), delta);
          if (known(nx + d[0], ny + d[1]))
            after = same_sign_abs(double(H(nx + d[0], ny + d[1])) - hn, delta);
          // What an incline rises along this line per cell, from the normals of both cells
          // (an edge tilts the normals around it, so the lower of the two is taken).
          const double along =
              std::min(Rise(nxl, nyl, x, y, sx, d, res), Rise(nxl, nyl, nx, ny, sx, d, res));
          if (std::fabs(delta) <= p.step_contrast * span * std::max({before, after, along}))
            continue;
          // Small steps must hold over two cells on each side (noise rarely does): the mean
          // of the pair beyond minus the mean of the pair before.
          if (std::fabs(delta) < p.wall_min_height_m && known(x - d[0], y - d[1]) &&
              known(nx + d[0], ny + d[1])) {
            const double wide = 0.5 * (double(hn) + H(nx + d[0], ny + d[1])) -
                                0.5 * (double(hc) + H(x - d[0], y - d[1]));
            if (std::fabs(wide) < 0.75 * p.min_step_height_m) continue;
          }
          const float height = static_cast<float>(std::fabs(delta));
          const float lo = std::min(hc, hn), hi = std::max(hc, hn);
          note(x, y, height, lo, hi);
          note(nx, ny, height, lo, hi);
          if (span == 2) note(mx, my, height, lo, hi);
        }
      }
    }
  }
  for (int y = w.y0; y < w.y1; ++y) {
    for (int x = w.x0; x < w.x1; ++x) {
      const size_t i = wi(x, y);
      const int64_t m = x + static_cast<int64_t>(y) * sx;
      if (!std::isnan(ddepth[m])) {
        cls[i] = kDitch;
      } else if (!std::isnan(edge[i])) {
        cls[i] = edge[i] >= p.wall_min_height_m ? kWall : kStep;
      } else if (bound != nullptr && !std::isnan(h[m])) {
        // A drop into a gap the sensor looked into (ditches own their rims).
        for (const auto& d : kNeighbours4) {
          if (!inside(x + d[0], y + d[1])) continue;
          const int64_t j = (x + d[0]) + static_cast<int64_t>(y + d[1]) * sx;
          if (!std::isnan(h[j]) || !std::isfinite(bound[j]) || !std::isnan(ddepth[j])) continue;
          const double drop = double(h[m]) - bound[j];
          if (drop >= p.min_drop_height_m && !(drop <= edge[i])) {
            cls[i] = kDrop;
            edge[i] = static_cast<float>(drop);
            low[i] = bound[j];
            high[i] = h[m];
          }
        }
      }
    }
  }
  // Ramps: inclined known cells with no edge next to them (an edge tilts the normals of the
  // cells around it).
  float* out_cls = map->at(kFeatureClassLayer).data();
  float* out_edge = map->at(kFeatureEdgeLayer).data();
  float* out_low = map->at(kFeatureLowLayer).data();
  float* out_high = map->at(kFeatureHighLayer).data();
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const size_t i = wi(x, y);
      const int64_t m = x + static_cast<int64_t>(y) * sx;
      uint8_t k = cls[i];
      if (k == kNone && !std::isnan(h[m]) && slope[m] >= p.min_ramp_slope_rad) {
        bool near_edge = false;
        for (const auto& d : kNeighbours8) {
          if (!in_w(x + d[0], y + d[1])) continue;
          const uint8_t nk = cls[wi(x + d[0], y + d[1])];
          near_edge |= nk == kDitch || nk == kWall || nk == kStep || nk == kDrop;
        }
        if (!near_edge) k = kRamp;
      }
      out_cls[m] = k;
      out_edge[m] = edge[i];
      out_low[m] = low[i];
      out_high[m] = high[i];
    }
  }
}

// 8-connected components over the cells whose class is in `classes`, skipping labelled cells.
std::vector<std::vector<int64_t>> Components(const Cells& c, std::initializer_list<uint8_t> classes,
                                             std::vector<int32_t>* label, int32_t* next_label) {
  auto wanted = [&](uint8_t k) {
    for (uint8_t w : classes) {
      if (k == w) return true;
    }
    return false;
  };
  std::vector<std::vector<int64_t>> out;
  std::vector<int64_t> stack;
  for (int y = 0; y < c.sy; ++y) {
    for (int x = 0; x < c.sx; ++x) {
      const int64_t start = c.Index(x, y);
      if ((*label)[start] != 0 || !wanted(c.Class(start))) continue;
      const int32_t id = (*next_label)++;
      std::vector<int64_t> cells;
      stack.assign(1, start);
      (*label)[start] = id;
      while (!stack.empty()) {
        const int64_t i = stack.back();
        stack.pop_back();
        cells.push_back(i);
        const int cx = static_cast<int>(i % c.sx), cy = static_cast<int>(i / c.sx);
        for (const auto& d : kNeighbours8) {
          const int nx = cx + d[0], ny = cy + d[1];
          if (!c.Inside(nx, ny)) continue;
          const int64_t j = c.Index(nx, ny);
          if ((*label)[j] == 0 && wanted(c.Class(j))) {
            (*label)[j] = id;
            stack.push_back(j);
          }
        }
      }
      out.push_back(std::move(cells));
    }
  }
  return out;
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

// Surfaces: 4-connected known cells, walls excepted, whose neighbours differ by less than
// `continuity` (a ramp stays one surface, a step separates two). -1 for cells on none.
void LabelSurfaces(const Cells& c, const float* h, double continuity, std::vector<int32_t>* label,
                   std::vector<int64_t>* size) {
  const size_t n = static_cast<size_t>(c.sx) * c.sy;
  label->assign(n, -1);
  size->clear();
  std::vector<int64_t> stack;
  for (size_t start = 0; start < n; ++start) {
    if ((*label)[start] >= 0 || std::isnan(h[start]) || c.Class(start) == kWall) continue;
    const int32_t id = static_cast<int32_t>(size->size());
    int64_t count = 0;
    (*label)[start] = id;
    stack.assign(1, static_cast<int64_t>(start));
    while (!stack.empty()) {
      const int64_t i = stack.back();
      stack.pop_back();
      ++count;
      const int x = static_cast<int>(i % c.sx), y = static_cast<int>(i / c.sx);
      for (const auto& d : kNeighbours4) {
        if (!c.Inside(x + d[0], y + d[1])) continue;
        const int64_t j = c.Index(x + d[0], y + d[1]);
        if ((*label)[j] >= 0 || std::isnan(h[j]) || c.Class(j) == kWall) continue;
        if (std::fabs(double(h[j]) - h[i]) >= continuity) continue;
        (*label)[j] = id;
        stack.push_back(j);
      }
    }
    size->push_back(count);
  }
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

// Outer boundary of a set of cells along the cell edges (counter-clockwise, in cell corner
// coordinates), simplified to `tol` cells. Cells touching at a corner stay one outline.
std::vector<Vector2> TraceOutline(const std::vector<int64_t>& cells, int sx, double tol) {
  int x0 = std::numeric_limits<int>::max(), y0 = x0, x1 = std::numeric_limits<int>::min(), y1 = x1;
  for (int64_t i : cells) {
    const int x = static_cast<int>(i % sx), y = static_cast<int>(i / sx);
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
  const int w = x1 - x0 + 3, hgt = y1 - y0 + 3;  // one empty cell of margin on each side
  std::vector<uint8_t> mask(static_cast<size_t>(w) * hgt, 0);
  for (int64_t i : cells) {
    const int x = static_cast<int>(i % sx) - x0 + 1, y = static_cast<int>(i / sx) - y0 + 1;
    mask[x + static_cast<size_t>(y) * w] = 1;
  }
  auto filled = [&](int x, int y) { return mask[x + static_cast<size_t>(y) * w] != 0; };
  // Directed boundary edges with the region on their left, stored at their start corner as
  // direction codes (0 +x, 1 +y, 2 -x, 3 -y); a corner has two when cells touch diagonally.
  using Corner = std::pair<int, int>;
  const int cw = w + 1;
  const size_t num_corners = static_cast<size_t>(cw) * (hgt + 1);
  std::vector<uint8_t> count(num_corners, 0);
  std::vector<uint8_t> dirs(2 * num_corners, 0);
  auto add = [&](int cx, int cy, uint8_t d) {
    const size_t c = cx + static_cast<size_t>(cy) * cw;
    dirs[2 * c + count[c]++] = d;
  };
  for (int y = 1; y < hgt - 1; ++y) {
    for (int x = 1; x < w - 1; ++x) {
      if (!filled(x, y)) continue;
      if (!filled(x, y - 1)) add(x, y, 0);
      if (!filled(x + 1, y)) add(x + 1, y, 1);
      if (!filled(x, y + 1)) add(x + 1, y + 1, 2);
      if (!filled(x - 1, y)) add(x, y + 1, 3);
    }
  }
  constexpr int kDx[4] = {1, 0, -1, 0}, kDy[4] = {0, 1, 0, -1};
  // Follow the edges into loops, turning right at a pinch corner; keep the largest
  // counter-clockwise loop (the outer boundary; holes run clockwise).
  std::vector<Corner> best;
  double best_area = 0;
  for (size_t start = 0; start < num_corners; ++start) {
    while (count[start] > 0) {
      std::vector<Corner> loop;
      int cx = static_cast<int>(start % cw), cy = static_cast<int>(start / cw);
      const Corner first{cx, cy};
      uint8_t d = dirs[2 * start + --count[start]];
      while (true) {
        loop.push_back({cx, cy});
        cx += kDx[d];
        cy += kDy[d];
        if (cx == first.first && cy == first.second) break;
        const size_t c = cx + static_cast<size_t>(cy) * cw;
        if (count[c] == 0) break;  // cannot happen on a closed boundary
        int pick = count[c] - 1;
        if (count[c] == 2) {
          const uint8_t right = static_cast<uint8_t>((d + 3) % 4);  // right turn of d
          pick = dirs[2 * c] == right ? 0 : 1;
        }
        const uint8_t next = dirs[2 * c + pick];
        if (pick == 0 && count[c] == 2) dirs[2 * c] = dirs[2 * c + 1];
        --count[c];
        d = next;
      }
      double area = 0;
      for (size_t k = 0; k < loop.size(); ++k) {
        const Corner& a = loop[k];
        const Corner& b = loop[(k + 1) % loop.size()];
        area += double(a.first) * b.second - double(b.first) * a.second;
      }
      if (area > best_area) {
        best_area = area;
        best = std::move(loop);
      }
    }
  }
  // Corner coordinates back to grid cells, dropping collinear corners, then Douglas-Peucker.
  std::vector<Vector2> pts;
  for (size_t k = 0; k < best.size(); ++k) {
    const Corner& prev = best[(k + best.size() - 1) % best.size()];
    const Corner& cur = best[k];
    const Corner& next = best[(k + 1) % best.size()];
    const int ax = cur.first - prev.first, ay = cur.second - prev.second;
    const int bx = next.first - cur.first, by = next.second - cur.second;
    if (ax * by - ay * bx == 0) continue;
    pts.emplace_back(cur.first + x0 - 1, cur.second + y0 - 1);
  }
  if (pts.size() <= 4 || tol <= 0) return pts;
  // Split the closed polygon at its first point and the point farthest from it.
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

// Measurements shared by every kind: centroid, outline, extents along the principal axes,
// area and cell count.
void MeasureShape(const GridMap& map, const std::vector<int64_t>& cells, const ObstacleParams& p,
                  Obstacle* o) {
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

std::string Format(const char* fmt, double a, double b) {
  char buf[128];
  std::snprintf(buf, sizeof(buf), fmt, a, b);
  return buf;
}

}  // namespace

void ObstacleParams::Validate() const {
  CAIRN_THROW_UNLESS(min_ramp_slope_rad >= 0 && min_ramp_slope_rad < M_PI / 2,
                     "min_ramp_slope_rad must be in [0, pi/2), got " << min_ramp_slope_rad);
  CAIRN_THROW_UNLESS(min_step_height_m > 0, "min_step_height_m must be positive");
  CAIRN_THROW_UNLESS(min_cells >= 1, "min_cells must be >= 1, got " << min_cells);
  CAIRN_THROW_UNLESS(step_contrast >= 1, "step_contrast must be >= 1, got " << step_contrast);
  CAIRN_THROW_UNLESS(wall_min_height_m > min_step_height_m,
                     "wall_min_height_m must exceed min_step_height_m");
  CAIRN_THROW_UNLESS(min_drop_height_m > 0, "min_drop_height_m must be positive");
  CAIRN_THROW_UNLESS(min_ramp_area_m2 >= 0, "min_ramp_area_m2 must be >= 0");
  CAIRN_THROW_UNLESS(
      small_step_height_m >= 0 && min_small_step_length_m >= 0 && min_small_step_elongation >= 0,
      "small step limits must be >= 0");
  CAIRN_THROW_UNLESS(surface_continuity_m > 0, "surface_continuity_m must be positive");
  CAIRN_THROW_UNLESS(outline_tolerance_cells >= 0, "outline_tolerance_cells must be >= 0");
}

void ComputeFeatureLayers(GridMap* map, const ObstacleParams& params, const CellRect& rect_in) {
  CAIRN_THROW_UNLESS(map != nullptr, "no map");
  params.Validate();
  for (const char* name :
       {layers::kElevation, layers::kSlope, layers::kDitchDepth, kNormalXLayer, kNormalYLayer}) {
    CAIRN_THROW_UNLESS(map->HasLayer(name), "the map has no '" << name << "' layer");
  }
  for (const char* name :
       {kFeatureClassLayer, kFeatureEdgeLayer, kFeatureLowLayer, kFeatureHighLayer}) {
    if (!map->HasLayer(name)) map->AddLayer(name);
  }
  const CellRect rect{std::max(0, rect_in.x0), std::max(0, rect_in.y0),
                      std::min(map->size_x(), rect_in.x1), std::min(map->size_y(), rect_in.y1)};
  if (rect.empty()) return;
  Classify(map, params, rect);
}

common::ObstacleRegistry ExtractObstacles(const GridMap& map_in, const ObstacleParams& params) {
  params.Validate();
  CAIRN_THROW_UNLESS(map_in.HasLayer(layers::kElevation),
                     "the map has no '" << layers::kElevation << "' layer");
  GridMap map = map_in;
  if (!map.HasLayer(layers::kSlope) || !map.HasLayer(layers::kDitchDepth) ||
      !map.HasLayer(kNormalXLayer) || !map.HasLayer(kNormalYLayer)) {
    ComputeGeometricLayers(&map, TraversabilityParams{});
  }
  ComputeFeatureLayers(&map, params, CellRect::All(map));
  return AssembleObstacles(map, params);
}

common::ObstacleRegistry AssembleObstacles(const GridMap& map_ref, const ObstacleParams& params) {
  params.Validate();
  for (const char* name :
       {layers::kElevation, layers::kSlope, layers::kDitchDepth, layers::kDitchWidth,
        kFeatureClassLayer, kFeatureEdgeLayer, kFeatureLowLayer, kFeatureHighLayer}) {
    CAIRN_THROW_UNLESS(map_ref.HasLayer(name), "the map has no '" << name << "' layer");
  }
  const GridMap* map = &map_ref;
  Cells cells;
  cells.sx = map->size_x();
  cells.sy = map->size_y();
  cells.cls = map->at(kFeatureClassLayer).data();
  cells.edge = map->at(kFeatureEdgeLayer).data();
  cells.low = map->at(kFeatureLowLayer).data();
  cells.high = map->at(kFeatureHighLayer).data();
  const int sx = map->size_x();
  const double res = map->resolution_m();
  const float* h = map->at(layers::kElevation).data();
  const float* slope = map->at(layers::kSlope).data();
  const float* ddepth = map->at(layers::kDitchDepth).data();
  const float* dwidth = map->at(layers::kDitchWidth).data();
  const size_t num_cells = static_cast<size_t>(cells.sx) * cells.sy;

  std::vector<int32_t> label(num_cells, 0);
  int32_t next_label = 1;
  struct Found {
    ObstacleKind kind;
    std::vector<int64_t> cells;
  };
  std::vector<Found> found;

  // Grows a component by the unlabelled cells of `classes` within two cells of it.
  auto absorb = [&](std::vector<int64_t>* comp, std::initializer_list<uint8_t> classes) {
    const int32_t id = label[comp->front()];
    size_t ring_begin = 0;
    for (int ring = 0; ring < 2; ++ring) {
      const size_t ring_end = comp->size();
      for (size_t k = ring_begin; k < ring_end; ++k) {
        const int64_t i = (*comp)[k];
        const int cx = static_cast<int>(i % sx), cy = static_cast<int>(i / sx);
        for (const auto& d : kNeighbours8) {
          if (!cells.Inside(cx + d[0], cy + d[1])) continue;
          const int64_t j = cells.Index(cx + d[0], cy + d[1]);
          if (label[j] != 0) continue;
          const uint8_t k2 = cells.Class(j);
          if (std::find(classes.begin(), classes.end(), k2) == classes.end()) continue;
          label[j] = id;
          comp->push_back(j);
        }
      }
      ring_begin = ring_end;
    }
  };
  // Ditches first: step, drop and ramp cells near a ditch are its rims and walls (a wall face
  // seen at an angle looks like a short ramp). Then walls and objects: low steps at their feet
  // are partly seen faces.
  for (auto& comp : Components(cells, {kDitch}, &label, &next_label)) {
    absorb(&comp, {kStep, kDrop, kRamp});
    found.push_back({ObstacleKind::kDitch, std::move(comp)});
  }
  for (auto& comp : Components(cells, {kWall}, &label, &next_label)) {
    absorb(&comp, {kStep, kDrop});
    found.push_back({ObstacleKind::kWallOrObject, std::move(comp)});
  }
  for (auto& comp : Components(cells, {kStep, kDrop}, &label, &next_label)) {
    found.push_back({ObstacleKind::kStepUp, std::move(comp)});
  }
  for (auto& comp : Components(cells, {kRamp}, &label, &next_label)) {
    found.push_back({ObstacleKind::kRamp, std::move(comp)});
  }

  // Surfaces (for the direction of steps), labelled on first use.
  std::vector<int32_t> surface;
  std::vector<int64_t> surface_size;
  std::vector<int32_t> ring_stamp(num_cells, 0);

  common::ObstacleRegistry registry;
  for (auto& f : found) {
    if (static_cast<int>(f.cells.size()) < params.min_cells) continue;
    if (f.kind == ObstacleKind::kRamp &&
        f.cells.size() * res * res + 1e-9 < params.min_ramp_area_m2) {
      continue;
    }
    Obstacle o;
    o.kind = f.kind;
    MeasureShape(*map, f.cells, params, &o);
    double max_slope = 0;
    for (int64_t i : f.cells) {
      if (!std::isnan(slope[i])) max_slope = std::max(max_slope, double(slope[i]));
    }
    o.slope_rad = max_slope;
    o.depth_m = 0.0;
    switch (f.kind) {
      case ObstacleKind::kDitch: {
        std::vector<double> widths;
        double depth_seen = kNaN;
        for (int64_t i : f.cells) {
          if (std::isnan(ddepth[i])) continue;  // a rim
          widths.push_back(dwidth[i]);
          if (!std::isnan(h[i])) {
            depth_seen =
                std::isnan(depth_seen) ? ddepth[i] : std::max(depth_seen, double(ddepth[i]));
          }
        }
        o.width_m = Median(widths);
        o.depth_m = depth_seen;
        o.height_m = std::isnan(depth_seen) ? 0.0 : depth_seen;
        break;
      }
      case ObstacleKind::kWallOrObject: {
        double tallest = 0;
        for (int64_t i : f.cells) tallest = std::max(tallest, double(cells.edge[i]));
        o.height_m = tallest;
        break;
      }
      case ObstacleKind::kStepUp: {
        std::vector<double> heights;
        bool all_drops = true;
        for (int64_t i : f.cells) {
          heights.push_back(cells.edge[i]);
          all_drops &= cells.Class(i) == kDrop;
        }
        o.height_m = Median(heights);
        if (all_drops) {
          o.kind = ObstacleKind::kStepDown;
          break;
        }
        // The step separates two surfaces: its height is the difference of their levels
        // next to it (a vertical face cut by a cell leaves intermediate edges that a median of
        // the edges would average in), and it goes up from the larger surface (the ground most
        // of the site is on) onto the smaller one, or down from it.
        if (surface.empty())
          LabelSurfaces(cells, h, params.surface_continuity_m, &surface, &surface_size);
        const int32_t own = label[f.cells.front()];
        std::map<int32_t, std::vector<double>> beside;  // surface -> heights next to the step
        std::vector<int64_t> ring;
        for (int64_t i : f.cells) {
          const int cx = static_cast<int>(i % sx), cy = static_cast<int>(i / sx);
          for (int dy = -2; dy <= 2; ++dy) {
            for (int dx = -2; dx <= 2; ++dx) {
              if (!cells.Inside(cx + dx, cy + dy)) continue;
              const int64_t j = cells.Index(cx + dx, cy + dy);
              if (label[j] == own || surface[j] < 0) continue;
              ring.push_back(j);
            }
          }
        }
        // Each ring cell once (stamped with this component's label).
        for (int64_t j : ring) {
          if (ring_stamp[j] == own) continue;
          ring_stamp[j] = own;
          beside[surface[j]].push_back(h[j]);
        }
        std::vector<std::pair<size_t, int32_t>> by_count;
        for (const auto& [id, hs] : beside) by_count.push_back({hs.size(), id});
        std::sort(by_count.rbegin(), by_count.rend());
        if (by_count.size() >= 2 && by_count[1].first >= 2) {
          const int32_t a = by_count[0].second, b = by_count[1].second;
          const double ha = Median(beside[a]), hb = Median(beside[b]);
          const int32_t lo = ha <= hb ? a : b, hi = ha <= hb ? b : a;
          o.height_m = std::fabs(ha - hb);
          o.kind = surface_size[lo] >= surface_size[hi] ? ObstacleKind::kStepUp
                                                        : ObstacleKind::kStepDown;
          break;
        }
        // One surface on both sides (a small step within continuity): the edges tell.
        int64_t low_side = 0, high_side = 0;
        for (int64_t i : f.cells) {
          if (surface[i] < 0) continue;
          const int64_t size = surface_size[surface[i]];
          if (double(h[i]) <= 0.5 * (double(cells.low[i]) + cells.high[i])) {
            low_side = std::max(low_side, size);
          } else {
            high_side = std::max(high_side, size);
          }
        }
        o.kind = low_side >= high_side ? ObstacleKind::kStepUp : ObstacleKind::kStepDown;
        break;
      }
      case ObstacleKind::kRamp: {
        // The sustained slope: the 75th percentile over the interior (cells whose 4-neighbours
        // are all ramp), which leaves out the tilted-normal cells at the foot and the top and
        // does not average a steep section away with a gentle one.
        std::vector<double> interior_slopes, all_slopes;
        double lo = 1e300, hi = -1e300;
        const int32_t own = label[f.cells.front()];
        for (int64_t i : f.cells) {
          const int cx = static_cast<int>(i % sx), cy = static_cast<int>(i / sx);
          bool interior = true;
          for (const auto& d : kNeighbours4) {
            interior &= cells.Inside(cx + d[0], cy + d[1]) &&
                        label[cells.Index(cx + d[0], cy + d[1])] == own;
          }
          all_slopes.push_back(slope[i]);
          if (interior) interior_slopes.push_back(slope[i]);
          lo = std::min(lo, double(h[i]));
          hi = std::max(hi, double(h[i]));
        }
        // ... and at least the slope of the plane fitted to the ramp's heights, which normals
        // at the edge of what was seen cannot flatten.
        o.slope_rad =
            std::max(Percentile(interior_slopes.empty() ? all_slopes : interior_slopes, 0.75),
                     PlaneSlope(*map, f.cells));
        o.height_m = hi - lo;
        break;
      }
      case ObstacleKind::kStepDown:
        break;
    }
    if ((o.kind == ObstacleKind::kStepUp || o.kind == ObstacleKind::kStepDown) &&
        o.height_m < params.small_step_height_m &&
        (o.length_m < params.min_small_step_length_m ||
         o.length_m < params.min_small_step_elongation * o.width_m)) {
      continue;  // a noise patch
    }
    registry.obstacles.push_back(std::move(o));
  }
  // Numbered by centroid (y, then x): the same map always gives the same ids.
  std::stable_sort(registry.obstacles.begin(), registry.obstacles.end(),
                   [](const Obstacle& a, const Obstacle& b) {
                     if (a.centroid_m.y() != b.centroid_m.y())
                       return a.centroid_m.y() < b.centroid_m.y();
                     return a.centroid_m.x() < b.centroid_m.x();
                   });
  int32_t id = 1;
  for (auto& o : registry.obstacles) o.id = id++;
  return registry;
}

namespace {
common::ObstacleVerdict JudgeWithHash(const Obstacle& o, const common::RobotProfile& profile,
                                      const std::string& hash);
}  // namespace

common::ObstacleVerdict JudgeObstacle(const Obstacle& o, const common::RobotProfile& profile) {
  return JudgeWithHash(o, profile, profile.ContentHash());
}

namespace {
// The verdict with the profile's content hash computed once by the caller.
common::ObstacleVerdict JudgeWithHash(const Obstacle& o, const common::RobotProfile& profile,
                                      const std::string& hash) {
  common::ObstacleVerdict v;
  v.profile = profile.name;
  v.profile_hash = hash;
  v.crossable = true;
  constexpr double kTol = 1e-6;
  switch (o.kind) {
    case ObstacleKind::kRamp: {
      const double limit = std::min(profile.max_slope_up_rad, profile.max_slope_down_rad);
      if (!(o.slope_rad < limit)) {
        v.crossable = false;
        v.reason = Format("slope %.1f deg >= %.1f deg", o.slope_rad * kRadToDeg, limit * kRadToDeg);
      }
      break;
    }
    case ObstacleKind::kStepUp:
      if (!(o.height_m <= profile.max_step_up_m + kTol)) {
        v.crossable = false;
        v.reason = Format("step up %.3f m > %.3f m", o.height_m, profile.max_step_up_m);
      }
      break;
    case ObstacleKind::kStepDown:
      if (!(o.height_m <= profile.max_step_down_m + kTol)) {
        v.crossable = false;
        v.reason = Format("step down %.3f m > %.3f m", o.height_m, profile.max_step_down_m);
      }
      break;
    case ObstacleKind::kDitch: {
      const bool bridged = o.width_m <= profile.max_ditch_width_m + kTol;
      const bool drivable =
          std::isfinite(o.depth_m) &&
          o.depth_m <= std::min(profile.max_step_down_m, profile.max_step_up_m) + kTol;
      if (!bridged && !drivable) {
        v.crossable = false;
        v.reason = std::isfinite(o.depth_m) ? Format("ditch %.2f m wide > %.2f m and too deep",
                                                     o.width_m, profile.max_ditch_width_m)
                                            : Format("ditch %.2f m wide > %.2f m, bottom unseen",
                                                     o.width_m, profile.max_ditch_width_m);
      }
      break;
    }
    case ObstacleKind::kWallOrObject:
      if (!(o.height_m <= profile.max_step_up_m + kTol)) {
        v.crossable = false;
        v.reason = Format("wall or object %.2f m high > %.3f m", o.height_m, profile.max_step_up_m);
      }
      break;
  }
  return v;
}
}  // namespace

void LabelObstacles(common::ObstacleRegistry* registry,
                    const std::vector<common::RobotProfile>& profiles) {
  CAIRN_THROW_UNLESS(registry != nullptr, "no registry");
  std::vector<std::string> hashes;
  for (const auto& profile : profiles) hashes.push_back(profile.ContentHash());
  for (auto& o : registry->obstacles) {
    for (size_t k = 0; k < profiles.size(); ++k) {
      const common::RobotProfile& profile = profiles[k];
      auto& vs = o.verdicts;
      vs.erase(std::remove_if(
                   vs.begin(), vs.end(),
                   [&](const common::ObstacleVerdict& v) { return v.profile == profile.name; }),
               vs.end());
      vs.push_back(JudgeWithHash(o, profile, hashes[k]));
    }
  }
}

ObstacleParams LoadObstacleParams(common::YamlMap& m) {
  ObstacleParams p;
  m.Get("min_ramp_slope_rad", &p.min_ramp_slope_rad);
  m.Get("min_step_height_m", &p.min_step_height_m);
  m.Get("min_cells", &p.min_cells);
  m.Get("step_contrast", &p.step_contrast);
  m.Get("wall_min_height_m", &p.wall_min_height_m);
  m.Get("min_drop_height_m", &p.min_drop_height_m);
  m.Get("min_ramp_area_m2", &p.min_ramp_area_m2);
  m.Get("small_step_height_m", &p.small_step_height_m);
  m.Get("min_small_step_length_m", &p.min_small_step_length_m);
  m.Get("min_small_step_elongation", &p.min_small_step_elongation);
  m.Get("surface_continuity_m", &p.surface_continuity_m);
  m.Get("outline_tolerance_cells", &p.outline_tolerance_cells);
  m.Finish();
  return p;
}

}  // namespace cairn::mapping
