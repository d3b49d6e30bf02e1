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
/// - LayerAssembler rebuilds a layer from tiles, checks each tile's checksum, compares its
///   holdings with the newest manifest and names the tiles it must ask for again.
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

/// Receiver side: rebuilds layers from tiles and manifests.
class LayerAssembler {
 public:
  /// Returns false (and counts a checksum error) when the tile's data do not match its CRC, or
  /// when the tile is compressed (its receiver decodes it first: mapstore::DecompressTile).
  bool OnTile(const cairn::lcmt_grid_tile& tile);
  bool OnTile(const cairn::lcmt_occupancy_tile& tile);
  /// A compressed tile its receiver decoded into `cells` with a codec that verified the bytes
  /// against the sender's own checksum (mapstore::DecodeTileCells: zstd's content checksum, of
  /// bytes whose CRC the sender declared): the tile's declared checksum stands for the cells,
  /// without a second CRC pass. False (a checksum error counted) when the cells do not fit.
  bool OnDecodedTile(const cairn::lcmt_grid_tile& tile, const std::vector<float>& cells);
  /// Where a compressed tile's cells go in its layer, for a receiver that decodes the tile
  /// straight into place: the tile's cell (0, 0) at `first`, rows `row_stride` floats apart,
  /// `cells_x` × `cells_y` cells (the tile clipped to its layer). No `first`: nothing to write.
  struct TileSlot {
    float* first{nullptr};
    int64_t row_stride{0};
    int cells_x{0};
    int cells_y{0};
  };
  /// Reserves the place of a compressed tile (allocating its layer at the layer's first tile).
  /// nullopt (a checksum error counted) when the tile does not fit a layer; a slot without
  /// cells, and no EndTile to call, when the tile is older than the one held there or lies
  /// outside its layer (it counts as held, as in OnTile). Until EndTile, the cells of a
  /// reserved place are undefined. A slot stays valid until a tile or manifest of another grid
  /// arrives for the same layer.
  std::optional<TileSlot> BeginTile(const cairn::lcmt_grid_tile& tile);
  /// Ends BeginTile. `decoded`: the receiver wrote every cell of the slot with a codec that
  /// verified them against the sender's checksum (as for OnDecodedTile), and the tile is held.
  /// Otherwise its place becomes unknown and no tile is held there.
  void EndTile(const cairn::lcmt_grid_tile& tile, bool decoded);
  void OnManifest(const cairn::lcmt_grid_manifest& manifest);

  /// Layers seen so far (from tiles or manifests).
  std::vector<std::string> layers() const;
  /// True when every tile of the newest manifest of `layer` is held with the same checksum.
  bool Complete(const std::string& layer) const;
  /// Version of the newest manifest of a layer (0 if none).
  int64_t version(const std::string& layer) const;
  /// Tiles of the newest manifest not held (or held stale), as (tile_ix, tile_iy).
  std::vector<std::pair<int, int>> Missing(const std::string& layer) const;
  /// A request for the missing tiles; nullopt when nothing is missing or no manifest arrived.
  std::optional<cairn::lcmt_tile_resend_request> MakeResendRequest(const std::string& layer,
                                                                   const std::string& requester,
                                                                   int64_t utime) const;
  /// The layer as a one-layer GridMap (cells of absent tiles are NaN); nullopt if the layer was
  /// never seen. Occupancy -1 becomes NaN.
  std::optional<common::GridMap> Layer(const std::string& layer) const;
  /// Layer without a copy: the cells move out and the layer is forgotten.
  std::optional<common::GridMap> TakeLayer(const std::string& layer);
  /// The checksum of the tile held at (tile_ix, tile_iy) of a layer (its cells are that tile's
  /// in Layer); nullopt when none is held.
  std::optional<uint32_t> HeldChecksum(const std::string& layer, int tile_ix, int tile_iy) const;
  /// The grid of a layer as Layer would return it, without assembling it.
  std::optional<common::GridGeometry> Geometry(const std::string& layer) const;
  /// Layers larger than this are refused (a tile declaring such a grid counts as an error).
  static constexpr int64_t kMaxLayerCells = 64'000'000;

  int64_t checksum_errors() const { return checksum_errors_; }
  /// Forget a layer.
  void Drop(const std::string& layer) { layers_.erase(layer); }

 private:
  // Tiles are pasted into their layer's cells as they arrive; a Held records one.
  struct Held {
    int64_t tile_version{0};
    uint32_t checksum{0};
    int cells_x{0};
    int cells_y{0};
  };
  struct LayerState {
    common::GridGeometry geometry;
    int tile_size{0};
    bool has_manifest{false};
    int64_t manifest_version{0};
    std::string robot;
    std::string map_name;
    std::map<std::pair<int, int>, uint32_t> expected;  // from the newest manifest
    std::map<std::pair<int, int>, Held> tiles;
    // Geometry-sized, allocated with the first tile. Cells of held tiles are theirs; the others
    // are undefined until Layer or TakeLayer makes them unknown.
    common::Layer cells;
  };
  LayerState& StateFor(const std::string& layer, const common::GridGeometry& geometry,
                       int tile_size);
  /// The layer state a tile goes to, its canvas allocated; null (an error counted) when the
  /// tile does not fit. `*older`: the tile is older than the one held there.
  template <typename TileMsg>
  LayerState* Admit(const TileMsg& tile, size_t size, uint32_t computed_crc, bool* older);
  template <typename TileMsg>
  bool OnTileImpl(const TileMsg& tile, const float* data, size_t size, uint32_t computed_crc);
  /// Fills the cells of tile `key` (clipped to the layer) with `data` (x fastest).
  static void Paste(LayerState* state, std::pair<int, int> key, int cells_x, int cells_y,
                    const float* data);
  /// Makes the cells of every place without a held tile unknown.
  static void FillUnheld(const LayerState& state, common::Layer* cells);

  std::map<std::string, LayerState> layers_;
  int64_t checksum_errors_{0};
};

}  // namespace cairn::runtime
