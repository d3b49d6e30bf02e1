#include "mapstore/map_eval.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <vector>

#include "common/check.h"
#include "common/layers.h"

namespace cairn::mapstore {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// kKnown: explored but neither free nor occupied (a C_nc between the two bounds).
enum Class : int8_t { kOutside = -2, kUnknown = -1, kFree = 0, kOccupied = 1, kKnown = 2 };

double Ratio(int64_t num, int64_t den) {
  return den > 0 ? static_cast<double>(num) / static_cast<double>(den) : kNaN;
}

// Cells as a flat array, x fastest (the GridMap storage order).
struct Grid {
  int nx{0};
  int ny{0};
  std::vector<int8_t> v;
  int8_t at(int ix, int iy) const { return v[ix + static_cast<size_t>(iy) * nx]; }
  bool inside(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < nx && iy < ny; }
};

// For each cell: is a cell of `set` within Chebyshev distance r? (separable dilation)
std::vector<uint8_t> Dilate(const std::vector<uint8_t>& set, int nx, int ny, int r) {
  if (r == 0) return set;
  std::vector<uint8_t> rows(set.size(), 0), out(set.size(), 0);
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      if (!set[ix + static_cast<size_t>(iy) * nx]) continue;
      for (int k = std::max(0, ix - r); k <= std::min(nx - 1, ix + r); ++k) {
        rows[k + static_cast<size_t>(iy) * nx] = 1;
      }
    }
  }
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      if (!rows[ix + static_cast<size_t>(iy) * nx]) continue;
      for (int k = std::max(0, iy - r); k <= std::min(ny - 1, iy + r); ++k) {
        out[ix + static_cast<size_t>(k) * nx] = 1;
      }
    }
  }
  return out;
}

// Length (cells) of the run of `occ` cells through (ix, iy) along (dx, dy).
int RunThrough(const std::vector<uint8_t>& occ, int nx, int ny, int ix, int iy, int dx, int dy) {
  auto is = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < nx && y < ny && occ[x + static_cast<size_t>(y) * nx];
  };
  int n = 1;
  for (int x = ix + dx, y = iy + dy; is(x, y); x += dx, y += dy) ++n;
  for (int x = ix - dx, y = iy - dy; is(x, y); x -= dx, y -= dy) ++n;
  return n;
}

struct Run {
  int begin;  // first cell (position along the line)
  int end;    // one past the last
};

// Runs of cells where pred(k) holds, k in [0, n).
template <typename Pred>
std::vector<Run> Runs(int n, Pred pred) {
  std::vector<Run> runs;
  int k = 0;
  while (k < n) {
    if (!pred(k)) {
      ++k;
      continue;
    }
    const int begin = k;
    while (k < n && pred(k)) ++k;
    runs.push_back({begin, k});
  }
  return runs;
}

// Doubled-wall crossings along one line of cells: map and truth occupancy by position.
template <typename MapOcc, typename TruthOcc, typename NearTruth>
int64_t DoubleWallsAlong(int n, MapOcc map_occ, TruthOcc truth_occ, NearTruth near_truth,
                         const MapEvalParams& p) {
  const std::vector<Run> runs = Runs(n, map_occ);
  int64_t count = 0;
  for (size_t i = 0; i + 1 < runs.size(); ++i) {
    const int gap = runs[i + 1].begin - runs[i].end;
    if (gap < p.double_wall_min_gap_cells || gap > p.double_wall_max_gap_cells) continue;
    // Two faces of one thin wall, its inside unseen: the gap lies within the truth's wall.
    bool gap_free = false;
    for (int k = runs[i].end; k < runs[i + 1].begin && !gap_free; ++k) gap_free = !truth_occ(k);
    if (!gap_free) continue;
    // A copy of a wall lies off it: one of the two runs has no cell within tolerance of the
    // truth. A stray cell at a wall's end or corner (within a cell of it, diagonally) is not one.
    const auto off_truth = [&](const Run& run) {
      for (int k = run.begin; k < run.end; ++k) {
        if (near_truth(k)) return false;
      }
      return true;
    };
    if (!off_truth(runs[i]) && !off_truth(runs[i + 1])) continue;
    const int lo = std::max(0, runs[i].begin - p.tolerance_cells);
    const int hi = std::min(n, runs[i + 1].end + p.tolerance_cells);
    const std::vector<Run> truth = Runs(hi - lo, [&](int k) { return truth_occ(lo + k); });
    if (truth.size() == 1) ++count;
  }
  return count;
}

std::string Number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

}  // namespace

void MapEvalParams::Validate() const {
  CAIRN_THROW_UNLESS(!layer.empty(), "layer must name a map layer");
  CAIRN_THROW_UNLESS(
      std::isfinite(occupied_above) && std::isfinite(free_below) && free_below <= occupied_above,
      "free_below (" << free_below << ") must not exceed occupied_above (" << occupied_above
                     << ")");
  CAIRN_THROW_UNLESS(std::isfinite(cnc_free_above) && std::isfinite(cnc_occupied_below) &&
                         cnc_occupied_below <= cnc_free_above,
                     "cnc_occupied_below (" << cnc_occupied_below
                                            << ") must not exceed cnc_free_above ("
                                            << cnc_free_above << ")");
  CAIRN_THROW_UNLESS(start_m.has_value(), "start_m is required (a free position in the world)");
  CAIRN_THROW_UNLESS(std::isfinite(start_m->x()) && std::isfinite(start_m->y()),
                     "start_m must be finite");
  CAIRN_THROW_UNLESS(tolerance_cells >= 0 && tolerance_cells <= 100,
                     "tolerance_cells must be in [0, 100] (got " << tolerance_cells << ")");
  CAIRN_THROW_UNLESS(max_wall_thickness_cells >= 1, "max_wall_thickness_cells must be >= 1 (got "
                                                        << max_wall_thickness_cells << ")");
  CAIRN_THROW_UNLESS(
      double_wall_min_gap_cells >= 1 && double_wall_max_gap_cells >= double_wall_min_gap_cells,
      "double_wall_min_gap_cells must be >= 1 and double_wall_max_gap_cells >= it");
}

MapEvalReport EvaluateMap(const common::GridMap& map, const common::GridMap& truth,
                          const MapEvalParams& params) {
  params.Validate();
  CAIRN_THROW_UNLESS(map.geometry() == truth.geometry(),
                     "the truth must be rasterised on the map's grid (geometries differ)");
  CAIRN_THROW_UNLESS(map.HasLayer(params.layer), "the map has no layer '" << params.layer << "'");
  CAIRN_THROW_UNLESS(truth.HasLayer(kTruthOccupied),
                     "the truth has no layer '" << kTruthOccupied << "'");
  const auto start = map.IndexOf(*params.start_m);
  CAIRN_THROW_UNLESS(start.has_value(), "start (" << params.start_m->x() << ", "
                                                  << params.start_m->y()
                                                  << ") lies outside the map");
  const int nx = map.size_x(), ny = map.size_y();
  const size_t n = static_cast<size_t>(nx) * ny;
  const common::Layer& layer = map.at(params.layer);
  const common::Layer& truth_occ = truth.at(kTruthOccupied);
  const bool cost = layers::IsCostLayer(params.layer);
  const bool cnc = params.layer == kInfoNavigability;
  const common::Layer* region = nullptr;
  if (!params.region_layer.empty()) {
    CAIRN_THROW_UNLESS(map.HasLayer(params.region_layer),
                       "the map has no region layer '" << params.region_layer << "'");
    region = &map.at(params.region_layer);
  }

  MapEvalReport r;
  r.layer = params.layer;
  r.resolution_m = map.resolution_m();

  // Classes per cell.
  Grid m{nx, ny, std::vector<int8_t>(n, kUnknown)};
  Grid t{nx, ny, std::vector<int8_t>(n, kOutside)};
  for (size_t i = 0; i < n; ++i) {
    const float tv = truth_occ.data()[i];
    if (std::isnan(tv)) continue;
    if (region && region->data()[i] != 1.f) continue;
    t.v[i] = tv >= 0.5f ? kOccupied : kFree;
    const float mv = layer.data()[i];
    if (std::isnan(mv)) {
      m.v[i] = kUnknown;
    } else if (cost) {
      m.v[i] = mv >= layers::kCostLethal ? kOccupied : kFree;
    } else if (cnc) {
      m.v[i] = mv > params.cnc_free_above       ? kFree
               : mv < params.cnc_occupied_below ? kOccupied
                                                : kKnown;
    } else {
      m.v[i] = mv > params.occupied_above ? kOccupied : mv < params.free_below ? kFree : kUnknown;
    }
  }
  const int64_t start_i = map.geometry().LinearIndex(*start);
  CAIRN_THROW_UNLESS(t.v[start_i] == kFree, "start (" << params.start_m->x() << ", "
                                                      << params.start_m->y()
                                                      << ") is not free in the truth");

  std::vector<uint8_t> map_occ(n, 0), truth_occ_set(n, 0);
  int64_t both_occ = 0, either_occ = 0, free_right = 0;
  for (size_t i = 0; i < n; ++i) {
    if (t.v[i] == kOutside) continue;
    ++r.truth_cells;
    const bool to = t.v[i] == kOccupied, mo = m.v[i] == kOccupied;
    r.truth_occupied_cells += to;
    r.truth_free_cells += !to;
    r.map_occupied_cells += mo;
    r.map_free_cells += m.v[i] == kFree;
    r.map_unknown_cells += m.v[i] == kUnknown;
    map_occ[i] = mo;
    truth_occ_set[i] = to;
    both_occ += to && mo;
    either_occ += to || mo;
    free_right += m.v[i] == kFree && !to;
  }
  r.occupied_iou = Ratio(both_occ, either_occ);
  r.free_precision = Ratio(free_right, r.map_free_cells);

  // Reachable area: truth-free cells 4-connected to the start.
  std::vector<uint8_t> reachable(n, 0);
  {
    std::deque<int64_t> queue{start_i};
    reachable[start_i] = 1;
    while (!queue.empty()) {
      const int64_t i = queue.front();
      queue.pop_front();
      const int ix = static_cast<int>(i % nx), iy = static_cast<int>(i / nx);
      const int d[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
      for (const auto& s : d) {
        const int x = ix + s[0], y = iy + s[1];
        if (!t.inside(x, y)) continue;
        const int64_t j = x + static_cast<int64_t>(y) * nx;
        if (reachable[j] || t.v[j] != kFree) continue;
        reachable[j] = 1;
        queue.push_back(j);
      }
    }
  }
  for (size_t i = 0; i < n; ++i) {
    if (!reachable[i]) continue;
    ++r.reachable_cells;
    r.reachable_known_cells += m.v[i] == kFree || m.v[i] == kOccupied || m.v[i] == kKnown;
  }
  r.coverage = Ratio(r.reachable_known_cells, r.reachable_cells);

  // Precision and recall with tolerance.
  const std::vector<uint8_t> near_truth = Dilate(truth_occ_set, nx, ny, params.tolerance_cells);
  const std::vector<uint8_t> near_map = Dilate(map_occ, nx, ny, params.tolerance_cells);
  const std::vector<uint8_t> near_reachable = Dilate(reachable, nx, ny, 1);
  {
    std::vector<uint8_t> truth_free(n, 0);
    for (size_t i = 0; i < n; ++i) truth_free[i] = t.v[i] == kFree;
    const std::vector<uint8_t> near_free = Dilate(truth_free, nx, ny, params.tolerance_cells);
    int64_t free_near = 0;
    for (size_t i = 0; i < n; ++i) free_near += m.v[i] == kFree && near_free[i];
    r.free_precision_tolerant = Ratio(free_near, r.map_free_cells);
  }
  int64_t precise = 0, recalled = 0, visible = 0, visible_recalled = 0;
  for (size_t i = 0; i < n; ++i) {
    if (map_occ[i]) precise += near_truth[i];
    if (truth_occ_set[i]) {
      recalled += near_map[i];
      if (near_reachable[i]) {
        ++visible;
        visible_recalled += near_map[i];
      }
    }
  }
  r.occupied_precision = Ratio(precise, r.map_occupied_cells);
  r.occupied_recall = Ratio(recalled, r.truth_occupied_cells);
  r.occupied_recall_visible = Ratio(visible_recalled, visible);

  // Wall thickness: the shorter of the row and column runs through each map-occupied cell near
  // a true wall; cells where both are longer than the cap (corners, blobs) are not measured.
  double thickness_sum = 0.0;
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      const size_t i = ix + static_cast<size_t>(iy) * nx;
      if (!map_occ[i] || !near_truth[i]) continue;
      const int across = std::min(RunThrough(map_occ, nx, ny, ix, iy, 1, 0),
                                  RunThrough(map_occ, nx, ny, ix, iy, 0, 1));
      if (across > params.max_wall_thickness_cells) continue;
      thickness_sum += across;
      ++r.wall_cells_measured;
    }
  }
  r.mean_wall_thickness_cells =
      r.wall_cells_measured > 0 ? thickness_sum / static_cast<double>(r.wall_cells_measured) : kNaN;
  r.mean_wall_thickness_m = r.mean_wall_thickness_cells * r.resolution_m;

  // Double walls along rows and columns.
  for (int iy = 0; iy < ny; ++iy) {
    r.double_wall_crossings += DoubleWallsAlong(
        nx, [&](int k) { return map_occ[k + static_cast<size_t>(iy) * nx] != 0; },
        [&](int k) { return truth_occ_set[k + static_cast<size_t>(iy) * nx] != 0; },
        [&](int k) { return near_truth[k + static_cast<size_t>(iy) * nx] != 0; }, params);
  }
  for (int ix = 0; ix < nx; ++ix) {
    r.double_wall_crossings += DoubleWallsAlong(
        ny, [&](int k) { return map_occ[ix + static_cast<size_t>(k) * nx] != 0; },
        [&](int k) { return truth_occ_set[ix + static_cast<size_t>(k) * nx] != 0; },
        [&](int k) { return near_truth[ix + static_cast<size_t>(k) * nx] != 0; }, params);
  }
  r.double_wall_length_m = r.double_wall_crossings * r.resolution_m;

  // Elevation against the ground, where the truth is free.
  if (map.HasLayer(params.elevation_layer) && truth.HasLayer(kTruthGround)) {
    const common::Layer& z = map.at(params.elevation_layer);
    const common::Layer& g = truth.at(kTruthGround);
    const auto error_over = [&](bool interior_only) {
      ElevationError e;
      double sum_abs = 0.0, sum_sq = 0.0;
      for (size_t i = 0; i < n; ++i) {
        if (t.v[i] != kFree || (interior_only && near_truth[i])) continue;
        const float a = z.data()[i], b = g.data()[i];
        if (std::isnan(a) || std::isnan(b)) continue;
        const double err = static_cast<double>(a) - static_cast<double>(b);
        ++e.cells;
        sum_abs += std::abs(err);
        sum_sq += err * err;
        e.max_abs_m = std::max(e.max_abs_m, std::abs(err));
      }
      if (e.cells > 0) {
        e.mean_abs_m = sum_abs / e.cells;
        e.rms_m = std::sqrt(sum_sq / e.cells);
      } else {
        e.mean_abs_m = e.rms_m = e.max_abs_m = kNaN;
      }
      return e;
    };
    r.elevation = error_over(false);
    r.elevation_interior = error_over(true);
  }
  return r;
}

std::string MapEvalReportToJson(const MapEvalReport& r) {
  std::string s = "{";
  auto field = [&](const char* name, const std::string& value) {
    if (s.size() > 1) s += ", ";
    s += "\"";
    s += name;
    s += "\": " + value;
  };
  auto count = [](int64_t v) { return std::to_string(v); };
  std::string layer;
  for (char c : r.layer) {
    if (c == '"' || c == '\\') layer += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) layer += c;
  }
  field("layer", "\"" + layer + "\"");
  field("resolution_m", Number(r.resolution_m));
  field("truth_cells", count(r.truth_cells));
  field("truth_occupied_cells", count(r.truth_occupied_cells));
  field("truth_free_cells", count(r.truth_free_cells));
  field("map_occupied_cells", count(r.map_occupied_cells));
  field("map_free_cells", count(r.map_free_cells));
  field("map_unknown_cells", count(r.map_unknown_cells));
  field("occupied_precision", Number(r.occupied_precision));
  field("occupied_recall", Number(r.occupied_recall));
  field("occupied_recall_visible", Number(r.occupied_recall_visible));
  field("free_precision", Number(r.free_precision));
  field("free_precision_tolerant", Number(r.free_precision_tolerant));
  field("occupied_iou", Number(r.occupied_iou));
  field("reachable_cells", count(r.reachable_cells));
  field("reachable_known_cells", count(r.reachable_known_cells));
  field("coverage", Number(r.coverage));
  field("wall_cells_measured", count(r.wall_cells_measured));
  field("mean_wall_thickness_cells", Number(r.mean_wall_thickness_cells));
  field("mean_wall_thickness_m", Number(r.mean_wall_thickness_m));
  field("double_wall_crossings", count(r.double_wall_crossings));
  field("double_wall_length_m", Number(r.double_wall_length_m));
  const auto elevation = [&](const char* name, const std::optional<ElevationError>& e) {
    if (!e) {
      field(name, "null");
      return;
    }
    field(name, "{\"cells\": " + count(e->cells) + ", \"mean_abs_m\": " + Number(e->mean_abs_m) +
                    ", \"rms_m\": " + Number(e->rms_m) +
                    ", \"max_abs_m\": " + Number(e->max_abs_m) + "}");
  };
  elevation("elevation", r.elevation);
  elevation("elevation_interior", r.elevation_interior);
  return s + "}";
}

}  // namespace cairn::mapstore
