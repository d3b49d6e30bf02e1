#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "common/layers.h"
#include "common/point_cloud.h"
#include "common/status.h"
#include "services/mapping/raytrace.h"

/// @file
/// Dynamic layers after seed 001 (a dynamic map server for domestic robots): a static map, a
/// short-term layer built from the laser that adds and forgets objects, a long-term layer that
/// adopts what stays and forgets what left but never erases a wall of the static map, and the
/// final layer composed from them.
///
/// Values. The short-term layer is a costmap: 0 free, 1..254 increasingly occupied, 255
/// unknown (uint8). The other layers use the occupancy-grid convention (int8): 0..100, -1
/// unknown. The short-term costs are read as occupancy through costmap_2d's publisher table
/// (CostToOccupancy). All layers share the static map's grid (resolution, size, origin).
///
/// One Update is one step of the 5 Hz loop and consumes the scans received since the last
/// step:
/// 1. Marking: a reading r with min_length_m < r < max_length_m marks its end cell; each
///    marked cell gets +cost_inc once (an unknown cell first becomes 0: "known, free").
/// 2. Clearing: every reading (those at or beyond max_length_m clipped to it) clears the cells
///    from the sensor's cell up to, not including, its end cell; each cleared cell gets
///    -cost_dec once (an unknown cell becomes 0). Cells marked in the same step are not
///    cleared.
/// 3. Long term, over every cell: a short-term occupancy above longterm_add_og (> 95, i.e.
///    cost >= 247) is copied in; one in [0, longterm_free_og) (< 5, cost <= 11) lowers the
///    long-term value by longterm_cost_dec unless the static map has a wall there
///    (>= static_wall_og) or the value would go below 0.
/// 4. Final = max(short-term occupancy, long-term), as int8 (so -1 only where both are -1).
///
/// Seed bugs fixed here, each noted where it happens: cells are found with the grid's origin
/// and floor (the seed used round(x / resolution) and ignored the origin); the bounds check is
/// `< size` (the seed's `<= size` wrote one cell past the row); repeated cells are removed by
/// marking each cell once per step (the seed's unique() on unsorted lists left duplicates, and
/// a fast laser incremented a cell several times per step); clearing uses the exact cell
/// traversal (the seed's staircase walk missed cells and cleared cells near the robot once per
/// ray, so they decayed faster than far cells); every beam of the scan is used (the seed's
/// loop assumed a symmetric scan); a cell marked in a step is not cleared by another ray of
/// the same step; and adopting a short-term value never lowers a static wall.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

inline constexpr uint8_t kCostFree = 0;
inline constexpr uint8_t kCostLethal = 254;
inline constexpr uint8_t kCostUnknown = 255;
inline constexpr int8_t kOccupancyUnknown = -1;

/// costmap_2d's Costmap2DPublisher translation of a cost to occupancy: 0 -> 0, 1..252 ->
/// 1 + floor(97 (c - 1) / 251) (1..98), 253 -> 99, 254 -> 100, 255 -> -1.
int8_t CostToOccupancy(uint8_t cost);

struct DynamicLayersParams {
  int cost_inc{4};            ///< added to a marked cell per step
  int cost_dec{1};            ///< subtracted from a cleared cell per step
  double min_length_m{0.23};  ///< readings at or below this are ignored
  double max_length_m{2.5};   ///< readings at or beyond this mark nothing and clear this far
  double update_hz{5.0};      ///< steps per second (the caller's loop)
  int longterm_add_og{95};    ///< short-term occupancy above this enters the long-term layer
  int longterm_free_og{5};    ///< short-term occupancy in [0, this) counts as seen free
  int longterm_cost_dec{1};   ///< subtracted from the long-term layer per step seen free
  int static_wall_og{95};     ///< static cells at or above this are walls, never lowered

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// Reads the seed 001 keys of a `dynamic` section over the defaults. Does not call Finish: the
/// section also holds the mapper layer's keys. @throws common::ConfigError for a bad value.
DynamicLayersParams ReadDynamicLayersParams(common::YamlMap& map);

/// What one step did.
struct DynamicUpdateStats {
  int64_t beams_used{0};
  int64_t beams_ignored{0};  ///< NaN, negative, or not beyond min_length_m
  int64_t cells_marked{0};
  int64_t cells_cleared{0};
  int64_t marks_outside{0};  ///< end cells outside the grid (not marked)
  int64_t long_term_changed{0};
};

/// The static, short-term, long-term and final layers over one grid. Copyable.
class DynamicLayers {
 public:
  /// The static map is `static_map`'s layer `layer` in 0..100 (values are rounded and
  /// clamped), NaN unknown; its geometry becomes every layer's grid. The short-term layer
  /// starts unknown (255) and the long-term layer as a copy of the static map.
  /// @throws std::invalid_argument for invalid params or an empty map;
  ///         std::out_of_range if the layer is missing.
  explicit DynamicLayers(const common::GridMap& static_map, const DynamicLayersParams& params = {},
                         const std::string& layer = layers::kStaticMap);
  DynamicLayers(const DynamicLayers&) = default;
  DynamicLayers& operator=(const DynamicLayers&) = default;
  DynamicLayers(DynamicLayers&&) = default;
  DynamicLayers& operator=(DynamicLayers&&) = default;

  /// One step from the scans received since the last step (a beam's angle is
  /// angle_min + i·increment; its end is placed with the full sensor pose and projected on the
  /// ground plane). @throws std::invalid_argument for a scan with a non-finite pose or angles.
  DynamicUpdateStats Update(const std::vector<common::LaserScan>& scans);
  /// One step from scans plus extra planar rays (the lidar's obstacle band). With no extra
  /// rays this is exactly Update(scans). A ray's length is treated as a reading; a ray that is
  /// not a hit only clears (up to max_length_m).
  DynamicUpdateStats Update(const std::vector<common::LaserScan>& scans,
                            const std::vector<PlanarRay>& extra_rays);

  const common::GridGeometry& geometry() const { return geometry_; }
  const DynamicLayersParams& params() const { return params_; }
  double update_period_s() const { return 1.0 / params_.update_hz; }
  int64_t updates() const { return updates_; }

  /// Raw layers, x fastest from the minimum corner (GridMap order).
  const std::vector<uint8_t>& short_term_costs() const { return short_cost_; }
  const std::vector<int8_t>& static_occupancy() const { return static_og_; }
  const std::vector<int8_t>& long_term_occupancy() const { return long_og_; }
  std::vector<int8_t> final_occupancy() const;

  /// Per cell (the cell must be inside the grid; CAIRN_DEMAND otherwise).
  uint8_t ShortTermCost(const common::CellIndex& cell) const { return short_cost_[Index(cell)]; }
  int8_t ShortTermOccupancy(const common::CellIndex& cell) const {
    return CostToOccupancy(ShortTermCost(cell));
  }
  int8_t StaticOccupancy(const common::CellIndex& cell) const { return static_og_[Index(cell)]; }
  int8_t LongTermOccupancy(const common::CellIndex& cell) const { return long_og_[Index(cell)]; }
  int8_t FinalOccupancy(const common::CellIndex& cell) const;

  /// Sets one short-term cost or long-term value (tools, manual edits such as adding a table
  /// the laser cannot see, tests).
  void SetShortTermCost(const common::CellIndex& cell, uint8_t cost);
  void SetLongTermOccupancy(const common::CellIndex& cell, int8_t value);

  /// Restores a stored long-term layer: `map`'s layer `layer` (0..100, NaN unknown) on the
  /// same grid. Cells where the static map has a wall (>= static_wall_og) keep at least the
  /// wall's value, so a layer stored before a wall was drawn cannot erase it.
  /// @throws std::invalid_argument if the geometry differs; std::out_of_range if the layer is
  /// missing.
  void SetLongTerm(const common::GridMap& map, const std::string& layer = layers::kLongTerm);

  /// The four layers as floats in 0..100, NaN unknown: layers::kStaticMap, kShortTerm (the
  /// short-term cost read as occupancy), kLongTerm and kFinal.
  common::GridMap ToGridMap() const;

 private:
  size_t Index(const common::CellIndex& cell) const;
  // Appends one reading as a ray, or counts it as ignored.
  void AddReading(const common::Vector2& origin_m, const common::Vector2& direction, double range_m,
                  bool hit, DynamicUpdateStats* stats);
  DynamicUpdateStats Step(DynamicUpdateStats stats);
  // The stages of a step: the end cells of the marking rays, the cells the rays cross, then
  // the long-term layer from the short-term one.
  void MarkEnds(DynamicUpdateStats* stats);
  void ClearRays(DynamicUpdateStats* stats);
  void UpdateLongTerm(DynamicUpdateStats* stats);
  bool Inside(int ix, int iy) const;
  size_t IndexOf(int ix, int iy) const;

  struct Ray {
    common::Vector2 origin;  // continuous cell coordinates
    common::Vector2 end;
    bool mark;
  };

  DynamicLayersParams params_;
  common::GridGeometry geometry_;
  std::vector<int8_t> static_og_;
  std::vector<uint8_t> short_cost_;
  std::vector<int8_t> long_og_;
  int64_t updates_{0};
  // Scratch of one step.
  std::vector<Ray> rays_;
  std::vector<uint8_t> step_state_;   // per cell: 0, marked, cleared
  std::vector<size_t> step_touched_;  // cells whose state must be reset
};

/// Loads a map in the ROS map_server format: a YAML file (image, resolution, origin [x, y,
/// yaw], negate, occupied_thresh, free_thresh, optional mode trinary | scale | raw) and its
/// PGM (P2/P5) or PNG image, whose first row is the top of the map. The result has one layer,
/// "static", in 0..100 with NaN unknown: trinary gives 0 / 100 / unknown, scale also grades
/// values between the thresholds (1..99), raw takes the pixel value (0..100, above unknown).
/// Fails with kInvalidArgument naming the file (and line for YAML) on a bad or unknown key,
/// kNotFound for a missing file, kCorrupt for an unreadable image.
common::Result<common::GridMap> LoadStaticMap(const std::string& yaml_path);

}  // namespace cairn::mapping
