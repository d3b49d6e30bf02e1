#include "services/mapping/ditch_detection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace cairn::mapping::internal {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The four line directions of the ditch analysis: x, y and both diagonals.
constexpr std::array<std::array<int, 2>, 4> kLineDirections{{{1, 0}, {0, 1}, {1, 1}, {1, -1}}};

CellRect Clip(const CellRect& r, int sx, int sy) {
  return {std::max(0, r.x0), std::max(0, r.y0), std::min(sx, r.x1), std::min(sy, r.y1)};
}

CellRect Grow(const CellRect& r, int margin) {
  return {r.x0 - margin, r.y0 - margin, r.x1 + margin, r.y1 + margin};
}

// Result of looking for the rims of a gap along one line through a cell.
struct GapLine {
  bool found{false};
  int k_pos{0};         // steps to the rim along +(dx, dy)
  int k_neg{0};         // steps to the rim along -(dx, dy)
  double rim_m{0.0};    // the lower of the two rims
  double width_m{0.0};  // distance between the rims minus one cell
  // The ground on each side continued into the gap at its own slope, at the cell: the higher
  // of the two is the lowest a smooth valley between the rims could lie there.
  double continued_m{0.0};
  // Per side (+, -): the rim's height above the gap's floor, and the largest rise between
  // consecutive known heights on the way there (the floor, the cells crossed, the rim).
  double rise_m[2]{0.0, 0.0};
  double wall_m[2]{0.0, 0.0};
};

// Walks from (x, y) along ±(dx, dy) through the gap: unknown cells and known cells lower than
// `rim_threshold`. The first known cell at or above the threshold on each side is a rim. An
// unknown cell whose ground bound is at or above the threshold ends the walk without a rim:
// the ground there may be at rim level, so the gap is not proven to continue. A rim must have
// two cells of known ground beyond it within `flatness_m` of its height: the top of a wall
// between two floors is no rim (else every corridor floor would lie in a "ditch"). `floor_m`:
// the gap's height at (x, y) (its bound, or a seen bottom's height).
GapLine FindRims(const TerrainView& v, int x, int y, int dx, int dy, double floor_m,
                 double rim_threshold, double flatness_m, int max_cells, double step_m) {
  GapLine line;
  int k_side[2] = {0, 0};
  double rim_side[2] = {0.0, 0.0};
  double continued_side[2] = {0.0, 0.0};
  double wall_side[2] = {0.0, 0.0};
  for (int side = 0; side < 2; ++side) {
    const int sdx = side == 0 ? dx : -dx, sdy = side == 0 ? dy : -dy;
    double last_known = floor_m;
    for (int k = 1; k <= max_cells; ++k) {
      const int cx = x + k * sdx, cy = y + k * sdy;
      if (!v.Inside(cx, cy)) return line;
      const float hc = v.H(cx, cy);
      if (std::isnan(hc)) {
        if (v.B(cx, cy) >= rim_threshold) return line;
        continue;
      }
      wall_side[side] = std::max(wall_side[side], double(hc) - last_known);
      last_known = hc;
      if (hc >= rim_threshold) {
        // A rim is ground that goes on beyond it at about its height for two more cells; a
        // wall or an object (ground again, or nothing known, behind it) bounds no ditch. Nor
        // does a cell some ray crossed within half the depth of the gap's own bound: that
        // cell's height is a face's returns, not ground at the rim (the floor cells in front of
        // a step, raised by returns from its face, with an unhit cell between them). A rim cell
        // that holds the ditch's edge is crossed lower than its height, but well above the gap.
        if (v.B(cx, cy) < rim_threshold - 0.5 * flatness_m) {
          // ... unless it holds the gap's far face: the face's top returns fell in it, the rays
          // that hit the face lower crossed it, and the ground beyond it is a clean rim at the
          // face's height. Then it is part of the gap and the next cell is the rim.
          const int nx = cx + sdx, ny = cy + sdy;
          const bool face_cell = k < max_cells && v.Inside(nx, ny) && !std::isnan(v.H(nx, ny)) &&
                                 std::fabs(double(v.H(nx, ny)) - hc) < flatness_m &&
                                 !(v.B(nx, ny) < rim_threshold - 0.5 * flatness_m);
          if (face_cell) continue;
          return line;
        }
        for (int e = 1; e <= 2; ++e) {
          const int ox = cx + e * sdx, oy = cy + e * sdy;
          if (!v.Inside(ox, oy)) return line;
          const float beyond = v.H(ox, oy);
          if (std::isnan(beyond) || std::fabs(double(beyond) - hc) >= flatness_m) return line;
        }
        k_side[side] = k;
        rim_side[side] = hc;
        // The ground beyond the rim falling towards the gap (per cell, over the two cells
        // beyond it), continued to the cell: a valley's flank, not a ditch's wall.
        const double fall = std::max(0.0, 0.5 * (double(v.H(cx + 2 * sdx, cy + 2 * sdy)) - hc));
        continued_side[side] = hc - fall * k;
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
  line.continued_m = std::max(continued_side[0], continued_side[1]);
  for (int side = 0; side < 2; ++side) {
    line.rise_m[side] = rim_side[side] - floor_m;
    line.wall_m[side] = wall_side[side];
  }
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

// The ditch test of a gap at cell (x, y) whose ground lies at or below `u`.
DitchCell TestGap(const TerrainView& v, int x, int y, double u, const TraversabilityParams& p,
                  int max_cells, double res) {
  DitchCell cell;
  for (size_t k = 0; k < kLineDirections.size(); ++k) {
    const auto& d = kLineDirections[k];
    const bool diagonal = d[0] != 0 && d[1] != 0;
    const double step_m = diagonal ? res * M_SQRT2 : res;
    const int cells = diagonal ? std::max(1, static_cast<int>(max_cells / M_SQRT2)) : max_cells;
    const GapLine line = FindRims(v, x, y, d[0], d[1], u, u + p.min_ditch_depth_m,
                                  p.min_ditch_depth_m, cells, step_m);
    if (!line.found) continue;
    const double depth = line.rim_m - u;
    if (depth + p.height_tolerance_m < p.min_ditch_depth_m) continue;
    // Natural ground: between two flanks falling towards each other (a valley, a shadow behind
    // a crest) the ground may lie well below both rims without any ditch. The gap must lie
    // min_depth below both flanks continued at their slopes too.
    if (line.continued_m - u + p.height_tolerance_m < p.min_ditch_depth_m) continue;
    // ... nor is a depression whose walls, on average, are gentler than min_ditch_wall_slope
    // (5 cm over a 2.4 m wide dip: 2.4 deg): ground to drive, judged by its slopes once seen.
    if (depth + p.height_tolerance_m < std::tan(p.min_ditch_wall_slope_rad) * 0.5 * line.width_m) {
      continue;
    }
    // ... and a ditch has two walls: on each side most of the rise to the rim (half of it at
    // least) happens at once, between two neighbouring known heights (or across unseen
    // cells, where a wall may stand anywhere). Between a rock and the hillside rising gently
    // beyond its shadow there is one wall, the rock's (its flat top passing for a far bank);
    // the hillside's rise is spread over its cells.
    if (line.wall_m[0] < 0.5 * line.rise_m[0] || line.wall_m[1] < 0.5 * line.rise_m[1]) continue;
    cell.lines[k] = line;
    if (!cell.ditch || line.width_m < cell.width_m) {
      cell.width_m = line.width_m;
      cell.rim_m = line.rim_m;
    }
    cell.depth_m = std::max(cell.depth_m, depth);
    cell.ditch = true;
  }
  // A gap bounded along one diagonal alone lies in a concave corner, where two faces meet at a
  // right angle (a platform's drop beside a ramp's side): the floor there is open along both
  // axes. A trench bounds its floor along an axis too (it runs within 45 deg of one), or along
  // both diagonals (a trench along an axis, at its end against a wall).
  if (cell.ditch) {
    int axes = 0, diagonals = 0;
    for (size_t k = 0; k < kLineDirections.size(); ++k) {
      if (!cell.lines[k].found) continue;
      const bool diagonal = kLineDirections[k][0] != 0 && kLineDirections[k][1] != 0;
      ++(diagonal ? diagonals : axes);
    }
    if (axes == 0 && diagonals < 2) return DitchCell{};
  }
  return cell;
}

DitchCell TestUnseenCell(const TerrainView& v, int x, int y, const TraversabilityParams& p,
                         int max_cells, double res) {
  const float u = v.B(x, y);
  if (!std::isnan(v.H(x, y)) || !std::isfinite(u)) return DitchCell{};
  return TestGap(v, x, y, u, p, max_cells, res);
}

// The unseen ditch cells of `outer` (the written rectangle grown by the search distance: the
// known bottoms look that far for them).
struct UnseenCells {
  CellRect outer;
  int ow{0};
  int oh{0};
  std::vector<DitchCell> cells;
  bool any{false};
  size_t Index(int x, int y) const {
    return (x - outer.x0) + static_cast<size_t>(y - outer.y0) * ow;
  }
  const DitchCell& At(int x, int y) const { return cells[Index(x, y)]; }
  bool Inside(int x, int y) const {
    return x >= outer.x0 && y >= outer.y0 && x < outer.x1 && y < outer.y1;
  }
};

UnseenCells FindUnseenDitchCells(const TerrainView& view, const TraversabilityParams& params, int K,
                                 double res, const CellRect& rect) {
  UnseenCells u;
  u.outer = Clip(Grow(rect, K), view.sx, view.sy);
  u.ow = u.outer.x1 - u.outer.x0;
  u.oh = u.outer.y1 - u.outer.y0;
  u.cells.resize(static_cast<size_t>(u.ow) * u.oh);
  for (int y = u.outer.y0; y < u.outer.y1; ++y) {
    for (int x = u.outer.x0; x < u.outer.x1; ++x) {
      if (!std::isnan(view.H(x, y)) || !std::isfinite(view.B(x, y))) continue;
      DitchCell& c = u.cells[u.Index(x, y)];
      c = TestUnseenCell(view, x, y, params, K, res);
      u.any |= c.ditch;
    }
  }
  return u;
}

// Cells within K (in x and y) of an unseen ditch cell: two passes of a sliding window count.
std::vector<uint8_t> NearDitchMask(const UnseenCells& u, int K) {
  const int ow = u.ow, oh = u.oh;
  std::vector<uint8_t> near_ditch(u.cells.size(), 0);
  std::vector<int> row(u.cells.size(), 0);
  for (int y = 0; y < oh; ++y) {
    int in_window = 0;
    for (int x = -K; x < ow; ++x) {
      const int add = x + K, drop = x - K - 1;
      if (add < ow) in_window += u.cells[add + static_cast<size_t>(y) * ow].ditch;
      if (drop >= 0) in_window -= u.cells[drop + static_cast<size_t>(y) * ow].ditch;
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
  return near_ditch;
}

// Unknown cells of `rect` on the gap segment of an unseen ditch cell (within K of it) belong to
// that ditch even when the rays over them stayed shallower: the gap runs from rim to rim.
struct PaintedCells {
  struct Cell {
    double depth_m{0.0};
    double width_m{std::numeric_limits<double>::infinity()};
  };
  CellRect rect;
  int rw{0};
  std::vector<Cell> cells;
  std::vector<uint8_t> painted;
  size_t Index(int x, int y) const { return (x - rect.x0) + static_cast<size_t>(y - rect.y0) * rw; }
};

PaintedCells PaintGapSegments(const UnseenCells& u, const TerrainView& view, const CellRect& rect,
                              int K) {
  PaintedCells p;
  p.rect = rect;
  p.rw = rect.x1 - rect.x0;
  const int rh = rect.y1 - rect.y0;
  p.cells.resize(static_cast<size_t>(p.rw) * rh);
  p.painted.assign(p.cells.size(), 0);
  for (int y = u.outer.y0; y < u.outer.y1; ++y) {
    for (int x = u.outer.x0; x < u.outer.x1; ++x) {
      const DitchCell& c = u.At(x, y);
      if (!c.ditch) continue;
      for (size_t k = 0; k < kLineDirections.size(); ++k) {
        const GapLine& line = c.lines[k];
        if (!line.found) continue;
        const auto& d = kLineDirections[k];
        for (int s = -std::min(line.k_neg - 1, K); s <= std::min(line.k_pos - 1, K); ++s) {
          const int cx = x + s * d[0], cy = y + s * d[1];
          if (s == 0 || cx < rect.x0 || cy < rect.y0 || cx >= rect.x1 || cy >= rect.y1) continue;
          if (!std::isnan(view.H(cx, cy))) continue;
          const size_t pi = p.Index(cx, cy);
          PaintedCells::Cell& pc = p.cells[pi];
          pc.depth_m = std::max(pc.depth_m, c.depth_m);
          pc.width_m = std::min(pc.width_m, line.width_m);
          p.painted[pi] = 1;
        }
      }
    }
  }
  return p;
}

// Pass 2: a known cell is a ditch bottom when, along some line, it shares a gap with an unseen
// ditch cell whose rims stand at least min_depth above it. The walk crosses only gap cells, so
// ground at rim level next to a ditch never joins it. Returns the cell found, or null.
const DitchCell* FindDitchBottom(const TerrainView& view, const UnseenCells& u, int x, int y,
                                 float hc, const TraversabilityParams& params, int K) {
  const double gap_limit = hc + params.min_ditch_depth_m;
  for (const auto& d : kLineDirections) {
    for (int side = 0; side < 2; ++side) {
      const int sdx = side == 0 ? d[0] : -d[0], sdy = side == 0 ? d[1] : -d[1];
      for (int k = 1; k <= K; ++k) {
        const int cx = x + k * sdx, cy = y + k * sdy;
        if (!view.Inside(cx, cy)) break;
        const float hn = view.H(cx, cy);
        if (!std::isnan(hn)) {
          if (hn >= gap_limit) break;  // a rim: the gap ends here
          continue;
        }
        if (!u.Inside(cx, cy)) break;
        const DitchCell& c = u.At(cx, cy);
        if (c.ditch && c.rim_m - hc + params.height_tolerance_m >= params.min_ditch_depth_m) {
          return &c;
        }
      }
    }
  }
  return nullptr;
}

}  // namespace

std::optional<SeenBottom> TestSeenBottom(const TerrainView& view, int x, int y,
                                         const TraversabilityParams& params, double resolution_m) {
  if (!view.Inside(x, y) || std::isnan(view.H(x, y))) return std::nullopt;
  const DitchCell c = TestGap(view, x, y, view.H(x, y), params,
                              DitchSearchCells(params, resolution_m), resolution_m);
  if (!c.ditch || c.width_m > params.max_ditch_search_m + 1e-6) return std::nullopt;
  return SeenBottom{c.rim_m - view.H(x, y), c.width_m};
}

int DitchSearchCells(const TraversabilityParams& params, double resolution_m) {
  return std::max(1, static_cast<int>(std::ceil(params.max_ditch_search_m / resolution_m - 1e-9)));
}

void ComputeDitchLayers(const TerrainView& view, const TraversabilityParams& params, double res,
                        const CellRect& rect, float* ditch_depth, float* ditch_width) {
  const int sx = view.sx;
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const int64_t i = x + static_cast<int64_t>(y) * sx;
      ditch_depth[i] = kNaN;
      ditch_width[i] = kNaN;
    }
  }
  // A gap nobody looked into stays plain unknown: between lidar rings the rays pass above the
  // ground, so their bound proves nothing.
  if (view.bound == nullptr) return;
  const int K = DitchSearchCells(params, res);
  const UnseenCells unseen = FindUnseenDitchCells(view, params, K, res, rect);
  if (!unseen.any) return;
  const std::vector<uint8_t> near_ditch = NearDitchMask(unseen, K);
  const PaintedCells painted = PaintGapSegments(unseen, view, rect, K);
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const int64_t i = x + static_cast<int64_t>(y) * sx;
      const float hc = view.h[i];
      if (std::isnan(hc)) {
        const DitchCell& c = unseen.At(x, y);
        const size_t pi = painted.Index(x, y);
        if (c.ditch || painted.painted[pi]) {
          const PaintedCells::Cell& p = painted.cells[pi];
          ditch_depth[i] = static_cast<float>(c.ditch ? std::max(c.depth_m, p.depth_m) : p.depth_m);
          ditch_width[i] = static_cast<float>(c.ditch ? std::min(c.width_m, p.width_m) : p.width_m);
        }
        continue;
      }
      // Only cells within K of an unseen ditch cell can be a bottom.
      if (!near_ditch[unseen.Index(x, y)]) continue;
      if (const DitchCell* c = FindDitchBottom(view, unseen, x, y, hc, params, K)) {
        ditch_depth[i] = static_cast<float>(c->rim_m - hc);
        ditch_width[i] = static_cast<float>(c->width_m);
      }
    }
  }
}

}  // namespace cairn::mapping::internal
