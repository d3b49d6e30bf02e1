#include "planner/global/grid_astar.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>

namespace cairn::planner {

using common::Vector2;

GridPath GridAStar(const CostMap& map, const Vector2& start_m, const Vector2& goal_m,
                   const GridAStarParams& params) {
  GridPath out;
  const auto& geometry = map.geometry();
  const auto start = geometry.IndexOf(start_m);
  const auto goal = geometry.IndexOf(goal_m);
  if (!start || !goal) return out;
  const int sx = geometry.size_x;
  const int sy = geometry.size_y;
  const double res = geometry.resolution_m;
  const double clearance_cells =
      params.clearance_m >= 0.0
          ? params.clearance_m / res
          : std::max(0.0, map.footprint().inscribed_radius_m() / res - (0.70710678 - 0.5) - 1e-3);
  const float* dist = map.blocked_distance_cells().data();
  auto passable = [&](int64_t i) { return dist[i] > 0.0f && dist[i] >= clearance_cells; };
  const float* cost = map.cost().data();
  const float unknown_cost = map.params().unknown_cost;
  const float lethal = map.params().lethal_cost;
  const double inscribed_cells = map.footprint().inscribed_radius_m() / res;
  const double inflation_cells = params.clearance_inflation_m / res;
  // Cell cost in units of cost/100, proximity folded in (same scale as the OMPL objective).
  auto traversal = [&](int64_t i) {
    const float v = cost[i];
    double c = std::isnan(v) ? unknown_cost : std::min(std::max(v, 0.0f), lethal);
    c *= params.traversal_cost_weight;
    if (params.clearance_weight > 0.0 && inflation_cells > 0.0 && std::isfinite(dist[i])) {
      c += 100.0 * params.clearance_weight *
           std::clamp(1.0 - (dist[i] - inscribed_cells) / inflation_cells, 0.0, 1.0);
    }
    return static_cast<float>(c);
  };

  const int64_t s = start->ix + static_cast<int64_t>(start->iy) * sx;
  const int64_t g = goal->ix + static_cast<int64_t>(goal->iy) * sx;
  if (!passable(s) || !passable(g)) return out;

  const int64_t n = geometry.num_cells();
  std::vector<float> g_cost(static_cast<size_t>(n), std::numeric_limits<float>::infinity());
  std::vector<int32_t> parent(static_cast<size_t>(n), -1);
  std::vector<uint8_t> closed(static_cast<size_t>(n), 0);
  using Entry = std::pair<float, int32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  const double w = 1.0 / 100.0;  // traversal() already carries the weights
  // Octile distance times the cheapest step cost is admissible.
  auto heuristic = [&](int64_t i) {
    const double dx = std::abs(static_cast<double>(i % sx - goal->ix));
    const double dy = std::abs(static_cast<double>(i / sx - goal->iy));
    return static_cast<float>(res * ((dx + dy) + (std::sqrt(2.0) - 2.0) * std::min(dx, dy)));
  };
  g_cost[s] = 0.0f;
  open.push({heuristic(s), static_cast<int32_t>(s)});
  static const int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  static const int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  while (!open.empty()) {
    const auto [f, i] = open.top();
    open.pop();
    if (closed[i]) continue;
    closed[i] = 1;
    ++out.expanded;
    if (i == g) break;
    const int ix = static_cast<int>(i % sx);
    const int iy = static_cast<int>(i / sx);
    const float ci = traversal(i);
    for (int k = 0; k < 8; ++k) {
      const int nx = ix + kDx[k];
      const int ny = iy + kDy[k];
      if (nx < 0 || ny < 0 || nx >= sx || ny >= sy) continue;
      const int64_t j = nx + static_cast<int64_t>(ny) * sx;
      if (closed[j] || !passable(j)) continue;
      const double step = (k < 4 ? 1.0 : std::sqrt(2.0)) * res;
      const float candidate =
          g_cost[i] + static_cast<float>(step * (1.0 + w * 0.5 * (ci + traversal(j))));
      if (candidate < g_cost[j]) {
        g_cost[j] = candidate;
        parent[j] = static_cast<int32_t>(i);
        open.push({candidate + heuristic(j), static_cast<int32_t>(j)});
      }
    }
  }
  if (!closed[g]) return out;
  out.found = true;
  out.cost = g_cost[g];
  for (int64_t i = g; i >= 0; i = parent[i]) {
    out.points_m.push_back(
        map.geometry().CenterOf({static_cast<int>(i % sx), static_cast<int>(i / sx)}));
    if (i == s) break;
  }
  std::reverse(out.points_m.begin(), out.points_m.end());
  for (size_t k = 1; k < out.points_m.size(); ++k) {
    out.length_m += (out.points_m[k] - out.points_m[k - 1]).norm();
  }
  return out;
}

}  // namespace cairn::planner
