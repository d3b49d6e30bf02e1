#include "services/explore/info_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cairn::explore {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// A point is steep when its normal is more than 45 degrees from the vertical: |n_z| < cos 45.
constexpr float kSteepNormalZ = 0.70710678f;
// With two levels, a point seen from below more than this under its level's ground lies under
// that surface: more than a deck's thickness, less than a cliff's last half metre.
constexpr float kUnderSurfaceM = 0.5f;

// A per-level layer's name: the lower level's as given, the upper level's under kUpperPrefix.
std::string LevelLayer(const char* lower, int level) {
  if (level == 0) return lower;
  return info_layers::kUpperPrefix + std::string(lower).substr(std::string("explore/").size());
}

}  // namespace

const std::array<InfoMap::Statistic, 13>& InfoMap::Statistics() {
  static const std::array<Statistic, 13> kStatistics = {{
      {info_layers::kPoints, &InfoMap::points_},
      {info_layers::kNavigablePoints, &InfoMap::navigable_points_},
      {info_layers::kObstaclePoints, &InfoMap::obstacle_points_},
      {info_layers::kSumNavigability, &InfoMap::sum_navigability_},
      {info_layers::kSumObstacle, &InfoMap::sum_obstacle_},
      {info_layers::kSumQuality, &InfoMap::sum_quality_},
      {info_layers::kSumX, &InfoMap::sum_x_},
      {info_layers::kSumY, &InfoMap::sum_y_},
      {info_layers::kSumZ, &InfoMap::sum_z_},
      {info_layers::kSumNormalX, &InfoMap::sum_nx_},
      {info_layers::kSumNormalY, &InfoMap::sum_ny_},
      {info_layers::kSumNormalZ, &InfoMap::sum_nz_},
      {info_layers::kSumNavigableZ, &InfoMap::sum_navigable_z_},
  }};
  return kStatistics;
}

void InfoMapParams::Validate() const {
  if (!(cell_size_m > 0.0) || !std::isfinite(cell_size_m)) {
    throw std::invalid_argument("info map: cell_size_m must be positive");
  }
  if (!(tau_f >= 0.0 && tau_f < 1.0)) {
    throw std::invalid_argument("info map: tau_f must lie in [0, 1)");
  }
  if (!(tau_b >= 0.0 && tau_b < 1.0)) {
    throw std::invalid_argument("info map: tau_b must lie in [0, 1)");
  }
  if (!(margin_m >= 0.0) || !std::isfinite(margin_m)) {
    throw std::invalid_argument("info map: margin_m must be >= 0");
  }
  if (!(max_step_m >= 0.0) || !std::isfinite(max_step_m)) {
    throw std::invalid_argument("info map: max_step_m must be >= 0 (0: no step term)");
  }
  if (!(level_gap_m >= 0.0) || !std::isfinite(level_gap_m)) {
    throw std::invalid_argument("info map: level_gap_m must be >= 0 (0: one level per cell)");
  }
}

double CellNavigability(double navigable_points, double sum_navigability, double obstacle_points,
                        double sum_obstacle) {
  const double total = navigable_points + obstacle_points;
  if (!(total > 0.0)) return 0.5;
  const double f_c = navigable_points > 0.0 ? sum_navigability / navigable_points : 0.0;
  const double b_c = obstacle_points > 0.0 ? sum_obstacle / obstacle_points : 0.0;
  const double r_fo = navigable_points / total;
  return r_fo * (0.5 + f_c / 2.0) + (1.0 - r_fo) * (0.5 - b_c / 2.0);
}

InfoMap::InfoMap(const WorkArea& area, const InfoMapParams& params) : area_(area), params_(params) {
  area_.Validate();
  params_.Validate();
  num_levels_ = params_.level_gap_m > 0.0 ? 2 : 1;
  const common::Vector2 lo = area_.MinCorner().array() - params_.margin_m;
  const common::Vector2 hi = area_.MaxCorner().array() + params_.margin_m;
  const double res = params_.cell_size_m;
  const double cells_x = std::ceil((hi.x() - lo.x()) / res);
  const double cells_y = std::ceil((hi.y() - lo.y()) / res);
  if (cells_x * cells_y * num_levels_ > 64.0e6) {
    throw std::invalid_argument(
        "info map: the work area needs " + std::to_string(static_cast<int64_t>(cells_x * cells_y)) +
        " cells of " + std::to_string(num_levels_) + " levels, more than 64 million nodes");
  }
  geometry_.resolution_m = res;
  geometry_.size_x = static_cast<int>(cells_x);
  geometry_.size_y = static_cast<int>(cells_y);
  geometry_.origin = common::Pose2{lo.x(), lo.y(), 0.0};
  const size_t n = static_cast<size_t>(geometry_.num_cells());
  in_area_.assign(n, 0);
  cell_explored_.assign(n, 0);
  for (int iy = 0; iy < geometry_.size_y; ++iy) {
    for (int ix = 0; ix < geometry_.size_x; ++ix) {
      const common::CellIndex c{ix, iy};
      if (area_.Contains(geometry_.CenterOf(c))) {
        in_area_[Linear(c)] = 1;
        ++work_area_cells_;
      }
    }
  }
  steep_low_z_.assign(n, kNaN);
  steep_high_z_.assign(n, kNaN);
  if (num_levels_ > 1) floor_z_.assign(n, kNaN);
  const size_t nodes = n * static_cast<size_t>(num_levels_);
  for (const Statistic& s : Statistics()) (this->*s.values).assign(nodes, 0.f);
  step_low_z_.assign(nodes, kNaN);
  step_high_z_.assign(nodes, kNaN);
  navigability_.assign(nodes, 0.5f);
  quality_.assign(nodes, kNaN);
}

void InfoMap::AddToNode(int64_t i, const ScoredPoint& p, bool steep, bool counts) {
  points_[i] += 1.f;
  sum_quality_[i] += p.quality;
  sum_x_[i] += p.position_m.x();
  sum_y_[i] += p.position_m.y();
  sum_z_[i] += p.position_m.z();
  if (p.normal.allFinite()) {
    sum_nx_[i] += p.normal.x();
    sum_ny_[i] += p.normal.y();
    sum_nz_[i] += p.normal.z();
  }
  if (!counts) return;
  if (steep) {
    // fmin/fmax: NaN (none yet) gives way to the point's height.
    step_low_z_[i] = std::fmin(step_low_z_[i], p.position_m.z());
    step_high_z_[i] = std::fmax(step_high_z_[i], p.position_m.z());
  }
  if (p.navigability > static_cast<float>(params_.tau_f)) {
    navigable_points_[i] += 1.f;
    sum_navigability_[i] += p.navigability;
    sum_navigable_z_[i] += p.position_m.z();
  }
  if (p.obstacle > static_cast<float>(params_.tau_b)) {
    obstacle_points_[i] += 1.f;
    sum_obstacle_[i] += p.obstacle;
  }
}

void InfoMap::LiftLowerLevel(int64_t cell) {
  const int64_t up = cell + num_cells();
  for (const Statistic& s : Statistics()) {
    std::vector<float>& v = this->*s.values;
    v[up] = v[cell];
    v[cell] = 0.f;
  }
  step_low_z_[up] = step_low_z_[cell];
  step_high_z_[up] = step_high_z_[cell];
  step_low_z_[cell] = step_high_z_[cell] = kNaN;
}

int64_t InfoMap::AddPoints(const std::vector<ScoredPoint>& points, float scanner_z_m) {
  const int64_t cells = num_cells();
  std::vector<int64_t> touched;
  touched.reserve(1024);
  std::vector<uint8_t> mark(static_cast<size_t>(cells), 0);
  const bool two = num_levels_ > 1;
  const float gap = static_cast<float>(params_.level_gap_m);
  // With two levels the points go in by height, lowest first: a cell's lowest point opens its
  // lower level before anything above it is placed.
  std::vector<uint32_t> order;
  if (two) {
    order.reserve(points.size());
    for (size_t k = 0; k < points.size(); ++k) {
      if (points[k].position_m.allFinite()) order.push_back(static_cast<uint32_t>(k));
    }
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return points[a].position_m.z() < points[b].position_m.z();
    });
  }
  const size_t count = two ? order.size() : points.size();
  int64_t used = 0;
  for (size_t k = 0; k < count; ++k) {
    const ScoredPoint& p = points[two ? order[k] : k];
    if (!p.position_m.allFinite() || !std::isfinite(p.navigability) || !std::isfinite(p.obstacle) ||
        !std::isfinite(p.quality)) {
      continue;
    }
    const auto cell = geometry_.IndexOf({p.position_m.x(), p.position_m.y()});
    if (!cell) continue;
    const int64_t c = Linear(*cell);
    const float z = p.position_m.z();
    // Steep: the normal more than 45 degrees from the vertical (a zero normal is none).
    const bool steep =
        p.normal.allFinite() && std::abs(p.normal.z()) < kSteepNormalZ * p.normal.norm();
    if (steep) {
      steep_low_z_[c] = std::fmin(steep_low_z_[c], z);
      steep_high_z_[c] = std::fmax(steep_high_z_[c], z);
    }
    int64_t node = c;
    bool counts = true;
    if (two) {
      if (std::isnan(floor_z_[c])) {
        floor_z_[c] = z;
      } else if (z > floor_z_[c] + gap) {
        // Above the lower level: its navigability counts what was seen from above only.
        node = c + cells;
        counts = !(scanner_z_m < z);
      } else if (z < floor_z_[c] - gap && !(points_[c + cells] > 0.f)) {
        // A surface below everything seen so far (the road under a deck seen first from the
        // deck): what was the lower level is now the upper one.
        LiftLowerLevel(c);
        floor_z_[c] = z;
      } else {
        floor_z_[c] = std::min(floor_z_[c], z);
        // Seen from below, well under the lower level's ground as seen from above: under that
        // surface (the wall below a deck's end, seen from the road), nothing to a robot on it.
        counts = !(scanner_z_m < z && z < GroundHeight(c) - kUnderSurfaceM);
      }
    }
    AddToNode(node, p, steep, counts);
    if (!mark[c]) {
      mark[c] = 1;
      touched.push_back(c);
    }
    ++used;
  }
  for (int64_t c : touched) {
    for (int l = 0; l < num_levels_; ++l) UpdateNode(c + l * cells);
  }
  // A step is judged against the 4 neighbours' ground too: theirs may have changed.
  if (params_.max_step_m > 0.0) {
    const int sx = geometry_.size_x, sy = geometry_.size_y;
    for (size_t t = 0, n = touched.size(); t < n; ++t) {
      const common::CellIndex c = Cell(touched[t]);
      const int64_t around[4][2] = {
          {c.ix - 1, c.iy}, {c.ix + 1, c.iy}, {c.ix, c.iy - 1}, {c.ix, c.iy + 1}};
      for (const auto& a : around) {
        if (a[0] < 0 || a[1] < 0 || a[0] >= sx || a[1] >= sy) continue;
        const int64_t j = a[0] + a[1] * static_cast<int64_t>(sx);
        if (mark[j]) continue;
        mark[j] = 2;
        for (int l = 0; l < num_levels_; ++l) UpdateNavigability(j + l * cells);
      }
    }
  }
  return used;
}

void InfoMap::UpdateNode(int64_t i) {
  UpdateNavigability(i);
  quality_[i] = points_[i] > 0.f ? sum_quality_[i] / points_[i] : kNaN;
  const int64_t c = NodeCell(i);
  if (!cell_explored_[c] && points_[i] > 0.f) {
    cell_explored_[c] = 1;
    if (in_area_[c]) ++explored_in_area_;
  }
}

int64_t InfoMap::NearestLevel(int64_t cell, float z_m) const {
  cell = NodeCell(cell);
  if (num_levels_ == 1 || std::isnan(z_m)) return cell;
  int64_t best = cell;
  float best_d = std::numeric_limits<float>::infinity();
  for (int l = 0; l < num_levels_; ++l) {
    const int64_t node = cell + l * num_cells();
    if (!(points_[node] > 0.f)) continue;
    float h = GroundHeight(node);
    if (std::isnan(h)) h = sum_z_[node] / points_[node];
    const float d = std::abs(h - z_m);
    if (d < best_d) {
      best_d = d;
      best = node;
    }
  }
  return best;
}

bool InfoMap::HasStep(int64_t i) const {
  const float step = static_cast<float>(params_.max_step_m);
  if (!(step > 0.f)) return false;
  // Steep points spanning more than the step: a kerb's face, a wall's foot (NaN compares
  // false).
  if (step_high_z_[i] - step_low_z_[i] > step) return true;
  // Or ground more than the step above or below a 4-neighbour's: a kerb's edge between two
  // cells. A slope the robot may climb rises less than this over one cell (12 degrees: 6 cm).
  const float h = GroundHeight(i);
  if (std::isnan(h)) return false;
  const int64_t cell = NodeCell(i);
  const common::CellIndex c = Cell(cell);
  const int sx = geometry_.size_x, sy = geometry_.size_y;
  auto differs = [&](int64_t j) { return std::abs(GroundHeight(NearestLevel(j, h)) - h) > step; };
  if (c.ix > 0 && differs(cell - 1)) return true;
  if (c.ix + 1 < sx && differs(cell + 1)) return true;
  if (c.iy > 0 && differs(cell - sx)) return true;
  if (c.iy + 1 < sy && differs(cell + sx)) return true;
  return false;
}

void InfoMap::UpdateNavigability(int64_t i) {
  navigability_[i] = static_cast<float>(CellNavigability(navigable_points_[i], sum_navigability_[i],
                                                         obstacle_points_[i], sum_obstacle_[i]));
  if (HasStep(i)) navigability_[i] = std::min(navigability_[i], kStepCnc);
}

Eigen::Vector3f InfoMap::Centroid(int64_t i) const {
  if (!(points_[i] > 0.f)) return Eigen::Vector3f::Constant(kNaN);
  return Eigen::Vector3f(sum_x_[i], sum_y_[i], sum_z_[i]) / points_[i];
}

float InfoMap::GroundHeight(int64_t i) const {
  return navigable_points_[i] > 0.f ? sum_navigable_z_[i] / navigable_points_[i] : kNaN;
}

Eigen::Vector3f InfoMap::MeanNormal(int64_t i) const {
  const Eigen::Vector3f n(sum_nx_[i], sum_ny_[i], sum_nz_[i]);
  const float norm = n.norm();
  return norm > 1e-6f ? Eigen::Vector3f(n / norm) : Eigen::Vector3f::Zero();
}

float InfoMap::CellQuality(int64_t cell) const {
  cell = NodeCell(cell);
  if (num_levels_ == 1) return quality_[cell];
  const int64_t up = cell + num_cells();
  const float n = points_[cell] + points_[up];
  return n > 0.f ? (sum_quality_[cell] + sum_quality_[up]) / n : kNaN;
}

Eigen::Vector3f InfoMap::CellCentroid(int64_t cell) const {
  cell = NodeCell(cell);
  if (num_levels_ == 1) return Centroid(cell);
  const int64_t up = cell + num_cells();
  const float n = points_[cell] + points_[up];
  if (!(n > 0.f)) return Eigen::Vector3f::Constant(kNaN);
  return Eigen::Vector3f(sum_x_[cell] + sum_x_[up], sum_y_[cell] + sum_y_[up],
                         sum_z_[cell] + sum_z_[up]) /
         n;
}

Eigen::Vector3f InfoMap::CellMeanNormal(int64_t cell) const {
  cell = NodeCell(cell);
  if (num_levels_ == 1) return MeanNormal(cell);
  const int64_t up = cell + num_cells();
  const Eigen::Vector3f n(sum_nx_[cell] + sum_nx_[up], sum_ny_[cell] + sum_ny_[up],
                          sum_nz_[cell] + sum_nz_[up]);
  const float norm = n.norm();
  return norm > 1e-6f ? Eigen::Vector3f(n / norm) : Eigen::Vector3f::Zero();
}

double InfoMap::Coverage() const {
  return work_area_cells_ > 0
             ? static_cast<double>(explored_in_area_) / static_cast<double>(work_area_cells_)
             : 0.0;
}

double InfoMap::MeanQuality() const {
  double sum = 0.0;
  int64_t n = 0;
  for (int64_t i = 0; i < num_cells(); ++i) {
    if (in_area_[i] && cell_explored_[i]) {
      sum += CellQuality(i);
      ++n;
    }
  }
  return n > 0 ? sum / static_cast<double>(n) : 0.0;
}

common::GridMap InfoMap::ToGridMap() const {
  common::GridMap grid(geometry_);
  const size_t n = static_cast<size_t>(num_cells());
  auto put = [&](const std::string& name, const std::vector<float>& v, size_t offset) {
    common::Layer& layer = grid.AddLayer(name, 0.f);
    std::copy(v.begin() + static_cast<std::ptrdiff_t>(offset),
              v.begin() + static_cast<std::ptrdiff_t>(offset + n), layer.data());
  };
  std::vector<float> area(n);
  for (size_t i = 0; i < n; ++i) area[i] = in_area_[i] ? 1.f : 0.f;
  put(info_layers::kWorkArea, area, 0);
  put(info_layers::kSteepLowZ, steep_low_z_, 0);
  put(info_layers::kSteepHighZ, steep_high_z_, 0);
  if (num_levels_ > 1) put(info_layers::kFloorZ, floor_z_, 0);
  for (int l = 0; l < num_levels_; ++l) {
    const size_t offset = n * static_cast<size_t>(l);
    std::vector<float> nav(n), explored(n);
    for (size_t i = 0; i < n; ++i) {
      const bool seen = points_[offset + i] > 0.f;
      nav[i] = seen ? navigability_[offset + i] : kNaN;
      explored[i] = seen ? 1.f : 0.f;
    }
    put(LevelLayer(info_layers::kNavigability, l), nav, 0);
    put(LevelLayer(info_layers::kQuality, l), quality_, offset);
    put(LevelLayer(info_layers::kExplored, l), explored, 0);
    for (const Statistic& s : Statistics()) put(LevelLayer(s.layer, l), this->*s.values, offset);
    if (num_levels_ > 1) {
      put(LevelLayer(info_layers::kStepLowZ, l), step_low_z_, offset);
      put(LevelLayer(info_layers::kStepHighZ, l), step_high_z_, offset);
    }
  }
  return grid;
}

InfoMap InfoMap::FromGridMap(const common::GridMap& grid, const WorkArea& area,
                             const InfoMapParams& params) {
  InfoMap map(area, params);
  if (grid.geometry() != map.geometry_) {
    throw std::invalid_argument(
        "info map: the stored grid's geometry differs from the work area's grid");
  }
  const size_t n = static_cast<size_t>(map.num_cells());
  auto get = [&](const std::string& name, std::vector<float>* v, size_t offset) {
    if (!grid.HasLayer(name)) {
      throw std::invalid_argument("info map: layer '" + name + "' is missing");
    }
    const common::Layer& layer = grid.at(name);
    std::copy(layer.data(), layer.data() + n, v->begin() + static_cast<std::ptrdiff_t>(offset));
  };
  // A map stored with one level loads with one level (its upper one empty); a map stored with two
  // loaded with one keeps its lower level.
  const bool stored_upper = grid.HasLayer(std::string(info_layers::kUpperPrefix) + "points");
  for (int l = 0; l < map.num_levels_; ++l) {
    if (l == 1 && !stored_upper) break;
    const size_t offset = n * static_cast<size_t>(l);
    for (const Statistic& s : Statistics()) get(LevelLayer(s.layer, l), &(map.*s.values), offset);
    if (grid.HasLayer(LevelLayer(info_layers::kStepLowZ, l))) {
      get(LevelLayer(info_layers::kStepLowZ, l), &map.step_low_z_, offset);
      get(LevelLayer(info_layers::kStepHighZ, l), &map.step_high_z_, offset);
    }
  }
  if (grid.HasLayer(info_layers::kSteepLowZ)) {
    get(info_layers::kSteepLowZ, &map.steep_low_z_, 0);
    get(info_layers::kSteepHighZ, &map.steep_high_z_, 0);
  }
  // Stored without a lower level's own steep range (one level): the cell's is the level's.
  if (!grid.HasLayer(info_layers::kStepLowZ)) {
    std::copy(map.steep_low_z_.begin(), map.steep_low_z_.end(), map.step_low_z_.begin());
    std::copy(map.steep_high_z_.begin(), map.steep_high_z_.end(), map.step_high_z_.begin());
  }
  if (map.num_levels_ > 1) {
    if (grid.HasLayer(info_layers::kFloorZ)) {
      get(info_layers::kFloorZ, &map.floor_z_, 0);
    } else {
      // Stored with one level: its points' mean height stands in for the lowest.
      for (size_t i = 0; i < n; ++i) {
        if (map.points_[i] > 0.f) map.floor_z_[i] = map.sum_z_[i] / map.points_[i];
      }
    }
  }
  for (int64_t i = 0; i < map.num_nodes(); ++i) {
    if (!(map.points_[i] >= 0.f) || !std::isfinite(map.points_[i])) {
      throw std::invalid_argument("info map: cell " + std::to_string(map.NodeCell(i)) +
                                  " has a negative or non-finite point count");
    }
  }
  for (int64_t i = 0; i < map.num_nodes(); ++i) map.UpdateNode(i);
  return map;
}

std::vector<ScoredPoint> FillSurfaceCells(const InfoMap& map,
                                          const std::vector<ScoredPoint>& points,
                                          const std::vector<uint8_t>& valid,
                                          const std::vector<Eigen::Vector3i>& triangles) {
  const common::GridGeometry& geometry = map.geometry();
  if (valid.size() != points.size()) {
    throw std::invalid_argument("info map: valid flags and points differ in size");
  }
  std::vector<ScoredPoint> filled;
  if (geometry.num_cells() == 0) return filled;
  // 0 untouched, 1 explored or a point fell in it, 2 filled by this call.
  std::vector<uint8_t> state(static_cast<size_t>(geometry.num_cells()), 0);
  for (int64_t i = 0; i < geometry.num_cells(); ++i) {
    if (map.CellExplored(i)) state[static_cast<size_t>(i)] = 1;
  }
  for (size_t i = 0; i < points.size(); ++i) {
    if (!valid[i]) continue;
    const auto cell = geometry.IndexOf({points[i].position_m.x(), points[i].position_m.y()});
    if (cell) state[static_cast<size_t>(geometry.LinearIndex(*cell))] = 1;
  }
  const double res = geometry.resolution_m;
  const int64_t n = static_cast<int64_t>(points.size());
  for (const Eigen::Vector3i& t : triangles) {
    if (t.minCoeff() < 0 || t.maxCoeff() >= n || !valid[t[0]] || !valid[t[1]] || !valid[t[2]]) {
      continue;
    }
    const ScoredPoint& a = points[t[0]];
    const ScoredPoint& b = points[t[1]];
    const ScoredPoint& c = points[t[2]];
    const double ax = a.position_m.x(), ay = a.position_m.y();
    const double bx = b.position_m.x() - ax, by = b.position_m.y() - ay;
    const double cx = c.position_m.x() - ax, cy = c.position_m.y() - ay;
    const double det = bx * cy - by * cx;  // twice the signed projected area
    if (!(std::abs(det) > 2e-6)) continue;
    const double min_x = std::min({ax, ax + bx, ax + cx}), max_x = std::max({ax, ax + bx, ax + cx});
    const double min_y = std::min({ay, ay + by, ay + cy}), max_y = std::max({ay, ay + by, ay + cy});
    const int ix0 =
        std::max(0, static_cast<int>(std::ceil((min_x - geometry.origin.x_m) / res - 0.5)));
    const int ix1 =
        std::min(geometry.size_x - 1,
                 static_cast<int>(std::floor((max_x - geometry.origin.x_m) / res - 0.5)));
    const int iy0 =
        std::max(0, static_cast<int>(std::ceil((min_y - geometry.origin.y_m) / res - 0.5)));
    const int iy1 =
        std::min(geometry.size_y - 1,
                 static_cast<int>(std::floor((max_y - geometry.origin.y_m) / res - 0.5)));
    for (int iy = iy0; iy <= iy1; ++iy) {
      for (int ix = ix0; ix <= ix1; ++ix) {
        const size_t k = static_cast<size_t>(ix + static_cast<int64_t>(iy) * geometry.size_x);
        if (state[k] != 0) continue;
        const double px = geometry.origin.x_m + (ix + 0.5) * res - ax;
        const double py = geometry.origin.y_m + (iy + 0.5) * res - ay;
        // Barycentric weights of the cell centre (u on b, v on c).
        const double u = (px * cy - py * cx) / det;
        const double v = (bx * py - by * px) / det;
        if (u < 0.0 || v < 0.0 || u + v > 1.0) continue;
        const float wa = static_cast<float>(1.0 - u - v), wb = static_cast<float>(u),
                    wc = static_cast<float>(v);
        ScoredPoint p;
        p.position_m = wa * a.position_m + wb * b.position_m + wc * c.position_m;
        const Eigen::Vector3f normal = wa * a.normal + wb * b.normal + wc * c.normal;
        p.normal =
            normal.norm() > 1e-6f ? Eigen::Vector3f(normal.normalized()) : Eigen::Vector3f::Zero();
        p.navigability = wa * a.navigability + wb * b.navigability + wc * c.navigability;
        p.obstacle = wa * a.obstacle + wb * b.obstacle + wc * c.obstacle;
        p.quality = wa * a.quality + wb * b.quality + wc * c.quality;
        state[k] = 2;
        filled.push_back(p);
      }
    }
  }
  return filled;
}

}  // namespace cairn::explore
