#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/grid_map.h"

/// @file
/// Large data in small messages. A lost UDP fragment loses a whole LCM message, so no message
/// on the bus exceeds about 256 KB (and most stay under one 64 KB datagram):
///
/// - LayerTiler splits a grid-map layer into tiles (100 x 100 cells = 40 KB of floats by
///   default), sends only the tiles whose content changed, and a manifest of every tile's
///   version and CRC-32. All-unknown tiles are left out of the manifest (absent = unknown).
/// - LayerAssembler (layer_assembler.h) rebuilds a layer from tiles on the receiving side.
///
/// Lidar revolutions travel as slices: services/runtime/revolution_assembler.h.

namespace cairn::runtime {

/// Encoding of a layer on the bus: float32 cells (lcmt_grid_tile) or int8 occupancy
/// (lcmt_occupancy_tile: NaN -> -1, else rounded and clamped to 0..100).
enum class TileEncoding { kFloat, kOccupancy };

inline constexpr int kDefaultTileSize = 100;
inline constexpr size_t kMaxMessageBytes = 256 * 1024;

/// Publisher side: remembers what it sent per layer.
class LayerTiler {
 public:
  /// Layer versions start after `version_base` (the first Update gives version_base + 1).
  /// Receivers ignore versions older than what they hold, so a publisher that may restart (a
  /// mapper under cairn-launch) passes a base from the wall clock (StartVersionBase()): its
  /// successor's versions then exceed its own and are taken at once.
  LayerTiler(std::string robot, std::string map_name, int tile_size_cells = kDefaultTileSize,
             int64_t version_base = 0);
  /// A version base that grows faster than any publisher bumps versions: the wall clock in
  /// milliseconds since the epoch.
  static int64_t StartVersionBase();

  struct Batch {
    std::vector<cairn::lcmt_grid_tile> tiles;
    std::vector<cairn::lcmt_occupancy_tile> occupancy_tiles;
    cairn::lcmt_grid_manifest manifest{};
    bool changed{false};  ///< false when nothing changed since the last Update
  };

  /// Tiles `layer` of `map`. Tiles whose bytes changed since the last call (all of them on the
  /// first call, after a geometry change, or with force_all) are returned, and the layer
  /// version is bumped when any did. @throws std::out_of_range if the layer is missing.
  Batch Update(const common::GridMap& map, const std::string& layer, TileEncoding encoding,
               int64_t utime, bool force_all = false);
  /// A float tile encoded elsewhere (a map store's blob sent as it is): its place and size, the
  /// CRC-32 of its float cells, and its wire encoding (lcmt_grid_tile::ENCODING_*) and bytes.
  struct EncodedTile {
    int tile_ix{0};
    int tile_iy{0};
    int cells_x{0};
    int cells_y{0};
    uint32_t checksum{0};
    int8_t encoding{0};
    std::vector<uint8_t> bytes;  ///< compressed encodings
    std::vector<float> data;     ///< ENCODING_FLOAT32: the cells, x fastest
  };
  /// Publishes a float layer of `geometry` from encoded tiles (absent tiles are all unknown):
  /// every tile is sent, the layer version bumps, and Resend serves the tiles as they are.
  /// @throws std::invalid_argument for a tile outside the grid or of the wrong size.
  Batch Adopt(const std::string& layer, const common::GridGeometry& geometry,
              std::vector<EncodedTile> tiles, int64_t utime);

  /// One tile of a float layer its owner keeps tile by tile (a map growing in tiles), for
  /// UpdateTiles: its place in the layer's grid, a counter the owner bumps whenever the tile's
  /// cells may have changed, and the cells (tile_size x tile_size floats, x fastest), or null
  /// when the owner has no cells of this layer there (all unknown).
  struct SourceTile {
    int tile_ix{0};
    int tile_iy{0};
    int64_t source_version{0};
    const float* cells{nullptr};
  };
  /// Tiles a float layer of `geometry` (a whole number of tiles) from its owner's tiles, reading
  /// only those whose source_version moved since the last call (all of them with force_all).
  /// Tiles not listed or all unknown are absent. The layer version bumps, and batch.changed is
  /// true, when a tile changed, appeared or went, on the layer's first call, on a new geometry or
  /// with force_all; only then do the manifest's utime and the changed tiles carry `utime`.
  /// @throws std::invalid_argument for a tile outside the grid.
  Batch UpdateTiles(const std::string& layer, const common::GridGeometry& geometry,
                    const std::vector<SourceTile>& tiles, int64_t utime, bool force_all = false);
  /// Every layer gets a new version and no tiles (their owner was cleared): their manifests.
  std::vector<cairn::lcmt_grid_manifest> ClearAll(int64_t utime);
  /// The manifest of a layer as last published; nullopt for a layer never published.
  std::optional<cairn::lcmt_grid_manifest> Manifest(const std::string& layer) const;
  /// Whether the layer was ever published.
  bool Has(const std::string& layer) const { return layers_.count(layer) > 0; }

  /// Tiles named by a resend request (all current tiles when it names none), from the last
  /// Update; an unknown layer gives an empty batch.
  Batch Resend(const cairn::lcmt_tile_resend_request& request) const;
  /// Current version of a layer (0 before its first Update).
  int64_t version(const std::string& layer) const;
  int tile_size() const { return tile_size_; }

 private:
  struct TileState {
    int64_t tile_version{0};
    uint32_t checksum{0};
    int cells_x{0};
    int cells_y{0};
    std::vector<float> data;        // kFloat
    std::vector<int8_t> occupancy;  // kOccupancy
    int8_t encoding{0};             // kFloat adopted: its wire encoding ...
    std::vector<uint8_t> bytes;     // ... and bytes (data stays empty)
    int64_t source_version{-1};     // UpdateTiles: the owner's counter when last read
  };
  struct LayerState {
    common::GridGeometry geometry;
    TileEncoding encoding{TileEncoding::kFloat};
    int64_t version{0};
    int64_t utime{0};
    std::map<std::pair<int, int>, TileState> tiles;  // non-empty tiles only
  };
  void AppendTile(const std::string& layer, const LayerState& state, int ix, int iy,
                  const TileState& tile, Batch* batch) const;
  cairn::lcmt_grid_manifest MakeManifest(const std::string& layer, const LayerState& state) const;

  std::string robot_;
  std::string map_name_;
  int tile_size_;
  int64_t version_base_;
  std::map<std::string, LayerState> layers_;
};

}  // namespace cairn::runtime
