#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "services/explore/work_area.h"
#include <Eigen/Core>

/// @file
/// The 2-D information map of seed 002 (chapter 4): every analysed 3-D point falls on a cell of
/// a 0.3 m grid over the work area, and each cell keeps the statistics of its points, from which
/// come the navigability C_nc, the quality Q_a and the explored state.
///
///   C_nc = R_fo (0.5 + F_c / 2) + (1 - R_fo) (0.5 - B_c / 2),  R_fo = n_pf / (n_pf + n_po)
///
/// where F_c is the mean F of the points with F > tau_F (n_pf of them) and B_c the mean B of the
/// points with B > tau_B (n_po). A cell with no such point is 0.5 (unknown navigability), and
/// Q_a is the mean D of all its points. Cells outside the work area are kept (the robot may drive
/// there) but count for neither coverage nor gain.
///
/// Two levels per cell (InfoMapParams::level_gap_m > 0), after the multi-level surface maps of
/// Triebel, Pfaff and Burgard (2006) kept to two: a bridge the robot drives both over and under,
/// a canopy above the ground. A cell's lower level holds its lowest surface (the points up to
/// level_gap_m above its lowest point); its upper level the points above that. Each level has its
/// own statistics, so its own C_nc, Q_a, ground and step. The upper level's navigability counts
/// only points seen from above (the scanner higher than the point): a deck's underside and the
/// walls under it, seen from the road below, say nothing of the deck's top. Nor does the lower
/// level's count a point seen from below more than 0.5 m under its ground seen from above (the
/// wall under a deck's end, where the deck is the lowest surface known). A map node is a cell
/// and a level: node = cell + level * num_cells(); with one level nodes are cells.

namespace cairn::explore {

/// One analysed point of a scan (world frame), the input of the map.
struct ScoredPoint {
  Eigen::Vector3f position_m{0.f, 0.f, 0.f};
  Eigen::Vector3f normal{0.f, 0.f, 0.f};  ///< unit; zero when unknown
  float navigability{0.f};                ///< F(p)
  float obstacle{0.f};                    ///< B(p)
  float quality{0.f};                     ///< D(p)
};

struct InfoMapParams {
  double cell_size_m{0.3};
  double tau_f{0.65};    ///< points with F above it count as navigable
  double tau_b{0.83};    ///< points with B above it count as obstacle
  double margin_m{3.0};  ///< grid margin around the work area's bounding box
  /// The robot's step (m; 0: no step term). A cell whose steep points span more than this (a
  /// kerb's face, a wall's foot), or whose ground lies more than this above or below a
  /// 4-neighbour's (a kerb's edge), has C_nc at most kStepCnc: not safe to drive, not an
  /// obstacle to the view. Seed 002's F and B read a kerb's top and foot as navigable ground.
  double max_step_m{0.0};
  /// Two levels per cell (0: one): a point more than this above its cell's lowest point belongs
  /// to the upper level. The robot's height plus a margin: a deck higher than that above the
  /// road leaves the road navigable.
  double level_gap_m{0.0};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Layer names (GridMap form, as stored and exported).
namespace info_layers {
inline constexpr char kNavigability[] = "explore/navigability";         ///< C_nc; NaN unexplored
inline constexpr char kQuality[] = "explore/quality";                   ///< Q_a; NaN unexplored
inline constexpr char kExplored[] = "explore/explored";                 ///< 1 explored, 0 not
inline constexpr char kWorkArea[] = "explore/work_area";                ///< 1 inside, 0 outside
inline constexpr char kPoints[] = "explore/points";                     ///< n_p
inline constexpr char kNavigablePoints[] = "explore/navigable_points";  ///< n_pf
inline constexpr char kObstaclePoints[] = "explore/obstacle_points";    ///< n_po
inline constexpr char kSumNavigability[] = "explore/sum_navigability";  ///< sum F over n_pf
inline constexpr char kSumObstacle[] = "explore/sum_obstacle";          ///< sum B over n_po
inline constexpr char kSumQuality[] = "explore/sum_quality";            ///< sum D
inline constexpr char kSumX[] = "explore/sum_x";                        ///< sums of positions
inline constexpr char kSumY[] = "explore/sum_y";
inline constexpr char kSumZ[] = "explore/sum_z";
inline constexpr char kSumNormalX[] = "explore/sum_normal_x";  ///< sums of unit normals
inline constexpr char kSumNormalY[] = "explore/sum_normal_y";
inline constexpr char kSumNormalZ[] = "explore/sum_normal_z";
inline constexpr char kSumNavigableZ[] = "explore/sum_navigable_z";  ///< sum z over n_pf
/// Lowest and highest z of the cell's steep points (a normal more than 45 degrees from the
/// vertical), NaN when none. Optional when a map is rebuilt: maps stored before they existed
/// read as NaN.
inline constexpr char kSteepLowZ[] = "explore/steep_low_z";
inline constexpr char kSteepHighZ[] = "explore/steep_high_z";
/// With two levels: the lowest z of each cell (NaN unexplored), the steep range of the lower
/// level's own points (the step term's; the steep layers above span both levels), and every
/// per-level layer above again for the upper level under kUpperPrefix (for example
/// "explore/upper/navigability"). Optional on load: a map stored with one level reads as one.
inline constexpr char kFloorZ[] = "explore/floor_z";
inline constexpr char kStepLowZ[] = "explore/step_low_z";
inline constexpr char kStepHighZ[] = "explore/step_high_z";
inline constexpr char kUpperPrefix[] = "explore/upper/";
}  // namespace info_layers

class InfoMap {
 public:
  /// @throws std::invalid_argument for a bad work area or bad params.
  InfoMap(const WorkArea& area, const InfoMapParams& params = {});

  /// Adds the points that fall on the grid (others and non-finite ones are skipped) and updates
  /// the cells they touch. Returns how many points were used. `scanner_z_m`, the height of the
  /// scanner that saw them (NaN: unknown, every point counts as seen from above), decides which
  /// upper-level points count for its navigability.
  int64_t AddPoints(const std::vector<ScoredPoint>& points,
                    float scanner_z_m = std::numeric_limits<float>::quiet_NaN());

  const common::GridGeometry& geometry() const { return geometry_; }
  const WorkArea& work_area() const { return area_; }
  const InfoMapParams& params() const { return params_; }
  int size_x() const { return geometry_.size_x; }
  int size_y() const { return geometry_.size_y; }
  int64_t num_cells() const { return geometry_.num_cells(); }
  /// 1, or 2 with InfoMapParams::level_gap_m.
  int num_levels() const { return num_levels_; }
  /// Cells times levels: node = cell + level * num_cells().
  int64_t num_nodes() const { return num_cells() * num_levels_; }
  int64_t Linear(const common::CellIndex& c) const { return geometry_.LinearIndex(c); }
  /// The cell of a cell index or of a node.
  common::CellIndex Cell(int64_t node) const {
    const int64_t linear = node % num_cells();
    return {static_cast<int>(linear % geometry_.size_x),
            static_cast<int>(linear / geometry_.size_x)};
  }
  int64_t NodeCell(int64_t node) const { return node % num_cells(); }
  int NodeLevel(int64_t node) const { return static_cast<int>(node / num_cells()); }
  /// The node of `cell` a robot standing near height z_m is on: of its explored levels, the one
  /// whose ground (or, without ground, mean height) is nearest; the lower level when z_m is NaN
  /// or no level is explored.
  int64_t NearestLevel(int64_t cell, float z_m) const;

  // Per node (a cell index is its lower level's node).
  /// C_nc: 0.5 where no qualifying point fell.
  float Navigability(int64_t node) const { return navigability_[node]; }
  /// Q_a, NaN where unexplored.
  float Quality(int64_t node) const { return quality_[node]; }
  bool Explored(int64_t node) const { return points_[node] > 0.f; }
  /// n_p: the points that fell on the node.
  float PointCount(int64_t node) const { return points_[node]; }
  /// Mean position of the node's points (NaN when unexplored).
  Eigen::Vector3f Centroid(int64_t node) const;
  /// Unit mean normal of the node's points (zero when none).
  Eigen::Vector3f MeanNormal(int64_t node) const;
  /// Mean height of the node's navigable points (the ground a robot would stand on; a tree's
  /// crown above it does not count); NaN when it has none.
  float GroundHeight(int64_t node) const;

  // Per cell, over its levels.
  bool InWorkArea(int64_t cell) const { return in_area_[NodeCell(cell)] != 0; }
  /// Explored on any level.
  bool CellExplored(int64_t cell) const { return cell_explored_[NodeCell(cell)] != 0; }
  /// Q_a, mean position and unit mean normal of all the cell's points (NaN, NaN, zero when
  /// unexplored); with one level, the node's.
  float CellQuality(int64_t cell) const;
  Eigen::Vector3f CellCentroid(int64_t cell) const;
  Eigen::Vector3f CellMeanNormal(int64_t cell) const;
  /// Lowest and highest z (m) of the cell's steep points (a normal more than 45 degrees from the
  /// vertical), on any level; NaN when it has none. A wall that spans a scanner's height hides
  /// the ground behind it from that scanner; a tree's crown (all of it above) or a kerb (all
  /// below) does not.
  float SteepLow(int64_t cell) const { return steep_low_z_[NodeCell(cell)]; }
  float SteepHigh(int64_t cell) const { return steep_high_z_[NodeCell(cell)]; }

  int64_t work_area_cells() const { return work_area_cells_; }
  int64_t explored_work_area_cells() const { return explored_in_area_; }
  /// Explored cells (on any level) of the work area over its cells, in [0, 1].
  double Coverage() const;
  /// Mean CellQuality over the explored cells of the work area (0 when none).
  double MeanQuality() const;

  /// The map as GridMap layers (info_layers), for storage, export and rendering.
  common::GridMap ToGridMap() const;
  /// Rebuilds a map from ToGridMap()'s layers.
  /// @throws std::invalid_argument when a layer is missing or the geometry disagrees.
  static InfoMap FromGridMap(const common::GridMap& grid, const WorkArea& area,
                             const InfoMapParams& params = {});

 private:
  void UpdateNode(int64_t node);
  /// C_nc from the node's statistics, at most kStepCnc where HasStep.
  void UpdateNavigability(int64_t node);
  /// A step higher than params_.max_step_m in the node or to a 4-neighbour's ground (the
  /// neighbour's level nearest in height).
  bool HasStep(int64_t node) const;
  /// Adds one point to a node; `counts` false: to its extent and quality only (an upper-level
  /// point seen from below).
  void AddToNode(int64_t node, const ScoredPoint& p, bool steep, bool counts);
  /// Moves the lower level of `cell` to its (empty) upper level.
  void LiftLowerLevel(int64_t cell);
  /// The per-node point statistics with their (lower level's) layer names.
  struct Statistic {
    const char* layer;
    std::vector<float> InfoMap::*values;
  };
  static const std::array<Statistic, 13>& Statistics();

  WorkArea area_;
  InfoMapParams params_;
  common::GridGeometry geometry_;
  int num_levels_{1};
  // Per cell.
  std::vector<uint8_t> in_area_, cell_explored_;
  int64_t work_area_cells_{0};
  int64_t explored_in_area_{0};
  std::vector<float> steep_low_z_, steep_high_z_;  // every steep point of the cell
  std::vector<float> floor_z_;                     // two levels: the lowest z
  // Statistics per node (struct of arrays).
  std::vector<float> points_, navigable_points_, obstacle_points_;
  std::vector<float> sum_navigability_, sum_obstacle_, sum_quality_;
  std::vector<float> sum_x_, sum_y_, sum_z_, sum_nx_, sum_ny_, sum_nz_;
  std::vector<float> sum_navigable_z_;
  std::vector<float> step_low_z_, step_high_z_;  // the steep points that count
  // Derived, per node.
  std::vector<float> navigability_, quality_;
};

/// The C_nc a cell with a step higher than InfoMapParams::max_step_m has at most: neither safe
/// (0.7) nor blocking the view (0.4).
inline constexpr float kStepCnc = 0.5f;

/// C_nc from a cell's statistics (eq. 4.4): 0.5 when neither count is positive.
double CellNavigability(double navigable_points, double sum_navigability, double obstacle_points,
                        double sum_obstacle);

/// The surface between a scan's points: for every accepted triangle (vertex indices into
/// `points`; a triangle with a vertex not in `valid` is skipped), each cell of `map` whose
/// centre lies inside the triangle's ground projection, that no valid point falls in and that
/// the map has not explored yet gets one point, interpolated from the corners at the cell's
/// centre (position, normal, F, B, D); an explored cell keeps its measured points alone. A
/// scanner 1 m up meets flat ground in rings about d^2 res_t / h apart (0.3 m at 6 m, 2 m at
/// 15 m): the mesh spans the rings and says what lies between, so the cells there are explored
/// too. Near-vertical triangles (ground projection under 1e-6 m^2) fill nothing.
std::vector<ScoredPoint> FillSurfaceCells(const InfoMap& map,
                                          const std::vector<ScoredPoint>& points,
                                          const std::vector<uint8_t>& valid,
                                          const std::vector<Eigen::Vector3i>& triangles);

}  // namespace cairn::explore
