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

}  // namespace

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
  const common::Vector2 lo = area_.MinCorner().array() - params_.margin_m;
  const common::Vector2 hi = area_.MaxCorner().array() + params_.margin_m;
  const double res = params_.cell_size_m;
  const double cells_x = std::ceil((hi.x() - lo.x()) / res);
  const double cells_y = std::ceil((hi.y() - lo.y()) / res);
  if (cells_x * cells_y > 64.0e6) {
    throw std::invalid_argument("info map: the work area needs " +
                                std::to_string(static_cast<int64_t>(cells_x * cells_y)) +
                                " cells, more than 64 million");
  }
  geometry_.resolution_m = res;
  geometry_.size_x = static_cast<int>(cells_x);
  geometry_.size_y = static_cast<int>(cells_y);
  geometry_.origin = common::Pose2{lo.x(), lo.y(), 0.0};
  const size_t n = static_cast<size_t>(geometry_.num_cells());
  in_area_.assign(n, 0);
  for (int iy = 0; iy < geometry_.size_y; ++iy) {
    for (int ix = 0; ix < geometry_.size_x; ++ix) {
      const common::CellIndex c{ix, iy};
      if (area_.Contains(geometry_.CenterOf(c))) {
        in_area_[Linear(c)] = 1;
        ++work_area_cells_;
      }
    }
  }
  for (auto* v : {&points_, &navigable_points_, &obstacle_points_, &sum_navigability_,
                  &sum_obstacle_, &sum_quality_, &sum_x_, &sum_y_, &sum_z_, &sum_nx_, &sum_ny_,
                  &sum_nz_, &sum_navigable_z_}) {
    v->assign(n, 0.f);
  }
  steep_low_z_.assign(n, kNaN);
  steep_high_z_.assign(n, kNaN);
  navigability_.assign(n, 0.5f);
  quality_.assign(n, kNaN);
}

int64_t InfoMap::AddPoints(const std::vector<ScoredPoint>& points) {
  std::vector<int64_t> touched;
  touched.reserve(1024);
  std::vector<uint8_t> mark(static_cast<size_t>(num_cells()), 0);
  const float tau_f = static_cast<float>(params_.tau_f);
  const float tau_b = static_cast<float>(params_.tau_b);
  int64_t used = 0;
  for (const ScoredPoint& p : points) {
    if (!p.position_m.allFinite() || !std::isfinite(p.navigability) || !std::isfinite(p.obstacle) ||
        !std::isfinite(p.quality)) {
      continue;
    }
    const auto cell = geometry_.IndexOf({p.position_m.x(), p.position_m.y()});
    if (!cell) continue;
    const int64_t i = Linear(*cell);
    points_[i] += 1.f;
    sum_quality_[i] += p.quality;
    sum_x_[i] += p.position_m.x();
    sum_y_[i] += p.position_m.y();
    sum_z_[i] += p.position_m.z();
    if (p.normal.allFinite()) {
      sum_nx_[i] += p.normal.x();
      sum_ny_[i] += p.normal.y();
      sum_nz_[i] += p.normal.z();
      // Steep: the normal more than 45 degrees from the vertical (a zero normal is none).
      const float nz = std::abs(p.normal.z());
      if (nz < kSteepNormalZ * p.normal.norm()) {
        // fmin/fmax: NaN (none yet) gives way to the point's height.
        steep_low_z_[i] = std::fmin(steep_low_z_[i], p.position_m.z());
        steep_high_z_[i] = std::fmax(steep_high_z_[i], p.position_m.z());
      }
    }
    if (p.navigability > tau_f) {
      navigable_points_[i] += 1.f;
      sum_navigability_[i] += p.navigability;
      sum_navigable_z_[i] += p.position_m.z();
    }
    if (p.obstacle > tau_b) {
      obstacle_points_[i] += 1.f;
      sum_obstacle_[i] += p.obstacle;
    }
    if (!mark[i]) {
      mark[i] = 1;
      touched.push_back(i);
    }
    ++used;
  }
  for (int64_t i : touched) UpdateCell(i);
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
        UpdateNavigability(j);
      }
    }
  }
  return used;
}

void InfoMap::UpdateCell(int64_t i) {
  const bool was_explored = !std::isnan(quality_[i]);
  UpdateNavigability(i);
  quality_[i] = points_[i] > 0.f ? sum_quality_[i] / points_[i] : kNaN;
  if (!was_explored && points_[i] > 0.f && in_area_[i]) ++explored_in_area_;
}

bool InfoMap::HasStep(int64_t i) const {
  const float step = static_cast<float>(params_.max_step_m);
  if (!(step > 0.f)) return false;
  // Steep points spanning more than the step: a kerb's face, a wall's foot (NaN compares
  // false).
  if (steep_high_z_[i] - steep_low_z_[i] > step) return true;
  // Or ground more than the step above or below a 4-neighbour's: a kerb's edge between two
  // cells. A slope the robot may climb rises less than this over one cell (12 degrees: 6 cm).
  const float h = GroundHeight(i);
  if (std::isnan(h)) return false;
  const common::CellIndex c = Cell(i);
  const int sx = geometry_.size_x, sy = geometry_.size_y;
  if (c.ix > 0 && std::abs(GroundHeight(i - 1) - h) > step) return true;
  if (c.ix + 1 < sx && std::abs(GroundHeight(i + 1) - h) > step) return true;
  if (c.iy > 0 && std::abs(GroundHeight(i - sx) - h) > step) return true;
  if (c.iy + 1 < sy && std::abs(GroundHeight(i + sx) - h) > step) return true;
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

double InfoMap::Coverage() const {
  return work_area_cells_ > 0
             ? static_cast<double>(explored_in_area_) / static_cast<double>(work_area_cells_)
             : 0.0;
}

double InfoMap::MeanQuality() const {
  double sum = 0.0;
  int64_t n = 0;
  for (int64_t i = 0; i < num_cells(); ++i) {
    if (in_area_[i] && points_[i] > 0.f) {
      sum += quality_[i];
      ++n;
    }
  }
  return n > 0 ? sum / static_cast<double>(n) : 0.0;
}

common::GridMap InfoMap::ToGridMap() const {
  common::GridMap grid(geometry_);
  auto put = [&](const char* name, const std::vector<float>& v) {
    common::Layer& layer = grid.AddLayer(name, 0.f);
    std::copy(v.begin(), v.end(), layer.data());
  };
  std::vector<float> nav(navigability_);
  std::vector<float> explored(navigability_.size());
  std::vector<float> area(navigability_.size());
  for (size_t i = 0; i < nav.size(); ++i) {
    if (!(points_[i] > 0.f)) nav[i] = kNaN;
    explored[i] = points_[i] > 0.f ? 1.f : 0.f;
    area[i] = in_area_[i] ? 1.f : 0.f;
  }
  put(info_layers::kNavigability, nav);
  put(info_layers::kQuality, quality_);
  put(info_layers::kExplored, explored);
  put(info_layers::kWorkArea, area);
  put(info_layers::kPoints, points_);
  put(info_layers::kNavigablePoints, navigable_points_);
  put(info_layers::kObstaclePoints, obstacle_points_);
  put(info_layers::kSumNavigability, sum_navigability_);
  put(info_layers::kSumObstacle, sum_obstacle_);
  put(info_layers::kSumQuality, sum_quality_);
  put(info_layers::kSumX, sum_x_);
  put(info_layers::kSumY, sum_y_);
  put(info_layers::kSumZ, sum_z_);
  put(info_layers::kSumNormalX, sum_nx_);
  put(info_layers::kSumNormalY, sum_ny_);
  put(info_layers::kSumNormalZ, sum_nz_);
  put(info_layers::kSumNavigableZ, sum_navigable_z_);
  put(info_layers::kSteepLowZ, steep_low_z_);
  put(info_layers::kSteepHighZ, steep_high_z_);
  return grid;
}

InfoMap InfoMap::FromGridMap(const common::GridMap& grid, const WorkArea& area,
                             const InfoMapParams& params) {
  InfoMap map(area, params);
  if (grid.geometry() != map.geometry_) {
    throw std::invalid_argument(
        "info map: the stored grid's geometry differs from the work area's grid");
  }
  auto get = [&](const char* name, std::vector<float>* v) {
    if (!grid.HasLayer(name)) {
      throw std::invalid_argument(std::string("info map: layer '") + name + "' is missing");
    }
    const common::Layer& layer = grid.at(name);
    v->assign(layer.data(), layer.data() + layer.size());
  };
  get(info_layers::kPoints, &map.points_);
  get(info_layers::kNavigablePoints, &map.navigable_points_);
  get(info_layers::kObstaclePoints, &map.obstacle_points_);
  get(info_layers::kSumNavigability, &map.sum_navigability_);
  get(info_layers::kSumObstacle, &map.sum_obstacle_);
  get(info_layers::kSumQuality, &map.sum_quality_);
  get(info_layers::kSumX, &map.sum_x_);
  get(info_layers::kSumY, &map.sum_y_);
  get(info_layers::kSumZ, &map.sum_z_);
  get(info_layers::kSumNormalX, &map.sum_nx_);
  get(info_layers::kSumNormalY, &map.sum_ny_);
  get(info_layers::kSumNormalZ, &map.sum_nz_);
  get(info_layers::kSumNavigableZ, &map.sum_navigable_z_);
  if (grid.HasLayer(info_layers::kSteepLowZ)) get(info_layers::kSteepLowZ, &map.steep_low_z_);
  if (grid.HasLayer(info_layers::kSteepHighZ)) get(info_layers::kSteepHighZ, &map.steep_high_z_);
  for (int64_t i = 0; i < map.num_cells(); ++i) {
    if (!(map.points_[i] >= 0.f) || !std::isfinite(map.points_[i])) {
      throw std::invalid_argument("info map: cell " + std::to_string(i) +
                                  " has a negative or non-finite point count");
    }
    map.UpdateCell(i);
  }
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
    if (map.Explored(i)) state[static_cast<size_t>(i)] = 1;
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
