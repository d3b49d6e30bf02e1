#include "mapstore/map_store.h"

#include "mapstore/blob_codec.h"

// The MapStore defaults of its optional methods: what an implementation that keeps no blobs of
// its own (InMemoryMapStore) answers.

namespace cairn::mapstore {

namespace {

// Every layer of `map` cut into tiles of `tile_size` and compressed as SqliteMapStore stores
// them (an all-unknown tile is left out).
common::Result<std::vector<StoredLayer>> TileLayers(const common::GridMap& map, int tile_size) {
  const std::vector<TileSpec> specs = TilesOf(map.geometry(), tile_size);
  std::vector<StoredLayer> out;
  try {
    for (const std::string& name : map.layer_names()) {
      StoredLayer layer;
      layer.name = name;
      layer.tile_size = tile_size;
      for (const TileSpec& spec : specs) {
        const std::vector<float> cells = ExtractTile(map.at(name), spec);
        if (AllUnknown(cells)) continue;
        EncodedBlob blob = EncodeBlob(cells.data(), cells.size() * sizeof(float),
                                      FloatCodec(cells.data(), cells.size()));
        layer.tiles.push_back({spec.tile_ix, spec.tile_iy, spec.cells_x, spec.cells_y,
                               static_cast<int>(blob.codec), blob.raw_crc32, std::move(blob.data),
                               blob.stored_crc32});
      }
      out.push_back(std::move(layer));
    }
  } catch (const std::exception& e) {
    return common::InternalError(std::string("compressing tiles: ") + e.what());
  }
  return out;
}

}  // namespace

common::Result<std::string> MapStore::GetProfileHash(const std::string& name) const {
  auto profile = GetProfile(name);
  if (!profile.ok()) return profile.status();
  return profile->content_hash;
}

common::Result<std::vector<StoredLayer>> MapStore::LoadStoredTiles(
    const MapRef& ref, const std::vector<std::string>& layers, int tile_size) const {
  if (tile_size <= 0) return common::InvalidArgumentError("the tile size must be positive");
  auto map = LoadLayers(ref, {layers, std::nullopt});
  if (!map.ok()) return map.status();
  return TileLayers(*map, tile_size);
}

common::Result<std::optional<StoredDerived>> MapStore::FindDerivedTiles(
    const MapRef& ref, const std::string& profile_hash, const std::string& code_version,
    const std::vector<std::string>& layers, int tile_size) const {
  if (tile_size <= 0) return common::InvalidArgumentError("the tile size must be positive");
  auto found = FindDerived(ref, profile_hash, code_version, {layers, std::nullopt});
  if (!found.ok()) return found.status();
  if (!found->has_value()) return std::optional<StoredDerived>();
  StoredDerived out;
  out.profile_name = (*found)->profile_name;
  out.registry = std::move((*found)->registry);
  auto tiles = TileLayers((*found)->layers, tile_size);
  if (!tiles.ok()) return tiles.status();
  out.layers = std::move(tiles).value();
  return std::optional<StoredDerived>(std::move(out));
}

}  // namespace cairn::mapstore
