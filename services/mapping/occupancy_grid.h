#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "common/grid_map.h"
#include "common/point_cloud.h"
#include "services/mapping/raytrace.h"

/// @file
/// 2-D occupancy in log-odds from planar rays: the planar laser (common::LaserScan) and the
/// lidar's obstacle band (occupancy_band.h).
///
/// Each cell holds l = log(p / (1 - p)); unknown cells hold NaN (prior p = 0.5, l = 0, but kept
/// apart from a cell that was observed and came back to 0). A ray applies `miss_logodds` to the
/// cells it crosses and `hit_logodds` to the cell of its end point when it is an obstacle
/// return; values are clamped to [clamp_min_logodds, clamp_max_logodds].
///
/// Defaults follow OctoMap (hit 0.7 -> +0.847, miss 0.4 -> -0.405, clamps -2.0 / +3.5, one
/// update per cell and scan with a hit winning over a miss). OccupancyParams::Seed003() gives
/// the values of seed 003 (hit +2.0, miss -0.7, clamps +-10 applied after each scan, misses
/// only where l < 2.0, every beam applied in turn, every second beam, 0.1 m minimum range,
/// readings of 4.95 m or more carry no hit and clear 4.9 m). Two of that mapper's bugs are
/// fixed here: cells use floor, not truncation toward zero, and a ray whose end lies outside
/// the grid never marks the last cell inside the grid as a hit.
///
/// Extent. The grid has a fixed extent (default 2 km x 2 km at 0.05 m around the site origin)
/// stored in square tiles that are allocated when a ray first touches them, so memory follows
/// the observed area: 4 bytes per observed cell, 64 KB per 6.4 m x 6.4 m tile, about 1.6 GB for
/// a fully observed square kilometre at 0.05 m (100 MB at 0.2 m). Cells outside the extent are
/// never updated.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

/// How a ray's cells are chosen.
enum class OccupancyTraversal {
  kExact,      ///< every cell the segment passes through (TraverseCells)
  kBresenham,  ///< the 8-connected integer line between the end cells (BresenhamCells)
};

struct OccupancyParams {
  // Inverse sensor model (log-odds).
  float hit_logodds{0.84729786f};    ///< log(0.7 / 0.3)
  float miss_logodds{-0.40546511f};  ///< log(0.4 / 0.6)
  float clamp_min_logodds{-2.0f};
  float clamp_max_logodds{3.5f};
  /// A miss changes a cell only while its log-odds is strictly below this (seed 003: 2.0, so a
  /// cell that reached 2.0 is never cleared again). +inf: misses always apply.
  float protect_occupied_logodds{std::numeric_limits<float>::infinity()};
  /// true: within one scan (one Insert call) each cell is updated at most once and a hit wins
  /// over a miss (OctoMap's insertPointCloud). false: every ray is applied in turn, so a cell
  /// hit by six beams of one scan receives six hits (seed 003).
  bool one_update_per_scan{true};
  /// true: clamp once at the end of each scan (seed 003, values may exceed the clamps while
  /// the scan is applied); false: clamp after every update (OctoMap).
  bool clamp_after_scan{false};

  // Beams.
  double min_range_m{0.1};  ///< shorter readings are ignored (a reading of exactly this counts)
  /// Readings at or beyond this (or at or beyond the scan's own range_max_m, or +inf) are no
  /// returns: they carry no hit and only clear space.
  double max_range_m{30.0};
  /// How far a no-return beam clears (never beyond the reading, nor for a laser scan beyond
  /// its range_max_m).
  double no_return_range_m{30.0};
  int beam_step{1};  ///< use beams 0, step, 2·step, ... of a laser scan
  /// A laser scan whose sensor tilts further than this from level (its z axis from the
  /// vertical: roll and pitch together) is skipped whole. The grid models a level plane: a
  /// robot pitched nose down by a bump or a hard stop puts a planar laser's beams on the floor
  /// a metre or two ahead, and seed 003's protected-occupied rule keeps such a hit for good.
  /// +inf (the default): every scan counts.
  double max_scan_tilt_rad{std::numeric_limits<double>::infinity()};
  OccupancyTraversal traversal{OccupancyTraversal::kExact};

  // Grid (site-fixed, axis-aligned with the world).
  double resolution_m{0.05};
  int size_x_cells{40000};
  int size_y_cells{40000};
  double origin_x_m{-1000.0};  ///< world position of the minimum corner of cell (0, 0)
  double origin_y_m{-1000.0};
  int tile_size_cells{128};  ///< a power of two

  /// Seed 003's sensor model and beam rules (the grid fields keep their values).
  static OccupancyParams Seed003();
  common::GridGeometry geometry() const;
  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// Reads the grid keys of an `occupancy` section over the defaults: `preset` (octomap, the
/// default, or seed003: OccupancyParams::Seed003()) first, then the sensor model, beam and grid
/// keys. Does not call Finish: the section also holds the mapper layer's keys.
/// @throws common::ConfigError naming the file and line of a bad key.
/// `base`: the params the octomap preset (or no preset key) starts from.
OccupancyParams ReadOccupancyParams(common::YamlMap& map, const OccupancyParams& base = {});

/// What one Insert call did.
struct OccupancyInsertStats {
  int64_t beams_used{0};     ///< rays traced
  int64_t beams_skipped{0};  ///< decimated by beam_step, or shorter than min_range_m
  int64_t beams_invalid{0};  ///< NaN or negative readings, non-finite ray coordinates
  int64_t hits{0};           ///< hit updates applied
  int64_t misses{0};         ///< miss updates applied
  int64_t hits_outside{0};   ///< obstacle returns whose cell lies outside the grid (not marked)
  int64_t scans_tilted{0};   ///< laser scans skipped whole: tilted beyond max_scan_tilt_rad
};

/// log(p / (1 - p)).
float LogOddsFromProbability(double probability);
/// 1 / (1 + exp(-l)).
double ProbabilityFromLogOdds(float logodds);
/// Occupancy in percent (100·p) for export: 0 free .. 100 occupied, NaN unknown.
float OccupancyPercent(float logodds);

/// The 2-D log-odds occupancy grid. Copyable (a value type); not thread-safe.
class OccupancyGrid {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit OccupancyGrid(const OccupancyParams& params = {});
  OccupancyGrid(const OccupancyGrid& other);
  OccupancyGrid& operator=(const OccupancyGrid& other);
  OccupancyGrid(OccupancyGrid&&) = default;
  OccupancyGrid& operator=(OccupancyGrid&&) = default;
  ~OccupancyGrid();

  /// Integrates one planar laser scan as one scan: beam i points at angle_min + i·increment in
  /// the sensor frame and its end is placed with the full sensor pose (a tilted laser lands
  /// where it hit), projected on the ground plane. NaN and negative readings are counted as
  /// invalid and skipped. @throws std::invalid_argument for a non-finite pose, angle or
  /// increment.
  OccupancyInsertStats InsertScan(const common::LaserScan& scan);

  /// Integrates rays (world metres) as one scan, with the same range rules as a laser scan:
  /// a hit ray shorter than min_range_m is skipped, one reaching max_range_m becomes a no-return
  /// ray; a no-return ray clears min(length, no_return_range_m).
  OccupancyInsertStats InsertRays(const std::vector<PlanarRay>& rays);

  /// Log-odds of a cell; NaN when unknown or outside the grid.
  float LogOdds(const common::CellIndex& cell) const;
  /// Log-odds at a world position; NaN when unknown or outside.
  float LogOddsAt(const common::Vector2& world_m) const;
  /// Sets a cell (restoring a map, tests). NaN makes it unknown again.
  /// @throws std::invalid_argument if the cell is outside the grid.
  void SetLogOdds(const common::CellIndex& cell, float logodds);

  const OccupancyParams& params() const { return params_; }
  const common::GridGeometry& geometry() const { return geometry_; }
  /// Cell of a world position, or nullopt outside the grid.
  std::optional<common::CellIndex> CellAt(const common::Vector2& world_m) const {
    return geometry_.IndexOf(world_m);
  }

  /// The smallest tile-aligned part of the grid that holds every allocated tile (size 0 when
  /// nothing was observed). Tile aligned, so it changes only when the robot reaches new tiles.
  common::GridGeometry ObservedBounds() const;

  /// Samples the grid into `window` as two layers: layers::kOccupancy (100·p, NaN unknown) and
  /// layers::kOccupancyLogOdds. When `window` shares this grid's resolution and cell borders
  /// the copy is exact; otherwise each window cell takes the highest log-odds of the grid cells
  /// sampled inside it (an occupied cell is never averaged away).
  common::GridMap Export(const common::GridGeometry& window) const;
  /// Export(ObservedBounds()).
  common::GridMap ExportObserved() const { return Export(ObservedBounds()); }
  /// Restores log-odds from a map's layers::kOccupancyLogOdds layer (finite cells only; each
  /// cell centre is looked up in this grid). @throws std::out_of_range if the layer is missing.
  void Import(const common::GridMap& map);

  /// Counts Insert calls that changed something (for publishing).
  int64_t version() const { return version_; }
  size_t num_tiles() const { return num_tiles_; }
  size_t memory_bytes() const;
  /// Forgets every cell.
  void Clear();

 private:
  struct Segment {
    double x0, y0, x1, y1;  // continuous cell coordinates
    bool hit;
  };

  float* MutableCell(int ix, int iy);  // allocates its tile; the cell must be inside
  const float* FindCell(int ix, int iy) const;
  bool Inside(int ix, int iy) const {
    return ix >= 0 && iy >= 0 && ix < geometry_.size_x && iy < geometry_.size_y;
  }
  // Range rules on a measured range: appends the segment from origin_m along `direction`
  // (world metres per metre of range) or counts the beam as skipped/invalid.
  void AddBeam(const common::Vector2& origin_m, const common::Vector2& direction, double range_m,
               bool hit, std::vector<Segment>* segments, OccupancyInsertStats* stats) const;
  OccupancyInsertStats Integrate(const std::vector<Segment>& segments, OccupancyInsertStats stats);
  void IntegratePerBeam(const std::vector<Segment>& segments, OccupancyInsertStats* stats);
  bool IntegrateOncePerScan(const std::vector<Segment>& segments, OccupancyInsertStats* stats);
  template <typename Visitor>
  void VisitRayCells(const Segment& segment, Visitor&& visit) const;
  void ApplyMiss(float* cell, OccupancyInsertStats* stats);
  void ApplyHit(float* cell, OccupancyInsertStats* stats);

  OccupancyParams params_;
  common::GridGeometry geometry_;
  int tile_shift_{7};
  int tile_mask_{127};
  int tiles_x_{0};
  int tiles_y_{0};
  std::vector<std::unique_ptr<float[]>> tiles_;  // tiles_x_ * tiles_y_, null until touched
  size_t num_tiles_{0};
  int64_t version_{0};

  // Scratch reused between scans.
  std::vector<float*> touched_;      // cells to clamp at the end of a scan
  std::vector<uint8_t> scan_state_;  // per cell of the scan's bounding box
  std::vector<Segment> segments_;
};

}  // namespace cairn::mapping
