#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/grid_map.h"
#include "services/mapping/terrain_map.h"
#include "services/runtime/tiler.h"

/// @file
/// TerrainPublisher: the terrain layers of a growing TerrainMap as lcmt_grid_tile messages,
/// through runtime::LayerTiler (layer versions, tile versions, CRC-32, manifests without
/// all-unknown tiles, resend), fed tile by tile from the map's sparse store
/// (LayerTiler::UpdateTiles): a tile whose change counter did not move is not even read, so the
/// cost of a publish follows what changed, not the size of the map.
///
/// The published grid ("layer geometry") is the map's bounding box rounded out to blocks of
/// `extent_tiles` tiles. It only grows; when it does, every tile is sent again (receivers reset
/// a layer whose geometry changed). Published tiles coincide with the map's storage tiles.

namespace cairn::mapping {

class TerrainPublisher {
 public:
  /// Layer versions start after `version_base`, as with runtime::LayerTiler: a restarted
  /// mapper given a larger base (LayerTiler::StartVersionBase) supersedes its predecessor's
  /// layers at every receiver at once.
  TerrainPublisher(std::string robot, std::string map_name, int extent_tiles = 4,
                   int64_t version_base = 0);

  struct Batch {
    std::vector<cairn::lcmt_grid_tile> tiles;
    std::vector<cairn::lcmt_grid_manifest> manifests;  ///< one per layer updated
    bool geometry_changed{false};
  };

  /// Tiles of `layers` that changed since the last Update (all of them after a geometry change
  /// or with force_all), and a manifest of every listed layer. A layer missing from the map
  /// (a removed profile) gets an empty manifest once.
  Batch Update(const TerrainMap& map, const std::vector<std::string>& layers, int64_t utime,
               bool force_all = false);
  /// Tiles named by a resend request (all held tiles when it names none), as last sent, with
  /// the layer's manifest. An unknown layer gives an empty batch.
  Batch Resend(const cairn::lcmt_tile_resend_request& request) const;

  /// The current manifest of a layer this publisher has published.
  std::optional<cairn::lcmt_grid_manifest> Manifest(const std::string& layer) const;
  /// After the map was cleared: every layer gets a new version with no tiles; returns those
  /// (empty) manifests so receivers drop what they hold. The next Update starts afresh.
  Batch Reset(int64_t utime);

  /// Current version of a layer (0 before its first change, then above the version base).
  int64_t version(const std::string& layer) const;
  const common::GridGeometry& geometry() const { return geometry_; }
  /// Whether this publisher handles `layer` (it has published it).
  bool Has(const std::string& layer) const { return tiler_ != nullptr && tiler_->Has(layer); }

 private:
  common::GridGeometry Extent(const TerrainMap& map) const;
  /// A manifest with the published grid (none between a Reset and the next Update).
  void WithPublishedGrid(cairn::lcmt_grid_manifest* manifest) const;

  std::string robot_;
  std::string map_name_;
  int extent_tiles_;
  int64_t version_base_;
  int tile_size_{0};
  common::GridGeometry geometry_;
  int origin_tx_{0};
  int origin_ty_{0};
  std::unique_ptr<runtime::LayerTiler> tiler_;  // made at the first Update (the map's tile size)
  std::map<std::string, bool> present_;         // per layer: the map held it at the last Update
};

}  // namespace cairn::mapping
