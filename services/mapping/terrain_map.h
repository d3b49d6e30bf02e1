#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/grid_map.h"
#include "common/obstacle.h"
#include "common/point_cloud.h"
#include "common/robot_profile.h"
#include "common/types.h"
#include "services/mapping/elevation_filter.h"
#include "services/mapping/obstacles.h"
#include "services/mapping/traversability.h"

/// @file
/// TerrainMap: the live terrain layers of one robot's site, growing in tiles as the robot
/// travels.
///
/// Geometry. A site-fixed grid: cell (i, j) covers world [i·res, (i+1)·res) × [j·res, (j+1)·res)
/// (world axes, origin at the world origin, floor for negative coordinates). Cells are stored in
/// square tiles of tile_size_cells, allocated when a measurement first lands in them, so memory
/// follows the explored area, not its bounding box; cell indices are 32-bit, so a square
/// kilometre (5000 x 5000 cells at 0.2 m) is far inside the addressable range. Export() gives
/// dense GridMap windows (by default the tile-aligned bounding box of every allocated tile).
///
/// Layers per cell:
/// - base (robot-agnostic): elevation, elevation_variance, observation_count, last_seen_s and
///   ground_bound (common/layers.h). The elevation layer follows the height filter in steps
///   larger than commit_epsilon_m, so derived layers are recomputed only where the terrain
///   changed, never for sub-millimetre filter jitter;
/// - derived (ComputeGeometricLayers, ComputeFeatureLayers, one ComputeCostLayer per profile),
///   updated by UpdateDerived() in the blocks around cells whose base layers changed, with
///   enough margin that every value equals a whole-map computation on the exported base layers.
///
/// Not thread-safe: one owner thread.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

struct TerrainMapParams {
  double resolution_m{0.2};
  int tile_size_cells{100};  ///< also the tile of the published layers
  ElevationFilterParams filter;
  double min_range_m{0.4};  ///< closer points (the robot itself) are dropped
  /// Points closer than this to the sensor horizontally are dropped: the robot's own body and
  /// the ground under it, which a real sensor cannot see (0 keeps them).
  double self_filter_radius_m{0.0};
  double max_range_m{30.0};  ///< farther points are dropped (counted)
  /// Points higher than this above the sensor are overhangs (tunnel ceilings, canopies) a 2.5-D
  /// map cannot hold; they are skipped.
  double max_height_above_sensor_m{1.0};
  /// Each downward ray records, over this last stretch before its return, the height at which
  /// it crossed each cell (the ground bound). <= 0 turns the bound off.
  double ray_bound_length_m{2.0};
  /// Only returns closer than this record the bound: farther rays run almost level and prove
  /// nothing deeper than the ground they hit.
  double ray_bound_max_range_m{12.0};
  /// Each ray is taken to end this much short of its return when it records bounds: a return
  /// measured long by the range noise puts the ray's last stretch below the surface, and the
  /// bound keeps the lowest ray, so without a margin the bounds around a robot at rest sink
  /// centimetres under the floor (false drops beside known cells). The bound is the lowest of
  /// many rays, so the margin must cover nearly all of them: at 3 cm (1.7 sigma of 1.8 cm range
  /// noise) one ray in twenty reached past it, and the deck cell behind a trench's far face
  /// read as crossed 20 cm down (no clean rim, no ditch: the terraces world's 0.6 m trench
  /// seen from the rover). 6 cm is 3.3 sigma.
  double ray_bound_margin_m{0.06};
  /// The published elevation (and ground bound) follows the filter in steps larger than this.
  double commit_epsilon_m{0.003};
  /// A cell a lidar ray passed beneath by more than visibility_tolerance_m (but less than
  /// max_visibility_conflict_m) mixes a surface with the gap next to it and is published
  /// unknown (see CommitHeight).
  double visibility_tolerance_m{0.03};
  double max_visibility_conflict_m{0.15};
  TraversabilityParams traversability;
  ObstacleParams obstacles;

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Reads a `terrain` section (every key optional, with the sub-sections filter, traversability
/// and obstacles) over the defaults. @throws common::ConfigError naming the file and line of a
/// bad or unknown key.
TerrainMapParams LoadTerrainMapParams(common::YamlMap& map);

/// What one Integrate() call did with its points.
struct IntegrateStats {
  int64_t points{0};
  int64_t used{0};           ///< changed a cell (initialised, fused, raised, multi-height)
  int64_t ignored_lower{0};  ///< lower than the cell, same scan
  int64_t nonfinite{0};      ///< NaN or infinite coordinates: bad input
  int64_t out_of_range{0};   ///< closer than min_range or farther than max_range
  int64_t self{0};           ///< within self_filter_radius of the sensor
  int64_t overhang{0};       ///< above max_height_above_sensor
  IntegrateStats& operator+=(const IntegrateStats& o);
};

/// What one UpdateDerived() call recomputed.
struct DerivedStats {
  int64_t geometric_cells{0};
  int64_t cost_cells{0};
};

class TerrainMap {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit TerrainMap(const TerrainMapParams& params = {});
  ~TerrainMap();
  TerrainMap(const TerrainMap&) = delete;
  TerrainMap& operator=(const TerrainMap&) = delete;

  const TerrainMapParams& params() const { return params_; }

  /// Adds a profile (or replaces the one with the same name) and computes its cost layer over
  /// the whole map. @throws std::invalid_argument for an invalid profile.
  void AddProfile(const common::RobotProfile& profile);
  /// Removes a profile and its cost layer; false if there was none of that name.
  bool RemoveProfile(const std::string& name);
  const std::vector<common::RobotProfile>& profiles() const { return profiles_; }
  const common::RobotProfile* FindProfile(const std::string& name) const;

  /// Fuses points given in the sensor frame, placed in the world with `sensor_pose`. `scan_id`
  /// names the revolution the points belong to (the filter's same-scan rule); `time_s` stamps
  /// last_seen_s. Bad points are counted and skipped; a non-finite pose skips every point.
  IntegrateStats Integrate(const std::vector<common::LidarPoint>& points,
                           const common::Pose3& sensor_pose, int64_t scan_id, double time_s);
  /// Every slice of a revolution with its own pose, as one scan.
  IntegrateStats Integrate(const common::LidarRevolution& revolution, double time_s);

  /// Recomputes the derived layers where the base layers changed since the last call, and the
  /// cost layers around the robot's previous and current position (blind zone; the whole
  /// neighbourhood when IMU compensation is on).
  DerivedStats UpdateDerived(const RobotContext& robot = {});

  /// The obstacle registry of the whole map, with verdicts for every profile.
  common::ObstacleRegistry BuildRegistry() const;

  /// True until a measurement has landed.
  bool empty() const { return tiles_.empty(); }
  /// Tile-aligned bounding box of every allocated tile grown by one empty tile on each side, so
  /// no known cell lies on the border of an export (an empty geometry when empty()).
  common::GridGeometry Bounds() const;
  /// The bounding box of the allocated tiles alone.
  common::GridGeometry AllocatedBounds() const;
  /// The geometry of a tile.
  common::GridGeometry TileGeometry(int tx, int ty) const;
  /// Dense copy of `layers` over `window` (which must be aligned with this grid's cells and
  /// axes); cells outside allocated tiles are NaN. @throws std::invalid_argument for a window
  /// off the grid or an unknown layer.
  common::GridMap Export(const std::vector<std::string>& layers,
                         const common::GridGeometry& window) const;
  /// Over Bounds().
  common::GridMap Export(const std::vector<std::string>& layers) const;

  /// Base and derived layer names (published and exportable), cost layers included.
  static std::vector<std::string> BaseLayers();
  std::vector<std::string> DerivedLayers() const;

  /// Allocated tiles, in (ty, tx) order.
  std::vector<std::pair<int, int>> Tiles() const;
  /// A tile's layers (nullptr if not allocated), and counters bumped when its base or derived
  /// layers change (publishers skip tiles whose counter did not move).
  const common::GridMap* TileLayers(int tx, int ty) const;
  int64_t TileBaseVersion(int tx, int ty) const;
  int64_t TileDerivedVersion(int tx, int ty) const;

  /// Forgets every measurement (profiles are kept).
  void Clear();
  /// Cells holding a height.
  int64_t known_cells() const;
  /// Approximate memory held by the tiles, bytes.
  size_t memory_bytes() const;

 private:
  struct Tile;
  struct ScanFrame;
  /// The slope of the last cell a point fell in and its spread variance (runs of points fall
  /// in one cell).
  struct SpreadCache {
    float slope;
    double variance;
  };
  using Key = std::pair<int, int>;
  struct KeyHash {
    size_t operator()(const Key& k) const {
      // Unsigned: shifting a negative index is undefined behaviour.
      return std::hash<uint64_t>()((uint64_t{static_cast<uint32_t>(k.first)} << 32) ^
                                   static_cast<uint32_t>(k.second));
    }
  };

  Tile* GetTile(int tx, int ty);
  const Tile* FindTile(int tx, int ty) const;
  Tile* TileForCell(int64_t cx, int64_t cy, int* lx, int* ly);
  /// A sensor-frame point in the world; false (counted in `stats`) when it is filtered out
  /// (not finite, out of range, the robot itself, an overhang).
  bool PlacePoint(const ScanFrame& scan, const common::LidarPoint& point, common::Vector3* pw,
                  double* range, IntegrateStats* stats) const;
  /// Fuses a world point (at `range` from the sensor) into its cell (cx, cy): the height
  /// filter, where the points lie in the cell, the counters, then the committed height.
  void FusePoint(const ScanFrame& scan, const common::Vector3& pw, double range, int64_t cx,
                 int64_t cy, SpreadCache* spread, IntegrateStats* stats);
  void MarkDirty(int64_t cx, int64_t cy);
  /// Records the ground bound along the last ray_bound_length_m of the segment from -> to; the
  /// cell (return_x, return_y) holds the return and gets none.
  void RecordBound(const common::Vector3& from, const common::Vector3& to, int64_t return_x,
                   int64_t return_y);
  /// Publishes the cell's filtered height (carried to the cell's centre on a trusted normal);
  /// with `only_to_carry`, only when it is carried now (a recommit).
  void CommitHeight(Tile* tile, size_t i, int64_t cx, int64_t cy, bool only_to_carry = false);
  /// Commits again the cells of `rects` whose last commit had no trusted normal.
  void RecommitUnsettled(const std::vector<CellRect>& rects);
  /// True when the cell's normal fit interpolates: of its 8 neighbours (in any tile) at most
  /// two lack a height, and some have one on each side along both axes.
  bool NormalInterpolates(const Tile& tile, size_t i, int64_t cx, int64_t cy) const;
  /// The committed height of the cell (dx, dy) from (cx, cy) (index i in `tile`), NaN unknown.
  float CommittedAt(const Tile& tile, size_t i, int64_t cx, int64_t cy, int dx, int dy) const;
  /// Limits the fitted gradient (gx, gy) of a cell, axis by axis, by the one-sided height
  /// differences to its neighbours (the MC limiter): an even ramp keeps its gradient, the foot
  /// and the top of a step get none, so a carry along it cannot spread the face.
  void LimitGradient(const Tile& tile, size_t i, int64_t cx, int64_t cy, double* gx,
                     double* gy) const;
  /// NormalInterpolates, answered again without looking while nothing it reads changed.
  bool CachedNormalInterpolates(const Tile& tile, size_t i, int64_t cx, int64_t cy);
  /// Copies `layers` of the global cell rectangle into a dense map (NaN outside tiles).
  common::GridMap Window(const CellRect& global, const std::vector<std::string>& layers) const;
  /// The same into `out` with geometry `g` (reusing its buffers when the geometry matches).
  void WindowInto(const CellRect& global, const std::vector<std::string>& layers,
                  const common::GridGeometry& g, common::GridMap* out) const;
  /// A window of the recomputation in the shared scratch map (local coordinates).
  common::GridMap& Scratch(const CellRect& global, const std::vector<std::string>& layers);
  /// Writes `layers` of `window` (whose cell (0,0) is global `origin_cell`) back for `rect`.
  void WriteBack(const common::GridMap& window, int64_t origin_x, int64_t origin_y,
                 const CellRect& rect, const std::vector<std::string>& layers);
  void RecomputeCosts(const std::vector<CellRect>& rects, const RobotContext& robot,
                      const std::vector<const common::RobotProfile*>& which);
  /// The blocks whose derived values can depend on a block changed since the last call.
  std::set<Key> TakeChangedRegion();
  /// Adds the blocks within `radius_m` of `xy` (world) to `region`.
  void AddBlocksAround(const common::Vector2& xy, double radius_m, std::set<Key>* region) const;
  /// The geometric, then the feature layers of `rects`; returns the cells recomputed.
  int64_t RecomputeGeometry(const std::vector<CellRect>& rects);
  std::vector<CellRect> RectsOfBlocks(const std::set<Key>& blocks) const;

  TerrainMapParams params_;
  std::vector<common::RobotProfile> profiles_;
  std::unordered_map<Key, std::unique_ptr<Tile>, KeyHash> tiles_;
  Tile* last_tile_{nullptr};
  Key last_key_{0, 0};
  std::set<Key> dirty_blocks_;  ///< blocks whose base layers changed
  Key last_dirty_{0, 0};        ///< the block MarkDirty inserted last (valid when has_last_dirty_)
  bool has_last_dirty_{false};
  double min_spread_nz2_{1.0};  ///< cos^2(filter.max_spread_slope_rad): CommitHeight's gate
  // NormalInterpolates of the last cell asked, while no committed height turned known or
  // unknown (runs of points fall in one cell). Reset by each Integrate.
  uint64_t known_epoch_{0};
  const Tile* interpolates_tile_{nullptr};
  size_t interpolates_i_{0};
  uint64_t interpolates_epoch_{0};
  bool interpolates_{false};
  // The carry's limited gradient of the last cell committed (LimitGradient), for the run of
  // points in it. Reset by each Integrate.
  const Tile* limited_tile_{nullptr};
  size_t limited_i_{0};
  double limited_gx_{0.0};
  double limited_gy_{0.0};
  std::optional<common::Vector2> last_robot_xy_;
  std::set<Key> last_region_;  ///< the blocks the last UpdateDerived derived (RecommitUnsettled)
  common::GridMap scratch_;    // recomputation windows
  mutable common::GridMap registry_scratch_;  // BuildRegistry's copy of the map
  int block_cells_{25};
};

}  // namespace cairn::mapping
