#include "planner/approach.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <vector>

namespace cairn::planner {

std::optional<common::Pose2> ApproachPose(const CostMap& map, const common::Pose2& start,
                                          const common::Vector2& goal) {
  const common::GridGeometry& g = map.geometry();
  const auto start_cell = g.IndexOf(start.position());
  if (!start_cell) return std::nullopt;
  const Eigen::MatrixXf& clearance_cells = map.blocked_distance_cells();
  // The search goes where the footprint's inscribed disc (and the planner's padding) keeps clear
  // of every blocking cell, and round the start within its circumscribed circle (a start that
  // fits only the way the robot faces); it ends where the robot can turn at any heading: its
  // circumscribed circle clear, so a plan can arrive from any side.
  const double padding_m = map.params().planning_padding_m;
  const double pass_cells = (map.footprint().inscribed_radius_m() + padding_m) / g.resolution_m;
  const double circle_m = map.footprint().circumscribed_radius_m() + padding_m;
  const double end_cells = circle_m / g.resolution_m;
  const common::Vector2 origin = start.position();
  auto passable = [&](int ix, int iy) {
    if (map.IsBlockedCell({ix, iy})) return false;
    return clearance_cells(ix, iy) >= pass_cells ||
           (g.CenterOf({ix, iy}) - origin).norm() <= circle_m + g.resolution_m;
  };
  std::vector<char> seen(static_cast<size_t>(g.num_cells()), 0);
  auto index = [&](int ix, int iy) { return static_cast<int64_t>(iy) * g.size_x + ix; };
  std::deque<common::CellIndex> queue{*start_cell};
  seen[index(start_cell->ix, start_cell->iy)] = 1;
  std::vector<std::pair<double, common::CellIndex>> reached;
  while (!queue.empty()) {
    const common::CellIndex c = queue.front();
    queue.pop_front();
    reached.push_back({(g.CenterOf(c) - goal).squaredNorm(), c});
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = c.ix + dx, ny = c.iy + dy;
        if ((dx == 0 && dy == 0) || !g.Contains({nx, ny}) || seen[index(nx, ny)]) continue;
        seen[index(nx, ny)] = 1;
        if (passable(nx, ny)) queue.push_back({nx, ny});
      }
    }
  }
  std::sort(reached.begin(), reached.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [distance, cell] : reached) {
    if (clearance_cells(cell.ix, cell.iy) < end_cells) continue;
    const common::Vector2 at = g.CenterOf(cell);
    const common::Vector2 to = goal - at;
    const double facing = to.norm() > 1e-6 ? std::atan2(to.y(), to.x()) : start.yaw_rad;
    if (map.IsValid({at.x(), at.y(), facing})) return common::Pose2{at.x(), at.y(), facing};
    for (int k = 0; k < 16; ++k) {
      const double yaw = facing + k * (2.0 * M_PI / 16.0);
      if (map.IsValid({at.x(), at.y(), yaw})) return common::Pose2{at.x(), at.y(), yaw};
    }
  }
  return std::nullopt;
}

}  // namespace cairn::planner
