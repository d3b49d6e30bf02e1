#include "planner/global/coarse_route.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <vector>

#include "common/check.h"

namespace cairn::planner {

using common::Vector2;

namespace {

// The cost layer as the coarse search reads it (cell index ix + iy * size_x).
class FineGrid {
 public:
  FineGrid(const CostMap& map, const CoarseRouteParams& params, const Vector2& start_m,
           const Vector2& goal_m)
      : map_(map),
        start_m_(start_m),
        goal_m_(goal_m),
        escape2_m2_(params.escape_radius_m * params.escape_radius_m),
        sx_(map.geometry().size_x),
        sy_(map.geometry().size_y),
        res_(map.geometry().resolution_m),
        dist_(map.blocked_distance_cells().data()),
        cost_(map.cost().data()),
        unknown_cost_(map.params().unknown_cost),
        lethal_(map.params().lethal_cost),
        weight_(params.traversal_cost_weight),
        clearance_weight_(params.clearance_weight),
        inscribed_cells_(map.footprint().inscribed_radius_m() / res_),
        inflation_cells_(params.clearance_inflation_m / res_),
        // The grid A*'s default passability: the inscribed radius less (half a cell diagonal -
        // half a cell).
        clearance_cells_(std::max(0.0, inscribed_cells_ - (0.70710678 - 0.5) - 1e-3)),
        circumscribed_cells_(
            (map.footprint().circumscribed_radius_m() + map.params().planning_padding_m) / res_) {}

  int size_x() const { return sx_; }
  int size_y() const { return sy_; }
  double resolution_m() const { return res_; }
  int64_t Index(int ix, int iy) const { return ix + static_cast<int64_t>(iy) * sx_; }
  float Distance(int64_t i) const { return dist_[i]; }
  Vector2 Center(int64_t i) const {
    return map_.geometry().CenterOf({static_cast<int>(i % sx_), static_cast<int>(i / sx_)});
  }
  // The inscribed disc keeps off blocking cells, and, nearer to them than the circumscribed
  // radius, the footprint fits at the cell's centre at some heading: padded, as the OMPL problem
  // checks it, away from the ends (a gap the disc passes but the footprint's corners do not, at
  // any heading, is not a way through).
  bool Passable(int64_t i) const {
    if (!(dist_[i] > 0.0f && dist_[i] >= clearance_cells_)) return false;
    if (dist_[i] > circumscribed_cells_ + 0.75) return true;
    const Vector2 c = Center(i);
    const bool near_end =
        (c - start_m_).squaredNorm() <= escape2_m2_ || (c - goal_m_).squaredNorm() <= escape2_m2_;
    return map_.FitsAtSomeHeading(i, near_end ? FootprintKind::kRobot : FootprintKind::kPadded);
  }
  // Cost / 100 plus proximity, as the grid A* and the OMPL objective weigh them.
  double Traversal(int64_t i) const {
    const float v = cost_[i];
    double c = std::isnan(v) ? unknown_cost_ : std::min(std::max(v, 0.0f), lethal_);
    c *= weight_;
    if (clearance_weight_ > 0.0 && inflation_cells_ > 0.0 && std::isfinite(dist_[i])) {
      c += 100.0 * clearance_weight_ *
           std::clamp(1.0 - (dist_[i] - inscribed_cells_) / inflation_cells_, 0.0, 1.0);
    }
    return c;
  }

  // Every cell the segment between the two cell centres passes (sampled every half cell) is
  // passable; far from blocking cells the distance field lets samples be skipped.
  bool LineOfSight(int64_t a, int64_t b) const {
    const double ax = static_cast<double>(a % sx_), ay = static_cast<double>(a / sx_);
    const double dx = static_cast<double>(b % sx_) - ax, dy = static_cast<double>(b / sx_) - ay;
    const double length = std::hypot(dx, dy);
    const int n = std::max(1, static_cast<int>(std::ceil(2.0 * length)));
    const double sample_cells = length / n;
    for (int k = 1; k < n;) {
      const double t = static_cast<double>(k) / n;
      const int64_t cell = Index(static_cast<int>(std::floor(ax + t * dx + 0.5)),
                                 static_cast<int>(std::floor(ay + t * dy + 0.5)));
      if (!Passable(cell)) return false;
      const double free_cells = dist_[cell] - clearance_cells_ - 1.5;
      if (free_cells >= length) return true;
      k += free_cells > sample_cells ? static_cast<int>(free_cells / sample_cells) : 1;
    }
    return true;
  }

  // Length times (1 + mean traversal / 100), the trapezoid rule over samples a cell apart.
  double LineCost(int64_t a, int64_t b) const {
    const double ax = static_cast<double>(a % sx_), ay = static_cast<double>(a / sx_);
    const double dx = static_cast<double>(b % sx_) - ax, dy = static_cast<double>(b / sx_) - ay;
    const double cells = std::hypot(dx, dy);
    const int n = std::max(1, static_cast<int>(std::ceil(cells)));
    double sum = 0.0;
    double previous = Traversal(a);
    for (int k = 1; k <= n; ++k) {
      const double t = static_cast<double>(k) / n;
      const int64_t cell = k == n ? b
                                  : Index(static_cast<int>(std::floor(ax + t * dx + 0.5)),
                                          static_cast<int>(std::floor(ay + t * dy + 0.5)));
      const double c = Traversal(cell);
      sum += 0.5 * (previous + c);
      previous = c;
    }
    return cells * res_ * (1.0 + sum / n / 100.0);
  }

 private:
  const CostMap& map_;
  Vector2 start_m_;
  Vector2 goal_m_;
  double escape2_m2_;
  int sx_;
  int sy_;
  double res_;
  const float* dist_;
  const float* cost_;
  float unknown_cost_;
  float lethal_;
  double weight_;
  double clearance_weight_;
  double inscribed_cells_;
  double inflation_cells_;
  double clearance_cells_;
  double circumscribed_cells_;
};

// A* over the blocks; each block's cell is found when the search first reaches it.
class BlockSearch {
 public:
  BlockSearch(const FineGrid& grid, int stride, int64_t start, int64_t goal)
      : grid_(grid),
        stride_(stride),
        bx_((grid.size_x() + stride - 1) / stride),
        by_((grid.size_y() + stride - 1) / stride),
        start_cell_(start),
        goal_cell_(goal) {
    const size_t n = static_cast<size_t>(bx_) * static_cast<size_t>(by_);
    g_cost_.assign(n, std::numeric_limits<double>::infinity());
    parent_.assign(n, -1);
    closed_.assign(n, 0);
    cell_.assign(n, kUnset);
    start_ = BlockOf(start);
    goal_ = BlockOf(goal);
    cell_[start_] = start;
    cell_[goal_] = goal;  // the same block: the goal's cell wins, the start's is joined below
  }

  GridPath Run(const std::function<bool()>& stop) {
    GridPath out;
    if (start_ == goal_) {
      if (!grid_.LineOfSight(start_cell_, goal_cell_)) return out;
      return Finish({start_cell_, goal_cell_}, grid_.LineCost(start_cell_, goal_cell_), 1);
    }
    g_cost_[start_] = 0.0;
    cell_[start_] = start_cell_;
    open_.push({Heuristic(start_cell_), start_});
    while (!open_.empty()) {
      const int32_t b = open_.top().second;
      open_.pop();
      if (closed_[b]) continue;
      closed_[b] = 1;
      ++out.expanded;
      if (b == goal_) break;
      if (stop && out.expanded % 256 == 1 && stop()) return GridPath{};
      Expand(b);
    }
    if (!closed_[goal_]) return out;
    std::vector<int64_t> cells;
    for (int32_t b = goal_; b >= 0; b = parent_[b]) {
      cells.push_back(cell_[b]);
      if (b == start_) break;
    }
    std::reverse(cells.begin(), cells.end());
    return Finish(cells, g_cost_[goal_], out.expanded);
  }

 private:
  static constexpr int64_t kUnset = -2;
  static constexpr int64_t kNone = -1;

  int32_t BlockOf(int64_t cell) const {
    const int ix = static_cast<int>(cell % grid_.size_x());
    const int iy = static_cast<int>(cell / grid_.size_x());
    return (ix / stride_) + (iy / stride_) * bx_;
  }
  double Heuristic(int64_t cell) const {
    return (grid_.Center(cell) - grid_.Center(goal_cell_)).norm();
  }
  // The block's passable cell farthest from blocking cells, or kNone.
  int64_t CellOf(int32_t b) {
    if (cell_[b] != kUnset) return cell_[b];
    const int x0 = (b % bx_) * stride_, y0 = (b / bx_) * stride_;
    int64_t best = kNone;
    float best_d = -1.0f;
    for (int iy = y0; iy < std::min(y0 + stride_, grid_.size_y()); ++iy) {
      for (int ix = x0; ix < std::min(x0 + stride_, grid_.size_x()); ++ix) {
        const int64_t i = grid_.Index(ix, iy);
        if (grid_.Passable(i) && grid_.Distance(i) > best_d) {
          best_d = grid_.Distance(i);
          best = i;
        }
      }
    }
    return cell_[b] = best;
  }
  void Expand(int32_t b) {
    static const int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
    static const int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
    const int x = b % bx_, y = b / bx_;
    const int64_t from = cell_[b];
    for (int k = 0; k < 8; ++k) {
      const int nx = x + kDx[k], ny = y + kDy[k];
      if (nx < 0 || ny < 0 || nx >= bx_ || ny >= by_) continue;
      const int32_t n = nx + ny * bx_;
      if (closed_[n]) continue;
      const int64_t to = CellOf(n);
      if (to == kNone || !grid_.LineOfSight(from, to)) continue;
      const double candidate = g_cost_[b] + grid_.LineCost(from, to);
      if (candidate < g_cost_[n]) {
        g_cost_[n] = candidate;
        parent_[n] = b;
        open_.push({candidate + Heuristic(to), n});
      }
    }
  }
  GridPath Finish(const std::vector<int64_t>& cells, double cost, int64_t expanded) const {
    GridPath out;
    out.found = true;
    out.cost = cost;
    out.expanded = expanded;
    for (const int64_t c : cells) out.points_m.push_back(grid_.Center(c));
    for (size_t k = 1; k < out.points_m.size(); ++k) {
      out.length_m += (out.points_m[k] - out.points_m[k - 1]).norm();
    }
    return out;
  }

  using Entry = std::pair<double, int32_t>;
  const FineGrid& grid_;
  int stride_;
  int bx_;
  int by_;
  int64_t start_cell_;
  int64_t goal_cell_;
  int32_t start_{0};
  int32_t goal_{0};
  std::vector<double> g_cost_;
  std::vector<int32_t> parent_;
  std::vector<uint8_t> closed_;
  std::vector<int64_t> cell_;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open_;
};

}  // namespace

GridPath CoarseGridRoute(const CostMap& map, const Vector2& start_m, const Vector2& goal_m,
                         const CoarseRouteParams& params, const std::function<bool()>& stop) {
  CAIRN_THROW_UNLESS(params.stride_cells >= 1, "stride_cells must be at least 1");
  const auto& geometry = map.geometry();
  const auto start = geometry.IndexOf(start_m);
  const auto goal = geometry.IndexOf(goal_m);
  if (!start || !goal) return {};
  const FineGrid grid(map, params, start_m, goal_m);
  const int64_t s = grid.Index(start->ix, start->iy);
  const int64_t g = grid.Index(goal->ix, goal->iy);
  if (!grid.Passable(s) || !grid.Passable(g)) return {};
  return BlockSearch(grid, params.stride_cells, s, g).Run(stop);
}

}  // namespace cairn::planner
