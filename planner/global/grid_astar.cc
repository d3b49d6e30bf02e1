#include "planner/global/grid_astar.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>

namespace cairn::planner {

using common::Vector2;

namespace {

// The grid as the search sees it: which cells are passable and what crossing them costs.
class SearchGrid {
 public:
  SearchGrid(const CostMap& map, const GridAStarParams& params)
      : map_(map),
        params_(params),
        sx_(map.geometry().size_x),
        sy_(map.geometry().size_y),
        res_(map.geometry().resolution_m),
        dist_(map.blocked_distance_cells().data()),
        nonfree_(map.nonfree_distance_cells().data()),
        cost_(map.cost().data()),
        unknown_cost_(map.params().unknown_cost),
        lethal_(map.params().lethal_cost),
        inscribed_cells_(map.footprint().inscribed_radius_m() / res_),
        inflation_cells_(params.clearance_inflation_m / res_) {
    clearance_cells_ = params.clearance_m >= 0.0
                           ? params.clearance_m / res_
                           : std::max(0.0, map.footprint().inscribed_radius_m() / res_ -
                                               (0.70710678 - 0.5) - 1e-3);
    if (map.one_way_cells() > 0) {
      for (int k = 0; k < 8; ++k) refused_[k] = map.heading_block_distance_cells(k).data();
    }
  }

  bool directed() const { return refused_[0] != nullptr; }
  // A step between neighbouring cells in heading bin k: refused when a one-way cell refusing
  // heading class k lies within the clearance disc of either cell (CostMap::MaybeConnected's
  // rule).
  bool StepAllowed(int64_t from, int64_t to, int bin) const {
    if (!directed()) return true;
    const float* d = refused_[bin];
    return d[from] > clearance_cells_ && d[to] > clearance_cells_;
  }

  int size_x() const { return sx_; }
  int size_y() const { return sy_; }
  double resolution_m() const { return res_; }
  int64_t Index(int ix, int iy) const { return ix + static_cast<int64_t>(iy) * sx_; }
  Vector2 Center(int64_t i) const {
    return map_.geometry().CenterOf({static_cast<int>(i % sx_), static_cast<int>(i / sx_)});
  }
  bool Passable(int64_t i) const { return dist_[i] > 0.0f && dist_[i] >= clearance_cells_; }
  // Cell cost in units of cost/100, proximity folded in (same scale as the OMPL objective).
  float Traversal(int64_t i) const {
    const float v = cost_[i];
    double c = std::isnan(v) ? unknown_cost_ : std::min(std::max(v, 0.0f), lethal_);
    c *= params_.traversal_cost_weight;
    if (params_.clearance_weight > 0.0 && inflation_cells_ > 0.0 && std::isfinite(dist_[i])) {
      c += 100.0 * params_.clearance_weight *
           std::clamp(1.0 - (dist_[i] - inscribed_cells_) / inflation_cells_, 0.0, 1.0);
    }
    return static_cast<float>(c);
  }

  // Every cell the segment between the two cell centres passes (sampled every quarter cell)
  // is passable. Samples whose cell is passable for certain are skipped: the distance field is
  // 1-Lipschitz between cell centres, so from a sample in a cell `clearance + 1.5 + s` cells
  // from blocking, every cell within s cells along the segment is passable (sphere tracing).
  // On a directed map, the segment's heading class must also keep its clearance disc off the
  // one-way cells refusing it, at the two ends as well.
  bool LineOfSight(int64_t a, int64_t b) const {
    const double ax = static_cast<double>(a % sx_), ay = static_cast<double>(a / sx_);
    const double dx = static_cast<double>(b % sx_) - ax, dy = static_cast<double>(b / sx_) - ay;
    const double length = std::hypot(dx, dy);
    const int n = std::max(1, static_cast<int>(std::ceil(4.0 * length)));
    const double sample_cells = length / n;
    const float* refused = directed() ? refused_[HeadingClass(std::atan2(dy, dx))] : nullptr;
    if (refused != nullptr && (refused[a] <= clearance_cells_ || refused[b] <= clearance_cells_)) {
      return false;
    }
    for (int k = 1; k < n;) {
      const double t = static_cast<double>(k) / n;
      const int64_t cell = Index(static_cast<int>(std::floor(ax + t * dx + 0.5)),
                                 static_cast<int>(std::floor(ay + t * dy + 0.5)));
      if (!Passable(cell)) return false;
      double free_cells = dist_[cell] - clearance_cells_ - 1.5;
      if (refused != nullptr) {
        if (refused[cell] <= clearance_cells_) return false;
        free_cells = std::min(free_cells, refused[cell] - clearance_cells_ - 1.5);
      }
      if (free_cells >= length) return true;  // nothing blocks within the segment's reach
      k += free_cells > sample_cells ? static_cast<int>(free_cells / sample_cells) : 1;
    }
    return true;
  }

  // The cost of the straight segment between two cell centres: its length times (1 + the mean
  // traversal / 100), by the trapezoid rule over samples about a cell apart. Samples where the
  // traversal is certainly 0 (ZeroCostReach) add nothing and are skipped.
  double LineCost(int64_t a, int64_t b) const {
    const double ax = static_cast<double>(a % sx_), ay = static_cast<double>(a / sx_);
    const double dx = static_cast<double>(b % sx_) - ax, dy = static_cast<double>(b / sx_) - ay;
    const double cells = std::hypot(dx, dy);
    const int n = std::max(1, static_cast<int>(std::ceil(cells)));
    const double sample_cells = cells / n;
    double sum = 0.0;
    double previous = Traversal(a);
    for (int k = 1; k <= n;) {
      const double t = static_cast<double>(k) / n;
      const int64_t cell = k == n ? b
                                  : Index(static_cast<int>(std::floor(ax + t * dx + 0.5)),
                                          static_cast<int>(std::floor(ay + t * dy + 0.5)));
      const double c = Traversal(cell);
      sum += 0.5 * (previous + c);
      previous = c;
      int skip = 0;
      if (c == 0.0) {
        const double reach = ZeroCostReach(cell);
        if (reach > sample_cells)
          skip = static_cast<int>(std::min<double>(n - k, reach / sample_cells));
      }
      k += 1 + skip;
    }
    return cells * res_ * (1.0 + sum / n / 100.0);
  }

  // Cells whose centre lies within this many cells of a point in cell i have a zero traversal
  // (free, and beyond the proximity band): the distance fields are 1-Lipschitz between cell
  // centres, less 1.5 cells for the points' offsets from their cells' centres.
  double ZeroCostReach(int64_t i) const {
    double reach = nonfree_[i];
    if (params_.clearance_weight > 0.0 && inflation_cells_ > 0.0) {
      reach = std::min(reach, static_cast<double>(dist_[i]) - inscribed_cells_ - inflation_cells_);
    }
    return reach - 1.5;
  }

 private:
  const CostMap& map_;
  const GridAStarParams& params_;
  int sx_;
  int sy_;
  double res_;
  const float* dist_;
  const float* nonfree_;
  const float* cost_;
  float unknown_cost_;
  float lethal_;
  double inscribed_cells_;
  double inflation_cells_;
  double clearance_cells_{0.0};
  std::array<const float*, 8> refused_{};  // per heading class, on a directed map
};

// The best-first search over the grid (A*, or Theta* with params.any_angle).
class Search {
 public:
  Search(const SearchGrid& grid, const GridAStarParams& params, int64_t start, int64_t goal)
      : grid_(grid), params_(params), start_(start), goal_(goal) {
    const size_t n = static_cast<size_t>(grid.size_x()) * static_cast<size_t>(grid.size_y());
    g_cost_.assign(n, std::numeric_limits<float>::infinity());
    parent_.assign(n, -1);
    closed_.assign(n, 0);
  }

  GridPath Run() {
    GridPath out;
    g_cost_[start_] = 0.0f;
    open_.push({Heuristic(start_), static_cast<int32_t>(start_)});
    while (!open_.empty()) {
      const int32_t i = open_.top().second;
      open_.pop();
      if (closed_[i]) continue;
      closed_[i] = 1;
      ++out.expanded;
      if (i == goal_) break;
      Expand(i);
    }
    if (!closed_[goal_]) return out;
    out.found = true;
    out.cost = g_cost_[goal_];
    for (int64_t i = goal_; i >= 0; i = parent_[i]) {
      out.points_m.push_back(grid_.Center(i));
      if (i == start_) break;
    }
    std::reverse(out.points_m.begin(), out.points_m.end());
    for (size_t k = 1; k < out.points_m.size(); ++k) {
      out.length_m += (out.points_m[k] - out.points_m[k - 1]).norm();
    }
    return out;
  }

 private:
  // A*: octile distance times the cheapest step cost is admissible. Theta*: the straight line.
  float Heuristic(int64_t i) const {
    const int sx = grid_.size_x();
    const double dx = std::abs(static_cast<double>(i % sx - goal_ % sx));
    const double dy = std::abs(static_cast<double>(i / sx - goal_ / sx));
    if (params_.any_angle) return static_cast<float>(grid_.resolution_m() * std::hypot(dx, dy));
    return static_cast<float>(grid_.resolution_m() *
                              ((dx + dy) + (std::sqrt(2.0) - 2.0) * std::min(dx, dy)));
  }

  void Relax(int64_t j, int64_t parent, float candidate) {
    if (candidate < g_cost_[j]) {
      g_cost_[j] = candidate;
      parent_[j] = static_cast<int32_t>(parent);
      open_.push({candidate + Heuristic(j), static_cast<int32_t>(j)});
    }
  }

  void Expand(int64_t i) {
    // Heading bins 0, 4, 2, 6 (the axes), then the diagonals 1, 7, 3, 5.
    static const int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
    static const int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
    static const int kBin[8] = {0, 4, 2, 6, 1, 7, 3, 5};
    const int sx = grid_.size_x();
    const int ix = static_cast<int>(i % sx);
    const int iy = static_cast<int>(i / sx);
    const float ci = grid_.Traversal(i);
    const int64_t grandparent = params_.any_angle ? parent_[i] : -1;
    for (int k = 0; k < 8; ++k) {
      const int nx = ix + kDx[k];
      const int ny = iy + kDy[k];
      if (nx < 0 || ny < 0 || nx >= sx || ny >= grid_.size_y()) continue;
      const int64_t j = grid_.Index(nx, ny);
      if (closed_[j] || !grid_.Passable(j) || !grid_.StepAllowed(i, j, kBin[k])) continue;
      // Theta*: straight from the parent when it sees the neighbour.
      if (grandparent >= 0 && grid_.LineOfSight(grandparent, j)) {
        Relax(j, grandparent,
              g_cost_[grandparent] + static_cast<float>(grid_.LineCost(grandparent, j)));
        continue;
      }
      const double step = (k < 4 ? 1.0 : std::sqrt(2.0)) * grid_.resolution_m();
      const float candidate =
          g_cost_[i] + static_cast<float>(step * (1.0 + kWeight * 0.5 * (ci + grid_.Traversal(j))));
      Relax(j, i, candidate);
    }
  }

  static constexpr double kWeight = 1.0 / 100.0;  // Traversal() already carries the weights
  using Entry = std::pair<float, int32_t>;
  const SearchGrid& grid_;
  const GridAStarParams& params_;
  int64_t start_;
  int64_t goal_;
  std::vector<float> g_cost_;
  std::vector<int32_t> parent_;
  std::vector<uint8_t> closed_;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open_;
};

}  // namespace

GridPath GridAStar(const CostMap& map, const Vector2& start_m, const Vector2& goal_m,
                   const GridAStarParams& params) {
  const auto& geometry = map.geometry();
  const auto start = geometry.IndexOf(start_m);
  const auto goal = geometry.IndexOf(goal_m);
  if (!start || !goal) return {};
  const SearchGrid grid(map, params);
  const int64_t s = grid.Index(start->ix, start->iy);
  const int64_t g = grid.Index(goal->ix, goal->iy);
  if (!grid.Passable(s) || !grid.Passable(g)) return {};
  return Search(grid, params, s, g).Run();
}

}  // namespace cairn::planner
