#include "services/explore/frontier.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

#include "common/check.h"

namespace cairn::explore {

namespace {

using common::CellIndex;
using common::Vector2;

enum CellClass : uint8_t { kFree, kOccupied, kUnknown, kUncertain };

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int64_t kFar = std::numeric_limits<int64_t>::max();  // beyond the clearance

// The 8 neighbours; the first four are the 4-neighbours.
constexpr int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
constexpr int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};

CellClass Classify(float value, const FrontierParams& params) {
  if (std::isnan(value)) return kUnknown;
  if (value < params.free_threshold) return kFree;
  if (value > params.occupied_threshold) return kOccupied;
  return kUncertain;
}

// Squared distance (cells²) from each cell centre to the nearest occupied cell centre, exact
// within `radius` cells and kFar beyond it.
std::vector<int64_t> OccupiedDistanceSq(const std::vector<uint8_t>& classes, int size_x, int size_y,
                                        int radius) {
  std::vector<int64_t> d2(classes.size(), kFar);
  for (int iy = 0; iy < size_y; ++iy) {
    for (int ix = 0; ix < size_x; ++ix) {
      if (classes[ix + static_cast<int64_t>(iy) * size_x] != kOccupied) continue;
      for (int dy = -radius; dy <= radius; ++dy) {
        const int y = iy + dy;
        if (y < 0 || y >= size_y) continue;
        for (int dx = -radius; dx <= radius; ++dx) {
          const int x = ix + dx;
          if (x < 0 || x >= size_x) continue;
          int64_t& cell = d2[x + static_cast<int64_t>(y) * size_x];
          cell = std::min<int64_t>(cell, int64_t{dx} * dx + int64_t{dy} * dy);
        }
      }
    }
  }
  return d2;
}

}  // namespace

void FrontierParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(free_threshold),
                     "FrontierParams.free_threshold must be finite, got " << free_threshold);
  CAIRN_THROW_UNLESS(
      std::isfinite(occupied_threshold),
      "FrontierParams.occupied_threshold must be finite, got " << occupied_threshold);
  CAIRN_THROW_UNLESS(free_threshold <= occupied_threshold,
                     "FrontierParams.free_threshold (" << free_threshold
                                                       << ") must not exceed occupied_threshold ("
                                                       << occupied_threshold << ")");
  CAIRN_THROW_UNLESS(
      std::isfinite(min_frontier_size_m) && min_frontier_size_m >= 0.0,
      "FrontierParams.min_frontier_size_m must be >= 0 and finite, got " << min_frontier_size_m);
  CAIRN_THROW_UNLESS(
      std::isfinite(potential_scale) && potential_scale >= 0.0,
      "FrontierParams.potential_scale must be >= 0 and finite, got " << potential_scale);
  CAIRN_THROW_UNLESS(std::isfinite(gain_scale) && gain_scale >= 0.0,
                     "FrontierParams.gain_scale must be >= 0 and finite, got " << gain_scale);
  CAIRN_THROW_UNLESS(std::isfinite(clearance_m) && clearance_m >= 0.0,
                     "FrontierParams.clearance_m must be >= 0 and finite, got " << clearance_m);
  CAIRN_THROW_UNLESS(
      std::isfinite(goal_clearance_m) && goal_clearance_m >= 0.0,
      "FrontierParams.goal_clearance_m must be >= 0 and finite, got " << goal_clearance_m);
  CAIRN_THROW_UNLESS(
      std::isfinite(blacklist_radius_m) && blacklist_radius_m >= 0.0,
      "FrontierParams.blacklist_radius_m must be >= 0 and finite, got " << blacklist_radius_m);
}

std::vector<Frontier> FindFrontiers(const common::GridMap& map, const std::string& layer,
                                    const Vector2& robot_m, const FrontierParams& params) {
  params.Validate();
  CAIRN_THROW_UNLESS(map.HasLayer(layer), "FindFrontiers: the map has no layer '" << layer << "'");
  CAIRN_THROW_UNLESS(robot_m.allFinite(), "FindFrontiers: the robot position must be finite, got ("
                                              << robot_m.x() << ", " << robot_m.y() << ")");
  const std::optional<CellIndex> robot_cell = map.IndexOf(robot_m);
  CAIRN_THROW_UNLESS(robot_cell.has_value(), "FindFrontiers: the robot position ("
                                                 << robot_m.x() << ", " << robot_m.y()
                                                 << ") lies outside the grid");

  const common::GridGeometry& geometry = map.geometry();
  const int size_x = geometry.size_x;
  const int size_y = geometry.size_y;
  const double resolution_m = geometry.resolution_m;
  const int64_t num_cells = geometry.num_cells();
  const float* values = map.at(layer).data();
  auto index = [size_x](int ix, int iy) { return ix + static_cast<int64_t>(iy) * size_x; };
  auto inside = [size_x, size_y](int ix, int iy) {
    return ix >= 0 && iy >= 0 && ix < size_x && iy < size_y;
  };

  std::vector<uint8_t> classes(num_cells);
  for (int64_t i = 0; i < num_cells; ++i) classes[i] = Classify(values[i], params);

  // Clearance: a cell is too close when its distance to the nearest occupied cell is below
  // clearance_m (a small tolerance keeps a distance of exactly clearance_m clear).
  const double clearance_cells = params.clearance_m / resolution_m;
  const double goal_clearance_cells = params.goal_clearance_m / resolution_m;
  const int radius = static_cast<int>(std::ceil(std::max(clearance_cells, goal_clearance_cells)));
  const std::vector<int64_t> occupied_d2 = OccupiedDistanceSq(classes, size_x, size_y, radius);
  auto at_least = [&](int64_t i, double cells) {
    const double below = std::max(0.0, cells - 1e-9);
    return occupied_d2[i] == kFar || static_cast<double>(occupied_d2[i]) >= below * below;
  };
  auto clear = [&](int64_t i) { return at_least(i, clearance_cells); };

  // Dijkstra from the robot's cell (path lengths in cells).
  std::vector<double> dist(num_cells, kInf);
  using Entry = std::pair<double, int64_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  const int64_t start = index(robot_cell->ix, robot_cell->iy);
  dist[start] = 0.0;
  open.push({0.0, start});
  while (!open.empty()) {
    const auto [d, i] = open.top();
    open.pop();
    if (d > dist[i]) continue;
    const int ix = static_cast<int>(i % size_x);
    const int iy = static_cast<int>(i / size_x);
    for (int k = 0; k < 8; ++k) {
      const int nx = ix + kDx[k];
      const int ny = iy + kDy[k];
      if (!inside(nx, ny)) continue;
      const int64_t n = index(nx, ny);
      if (classes[n] != kFree) continue;
      if (!clear(n) && occupied_d2[n] < occupied_d2[i]) continue;
      const bool diagonal = k >= 4;
      if (diagonal && (classes[index(nx, iy)] != kFree || classes[index(ix, ny)] != kFree)) {
        continue;
      }
      const double nd = d + (diagonal ? M_SQRT2 : 1.0);
      if (nd < dist[n]) {
        dist[n] = nd;
        open.push({nd, n});
      }
    }
  }

  // Frontier cells.
  std::vector<uint8_t> is_frontier(num_cells, 0);
  for (int iy = 0; iy < size_y; ++iy) {
    for (int ix = 0; ix < size_x; ++ix) {
      const int64_t i = index(ix, iy);
      if (classes[i] != kFree) continue;
      for (int k = 0; k < 4; ++k) {
        const int nx = ix + kDx[k];
        const int ny = iy + kDy[k];
        if (inside(nx, ny) && classes[index(nx, ny)] == kUnknown) {
          is_frontier[i] = 1;
          break;
        }
      }
    }
  }

  // 8-connected clusters, seeded in linear-index order.
  std::vector<Frontier> frontiers;
  std::vector<uint8_t> assigned(num_cells, 0);
  std::vector<int64_t> cluster;
  for (int64_t seed = 0; seed < num_cells; ++seed) {
    if (!is_frontier[seed] || assigned[seed]) continue;
    cluster.clear();
    cluster.push_back(seed);
    assigned[seed] = 1;
    for (size_t head = 0; head < cluster.size(); ++head) {
      const int ix = static_cast<int>(cluster[head] % size_x);
      const int iy = static_cast<int>(cluster[head] / size_x);
      for (int k = 0; k < 8; ++k) {
        const int nx = ix + kDx[k];
        const int ny = iy + kDy[k];
        if (!inside(nx, ny)) continue;
        const int64_t n = index(nx, ny);
        if (is_frontier[n] && !assigned[n]) {
          assigned[n] = 1;
          cluster.push_back(n);
        }
      }
    }
    const double size_m = static_cast<double>(cluster.size()) * resolution_m;
    if (size_m < params.min_frontier_size_m) continue;
    std::sort(cluster.begin(), cluster.end());

    Frontier f;
    f.size_m = size_m;
    f.cells.reserve(cluster.size());
    Vector2 sum(0.0, 0.0);
    for (const int64_t i : cluster) {
      const CellIndex cell{static_cast<int>(i % size_x), static_cast<int>(i / size_x)};
      f.cells.push_back(cell);
      sum += geometry.CenterOf(cell);
    }
    f.centroid_m = sum / static_cast<double>(cluster.size());

    struct Ranked {
      int64_t index;
      bool clear;
      double centroid_d2;
    };
    std::vector<Ranked> reached;
    for (const int64_t i : cluster) {
      if (dist[i] == kInf) continue;
      const CellIndex cell{static_cast<int>(i % size_x), static_cast<int>(i / size_x)};
      reached.push_back({i, at_least(i, goal_clearance_cells),
                         (geometry.CenterOf(cell) - f.centroid_m).squaredNorm()});
    }
    if (reached.empty()) continue;  // unreachable
    // Clear cells first, then nearest the centroid, the shorter path, the lower index.
    std::sort(reached.begin(), reached.end(), [&](const Ranked& a, const Ranked& b) {
      if (a.clear != b.clear) return a.clear;
      if (a.centroid_d2 != b.centroid_d2) return a.centroid_d2 < b.centroid_d2;
      if (dist[a.index] != dist[b.index]) return dist[a.index] < dist[b.index];
      return a.index < b.index;
    });
    f.candidates.reserve(reached.size());
    for (const Ranked& r : reached) {
      const CellIndex cell{static_cast<int>(r.index % size_x), static_cast<int>(r.index / size_x)};
      f.candidates.push_back(
          {cell, geometry.CenterOf(cell), dist[r.index] * resolution_m, r.clear});
    }
    f.goal_cell = f.candidates.front().cell;
    f.goal_m = f.candidates.front().position_m;
    f.distance_m = f.candidates.front().distance_m;
    f.cost = FrontierCost(params, f.distance_m, f.size_m);
    frontiers.push_back(std::move(f));
  }

  std::stable_sort(frontiers.begin(), frontiers.end(), [&](const Frontier& a, const Frontier& b) {
    if (a.cost != b.cost) return a.cost < b.cost;
    if (a.distance_m != b.distance_m) return a.distance_m < b.distance_m;
    return geometry.LinearIndex(a.goal_cell) < geometry.LinearIndex(b.goal_cell);
  });
  return frontiers;
}

std::optional<Frontier> ChooseFrontierGoal(const std::vector<Frontier>& frontiers,
                                           const std::vector<Vector2>& failed_goals_m,
                                           const FrontierParams& params) {
  params.Validate();
  for (const Vector2& failed : failed_goals_m) {
    CAIRN_THROW_UNLESS(failed.allFinite(), "ChooseFrontierGoal: failed goals must be finite, got ("
                                               << failed.x() << ", " << failed.y() << ")");
  }
  auto blacklisted = [&](const Vector2& goal_m) {
    return std::any_of(failed_goals_m.begin(), failed_goals_m.end(), [&](const Vector2& failed) {
      return (goal_m - failed).norm() <= params.blacklist_radius_m;
    });
  };
  // The best frontier and its first candidate outside the blacklist (nullptr: its own goal).
  const Frontier* best = nullptr;
  const FrontierGoalCandidate* best_goal = nullptr;
  double best_cost = 0.0;
  for (const Frontier& f : frontiers) {
    const FrontierGoalCandidate* goal = nullptr;
    if (f.candidates.empty()) {
      if (blacklisted(f.goal_m)) continue;
    } else {
      for (const FrontierGoalCandidate& c : f.candidates) {
        if (!blacklisted(c.position_m)) {
          goal = &c;
          break;
        }
      }
      if (goal == nullptr) continue;
    }
    const double cost = goal != nullptr ? FrontierCost(params, goal->distance_m, f.size_m) : f.cost;
    if (best == nullptr || cost < best_cost) {
      best = &f;
      best_goal = goal;
      best_cost = cost;
    }
  }
  if (best == nullptr) return std::nullopt;
  Frontier chosen = *best;
  if (best_goal != nullptr) {
    chosen.goal_cell = best_goal->cell;
    chosen.goal_m = best_goal->position_m;
    chosen.distance_m = best_goal->distance_m;
    chosen.cost = best_cost;
  }
  return chosen;
}

std::optional<Frontier> ChooseFrontierGoal(const common::GridMap& map, const std::string& layer,
                                           const Vector2& robot_m,
                                           const std::vector<Vector2>& failed_goals_m,
                                           const FrontierParams& params) {
  return ChooseFrontierGoal(FindFrontiers(map, layer, robot_m, params), failed_goals_m, params);
}

}  // namespace cairn::explore
