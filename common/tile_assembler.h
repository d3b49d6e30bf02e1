#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/grid_map.h"

/// @file
/// Layers rebuilt from tiles, in core terms (no LCM): the one receiver of tiled layers, under
/// runtime::LayerAssembler (the bus's tiles and manifests) and the map store's save assembly. A
/// sender cuts a layer into tiles of `tile_size` cells per side
/// (tile (ix, iy) covers cells [ix * tile_size, + cells_x) x [iy * tile_size, + cells_y)) and
/// announces, in a manifest, every tile it holds with its version and CRC-32; a tile absent from
/// the manifest is all unknown. The receiver checks each tile's cells against its CRC before it
/// hands the tile over (CheckedTile): the assembler never reads cells twice.
///
/// The bus adapter (services/runtime/tile_conversions.h) turns lcmt_grid_tile,
/// lcmt_occupancy_tile and lcmt_grid_manifest into these types and a TileRequest into an
/// lcmt_tile_resend_request.

namespace cairn::common {

/// Where a tile lies, in which grid, and what its sender declared about it.
struct TileHeader {
  std::string robot;
  std::string map_name;
  std::string layer;
  common::GridGeometry geometry;  ///< the whole layer's grid
  int tile_size{0};               ///< cells per side of a whole tile
  int tile_ix{0};
  int tile_iy{0};
  int cells_x{0};  ///< cells of this tile (fewer at the grid's far edges)
  int cells_y{0};
  int64_t tile_version{0};
  uint32_t checksum{0};  ///< CRC-32 of the cells as sent (float bytes, or int8 occupancy)
};

/// A tile whose cells its receiver checked against `header.checksum` (by computing the CRC, or
/// with a codec that verified the bytes the sender declared). The cells are borrowed for the
/// call that takes the tile.
struct CheckedTile {
  TileHeader header;
  const float* cells{nullptr};  ///< cells_x * cells_y floats, x fastest
  size_t num_cells{0};
};

/// The tiles a sender holds of one layer: its newest manifest.
struct TileManifest {
  std::string robot;
  std::string map_name;
  std::string layer;
  int64_t layer_version{0};
  common::GridGeometry geometry;
  int tile_size{0};
  struct Entry {
    int tile_ix{0};
    int tile_iy{0};
    int64_t tile_version{0};
    uint32_t checksum{0};
  };
  std::vector<Entry> tiles;
};

/// Tiles a receiver asks its sender for again: the tiles named, or the whole layer (its manifest
/// comes with it) when none is named.
struct TileRequest {
  std::string robot;
  std::string map_name;
  std::string layer;
  int64_t layer_version{0};
  std::vector<std::pair<int, int>> tiles;  ///< (tile_ix, tile_iy); empty: every tile
};

/// Rebuilds layers from checked tiles and manifests. Not thread-safe.
///
/// Versions. A sender numbers a layer's versions from its wall clock at start, in milliseconds
/// since the epoch, plus one per update (runtime::LayerTiler::StartVersionBase), so an honest
/// version never runs ahead of the sender's clock, and a restarted sender outranks its
/// predecessor. A tile or manifest numbered more than kVersionLeadMs ahead of this receiver's
/// clock is refused: numbered INT64_MAX, it would outrank everything its sender sends later and
/// freeze its layer. A held version ahead of the clock (one let in within the lead) outranks
/// nothing: the next tile at its place, or the next manifest, replaces it whatever its version.
class TileAssembler {
 public:
  /// Milliseconds since the epoch, as senders number versions.
  using VersionClock = std::function<int64_t()>;
  /// The wall clock.
  static int64_t WallClockMs();
  /// How far ahead of the receiver's clock a version may be: the clock skew between hosts that
  /// share a bus.
  static constexpr int64_t kVersionLeadMs = 60'000;

  TileAssembler() = default;
  /// An assembler that reads `clock` for the version bound (tests; the default is WallClockMs).
  explicit TileAssembler(VersionClock clock) : clock_(std::move(clock)) {}
  TileAssembler(const TileAssembler&) = default;
  TileAssembler& operator=(const TileAssembler&) = default;
  TileAssembler(TileAssembler&&) = default;
  TileAssembler& operator=(TileAssembler&&) = default;

  /// Layers larger than this are refused (a tile declaring such a grid is refused).
  static constexpr int64_t kMaxLayerCells = 64'000'000;

  /// Pastes a tile into its layer. False (and counted as refused) when its size disagrees with
  /// its header, its grid is unusable, or its version is negative or from the future. A tile older than the one held at its place is ignored
  /// (true); a tile of another grid than its layer's restarts the layer.
  bool OnTile(const CheckedTile& tile);
  /// Where a tile's cells go in its layer, for a receiver that decodes a compressed tile
  /// straight into place: the tile's cell (0, 0) at `first`, rows `row_stride` floats apart,
  /// `cells_x` × `cells_y` cells (the tile clipped to its layer). No `first`: nothing to write.
  struct TileSlot {
    float* first{nullptr};
    int64_t row_stride{0};
    int cells_x{0};
    int cells_y{0};
  };
  /// Reserves the place of a tile (allocating its layer at the layer's first tile). nullopt (a
  /// refusal counted) when the header does not fit a layer; a slot without cells, and no EndTile
  /// to call, when the tile is older than the one held there or lies outside its layer (it counts
  /// as held, as in OnTile). Until EndTile, the cells of a reserved place are undefined. A slot
  /// stays valid until a tile or manifest of another grid arrives for the same layer.
  std::optional<TileSlot> BeginTile(const TileHeader& header);
  /// Ends BeginTile. `decoded`: the receiver wrote every cell of the slot and checked them
  /// against the header's checksum, and the tile is held. Otherwise its place becomes unknown
  /// and no tile is held there.
  void EndTile(const TileHeader& header, bool decoded);
  /// Takes a manifest unless an older one than the layer's newest; tiles it no longer lists
  /// become unknown. False (counted, and nothing held changes) for a manifest that cannot be a
  /// sender's: a grid that is not usable or holds more than kMaxLayerCells, a tile size not in
  /// [1, kMaxTileSize], a negative version or one from the future (see Versions above), or a
  /// tile listed twice or outside the grid.
  bool OnManifest(const TileManifest& manifest);
  static constexpr int kMaxTileSize = 4096;

  /// Layers seen so far (from tiles or manifests), sorted.
  std::vector<std::string> layers() const;
  /// True when every tile of the newest manifest of `layer` is held with its checksum.
  bool Complete(const std::string& layer) const;
  /// Version of the newest manifest of a layer (0 if none).
  int64_t version(const std::string& layer) const;
  /// Tiles of the newest manifest not held (or held stale), as (tile_ix, tile_iy).
  std::vector<std::pair<int, int>> Missing(const std::string& layer) const;
  /// A request for the missing tiles (robot and map name as the manifest said); nullopt when
  /// nothing is missing or no manifest arrived.
  std::optional<TileRequest> MissingRequest(const std::string& layer) const;
  /// The grid of a layer as Layer would return it, without assembling it.
  std::optional<common::GridGeometry> Geometry(const std::string& layer) const;
  /// The checksum of the tile held at (tile_ix, tile_iy) of a layer; nullopt when none is held.
  std::optional<uint32_t> HeldChecksum(const std::string& layer, int tile_ix, int tile_iy) const;
  /// The layer as a one-layer GridMap (cells of tiles not held are unknown); nullopt if the
  /// layer was never seen.
  std::optional<common::GridMap> Layer(const std::string& layer) const;
  /// Layer without a copy: the cells move out and the layer is forgotten.
  std::optional<common::GridMap> TakeLayer(const std::string& layer);

  /// Tiles refused so far.
  int64_t refused_tiles() const { return refused_tiles_; }
  /// Manifests refused so far.
  int64_t refused_manifests() const { return refused_manifests_; }

 private:
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
  /// Pastes `cells` (x fastest) into the place of tile `key`, clipped to the layer.
  /// The layer a tile goes to, its canvas allocated; null (a refusal counted) when the header
  /// does not fit a layer. `*older`: the tile is older than the one held at its place.
  LayerState* Admit(const TileHeader& header, bool* older);
  /// Records the tile of `header` as held at its place.
  static void Hold(LayerState* state, const TileHeader& header);
  static void Paste(LayerState* state, std::pair<int, int> key, int cells_x, int cells_y,
                    const float* cells);
  /// Makes the cells of every place without a held tile unknown.
  static void FillUnheld(const LayerState& state, common::Layer* cells);
  static common::GridMap AsMap(const std::string& layer, const LayerState& state,
                               common::Layer cells);

  /// Whether a version read from the bus is beyond any honest sender's (see Versions).
  bool FromTheFuture(int64_t version, int64_t now_ms) const;

  VersionClock clock_{&TileAssembler::WallClockMs};
  std::map<std::string, LayerState> layers_;
  int64_t refused_tiles_{0};
  int64_t refused_manifests_{0};
};

}  // namespace cairn::common
