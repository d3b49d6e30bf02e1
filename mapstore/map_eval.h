#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "common/grid_map.h"
#include "common/types.h"

/// @file
/// Map quality against ground truth (seed 003 §7.6): how well a stored 2-D map matches a
/// world's geometry rasterised on the map's own grid (simulator/ground_truth.h makes the truth;
/// `cairn-map eval` runs both). Pure code: two GridMaps in, figures out.
///
/// Classes of a map cell, from one layer:
/// - `occupancy` and other 0..100 layers (100·p, NaN unknown): occupied above
///   occupied_above, free below free_below, otherwise (and NaN) unknown;
/// - `cost/<profile>` (common/layers.h): occupied at 100 (lethal), free from 0 to 99, NaN unknown;
/// - `explore/navigability` (the next-best-view information map's C_nc, 0..1, NaN unexplored):
///   free above cnc_free_above (the explorer's safe cells), occupied below cnc_occupied_below
///   (the cells that block its view), known but neither in between (counted in coverage only).
/// With region_layer, only the cells where that map layer is 1 count (for instance
/// `explore/work_area`: the explorer's work area); the others are left out like cells outside
/// the world.
/// The truth: `truth/occupied` 1 occupied, 0 free, NaN outside the world (such cells are left
/// out of every figure); `truth/ground` (optional) the ground height.
///
/// Figures (cells are counted where the truth is known):
/// - occupied precision: map-occupied cells with a truth-occupied cell within tolerance_cells
///   (Chebyshev distance), over the map-occupied cells; occupied recall: truth-occupied cells
///   with a map-occupied cell within tolerance_cells, over the truth-occupied cells; the visible
///   recall counts only truth-occupied cells that touch (8-neighbourhood) the reachable area,
///   the faces a robot there could see;
/// - free precision: map-free cells that are truth-free, over the map-free cells (no tolerance);
/// - coverage: the reachable area is the truth-free cells 4-connected to the start; coverage is
///   the fraction of it the map knows (free or occupied);
/// - IoU of the occupied sets (no tolerance);
/// - wall thickness: for each map-occupied cell with a truth-occupied cell within tolerance, the
///   shorter of the occupied runs through it along its row and its column (a straight wall's
///   width across), averaged in cells and metres; cells where both runs are longer than
///   max_wall_thickness_cells (the corner block of two walls, large blobs) are not measured;
/// - double walls: along every row and column, two consecutive map-occupied runs separated by
///   double_wall_min_gap_cells..double_wall_max_gap_cells non-occupied cells, where the truth
///   over the stretch from the first run's start to the second run's end (widened by
///   tolerance_cells) holds exactly one occupied run, some cell of the gap is truth-free and one
///   of the two runs lies wholly off the truth (no cell within tolerance_cells of it): one wall
///   mapped twice. The two faces of a thin wall whose inside was never seen are not, and neither
///   is a stray cell within a cell of a wall's end or corner.
///   Counted per crossing (a doubled wall n cells long crossed by n rows or columns counts n);
/// - free precision, strict and within tolerance_cells (a map-free cell with a truth-free cell
///   within tolerance is right);
/// - elevation (when the map has `elevation` and the truth `truth/ground`): map − truth on the
///   truth-free cells both know (the ground is what a mapper measures there), and on those of
///   them with no truth obstacle within tolerance_cells (elevation_interior).
///
/// A figure whose denominator is zero is NaN.

namespace cairn::mapstore {

/// Layer names of the truth (the same strings as simulator/ground_truth.h's).
inline constexpr char kTruthOccupied[] = "truth/occupied";
inline constexpr char kTruthGround[] = "truth/ground";
/// The information map's C_nc layer (services/explore/info_map.h).
inline constexpr char kInfoNavigability[] = "explore/navigability";

struct MapEvalParams {
  /// The map layer judged: 0..100 occupancy-like, or cost/<profile>.
  std::string layer{"occupancy"};
  double occupied_above{65.0};     ///< 0..100 layers: occupied when > this
  double free_below{25.0};         ///< 0..100 layers: free when < this
  double cnc_free_above{0.7};      ///< explore/navigability: free above this C_nc
  double cnc_occupied_below{0.4};  ///< explore/navigability: occupied below this C_nc
  /// Optional map layer (1 inside): the figures count only the cells inside.
  std::string region_layer;
  /// World position the reachable area grows from (required; must be truth-free).
  std::optional<common::Vector2> start_m;
  int tolerance_cells{1};
  /// Wall thickness: cells whose row and column runs both exceed this are not measured.
  int max_wall_thickness_cells{10};
  int double_wall_min_gap_cells{2};
  int double_wall_max_gap_cells{6};
  /// Map layer compared with truth/ground (skipped when the map lacks it).
  std::string elevation_layer{"elevation"};

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

struct ElevationError {
  int64_t cells{0};  ///< cells compared (0: none; the other figures are then NaN)
  double mean_abs_m{0.0};
  double rms_m{0.0};
  double max_abs_m{0.0};
};

struct MapEvalReport {
  std::string layer;
  double resolution_m{0.0};
  int64_t truth_cells{0};  ///< cells where the truth is known
  int64_t truth_occupied_cells{0};
  int64_t truth_free_cells{0};
  int64_t map_occupied_cells{0};  ///< of the truth_cells
  int64_t map_free_cells{0};
  int64_t map_unknown_cells{0};

  double occupied_precision{0.0};
  double occupied_recall{0.0};
  double occupied_recall_visible{0.0};
  double free_precision{0.0};
  /// Map-free cells with a truth-free cell within tolerance_cells (the twin of occupied
  /// precision's tolerance): a free cell at an obstacle's edge, whose truth cell holds a sliver
  /// of the obstacle, is not counted wrong.
  double free_precision_tolerant{0.0};
  double occupied_iou{0.0};

  int64_t reachable_cells{0};
  int64_t reachable_known_cells{0};
  double coverage{0.0};  ///< reachable_known_cells / reachable_cells

  int64_t wall_cells_measured{0};
  double mean_wall_thickness_cells{0.0};
  double mean_wall_thickness_m{0.0};

  int64_t double_wall_crossings{0};
  double double_wall_length_m{0.0};  ///< crossings × resolution

  std::optional<ElevationError> elevation;  ///< when both sides have heights
  /// The same over the truth-free cells with no truth obstacle within tolerance_cells (a cell at
  /// a wall's foot mixes floor and wall returns at the map's resolution).
  std::optional<ElevationError> elevation_interior;
};

/// Judges `map`'s layer against `truth` (the same grid geometry: rasterise the truth on the
/// map's grid). @throws std::invalid_argument for invalid params, differing geometries, a
/// missing layer, or a start outside the map or not free in the truth.
MapEvalReport EvaluateMap(const common::GridMap& map, const common::GridMap& truth,
                          const MapEvalParams& params);

/// The report as one JSON object (NaN figures as null).
std::string MapEvalReportToJson(const MapEvalReport& report);

}  // namespace cairn::mapstore
