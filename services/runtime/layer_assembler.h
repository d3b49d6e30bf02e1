#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cairn/lcmt_grid_manifest.hpp"
#include "cairn/lcmt_grid_tile.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/grid_map.h"
#include "common/tile_assembler.h"

/// @file
/// The receiving side of tiled layers (services/runtime/tiler.h is the sending side): tiles and
/// manifests from the bus become layers; the tiles a newer manifest lists and the receiver does
/// not hold are named for a resend request.

namespace cairn::runtime {

/// Receiver side: rebuilds layers from the bus's tiles and manifests. The wire's face of
/// common::TileAssembler: it checks each tile's CRC (or takes a verified decoder's word for it)
/// before the core pastes it.
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
  using TileSlot = common::TileAssembler::TileSlot;
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
  /// False when refused: arrays that disagree with num_tiles, or a manifest the core refuses
  /// (TileAssembler::OnManifest). A refused manifest changes nothing.
  bool OnManifest(const cairn::lcmt_grid_manifest& manifest);

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
  static constexpr int64_t kMaxLayerCells = common::TileAssembler::kMaxLayerCells;

  /// Tiles refused so far: a checksum that fails, cells that disagree with their count, a grid
  /// that no layer can have.
  int64_t checksum_errors() const { return errors_ + core_.refused_tiles(); }
  /// Forget a layer.
  void Drop(const std::string& layer) { core_.TakeLayer(layer); }

 private:
  common::TileAssembler core_;
  int64_t errors_{0};
};

}  // namespace cairn::runtime
