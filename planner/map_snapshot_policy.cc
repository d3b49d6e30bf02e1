#include "planner/map_snapshot_policy.h"

#include <algorithm>
#include <exception>
#include <optional>
#include <utility>

#include "common/check.h"
#include "common/layers.h"
#include "planner/footprint.h"

namespace cairn::planner {

void MapSnapshotParams::Validate() const {
  cost.Validate();
  if (encoding == MapEncoding::kOccupancy) occupancy.Validate();
  CAIRN_THROW_UNLESS(incomplete_timeout_s >= 0.0, "incomplete_timeout_s must not be negative");
}

void FillTiles(const std::vector<std::pair<int, int>>& tiles, int tile_size_cells, float value,
               common::Layer* cells) {
  if (tile_size_cells <= 0) return;
  for (const auto& [tx, ty] : tiles) {
    const int64_t x0 = std::max<int64_t>(0, int64_t{tx} * tile_size_cells);
    const int64_t y0 = std::max<int64_t>(0, int64_t{ty} * tile_size_cells);
    const int64_t x1 = std::min<int64_t>((int64_t{tx} + 1) * tile_size_cells, cells->rows());
    const int64_t y1 = std::min<int64_t>((int64_t{ty} + 1) * tile_size_cells, cells->cols());
    for (int64_t iy = y0; iy < y1; ++iy) {
      for (int64_t ix = x0; ix < x1; ++ix) (*cells)(ix, iy) = value;
    }
  }
}

MapSnapshotPolicy::MapSnapshotPolicy(MapSnapshotParams params,
                                     std::vector<common::Vector2> footprint_m)
    : params_(std::move(params)), footprint_m_(std::move(footprint_m)) {
  params_.Validate();
  FootprintRasterizer check(footprint_m_);  // throws on a bad footprint
}

SnapshotAction MapSnapshotPolicy::Decide(int64_t version, bool complete, bool allow_incomplete,
                                         int64_t now_utime) {
  if (version == 0) return SnapshotAction::kWait;
  // A version built with holes is built again once complete, never again with holes.
  if (version == built_version_ && (!built_incomplete_ || allow_incomplete)) {
    return SnapshotAction::kWait;
  }
  if (pending_since_utime_ == 0) pending_since_utime_ = now_utime;
  if (!allow_incomplete && !complete) return SnapshotAction::kWait;
  return allow_incomplete ? SnapshotAction::kBuildIncomplete : SnapshotAction::kBuild;
}

SnapshotAction MapSnapshotPolicy::OnLayerChanged(int64_t version, bool complete,
                                                 int64_t now_utime) {
  return Decide(version, complete, false, now_utime);
}

SnapshotAction MapSnapshotPolicy::OnPoll(int64_t version, bool complete, int64_t now_utime) {
  if (version == 0 || (version == built_version_ && !built_incomplete_)) {
    return SnapshotAction::kWait;
  }
  if (!complete) {
    const auto timeout_utime = static_cast<int64_t>(params_.incomplete_timeout_s * 1e6);
    if (pending_since_utime_ > 0 && now_utime - pending_since_utime_ >= timeout_utime) {
      return Decide(version, complete, true, now_utime);
    }
    return SnapshotAction::kWait;
  }
  // The missing tiles of the version in use came in.
  if (built_incomplete_) return Decide(version, complete, false, now_utime);
  return SnapshotAction::kWait;
}

bool MapSnapshotPolicy::WantsMissingTiles(int64_t version, bool complete) const {
  if (version == 0 || (version == built_version_ && !built_incomplete_)) return false;
  return !complete;
}

void MapSnapshotPolicy::Record(int64_t version, bool incomplete) {
  built_version_ = version;
  built_incomplete_ = incomplete;
  pending_since_utime_ = 0;
}

common::Result<std::shared_ptr<const CostMap>> MapSnapshotPolicy::Build(AssembledLayer layer,
                                                                        int64_t now_utime) {
  common::Layer& cells = layer.cells;
  if (params_.encoding == MapEncoding::kOccupancy) {
    cells = OccupancyToCostLayer(cells, params_.occupancy, params_.cost.lethal_cost);
  }
  // Tiles the publisher announced but we never got: block them rather than read them as
  // unexplored (which the planners may be allowed to cross).
  FillTiles(layer.missing_tiles, layer.tile_size_cells, params_.cost.lethal_cost, &cells);
  const int missing = static_cast<int>(layer.missing_tiles.size());
  std::optional<common::Layer> directed;
  if (params_.encoding == MapEncoding::kCost && layer.directed) {
    directed = std::move(layer.directed);
    // Directed tiles not held read as 0: the cost layer alone there (its lethal cells stay
    // lethal, one-way or not), never stricter than the cost layer.
    FillTiles(layer.directed_missing_tiles, layer.tile_size_cells, 0.f, &*directed);
  }
  try {
    // The planning twin copies the layers only when the directed layer marks unseen drops.
    std::optional<std::pair<common::Layer, common::Layer>> twin_layers;
    if (params_.look_at_unseen_drops && directed &&
        (directed->array() == layers::kUnseenDrop).any()) {
      twin_layers.emplace(cells, *directed);
    }
    auto map = std::make_shared<CostMap>(layer.geometry, std::move(cells), std::move(directed),
                                         footprint_m_, params_.cost);
    map->set_stamp(layer.version, now_utime);
    map->set_missing_tiles(missing);
    if (twin_layers) {
      CostMapParams relaxed = params_.cost;
      relaxed.unseen_drop_is_unknown = true;
      auto twin = std::make_shared<CostMap>(layer.geometry, std::move(twin_layers->first),
                                            std::move(twin_layers->second), footprint_m_, relaxed);
      twin->set_stamp(layer.version, now_utime);
      twin->set_missing_tiles(missing);
      map->set_planning_map(std::move(twin));
    }
    Record(layer.version, missing > 0);
    return std::shared_ptr<const CostMap>(std::move(map));
  } catch (const std::exception& e) {
    Record(layer.version, false);  // do not retry the same bad version
    return common::InvalidArgumentError(e.what());
  }
}

}  // namespace cairn::planner
