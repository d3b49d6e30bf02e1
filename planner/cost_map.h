#pragma once

#include <array>
#include <atomic>
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
///
/// With the profile's directed layer ("directed/<profile>", common/layers.h) beside the cost
/// layer, steps and slopes may be one-way: a cell the directed layer lets the robot leave in some
/// headings but not others (a mask in 1..254) is a one-way cell. It does not block poses (the
/// cost layer has it lethal; here it costs CostMapParams::one_way_cost) and MotionAllowed()
/// refuses the motions that drive over it in a heading it blocks. A mask of 255 blocks like a
/// lethal cell. Without a directed layer everything reads the cost layer alone.
///
/// The crossing rule (conservative): a motion whose displacement has grid-frame heading theta
/// crosses bit k of a cell under the footprint when a point moving at theta can leave the cell
/// into its neighbour k: into an edge neighbour (even k) whenever the displacement has a
/// positive component towards it, |theta - k*45 deg| < 90 deg; into a diagonal neighbour (odd
/// k), which touches the cell at one corner only, when theta lies strictly between the two axes
/// around k, |theta - k*45 deg| < 45 deg. So a motion along +x exactly is refused by bit 0 only,
/// one at 30 deg by bits 0, 1 and 2; a robot driving along the foot of a step (parallel to it) is
/// not refused by the step's "up" bits, one turning into it is. Every cell under the footprint
/// anywhere along the motion counts, also cells whose neighbour the footprint never reaches (the
/// conservative part). Pure rotation crosses nothing. The direction of travel is that of the
/// displacement, so a reversing robot is checked against the heading behind it.

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
  /// Margin around the robot's own footprint (FootprintKind::kRobot, both planners), 0 by
  /// default: water a hull keeps round it when its map draws obstacles thinly (a sonar's peaks
  /// on the faces it looked at, sides it never saw).
  double footprint_padding_m{0.0};
  /// Cost of a one-way cell (only with a directed layer, see the file comment), >= 0: graded
  /// high, so paths cross steps where they must and not along them. At or above lethal_cost it
  /// reads as the highest graded cost below it.
  float one_way_cost{90.0f};
  /// How a directed layer's layers::kUnseenDrop cells read (a rim whose ground beyond fell out
  /// of sight, not yet deeper than the profile's step down): false, blocking like 255; true, a
  /// look-out that a plan may lead over to look: one-way, refusing the headings from each unknown
  /// 4-neighbour into it (the climb from the unseen side), or unknown ground (NaN) when no
  /// 4-neighbour is unknown. The navigator builds the
  /// snapshot its plans use this way when its map config allows (`look_at_unseen_drops`), and
  /// drives on the strict one.
  bool unseen_drop_is_unknown{false};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Heading classes of motions on a directed layer: class k (0..7) holds the headings that the
/// same bits of the directed layer refuse. An even class is the axis heading k * 45 deg exactly
/// (within 1e-6 rad), refused by bit k alone; an odd class is the open quadrant around the
/// diagonal k * 45 deg, refused by bits k - 1, k and k + 1 (mod 8).
int HeadingClass(double heading_grid_rad);
/// The directed-layer bits that refuse a motion of heading class `heading_class`.
uint8_t HeadingClassBits(int heading_class);
/// Grid step of heading bin k (0..7): (+1, 0), (+1, +1), (0, +1), (-1, +1), ... counter-clockwise.
common::CellIndex HeadingStep(int bin);

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
  /// The same with the profile's directed layer of the same geometry (common/layers.h), or
  /// without one (nullopt: exactly the constructor above). Its cells are read as: NaN or 0, no
  /// restriction (the cost layer alone); 255, blocking (lethal, whatever the cost layer says);
  /// 1..254, a one-way cell (cost one_way_cost, or the cost layer's where that is graded and
  /// higher; NaN stays unknown); layers::kUnseenDrop, blocking or unknown (see
  /// unseen_drop_is_unknown). Any other value that is not a whole number in [0, 255] reads as 255.
  /// @throws std::invalid_argument as above, or for a directed layer of another size.
  CostMap(const common::GridGeometry& geometry, common::Layer cost,
          std::optional<common::Layer> directed, const std::vector<common::Vector2>& footprint_m,
          const CostMapParams& params = {});
  CostMap(const CostMap&) = delete;
  CostMap& operator=(const CostMap&) = delete;

  const common::GridGeometry& geometry() const { return geometry_; }
  /// The cost layer as the planners read it: with a directed layer, its one-way cells carry
  /// one_way_cost and its 255 cells the lethal cost.
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

  /// Cells of the directed layer marked layers::kUnseenDrop (0 without a directed layer).
  int64_t unseen_drop_cells() const { return unseen_drop_cells_; }
  /// The snapshot global plans use: the one set with set_planning_map (the same data with
  /// unseen drops read as unknown), else this one.
  const CostMap& planning_map() const { return planning_map_ ? *planning_map_ : *this; }
  std::shared_ptr<const CostMap> planning_map_shared() const { return planning_map_; }
  void set_planning_map(std::shared_ptr<const CostMap> map) { planning_map_ = std::move(map); }

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

  /// True when the snapshot was built with a directed layer.
  bool has_directed() const { return has_directed_; }
  /// One-way cells (directed mask in 1..254); 0 without a directed layer.
  int64_t one_way_cells() const { return one_way_cells_; }
  /// The directed mask of a one-way cell (1..254); 0 for every other cell and outside the grid.
  uint8_t OneWayMask(const common::CellIndex& cell) const;
  /// False when the robot may not drive from `from` to `to` over the one-way cells (see the file
  /// comment): the displacement's heading (in the grid frame) and the footprint of `kind` at
  /// poses along the straight motion (position and yaw interpolated, at most half a cell
  /// apart). Only the directions: blocking cells are IsValid's business. True without one-way
  /// cells, for a pure rotation, and whenever no one-way cell of the motion's heading class
  /// lies within reach of the motion (one distance-field lookup per stretch of free space).
  bool MotionAllowed(const common::Pose2& from, const common::Pose2& to,
                     FootprintKind kind = FootprintKind::kRobot) const;
  /// A one-way cell's refusals that a robot already straddles: the bits of `cell` whose
  /// neighbour lies under the robot's footprint too.
  struct StraddledBits {
    int64_t cell{0};  ///< linear index
    uint8_t bits{0};
  };
  /// The refusals the robot's footprint straddles at a pose (sorted by cell): it stands on both
  /// sides of those edges already, so driving on does not cross them. What a robot whose map
  /// changed under it (a step read from noisy heights beneath its body) needs to drive off;
  /// refusals whose neighbour lies outside the footprint still hold.
  std::vector<StraddledBits> StraddledOneWayBits(const common::Pose2& pose_world) const;
  /// MotionAllowed with the `straddled` refusals (StraddledOneWayBits, sorted) not counted.
  bool MotionAllowed(const common::Pose2& from, const common::Pose2& to, FootprintKind kind,
                     const std::vector<StraddledBits>& straddled) const;
  /// Distance in cells from every cell centre to the nearest one-way cell that refuses motions
  /// of heading class `heading_class` (+infinity everywhere when none does), exact up to
  /// ClassFieldMarginCells() (at least 64 cells; farther cells hold that margin, a lower bound).
  /// Computed once per class, on first use, over the refusing cells' bounding box.
  const Eigen::MatrixXf& heading_block_distance_cells(int heading_class) const;

  /// Distance (m) from the cell holding the point to the nearest blocking cell, between cell
  /// centres; 0 outside the grid, +infinity when nothing blocks.
  double ClearanceAt(const common::Vector2& world_m) const;
  /// The same distance field interpolated bilinearly between cell centres (m): continuous in
  /// the position, for costs that should not jump from cell to cell. 0 outside the grid.
  double SmoothClearanceAt(const common::Vector2& world_m) const;
  /// Distance (m) to the nearest one-way cell, interpolated like SmoothClearanceAt: what keeps
  /// the global planner's paths off the edges of steps they do not cross (a path along a ramp's
  /// side is drivable only while no footprint of the local planner touches the edge's cells).
  /// +infinity without one-way cells; beyond ClassFieldMarginCells() a lower bound. The field is
  /// computed once, on first use.
  double SmoothOneWayClearanceAt(const common::Vector2& world_m) const;
  /// Distance in cells from every cell centre to the nearest one-way cell (as above).
  const Eigen::MatrixXf& one_way_distance_cells() const;
  /// Distances in cells to the nearest blocking / non-free cell, per cell.
  const Eigen::MatrixXf& blocked_distance_cells() const { return blocked_distance_; }
  const Eigen::MatrixXf& nonfree_distance_cells() const { return nonfree_distance_; }

  /// False only when no collision-free path can join the two points: the footprint's inscribed
  /// disc must clear every blocking cell, and the cells where that is possible for some position
  /// inside them are grouped into 8-connected components (computed once, on first use). A true
  /// answer does not promise a path. With one-way cells it also answers "from a to b": false
  /// when no grid route of such cells leads from a to b whose every step (towards heading bin
  /// k) keeps the inscribed disc, at both cells, off the one-way cells refusing heading class k
  /// (a breadth-first search; any path the robot could drive makes such a route).
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
  /// from `a` (linear in the cells it reaches). With one-way cells, by the directed steps of
  /// MaybeConnected.
  bool ConnectedWithinHorizon(const common::Vector2& a_world_m, const common::Vector2& b_world_m,
                              double horizon_m, double goal_radius_m) const;

  /// True when the footprint centred on the cell (linear index) is valid at one of 16 headings.
  /// Each cell is answered once per snapshot and kind, and kept (safe from several threads).
  bool FitsAtSomeHeading(int64_t cell, FootprintKind kind = FootprintKind::kRobot) const;

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
  void ReadDirected(const common::Layer& directed);
  /// For a layers::kUnseenDrop cell `i` read as a look-out: the heading bits from each of its
  /// unknown 4-neighbours into it (0 when none is unknown), `directed` the layer's cells.
  int ClimbFromUnknownMask(int64_t i, const float* directed) const;
  bool DirectedReachable(const common::Vector2& a_world_m, const common::Vector2& b_world_m) const;
  int ClassFieldMarginCells() const;
  /// Distance in cells to the nearest one-way cell having one of `bits` (see
  /// heading_block_distance_cells for the margin).
  Eigen::MatrixXf RefusalDistance(uint8_t bits) const;
  /// Bilinear interpolation of a distance field (cells) between cell centres, in metres.
  double SmoothDistance(const Eigen::MatrixXf& field_cells, const common::Vector2& world_m) const;
  bool FootprintCrosses(double x_cells, double y_cells, double yaw_grid_rad, const Shape& shape,
                        uint8_t bits, const std::vector<StraddledBits>* straddled = nullptr) const;

  common::GridGeometry geometry_;
  common::Layer cost_;
  CostMapParams params_;
  std::vector<Shape> shapes_;  // indexed by FootprintKind
  int64_t version_{0};
  int64_t utime_{0};
  int missing_tiles_{0};
  int64_t unseen_drop_cells_{0};
  std::shared_ptr<const CostMap> planning_map_;
  double cos_origin_{1.0};
  double sin_origin_{0.0};
  std::optional<std::pair<common::CellIndex, common::CellIndex>> known_cells_;
  Eigen::MatrixXf blocked_distance_;  // cells
  Eigen::MatrixXf nonfree_distance_;  // cells
  // Directed layer: the masks of the one-way cells (empty when there are none), and per heading
  // class the distance to the nearest one-way cell refusing it (lazily).
  bool has_directed_{false};
  int64_t one_way_cells_{0};
  std::vector<uint8_t> one_way_mask_;
  mutable std::array<std::once_flag, 8> class_once_;
  mutable std::array<Eigen::MatrixXf, 8> class_distance_;
  mutable std::once_flag one_way_once_;
  mutable Eigen::MatrixXf one_way_distance_;
  // Connectivity labels, built lazily (only the global planner needs them).
  mutable std::once_flag components_once_;
  mutable std::vector<int32_t> components_;
  mutable std::once_flag ridges_once_;
  mutable std::vector<int32_t> ridges_;
  // FitsAtSomeHeading's answers per kind and cell: 0 not asked yet, 1 fits, 2 does not.
  mutable std::array<std::once_flag, 2> fits_once_;
  mutable std::array<std::unique_ptr<std::atomic<uint8_t>[]>, 2> fits_;
};

}  // namespace cairn::planner
