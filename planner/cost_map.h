#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <utility>
#include <vector>

#include "common/grid_map.h"
#include "common/types.h"
#include "planner/distance_transform.h"
#include "planner/footprint.h"

/// @file
/// CostMap: one immutable snapshot of a cost layer ("cost/<profile>": 0 free, (0, 100) graded,
/// 100 lethal, NaN unknown) with the robot's footprint, answering the questions both planners
/// ask: is this pose valid, what does the footprint cost, how far is the nearest obstacle, and
/// can two points possibly be connected.

namespace cairn::planner {

/// How the planners read the cost layer.
struct CostMapParams {
  /// Unknown cells (NaN, and cells outside the grid) are traversable at `unknown_cost`;
  /// otherwise they block like lethal cells.
  bool unknown_is_traversable{false};
  /// Cost given to an unknown cell when it is traversable, in [0, lethal_cost).
  float unknown_cost{50.0f};
  /// Cells whose cost is at or above this are lethal.
  float lethal_cost{100.0f};
  /// Margin around the footprint for FootprintKind::kPadded (the global planner's states), so
  /// that poses between the states it checked keep clear too.
  double planning_padding_m{0.05};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Which footprint a check uses: the robot's own, or the robot's grown by planning_padding_m.
enum class FootprintKind { kRobot = 0, kPadded = 1 };

/// The cost of a footprint placed at a pose.
struct FootprintCost {
  bool valid{true};      ///< false when it touches a lethal or a blocking unknown cell
  float max_cost{0.0f};  ///< highest cell cost under it; unknown counts as unknown_cost
  bool touches_unknown{false};
};

/// An immutable cost-layer snapshot. Build it once per map update and share it (read-only, so
/// safe from several threads) between the control loop and the global planner.
class CostMap {
 public:
  /// Precomputes the distance from every cell to the nearest blocking cell and to the nearest
  /// non-free cell (two exact distance transforms, linear in the number of cells).
  /// @param cost layer of geometry.size_x × geometry.size_y cells (common::Layer convention).
  /// @param footprint_m robot footprint polygon in the base frame.
  /// @throws std::invalid_argument for an invalid geometry, a layer of another size, a bad
  /// footprint or bad params.
  CostMap(const common::GridGeometry& geometry, common::Layer cost,
          const std::vector<common::Vector2>& footprint_m, const CostMapParams& params = {});
  CostMap(const CostMap&) = delete;
  CostMap& operator=(const CostMap&) = delete;

  const common::GridGeometry& geometry() const { return geometry_; }
  const common::Layer& cost() const { return cost_; }
  const CostMapParams& params() const { return params_; }
  const FootprintRasterizer& footprint(FootprintKind kind = FootprintKind::kRobot) const {
    return shapes_[static_cast<int>(kind)].rasterizer;
  }
  double resolution_m() const { return geometry_.resolution_m; }

  /// Layer version and time stamp of the data this snapshot was built from (informational).
  int64_t version() const { return version_; }
  int64_t utime() const { return utime_; }
  void set_stamp(int64_t version, int64_t utime) {
    version_ = version;
    utime_ = utime;
  }
  /// Tiles the publisher announced that this snapshot lacks (they read as lethal); a navigator
  /// waits for them rather than plan on a layer with holes.
  int missing_tiles() const { return missing_tiles_; }
  void set_missing_tiles(int count) { missing_tiles_ = count; }

  /// True when the world point lies inside the grid.
  bool Contains(const common::Vector2& world_m) const;
  /// Raw cost of the cell holding a world point; NaN when unknown or outside the grid.
  float CostAt(const common::Vector2& world_m) const;
  /// Cost for path costs: unknown and outside become unknown_cost, capped at lethal_cost.
  float TraversalCostAt(const common::Vector2& world_m) const;
  /// True when a cell blocks (lethal, or unknown when unknown is not traversable).
  bool IsBlockedCell(const common::CellIndex& cell) const;

  /// Footprint validity and cost at a world pose. Uses the distance fields to answer without
  /// rasterising when the footprint's circumscribed circle is clear (or the inscribed one is
  /// certainly hit), and the exact rasterisation otherwise: the answer always equals
  /// CheckFootprintExact's validity, and its max_cost too when the pose is valid.
  FootprintCost CheckFootprint(const common::Pose2& pose_world,
                               FootprintKind kind = FootprintKind::kRobot) const;
  /// Validity only (the global planner's state check): same answer as CheckFootprint().valid.
  bool IsValid(const common::Pose2& pose_world, FootprintKind kind = FootprintKind::kRobot) const;
  /// Rasterises the footprint and reads every covered cell (no shortcuts).
  FootprintCost CheckFootprintExact(const common::Pose2& pose_world,
                                    FootprintKind kind = FootprintKind::kRobot) const;

  /// Linear indices (sorted) of the in-grid blocking cells the robot's footprint touches at a
  /// pose: what a robot that finds itself "in collision" on the map (a new obstacle under it, a
  /// wall grown by a cell) has to move away from.
  std::vector<int64_t> BlockingCellsUnder(const common::Pose2& pose_world) const;
  /// CheckFootprintExact with the given cells (sorted linear indices) counted as free.
  FootprintCost CheckFootprintIgnoring(const common::Pose2& pose_world,
                                       const std::vector<int64_t>& ignored_cells) const;

  /// Distance (m) from the cell holding the point to the nearest blocking cell, between cell
  /// centres; 0 outside the grid, +infinity when nothing blocks.
  double ClearanceAt(const common::Vector2& world_m) const;
  /// The same distance field interpolated bilinearly between cell centres (m): continuous in
  /// the position, for costs that should not jump from cell to cell. 0 outside the grid.
  double SmoothClearanceAt(const common::Vector2& world_m) const;
  /// Distances in cells to the nearest blocking / non-free cell, per cell.
  const Eigen::MatrixXf& blocked_distance_cells() const { return blocked_distance_; }
  const Eigen::MatrixXf& nonfree_distance_cells() const { return nonfree_distance_; }

  /// False only when no collision-free path can join the two points: the footprint's inscribed
  /// disc must clear every blocking cell, and the cells where that is possible for some position
  /// inside them are grouped into 8-connected components (computed once, on first use). A true
  /// answer does not promise a path.
  bool MaybeConnected(const common::Vector2& a_world_m, const common::Vector2& b_world_m) const;
  /// The smallest cell rectangle holding every known (non-NaN) cell, as [min, max] indices;
  /// nullopt when every cell is unknown.
  std::optional<std::pair<common::CellIndex, common::CellIndex>> known_cells() const {
    return known_cells_;
  }

  /// Cells on the ridges of the distance field (the medial axis of free space): passable cells
  /// at least as far from blocking cells as their neighbours on both sides along some axis or
  /// diagonal, and closer than 10 m to one. Linear indices, computed once, on first use.
  /// Sampling them puts states in the middle of corridors and doors (MAPRM's idea).
  const std::vector<int32_t>& RidgeCells() const;

  /// Like MaybeConnected, but unknown cells only count within `horizon_m` of `a` or within
  /// `goal_radius_m` of `b`: "is there a route through what the robot knows, and through the
  /// unexplored space it can see around it?" Unknown space far away (between distant lidar
  /// rings, behind unobserved stretches of wall) is not assumed open. A breadth-first search
  /// from `a` (linear in the cells it reaches).
  bool ConnectedWithinHorizon(const common::Vector2& a_world_m, const common::Vector2& b_world_m,
                              double horizon_m, double goal_radius_m) const;

  /// Component label of the cell holding a point; -1 when impassable or outside.
  int ComponentOf(const common::Vector2& world_m) const;

  /// World point to grid-frame continuous cell coordinates, and yaw to grid-frame yaw.
  common::Vector2 ToGridCells(const common::Vector2& world_m) const;
  double ToGridYaw(double yaw_rad) const { return yaw_rad - geometry_.origin.yaw_rad; }

 private:
  struct Shape {
    FootprintRasterizer rasterizer;
    double circumscribed_cells{0.0};
    double inscribed_cells{0.0};
  };
  FootprintCost ExactAtGridPose(double x_cells, double y_cells, double yaw_grid_rad,
                                const Shape& shape,
                                const std::vector<int64_t>* ignored = nullptr) const;
  enum class Quick { kValidFree, kValid, kInvalid, kUnknown };
  Quick QuickCheck(double x_cells, double y_cells, const Shape& shape) const;
  void ComputeComponents() const;

  common::GridGeometry geometry_;
  common::Layer cost_;
  CostMapParams params_;
  std::vector<Shape> shapes_;  // indexed by FootprintKind
  int64_t version_{0};
  int64_t utime_{0};
  int missing_tiles_{0};
  double cos_origin_{1.0};
  double sin_origin_{0.0};
  std::optional<std::pair<common::CellIndex, common::CellIndex>> known_cells_;
  Eigen::MatrixXf blocked_distance_;  // cells
  Eigen::MatrixXf nonfree_distance_;  // cells
  // Connectivity labels, built lazily (only the global planner needs them).
  mutable std::once_flag components_once_;
  mutable std::vector<int32_t> components_;
  mutable std::once_flag ridges_once_;
  mutable std::vector<int32_t> ridges_;
};

}  // namespace cairn::planner
