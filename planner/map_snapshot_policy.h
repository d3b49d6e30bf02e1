#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "common/grid_map.h"
#include "common/status.h"
#include "common/types.h"
#include "planner/cost_map.h"
#include "planner/occupancy_cost.h"

/// @file
/// MapSnapshotPolicy: the navigator's map policy, apart from the transport that assembles the
/// layer from tiles (lcm/lcm_map_client.h). It decides when an assembled layer version becomes
/// a CostMap snapshot and what the snapshot holds:
///
/// - a complete version is taken at once;
/// - a version still missing tiles waits `incomplete_timeout_s` (from when it was first seen),
///   then is taken with the cells of the missing tiles lethal: their content is unknown to us,
///   not unexplored, and the planners may be allowed to cross unexplored cells;
/// - a version taken with holes is taken again once its tiles came, never again with holes;
/// - a version the CostMap refuses (a bad geometry) is not tried again;
/// - an occupancy layer (MapEncoding::kOccupancy) is converted to cost (occupancy_cost.h);
/// - a directed layer handed in beside a cost layer goes into the snapshot (CostMap's one-way
///   cells), its missing tiles blocking every heading.

namespace cairn::planner {

struct MapSnapshotParams {
  /// kCost: the layer is a cost layer; kOccupancy: occupancy (0..100, NaN unknown) converted
  /// with `occupancy`.
  MapEncoding encoding{MapEncoding::kCost};
  OccupancyCostParams occupancy;
  /// How the snapshots read the cost (unknown cells, lethal cost, planning padding).
  CostMapParams cost;
  /// Take a version with missing tiles after waiting this long for them (s, >= 0).
  double incomplete_timeout_s{1.0};
  /// A snapshot whose directed layer marks unseen drops also carries a planning twin that reads
  /// them as unknown (CostMap::planning_map, CostMapParams::unseen_drop_is_unknown).
  bool look_at_unseen_drops{false};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// The newest version of the layer as the transport assembled it.
struct AssembledLayer {
  int64_t version{0};
  common::GridGeometry geometry;
  common::Layer cells;     ///< the layer's cells (common::Layer convention), NaN unknown
  int tile_size_cells{0};  ///< tile edge of the version's manifest; 0: unknown
  /// Tiles the version announced that are not held, as (tile_ix, tile_iy).
  std::vector<std::pair<int, int>> missing_tiles;
  /// The profile's directed layer ("directed/<profile>") on the same grid, when the transport
  /// holds one (cost encoding only); nullopt: the snapshot reads the cost layer alone.
  std::optional<common::Layer> directed;
  /// Tiles of the directed layer's newest version not held: they read as 0, the cost layer
  /// alone (its lethal cells block, one-way or not; its free cells stay free).
  std::vector<std::pair<int, int>> directed_missing_tiles;
};

/// What the transport should do about the newest version.
enum class SnapshotAction {
  kWait,             ///< nothing now
  kBuild,            ///< build a snapshot of the complete version
  kBuildIncomplete,  ///< build one with whatever tiles are missing (they read as lethal)
};

/// Not thread-safe: call it from the thread that assembles the layer.
class MapSnapshotPolicy {
 public:
  /// @throws std::invalid_argument for invalid params or footprint.
  MapSnapshotPolicy(MapSnapshotParams params, std::vector<common::Vector2> footprint_m);
  MapSnapshotPolicy(const MapSnapshotPolicy&) = delete;
  MapSnapshotPolicy& operator=(const MapSnapshotPolicy&) = delete;
  MapSnapshotPolicy(MapSnapshotPolicy&&) = default;
  MapSnapshotPolicy& operator=(MapSnapshotPolicy&&) = default;

  /// A tile or a manifest of the layer arrived. `version`: the newest announced (0: none yet);
  /// `complete`: every tile it announced is held. Times in µs of the caller's clock.
  SnapshotAction OnLayerChanged(int64_t version, bool complete, int64_t now_utime);
  /// Called periodically: builds an overdue incomplete version, and the version in use again
  /// once its missing tiles came.
  SnapshotAction OnPoll(int64_t version, bool complete, int64_t now_utime);
  /// True while `version` lacks tiles and is not the complete version in use: the transport
  /// asks the publisher for them.
  bool WantsMissingTiles(int64_t version, bool complete) const;

  /// Builds the snapshot of `layer` (converted to cost, missing tiles lethal, stamped with its
  /// version, `now_utime` and the count of missing tiles) and records its version as the one in
  /// use. A layer the CostMap refuses is an InvalidArgument error; its version is recorded too,
  /// so it is not tried again.
  common::Result<std::shared_ptr<const CostMap>> Build(AssembledLayer layer, int64_t now_utime);

  /// Version of the snapshot in use (-1 before the first), and whether it has holes.
  int64_t built_version() const { return built_version_; }
  bool built_incomplete() const { return built_incomplete_; }
  const MapSnapshotParams& params() const { return params_; }

 private:
  SnapshotAction Decide(int64_t version, bool complete, bool allow_incomplete, int64_t now_utime);
  void Record(int64_t version, bool incomplete);

  MapSnapshotParams params_;
  std::vector<common::Vector2> footprint_m_;
  int64_t built_version_{-1};
  bool built_incomplete_{false};    // the version in use was built with missing tiles
  int64_t pending_since_utime_{0};  // when the newest unbuilt version was first seen
};

/// Sets every cell of the listed tiles (tile_ix, tile_iy) of `tile_size_cells` to `value`,
/// clipped to the layer; tiles outside it change nothing.
void FillTiles(const std::vector<std::pair<int, int>>& tiles, int tile_size_cells, float value,
               common::Layer* cells);

}  // namespace cairn::planner
