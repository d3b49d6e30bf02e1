#include "services/mapping/feature_classes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "common/check.h"
#include "common/layers.h"
#include "services/mapping/obstacles.h"

/// ComputeFeatureLayers (declared in obstacles.h): the classification of every cell into the
/// feature layers the obstacle registry is assembled from.

namespace cairn::mapping {
namespace {

using common::GridMap;
using namespace internal;  // the CellClass values

constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

constexpr std::array<std::array<int, 2>, 4> kNeighbours4{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};
constexpr std::array<std::array<int, 2>, 8> kNeighbours8{
    {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {1, -1}, {-1, 1}, {-1, -1}}};

// Rise per cell along direction d of the plane with the cell's normal (0 where unknown).
double Rise(const float* nx, const float* ny, int x, int y, int sx, const std::array<int, 2>& d,
            double res) {
  const int64_t i = x + static_cast<int64_t>(y) * sx;
  const double a = nx[i], b = ny[i];
  if (std::isnan(a) || std::isnan(b)) return 0.0;
  const double nz = std::sqrt(std::max(1e-6, 1.0 - a * a - b * b));
  return res * std::fabs(a * d[0] + b * d[1]) / nz;
}

// The classification window: the written rectangle grown by one cell (the ramp rule looks at
// the classes of the 8-neighbours), with each cell's class and its largest discontinuity.
struct Window {
  CellRect w;
  int ww{0};
  std::vector<uint8_t> cls;
  std::vector<float> edge, low, high;

  Window(const CellRect& rect, int sx, int sy)
      : w{std::max(0, rect.x0 - 1), std::max(0, rect.y0 - 1), std::min(sx, rect.x1 + 1),
          std::min(sy, rect.y1 + 1)},
        ww(w.x1 - w.x0) {
    const size_t n = static_cast<size_t>(ww) * (w.y1 - w.y0);
    cls.assign(n, kNone);
    edge.assign(n, kNaNf);
    low.assign(n, kNaNf);
    high.assign(n, kNaNf);
  }
  size_t Index(int x, int y) const { return (x - w.x0) + static_cast<size_t>(y - w.y0) * ww; }
  bool Inside(int x, int y) const { return x >= w.x0 && y >= w.y0 && x < w.x1 && y < w.y1; }
  // Keeps the largest discontinuity at a cell.
  void Note(int x, int y, float height, float lo, float hi) {
    if (!Inside(x, y)) return;
    const size_t i = Index(x, y);
    if (!(height <= edge[i])) {
      edge[i] = height;
      low[i] = lo;
      high[i] = hi;
    }
  }
};

// The layers the classification reads.
struct FeatureInputs {
  const float* h;
  const float* slope;
  const float* ddepth;
  const float* nx;
  const float* ny;
  const float* bound;  // or nullptr
  const float* var;    // elevation variance, or nullptr
  int sx;
  int sy;
  double res;
  explicit FeatureInputs(const GridMap& map)
      : h(map.at(layers::kElevation).data()),
        slope(map.at(layers::kSlope).data()),
        ddepth(map.at(layers::kDitchDepth).data()),
        nx(map.at(kNormalXLayer).data()),
        ny(map.at(kNormalYLayer).data()),
        bound(map.HasLayer(layers::kGroundBound) ? map.at(layers::kGroundBound).data() : nullptr),
        var(map.HasLayer(layers::kElevationVariance) ? map.at(layers::kElevationVariance).data()
                                                     : nullptr),
        sx(map.size_x()),
        sy(map.size_y()),
        res(map.resolution_m()) {}
  float H(int x, int y) const { return h[x + static_cast<int64_t>(y) * sx]; }
  bool Inside(int x, int y) const { return x >= 0 && y >= 0 && x < sx && y < sy; }
  bool Known(int x, int y) const { return Inside(x, y) && !std::isnan(H(x, y)); }
};

// The standard deviation of the height difference between two cells as their heights stand for
// their centres: each cell's elevation variance (what the fused returns support), plus the
// spread of a sloped cell's height across it (the returns of a lidar ring land anywhere in the
// cell: res^2 / 12 * tan^2(slope) for a point uniform in the cell along the fall line). 0 when
// the map has no variance layer.
double DifferenceSigma(const FeatureInputs& in, int x, int y, int nx, int ny) {
  if (in.var == nullptr) return 0.0;
  const int64_t a = x + static_cast<int64_t>(y) * in.sx;
  const int64_t b = nx + static_cast<int64_t>(ny) * in.sx;
  // tan^2 of the slope from the cell's unit normal: (nx^2 + ny^2) / nz^2.
  auto tan2 = [&](int64_t i) {
    const double h2 = double(in.nx[i]) * in.nx[i] + double(in.ny[i]) * in.ny[i];
    return std::isnan(h2) ? 0.0 : h2 / std::max(1e-6, 1.0 - h2);
  };
  const double va = std::isfinite(in.var[a]) ? in.var[a] : 0.0;
  const double vb = std::isfinite(in.var[b]) ? in.var[b] : 0.0;
  return std::sqrt(va + vb + in.res * in.res / 12.0 * (tan2(a) + tan2(b)));
}

// The difference from (x, y) to the cell `span` cells along d, when it is a step: it stands
// out from the same-direction differences just before and after it (a ramp rises evenly; a
// spike rises and falls). A two-cell span (a vertical face left an intermediate height in the
// cell it cuts) is compared with twice the outer differences, as a ramp would rise that much
// over two cells. Noted at the cells it joins.
void TestSpan(const FeatureInputs& in, const ObstacleParams& p, int x, int y,
              const std::array<int, 2>& d, int span, Window* win) {
  auto same_sign_abs = [](double v, double ref) {
    return (v > 0) == (ref > 0) ? std::fabs(v) : 0.0;
  };
  const int nx = x + span * d[0], ny = y + span * d[1];
  if (!in.Known(nx, ny)) return;
  const int mx = x + d[0], my = y + d[1];  // the intermediate cell of a two-cell span
  if (!win->Inside(x, y) && !win->Inside(nx, ny) && !(span == 2 && win->Inside(mx, my))) return;
  const float hc = in.H(x, y), hn = in.H(nx, ny);
  const double delta = double(hn) - hc;
  if (std::fabs(delta) < p.min_step_height_m) return;
  if (span == 2) {
    if (!in.Known(mx, my)) return;
    const double hm = in.H(mx, my);
    if ((hm - hc) * delta < 0 || (hn - hm) * delta < 0) return;  // not monotonic
  }
  double before = 0, after = 0;
  const bool before_known = in.Known(x - d[0], y - d[1]);
  const bool after_known = in.Known(nx + d[0], ny + d[1]);
  if (before_known) before = same_sign_abs(double(hc) - in.H(x - d[0], y - d[1]), delta);
  if (after_known) after = same_sign_abs(double(in.H(nx + d[0], ny + d[1])) - hn, delta);
  // What an incline rises along this line per cell, from the normals of both cells (an edge
  // tilts the normals around it, so the lower of the two is taken).
  const double along = std::min(Rise(in.nx, in.ny, x, y, in.sx, d, in.res),
                                Rise(in.nx, in.ny, nx, ny, in.sx, d, in.res));
  if (std::fabs(delta) <= p.step_contrast * span * std::max({before, after, along})) return;
  // What the difference exceeds the incline's own rise by must stand out of the noise of the
  // two heights. The rise: the normals' (tilted up by an object's own edge, so no more than the
  // larger of the differences before and after where either is known; with neither, two cells
  // seen alone on a hillside, the normals' rise is all there is to go by).
  // A difference of a wall's height is no noise whatever the variance says (a cell that straddles
  // a wall's foot or top mixes both levels and its variance is of the wall's height).
  const double rise =
      before_known || after_known ? std::min(along, std::max(before, after)) : along;
  if (std::fabs(delta) < p.wall_min_height_m &&
      std::fabs(delta) - span * rise < p.step_noise_sigmas * DifferenceSigma(in, x, y, nx, ny)) {
    return;
  }
  // Small steps must hold over two cells on each side (noise rarely does): the mean of the
  // pair beyond minus the mean of the pair before.
  if (std::fabs(delta) < p.wall_min_height_m && in.Known(x - d[0], y - d[1]) &&
      in.Known(nx + d[0], ny + d[1])) {
    const double wide = 0.5 * (double(hn) + in.H(nx + d[0], ny + d[1])) -
                        0.5 * (double(hc) + in.H(x - d[0], y - d[1]));
    if (std::fabs(wide) < 0.75 * p.min_step_height_m) return;
  }
  const float height = static_cast<float>(std::fabs(delta));
  const float lo = std::min(hc, hn), hi = std::max(hc, hn);
  win->Note(x, y, height, lo, hi);
  win->Note(nx, ny, height, lo, hi);
  if (span == 2) win->Note(mx, my, height, lo, hi);
}

// Discontinuities along x and y over one or two cells; spans start up to two cells before
// the window.
void FindEdges(const FeatureInputs& in, const ObstacleParams& p, Window* win) {
  for (int y = std::max(0, win->w.y0 - 2); y < win->w.y1; ++y) {
    for (int x = std::max(0, win->w.x0 - 2); x < win->w.x1; ++x) {
      if (std::isnan(in.H(x, y))) continue;
      for (const auto& d : {std::array<int, 2>{1, 0}, std::array<int, 2>{0, 1}}) {
        for (int span = 1; span <= 2; ++span) TestSpan(in, p, x, y, d, span, win);
      }
    }
  }
}

// The class of every window cell but ramps: ditch, wall or step at a discontinuity, or a drop
// into a gap the sensor looked into (ditches own their rims).
void ClassifyCells(const FeatureInputs& in, const ObstacleParams& p, Window* win) {
  for (int y = win->w.y0; y < win->w.y1; ++y) {
    for (int x = win->w.x0; x < win->w.x1; ++x) {
      const size_t i = win->Index(x, y);
      const int64_t m = x + static_cast<int64_t>(y) * in.sx;
      if (!std::isnan(in.ddepth[m])) {
        win->cls[i] = kDitch;
      } else if (!std::isnan(win->edge[i])) {
        win->cls[i] = win->edge[i] >= p.wall_min_height_m ? kWall : kStep;
      } else if (in.bound != nullptr && !std::isnan(in.h[m])) {
        for (const auto& d : kNeighbours4) {
          if (!in.Inside(x + d[0], y + d[1])) continue;
          const int64_t j = (x + d[0]) + static_cast<int64_t>(y + d[1]) * in.sx;
          if (!std::isnan(in.h[j]) || !std::isfinite(in.bound[j]) || !std::isnan(in.ddepth[j])) {
            continue;
          }
          const double drop = double(in.h[m]) - in.bound[j];
          if (drop >= p.min_drop_height_m && !(drop <= win->edge[i])) {
            win->cls[i] = kDrop;
            win->edge[i] = static_cast<float>(drop);
            win->low[i] = in.bound[j];
            win->high[i] = in.h[m];
          }
        }
      }
    }
  }
}

// Writes the classes of `rect` into the feature layers; ramps: inclined known cells with no
// edge next to them (an edge tilts the normals of the cells around it).
void WriteClasses(const FeatureInputs& in, const ObstacleParams& p, const Window& win,
                  const CellRect& rect, GridMap* map) {
  float* out_cls = map->at(kFeatureClassLayer).data();
  float* out_edge = map->at(kFeatureEdgeLayer).data();
  float* out_low = map->at(kFeatureLowLayer).data();
  float* out_high = map->at(kFeatureHighLayer).data();
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const size_t i = win.Index(x, y);
      const int64_t m = x + static_cast<int64_t>(y) * in.sx;
      uint8_t k = win.cls[i];
      if (k == kNone && !std::isnan(in.h[m]) && in.slope[m] >= p.min_ramp_slope_rad) {
        bool near_edge = false;
        for (const auto& d : kNeighbours8) {
          if (!win.Inside(x + d[0], y + d[1])) continue;
          const uint8_t nk = win.cls[win.Index(x + d[0], y + d[1])];
          near_edge |= nk == kDitch || nk == kWall || nk == kStep || nk == kDrop;
        }
        if (!near_edge) k = kRamp;
      }
      out_cls[m] = k;
      out_edge[m] = win.edge[i];
      out_low[m] = win.low[i];
      out_high[m] = win.high[i];
    }
  }
}

// Classification of the cells of `rect` into the feature layers.
void Classify(GridMap* map, const ObstacleParams& p, const CellRect& rect) {
  const FeatureInputs in(*map);
  Window win(rect, in.sx, in.sy);
  FindEdges(in, p, &win);
  ClassifyCells(in, p, &win);
  WriteClasses(in, p, win, rect, map);
}

}  // namespace

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

}  // namespace cairn::mapping
