#include "services/mapping/traversability.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "common/check.h"
#include "common/layers.h"
#include "common/yaml_reader.h"
#include <Eigen/Eigenvalues>

namespace cairn::mapping {
namespace {

using common::GridMap;
using common::Layer;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// How far past a known cell the cost layer looks through unknown cells for the lowest ray bound:
// the cell on an edge is often mixed (part rim, part gap) and published unknown, its bound
// barely below the rim, while the rays show the drop a cell further.
constexpr double kUnseenDropReachM = 0.4;
int UnseenDropReachCells(double resolution_m) {
  return std::max(1, static_cast<int>(std::ceil(kUnseenDropReachM / resolution_m - 1e-9)));
}

// The four line directions of the ditch analysis: x, y and both diagonals.
constexpr std::array<std::array<int, 2>, 4> kLineDirections{{{1, 0}, {0, 1}, {1, 1}, {1, -1}}};
// 4-neighbourhood: +x, -x, +y, -y (the seed's RIGHT, LEFT, UP, DOWN).
constexpr std::array<std::array<int, 2>, 4> kNeighbours{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};

int SearchCells(const TraversabilityParams& params, double resolution_m) {
  return std::max(1, static_cast<int>(std::ceil(params.max_ditch_search_m / resolution_m - 1e-9)));
}

CellRect Clip(const CellRect& r, int sx, int sy) {
  return {std::max(0, r.x0), std::max(0, r.y0), std::min(sx, r.x1), std::min(sy, r.y1)};
}

CellRect Grow(const CellRect& r, int margin) {
  return {r.x0 - margin, r.y0 - margin, r.x1 + margin, r.y1 + margin};
}

// Read-only view of the layers the ditch analysis needs.
struct TerrainView {
  const float* h;      // elevation
  const float* bound;  // ground bound, or nullptr
  int sx;
  int sy;
  bool Inside(int x, int y) const { return x >= 0 && y >= 0 && x < sx && y < sy; }
  float H(int x, int y) const { return h[x + static_cast<int64_t>(y) * sx]; }
  float B(int x, int y) const { return bound ? bound[x + static_cast<int64_t>(y) * sx] : kNaN; }
};

// Result of looking for the rims of a gap along one line through a cell.
struct GapLine {
  bool found{false};
  int k_pos{0};         // steps to the rim along +(dx, dy)
  int k_neg{0};         // steps to the rim along -(dx, dy)
  double rim_m{0.0};    // the lower of the two rims
  double width_m{0.0};  // distance between the rims minus one cell
};

// Walks from (x, y) along ±(dx, dy) through the gap: unknown cells and known cells lower than
// `rim_threshold`. The first known cell at or above the threshold on each side is a rim. An
// unknown cell whose ground bound is at or above the threshold ends the walk without a rim:
// the ground there may be at rim level, so the gap is not proven to continue. A rim must have
// two cells of known ground beyond it within `flatness_m` of its height: the top of a wall
// between two floors is no rim (else every corridor floor would lie in a "ditch").
GapLine FindRims(const TerrainView& v, int x, int y, int dx, int dy, double rim_threshold,
                 double flatness_m, int max_cells, double step_m) {
  GapLine line;
  int k_side[2] = {0, 0};
  double rim_side[2] = {0.0, 0.0};
  for (int side = 0; side < 2; ++side) {
    const int sdx = side == 0 ? dx : -dx, sdy = side == 0 ? dy : -dy;
    for (int k = 1; k <= max_cells; ++k) {
      const int cx = x + k * sdx, cy = y + k * sdy;
      if (!v.Inside(cx, cy)) return line;
      const float hc = v.H(cx, cy);
      if (std::isnan(hc)) {
        if (v.B(cx, cy) >= rim_threshold) return line;
        continue;
      }
      if (hc >= rim_threshold) {
        // A rim is ground that goes on beyond it at about its height for two more cells; a
        // wall or an object (ground again, or nothing known, behind it) bounds no ditch. Nor
        // does a cell some ray crossed within half the depth of the gap's own bound: that
        // cell's height is a face's returns, not ground at the rim (the floor cells in front of
        // a step, raised by returns from its face, with an unhit cell between them). A rim cell
        // that holds the ditch's edge is crossed lower than its height, but well above the gap.
        if (v.B(cx, cy) < rim_threshold - 0.5 * flatness_m) return line;
        for (int e = 1; e <= 2; ++e) {
          const int ox = cx + e * sdx, oy = cy + e * sdy;
          if (!v.Inside(ox, oy)) return line;
          const float beyond = v.H(ox, oy);
          if (std::isnan(beyond) || std::fabs(double(beyond) - hc) >= flatness_m) return line;
        }
        k_side[side] = k;
        rim_side[side] = hc;
        break;
      }
    }
    if (k_side[side] == 0) return line;
  }
  line.found = true;
  line.k_pos = k_side[0];
  line.k_neg = k_side[1];
  line.rim_m = std::min(rim_side[0], rim_side[1]);
  line.width_m = (k_side[0] + k_side[1] - 1) * step_m;
  return line;
}

// Ditch test of an unknown cell the sensor looked into: its terrain lies below its bound u, so
// it is part of a ditch when both rims along some line stand at least min_depth above u. Keeps
// the depth (a lower bound), the narrowest width, the rim reference and the qualifying lines.
struct DitchCell {
  bool ditch{false};
  double depth_m{0.0};
  double width_m{std::numeric_limits<double>::infinity()};
  double rim_m{0.0};
  std::array<GapLine, 4> lines{};  // per kLineDirections entry; found = qualifies
};

DitchCell TestUnseenCell(const TerrainView& v, int x, int y, const TraversabilityParams& p,
                         int max_cells, double res) {
  DitchCell cell;
  const float u = v.B(x, y);
  if (!std::isnan(v.H(x, y)) || !std::isfinite(u)) return cell;
  for (size_t k = 0; k < kLineDirections.size(); ++k) {
    const auto& d = kLineDirections[k];
    const bool diagonal = d[0] != 0 && d[1] != 0;
    const double step_m = diagonal ? res * M_SQRT2 : res;
    const int cells = diagonal ? std::max(1, static_cast<int>(max_cells / M_SQRT2)) : max_cells;
    const GapLine line =
        FindRims(v, x, y, d[0], d[1], u + p.min_ditch_depth_m, p.min_ditch_depth_m, cells, step_m);
    if (!line.found) continue;
    const double depth = line.rim_m - u;
    if (depth + p.height_tolerance_m < p.min_ditch_depth_m) continue;
    cell.lines[k] = line;
    if (!cell.ditch || line.width_m < cell.width_m) {
      cell.width_m = line.width_m;
      cell.rim_m = line.rim_m;
    }
    cell.depth_m = std::max(cell.depth_m, depth);
    cell.ditch = true;
  }
  return cell;
}

// Surface normal and roughness by PCA over the cells within the normal radius (grid_map's
// NormalVectorsFilter "area" method): fewer than 3 points or a degenerate spread gives the
// vertical normal, and cells on one line the slope along it.
struct NormalResult {
  Eigen::Vector3d normal{0.0, 0.0, 1.0};
  double roughness_m{0.0};
};

NormalResult FitNormal(const float* h, int sx, int sy, int x, int y,
                       const std::vector<std::array<int, 2>>& offsets, double res) {
  NormalResult r;
  const double h0 = h[x + static_cast<int64_t>(y) * sx];
  double n = 0, sxx = 0, syy = 0, szz = 0, sxy = 0, sxz = 0, syz = 0, mx = 0, my = 0, mz = 0;
  for (const auto& o : offsets) {
    const int cx = x + o[0], cy = y + o[1];
    if (cx < 0 || cy < 0 || cx >= sx || cy >= sy) continue;
    const float hc = h[cx + static_cast<int64_t>(cy) * sx];
    if (std::isnan(hc)) continue;
    const double px = o[0] * res, py = o[1] * res, pz = hc - h0;
    n += 1;
    mx += px;
    my += py;
    mz += pz;
    sxx += px * px;
    syy += py * py;
    szz += pz * pz;
    sxy += px * py;
    sxz += px * pz;
    syz += py * pz;
  }
  if (n < 3) return r;
  mx /= n;
  my /= n;
  mz /= n;
  Eigen::Matrix3d c;
  c(0, 0) = sxx / n - mx * mx;
  c(1, 1) = syy / n - my * my;
  c(2, 2) = szz / n - mz * mz;
  c(0, 1) = c(1, 0) = sxy / n - mx * my;
  c(0, 2) = c(2, 0) = sxz / n - mx * mz;
  c(1, 2) = c(2, 1) = syz / n - my * mz;
  // Cells on one line of the grid (a lidar ring seen from afar crosses a ramp as a one-cell-wide
  // strip between unknown cells) fix the tilt along the line only. The 3-D fit would pass the
  // plane through the line vertically, and read a strip across a 5 degree ramp as a 90 degree
  // wall. Such a fit keeps the slope along the line (a lower bound of the true slope) instead.
  const double cxx = c(0, 0), cyy = c(1, 1), cxy = c(0, 1);
  const double half_trace = 0.5 * (cxx + cyy);
  const double spread = std::sqrt(std::max(0.0, 0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy));
  const double minor_xy = half_trace - spread, major_xy = half_trace + spread;
  const double line_spread = 0.05 * res;  // m, across the line
  if (major_xy > 0 && minor_xy < line_spread * line_spread) {
    // Direction of the line: the major axis of the cells' horizontal spread.
    const double angle = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
    const double ux = std::cos(angle), uy = std::sin(angle);
    const double var_s = ux * ux * cxx + 2 * ux * uy * cxy + uy * uy * cyy;
    const double cov_sz = ux * c(0, 2) + uy * c(1, 2);
    if (!(var_s > 0)) return r;
    const double gradient = cov_sz / var_s;  // dz per m along the line
    const Eigen::Vector3d normal(-gradient * ux, -gradient * uy, 1.0);
    if (!normal.allFinite()) return r;
    r.normal = normal.normalized();
    r.roughness_m = std::sqrt(std::max(0.0, c(2, 2) - cov_sz * gradient));
    return r;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(c);
  const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
  // Collinear cells span no plane: keep the vertical normal.
  if (!(ev(1) > 1e-9 * std::max(ev(2), 1e-30))) return r;
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.z() < 0) normal = -normal;
  if (!normal.allFinite() || normal.norm() < 0.5) return r;
  r.normal = normal.normalized();
  r.roughness_m = std::sqrt(std::max(0.0, ev(0)));
  return r;
}

Layer& EnsureLayer(GridMap* map, const char* name) {
  if (!map->HasLayer(name)) return map->AddLayer(name);
  return map->at(name);
}

}  // namespace

void TraversabilityParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(normal_radius_m) && normal_radius_m > 0,
                     "normal_radius_m must be positive, got " << normal_radius_m);
  CAIRN_THROW_UNLESS(std::isfinite(blind_zone_half_size_m) && blind_zone_half_size_m >= 0,
                     "blind_zone_half_size_m must be >= 0, got " << blind_zone_half_size_m);
  CAIRN_THROW_UNLESS(graded_cost_max > 0 && graded_cost_max < 100,
                     "graded_cost_max must be in (0, 100), got " << graded_cost_max);
  CAIRN_THROW_UNLESS(free_fraction >= 0 && free_fraction < 1,
                     "free_fraction must be in [0, 1), got " << free_fraction);
  CAIRN_THROW_UNLESS(std::isfinite(min_ditch_depth_m) && min_ditch_depth_m > 0,
                     "min_ditch_depth_m must be positive, got " << min_ditch_depth_m);
  CAIRN_THROW_UNLESS(std::isfinite(max_ditch_search_m) && max_ditch_search_m > 0,
                     "max_ditch_search_m must be positive, got " << max_ditch_search_m);
  CAIRN_THROW_UNLESS(std::isfinite(unseen_drop_m) && unseen_drop_m >= 0,
                     "unseen_drop_m must be >= 0, got " << unseen_drop_m);
  CAIRN_THROW_UNLESS(height_tolerance_m >= 0 && height_tolerance_m < 0.01,
                     "height_tolerance_m must be in [0, 0.01), got " << height_tolerance_m);
  CAIRN_THROW_UNLESS(min_step_edge_cells == 1 || min_step_edge_cells == 2,
                     "min_step_edge_cells must be 1 or 2, got " << min_step_edge_cells);
}

int DependencyRadiusCells(const TraversabilityParams& params, double resolution_m) {
  const int normal = static_cast<int>(std::ceil(params.normal_radius_m / resolution_m));
  // Known ditch bottoms look up to K cells for an unseen ditch cell, which looks K further for
  // its rims and two beyond them; the cost layer reads the 4-neighbours of each cell and the
  // unknown cells beyond them (UnseenDropReachCells).
  return std::max(normal, 2 * SearchCells(params, resolution_m) + 2) +
         UnseenDropReachCells(resolution_m);
}

void ComputeGeometricLayers(GridMap* map, const TraversabilityParams& params) {
  CAIRN_THROW_UNLESS(map != nullptr, "no map");
  ComputeGeometricLayers(map, params, CellRect::All(*map));
}

void ComputeGeometricLayers(GridMap* map, const TraversabilityParams& params,
                            const CellRect& rect_in) {
  CAIRN_THROW_UNLESS(map != nullptr, "no map");
  CAIRN_THROW_UNLESS(map->HasLayer(layers::kElevation),
                     "the map has no '" << layers::kElevation << "' layer");
  params.Validate();
  const int sx = map->size_x(), sy = map->size_y();
  const double res = map->resolution_m();
  const CellRect rect = Clip(rect_in, sx, sy);

  Layer& slope = EnsureLayer(map, layers::kSlope);
  Layer& step = EnsureLayer(map, layers::kStepMax);
  Layer& rough = EnsureLayer(map, layers::kRoughness);
  Layer& nxl = EnsureLayer(map, kNormalXLayer);
  Layer& nyl = EnsureLayer(map, kNormalYLayer);
  Layer& ditch_depth = EnsureLayer(map, layers::kDitchDepth);
  Layer& ditch_width = EnsureLayer(map, layers::kDitchWidth);
  if (rect.empty()) return;
  const Layer& elevation = map->at(layers::kElevation);
  const float* h = elevation.data();
  const float* bound =
      map->HasLayer(layers::kGroundBound) ? map->at(layers::kGroundBound).data() : nullptr;
  const TerrainView view{h, bound, sx, sy};

  // Offsets of the normal window: every cell centre within the radius.
  const int rc = static_cast<int>(std::floor(params.normal_radius_m / res + 1e-9));
  std::vector<std::array<int, 2>> offsets;
  const double r2 = params.normal_radius_m * params.normal_radius_m + 1e-12;
  for (int dy = -rc; dy <= rc; ++dy) {
    for (int dx = -rc; dx <= rc; ++dx) {
      if ((dx * dx + dy * dy) * res * res <= r2) offsets.push_back({dx, dy});
    }
  }

  // Normals, slope, roughness and the step layer.
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const int64_t i = x + static_cast<int64_t>(y) * sx;
      const float hc = h[i];
      if (std::isnan(hc)) {
        slope.data()[i] = step.data()[i] = rough.data()[i] = kNaN;
        nxl.data()[i] = nyl.data()[i] = kNaN;
        continue;
      }
      const NormalResult nr = FitNormal(h, sx, sy, x, y, offsets, res);
      slope.data()[i] = static_cast<float>(std::acos(std::clamp(nr.normal.z(), -1.0, 1.0)));
      rough.data()[i] = static_cast<float>(nr.roughness_m);
      nxl.data()[i] = static_cast<float>(nr.normal.x());
      nyl.data()[i] = static_cast<float>(nr.normal.y());
      float max_step = 0.f;
      for (const auto& d : kNeighbours) {
        const int cx = x + d[0], cy = y + d[1];
        if (!view.Inside(cx, cy)) continue;
        const float hn = view.H(cx, cy);
        if (!std::isnan(hn)) max_step = std::max(max_step, std::fabs(hn - hc));
      }
      step.data()[i] = max_step;
    }
  }

  // Ditches. Pass 1: unknown cells the sensor looked into (a finite ground bound) whose rims
  // stand above that bound. A gap nobody looked into stays plain unknown: between lidar rings
  // the rays pass above the ground, so their bound proves nothing.
  const int K = SearchCells(params, res);
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const int64_t i = x + static_cast<int64_t>(y) * sx;
      ditch_depth.data()[i] = kNaN;
      ditch_width.data()[i] = kNaN;
    }
  }
  if (bound == nullptr) return;
  // Unseen ditch cells are needed K cells around the rectangle (for the known bottoms).
  const CellRect outer = Clip(Grow(rect, K), sx, sy);
  const int ow = outer.x1 - outer.x0, oh = outer.y1 - outer.y0;
  std::vector<DitchCell> unseen(static_cast<size_t>(ow) * oh);
  bool any_unseen = false;
  for (int y = outer.y0; y < outer.y1; ++y) {
    for (int x = outer.x0; x < outer.x1; ++x) {
      if (!std::isnan(view.H(x, y)) || !std::isfinite(view.B(x, y))) continue;
      DitchCell& c = unseen[(x - outer.x0) + static_cast<size_t>(y - outer.y0) * ow];
      c = TestUnseenCell(view, x, y, params, K, res);
      any_unseen |= c.ditch;
    }
  }
  if (!any_unseen) return;
  auto unseen_at = [&](int x, int y) -> const DitchCell& {
    return unseen[(x - outer.x0) + static_cast<size_t>(y - outer.y0) * ow];
  };
  // Cells within K (in x and y) of an unseen ditch cell: two passes of a sliding window count.
  std::vector<uint8_t> near_ditch(unseen.size(), 0);
  {
    std::vector<int> row(unseen.size(), 0);
    for (int y = 0; y < oh; ++y) {
      int in_window = 0;
      for (int x = -K; x < ow; ++x) {
        const int add = x + K, drop = x - K - 1;
        if (add < ow) in_window += unseen[add + static_cast<size_t>(y) * ow].ditch;
        if (drop >= 0) in_window -= unseen[drop + static_cast<size_t>(y) * ow].ditch;
        if (x >= 0) row[x + static_cast<size_t>(y) * ow] = in_window;
      }
    }
    for (int x = 0; x < ow; ++x) {
      int in_window = 0;
      for (int y = -K; y < oh; ++y) {
        const int add = y + K, drop = y - K - 1;
        if (add < oh) in_window += row[x + static_cast<size_t>(add) * ow] > 0;
        if (drop >= 0) in_window -= row[x + static_cast<size_t>(drop) * ow] > 0;
        if (y >= 0) near_ditch[x + static_cast<size_t>(y) * ow] = in_window > 0;
      }
    }
  }
  // Unknown cells on the gap segment of an unseen ditch cell (within K of it) belong to that
  // ditch even when the rays over them stayed shallower: the gap runs from rim to rim.
  struct Painted {
    double depth_m{0.0};
    double width_m{std::numeric_limits<double>::infinity()};
  };
  const int rw = rect.x1 - rect.x0, rh = rect.y1 - rect.y0;
  std::vector<Painted> painted(static_cast<size_t>(rw) * rh);
  std::vector<uint8_t> is_painted(painted.size(), 0);
  for (int y = outer.y0; y < outer.y1; ++y) {
    for (int x = outer.x0; x < outer.x1; ++x) {
      const DitchCell& c = unseen_at(x, y);
      if (!c.ditch) continue;
      for (size_t k = 0; k < kLineDirections.size(); ++k) {
        const GapLine& line = c.lines[k];
        if (!line.found) continue;
        const auto& d = kLineDirections[k];
        for (int s = -std::min(line.k_neg - 1, K); s <= std::min(line.k_pos - 1, K); ++s) {
          const int cx = x + s * d[0], cy = y + s * d[1];
          if (s == 0 || cx < rect.x0 || cy < rect.y0 || cx >= rect.x1 || cy >= rect.y1) continue;
          if (!std::isnan(view.H(cx, cy))) continue;
          const size_t pi = (cx - rect.x0) + static_cast<size_t>(cy - rect.y0) * rw;
          Painted& pc = painted[pi];
          pc.depth_m = std::max(pc.depth_m, c.depth_m);
          pc.width_m = std::min(pc.width_m, line.width_m);
          is_painted[pi] = 1;
        }
      }
    }
  }
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const int64_t i = x + static_cast<int64_t>(y) * sx;
      const float hc = h[i];
      if (std::isnan(hc)) {
        const DitchCell& c = unseen_at(x, y);
        const size_t pi = (x - rect.x0) + static_cast<size_t>(y - rect.y0) * rw;
        if (c.ditch || is_painted[pi]) {
          const double depth =
              c.ditch ? std::max(c.depth_m, painted[pi].depth_m) : painted[pi].depth_m;
          const double width =
              c.ditch ? std::min(c.width_m, painted[pi].width_m) : painted[pi].width_m;
          ditch_depth.data()[i] = static_cast<float>(depth);
          ditch_width.data()[i] = static_cast<float>(width);
        }
        continue;
      }
      // Pass 2: a known cell is a ditch bottom when, along some line, it shares a gap with an
      // unseen ditch cell whose rims stand at least min_depth above it. The walk crosses only
      // gap cells, so ground at rim level next to a ditch never joins it. Only cells within K
      // of an unseen ditch cell can.
      if (!near_ditch[(x - outer.x0) + static_cast<size_t>(y - outer.y0) * ow]) continue;
      const double gap_limit = hc + params.min_ditch_depth_m;
      bool found = false;
      for (const auto& d : kLineDirections) {
        for (int side = 0; side < 2 && !found; ++side) {
          const int sdx = side == 0 ? d[0] : -d[0], sdy = side == 0 ? d[1] : -d[1];
          for (int k = 1; k <= K; ++k) {
            const int cx = x + k * sdx, cy = y + k * sdy;
            if (!view.Inside(cx, cy)) break;
            const float hn = view.H(cx, cy);
            if (!std::isnan(hn)) {
              if (hn >= gap_limit) break;  // a rim: the gap ends here
              continue;
            }
            if (cx < outer.x0 || cy < outer.y0 || cx >= outer.x1 || cy >= outer.y1) break;
            const DitchCell& c = unseen_at(cx, cy);
            if (c.ditch && c.rim_m - hc + params.height_tolerance_m >= params.min_ditch_depth_m) {
              ditch_depth.data()[i] = static_cast<float>(c.rim_m - hc);
              ditch_width.data()[i] = static_cast<float>(c.width_m);
              found = true;
              break;
            }
          }
        }
        if (found) break;
      }
    }
  }
}

void ComputeCostLayer(GridMap* map, const common::RobotProfile& profile,
                      const TraversabilityParams& params, std::optional<common::Vector2> robot_xy_m,
                      double robot_pitch_rad) {
  CAIRN_THROW_UNLESS(map != nullptr, "no map");
  if (!map->HasLayer(layers::kSlope) || !map->HasLayer(layers::kDitchDepth) ||
      !map->HasLayer(kNormalXLayer)) {
    ComputeGeometricLayers(map, params);
  }
  RobotContext robot;
  robot.xy_m = robot_xy_m;
  robot.pitch_rad = robot_pitch_rad;
  ComputeCostLayer(map, profile, params, robot, CellRect::All(*map));
}

void ComputeCostLayer(GridMap* map, const common::RobotProfile& profile,
                      const TraversabilityParams& params, const RobotContext& robot,
                      const CellRect& rect_in) {
  CAIRN_THROW_UNLESS(map != nullptr, "no map");
  profile.Validate();
  params.Validate();
  for (const char* name :
       {layers::kElevation, layers::kSlope, layers::kRoughness, layers::kDitchDepth,
        layers::kDitchWidth, kNormalXLayer, kNormalYLayer}) {
    CAIRN_THROW_UNLESS(map->HasLayer(name), "the map has no '" << name << "' layer");
  }
  const int sx = map->size_x(), sy = map->size_y();
  const CellRect rect = Clip(rect_in, sx, sy);
  const std::string cost_name = layers::CostLayer(profile.name);
  if (!map->HasLayer(cost_name)) map->AddLayer(cost_name);
  Layer& cost = map->at(cost_name);
  if (rect.empty()) return;

  const float* h = map->at(layers::kElevation).data();
  const float* slope = map->at(layers::kSlope).data();
  const float* rough = map->at(layers::kRoughness).data();
  const float* nx = map->at(kNormalXLayer).data();
  const float* ny = map->at(kNormalYLayer).data();
  const float* ddepth = map->at(layers::kDitchDepth).data();
  const float* dwidth = map->at(layers::kDitchWidth).data();
  const float* bound =
      map->HasLayer(layers::kGroundBound) ? map->at(layers::kGroundBound).data() : nullptr;
  const double tol = params.height_tolerance_m;
  const double max_slope = std::min(profile.max_slope_up_rad, profile.max_slope_down_rad);
  const double up_limit = profile.max_step_up_m, down_limit = profile.max_step_down_m;
  const double rough_limit = profile.max_roughness_m, ditch_limit = profile.max_ditch_width_m;
  const float unknown_value = params.unknown_is_lethal ? layers::kCostLethal : kNaN;
  const double ff = params.free_fraction;
  // Cost of terrain using the share r of its most used limit: free up to free_fraction, then a
  // whole number in [1, graded_cost_max] (see common/layers.h).
  const double graded_top = std::min(99.0, std::floor(params.graded_cost_max));
  auto graded = [&](double r) {
    if (r <= ff) return layers::kCostFree;
    const double raw = params.graded_cost_max * (std::min(1.0, r) - ff) / (1.0 - ff);
    return static_cast<float>(std::clamp(std::round(raw), 1.0, std::max(1.0, graded_top)));
  };

  // Share of a limit used by a measurement (values above the limit are caught as lethal first).
  auto share = [](double value, double limit) {
    if (!(value > 0)) return 0.0;
    if (!(limit > 0)) return std::numeric_limits<double>::infinity();
    return std::isinf(limit) ? 0.0 : value / limit;
  };

  // Blind zone: a square around the robot's current position, strict bounds (seed 000).
  const bool blind = robot.xy_m.has_value() && params.blind_zone_half_size_m > 0;
  Eigen::Vector2d robot_cells(0, 0);
  double blind_cells = 0;
  if (blind) {
    robot_cells = map->geometry().ContinuousIndexOf(*robot.xy_m);
    blind_cells = params.blind_zone_half_size_m / map->resolution_m();
  }
  // IMU compensation: the robot's heading in the grid frame.
  const bool compensate = params.imu_pitch_compensation && robot.pitch_rad != 0.0;
  const double heading = robot.yaw_rad ? *robot.yaw_rad - map->geometry().origin.yaw_rad : 0.0;
  const double cp = std::cos(robot.pitch_rad), sp = std::sin(robot.pitch_rad);
  const bool exact_tilt = compensate && robot.yaw_rad.has_value();
  const double res = map->resolution_m();
  const int reach_cells = UnseenDropReachCells(res);
  const double cos_heading = std::cos(heading), sin_heading = std::sin(heading);
  std::array<int64_t, 4> neighbour_offset{};
  std::array<double, 4> forward_m{};
  for (int k = 0; k < 4; ++k) {
    neighbour_offset[k] = kNeighbours[k][0] + static_cast<int64_t>(kNeighbours[k][1]) * sx;
    forward_m[k] = (kNeighbours[k][0] * cos_heading + kNeighbours[k][1] * sin_heading) * res;
  }
  // 1 / limit, 0 for "no limit" (a zero limit makes any positive value lethal first).
  auto inverse = [](double limit) {
    return std::isinf(limit) ? 0.0 : (limit > 0 ? 1.0 / limit : 0.0);
  };
  const double inv_slope = inverse(max_slope), inv_rough = inverse(rough_limit);
  const double inv_up = inverse(up_limit), inv_down = inverse(down_limit);
  // Rows holding a ditch cell (in or next to the rectangle): the per-neighbour ditch checks
  // are needed only on them and the rows next to them.
  std::vector<uint8_t> ditch_row(static_cast<size_t>(sy) + 2, 0);
  for (int y = std::max(0, rect.y0 - 1); y < std::min(sy, rect.y1 + 1); ++y) {
    const float* row = ddepth + static_cast<int64_t>(y) * sx;
    for (int x = std::max(0, rect.x0 - 1); x < std::min(sx, rect.x1 + 1); ++x) {
      if (!std::isnan(row[x])) {
        ditch_row[y + 1] = 1;
        break;
      }
    }
  }

  for (int y = rect.y0; y < rect.y1; ++y) {
    const bool any_ditch = ditch_row[y] || ditch_row[y + 1] || ditch_row[y + 2];
    for (int x = rect.x0; x < rect.x1; ++x) {
      const int64_t i = x + static_cast<int64_t>(y) * sx;
      const float hc = h[i];
      const bool in_ditch = !std::isnan(ddepth[i]);
      const bool ditch_lethal = in_ditch && dwidth[i] > ditch_limit + tol;
      if (std::isnan(hc)) {
        if (ditch_lethal) {
          cost.data()[i] = layers::kCostLethal;
        } else if (in_ditch) {
          // A ditch the robot can bridge: graded by the width it uses.
          cost.data()[i] = graded(share(dwidth[i], ditch_limit));
        } else if (blind && std::fabs(x + 0.5 - robot_cells.x()) < blind_cells &&
                   std::fabs(y + 0.5 - robot_cells.y()) < blind_cells) {
          cost.data()[i] = layers::kCostFree;
        } else {
          cost.data()[i] = unknown_value;
        }
        continue;
      }
      // A known cell at the map border cannot be judged against all its neighbours.
      if (x == 0 || y == 0 || x == sx - 1 || y == sy - 1) {
        cost.data()[i] = unknown_value;
        continue;
      }
      if (in_ditch && !ditch_lethal) {
        // The bottom of a ditch the robot bridges: its wheels never touch it.
        cost.data()[i] = graded(share(dwidth[i], ditch_limit));
        continue;
      }
      if (ditch_lethal) {
        cost.data()[i] = layers::kCostLethal;
        continue;
      }
      // The rules below stop at the first that makes the cell lethal; until then `ratio` keeps
      // the largest share of a limit in use.
      double ratio = 0.0;
      bool lethal = false;

      // Slope, optionally compensated by the IMU pitch.
      double s = slope[i];
      if (compensate) {
        if (exact_tilt) {
          const double nzc =
              std::sqrt(std::max(0.0, 1.0 - double(nx[i]) * nx[i] - double(ny[i]) * ny[i]));
          const double nh = nx[i] * cos_heading + ny[i] * sin_heading;
          const double nz_world = nh * sp + nzc * cp;
          s = std::acos(std::clamp(std::fabs(nz_world), 0.0, 1.0));
        } else {
          s = std::max(0.0, s + robot.pitch_rad);
        }
      }
      if (s >= max_slope || rough[i] > rough_limit + tol) {
        cost.data()[i] = layers::kCostLethal;
        continue;
      }
      ratio = std::max(s * inv_slope, rough[i] > 0 ? rough[i] * inv_rough : 0.0);

      // Steps to the 4-neighbours, inclusive bounds. Fast path: all four known, no ditch
      // nearby, no tilt: only the highest and the lowest neighbour matter.
      if (!any_ditch && !exact_tilt) {
        const float a = h[i + neighbour_offset[0]], b = h[i + neighbour_offset[1]];
        const float c = h[i + neighbour_offset[2]], d = h[i + neighbour_offset[3]];
        if (!std::isnan(a) && !std::isnan(b) && !std::isnan(c) && !std::isnan(d)) {
          const double up = double(std::max(std::max(a, b), std::max(c, d))) - hc;
          const double down = hc - double(std::min(std::min(a, b), std::min(c, d)));
          if (up <= up_limit + tol && down <= down_limit + tol) {
            ratio = std::max({ratio, up > 0 ? up * inv_up : 0.0, down > 0 ? down * inv_down : 0.0});
            cost.data()[i] = graded(ratio);
            continue;
          }
          // A limit is exceeded: the per-neighbour rules below decide (edge length).
        }
      }
      for (int k = 0; k < 4 && !lethal; ++k) {
        const int64_t j = i + neighbour_offset[k];
        // A bridged ditch is no step: the robot spans it.
        if (!std::isnan(ddepth[j]) && !(dwidth[j] > ditch_limit + tol)) continue;
        const float hn = h[j];
        if (!std::isnan(hn)) {
          double rise = double(hn) - hc;
          // In a robot-levelled map the neighbour offset is tilted by the pitch as well.
          if (exact_tilt) rise = forward_m[k] * sp + rise * cp;
          if (rise > up_limit + tol || -rise > down_limit + tol) {
            // The same edge one cell to either side must exceed the limit too (see
            // min_step_edge_cells); otherwise the pair counts as a step at the limit.
            bool supported = params.min_step_edge_cells <= 1;
            const int64_t side = kNeighbours[k][1] + static_cast<int64_t>(kNeighbours[k][0]) * sx;
            for (const int64_t s : {side, -side}) {
              if (supported) break;
              const float hs = h[i + s], hn_s = h[j + s];
              if (std::isnan(hs) || std::isnan(hn_s)) continue;
              double rise_s = double(hn_s) - hs;
              if (exact_tilt) rise_s = forward_m[k] * sp + rise_s * cp;
              supported = rise > 0 ? rise_s > up_limit + tol : -rise_s > down_limit + tol;
            }
            if (supported) {
              lethal = true;
            } else {
              ratio = std::max(ratio, 1.0);
            }
          } else {
            ratio = std::max(ratio, rise > 0 ? rise * inv_up : -rise * inv_down);
          }
        } else if (bound != nullptr && std::isfinite(bound[j])) {
          // The sensor looked into this neighbour and found nothing down to bound[j], nor in
          // the unknown cells beyond it down to theirs.
          float lowest = bound[j];
          for (int s = 2; s <= reach_cells; ++s) {
            const int nx = x + s * kNeighbours[k][0], ny = y + s * kNeighbours[k][1];
            if (nx < 0 || ny < 0 || nx >= sx || ny >= sy) break;
            const int64_t jj = nx + static_cast<int64_t>(ny) * sx;
            if (!std::isnan(h[jj])) break;
            if (std::isfinite(bound[jj])) lowest = std::min(lowest, bound[jj]);
          }
          double drop = double(hc) - lowest;
          if (exact_tilt) drop = drop * cp - forward_m[k] * sp;
          if (drop > down_limit + tol ||
              (params.unseen_drop_m > 0 && drop >= params.unseen_drop_m - tol)) {
            lethal = true;
          } else if (drop > 0) {
            ratio = std::max(ratio, drop * inv_down);
          }
        }
      }

      cost.data()[i] = lethal ? layers::kCostLethal : graded(ratio);
    }
  }
}

TraversabilityParams LoadTraversabilityParams(common::YamlMap& m) {
  TraversabilityParams p;
  m.Get("normal_radius_m", &p.normal_radius_m);
  m.Get("blind_zone_half_size_m", &p.blind_zone_half_size_m);
  m.Get("imu_pitch_compensation", &p.imu_pitch_compensation);
  m.Get("unknown_is_lethal", &p.unknown_is_lethal);
  m.Get("graded_cost_max", &p.graded_cost_max);
  m.Get("free_fraction", &p.free_fraction);
  m.Get("min_ditch_depth_m", &p.min_ditch_depth_m);
  m.Get("unseen_drop_m", &p.unseen_drop_m);
  m.Get("max_ditch_search_m", &p.max_ditch_search_m);
  m.Get("height_tolerance_m", &p.height_tolerance_m);
  m.Get("min_step_edge_cells", &p.min_step_edge_cells);
  m.Finish();
  return p;
}

}  // namespace cairn::mapping
