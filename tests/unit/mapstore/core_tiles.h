#pragma once

#include <string>
#include <vector>

#include "common/crc32.h"
#include "common/grid_map.h"
#include "mapstore/blob_codec.h"
#include "mapstore/save_assembler.h"

// Layers cut into core tiles and manifests, as a sender on the bus cuts them (runtime's
// LayerTiler): for the save assembly's unit tests, which never see a bus.

namespace cairn::mapstore::testing {

/// A tile with its cells owned; As() lends them as a CheckedTile.
struct OwnedTile {
  TileHeader header;
  std::vector<float> cells;
  CheckedTile As() const { return CheckedTile{header, cells.data(), cells.size()}; }
  /// The cells compressed with the store's codec: what a push sends instead of floats.
  EncodedBlob Compressed() const {
    return EncodeBlob(cells.data(), cells.size() * sizeof(float),
                      FloatCodec(cells.data(), cells.size()), 1, header.checksum);
  }
};

struct TiledLayer {
  TileManifest manifest;
  std::vector<OwnedTile> tiles;  ///< row by row; all-unknown tiles are left out
};

/// Cuts `layer` of `map` into tiles of `tile_size` (version `version`, tile versions 1).
inline TiledLayer CutLayer(const common::GridMap& map, const std::string& layer, int tile_size,
                           const std::string& map_name, const std::string& robot = "rover1",
                           int64_t version = 1) {
  TiledLayer out;
  out.manifest.robot = robot;
  out.manifest.map_name = map_name;
  out.manifest.layer = layer;
  out.manifest.layer_version = version;
  out.manifest.geometry = map.geometry();
  out.manifest.tile_size = tile_size;
  const common::Layer& values = map.at(layer);
  const int nx = (map.size_x() + tile_size - 1) / tile_size;
  const int ny = (map.size_y() + tile_size - 1) / tile_size;
  for (int ty = 0; ty < ny; ++ty) {
    for (int tx = 0; tx < nx; ++tx) {
      OwnedTile t;
      t.header.robot = robot;
      t.header.map_name = map_name;
      t.header.layer = layer;
      t.header.geometry = map.geometry();
      t.header.tile_size = tile_size;
      t.header.tile_ix = tx;
      t.header.tile_iy = ty;
      t.header.cells_x = std::min(tile_size, map.size_x() - tx * tile_size);
      t.header.cells_y = std::min(tile_size, map.size_y() - ty * tile_size);
      t.header.tile_version = 1;
      bool known = false;
      for (int y = 0; y < t.header.cells_y; ++y) {
        for (int x = 0; x < t.header.cells_x; ++x) {
          const float v = values(tx * tile_size + x, ty * tile_size + y);
          known |= !std::isnan(v);
          t.cells.push_back(v);
        }
      }
      if (!known) continue;
      t.header.checksum = common::Crc32(t.cells.data(), t.cells.size() * sizeof(float));
      out.manifest.tiles.push_back({tx, ty, 1, t.header.checksum});
      out.tiles.push_back(std::move(t));
    }
  }
  return out;
}

}  // namespace cairn::mapstore::testing
