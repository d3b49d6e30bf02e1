#include "services/runtime/layer_assembler.h"

#include "services/runtime/tile_conversions.h"

namespace cairn::runtime {

bool LayerAssembler::OnTile(const cairn::lcmt_grid_tile& tile) {
  // Compressed tiles are decoded by their receiver (the map store's client) before they get here.
  auto checked = CheckFloatTile(tile);
  if (!checked.ok()) {
    ++errors_;
    return false;
  }
  return core_.OnTile(*checked);
}

bool LayerAssembler::OnDecodedTile(const cairn::lcmt_grid_tile& tile,
                                   const std::vector<float>& cells) {
  return core_.OnTile(DecodedTile(tile, cells));
}

bool LayerAssembler::OnTile(const cairn::lcmt_occupancy_tile& tile) {
  std::vector<float> cells;
  auto checked = CheckOccupancyTile(tile, &cells);
  if (!checked.ok()) {
    ++errors_;
    return false;
  }
  return core_.OnTile(*checked);
}

std::optional<LayerAssembler::TileSlot> LayerAssembler::BeginTile(
    const cairn::lcmt_grid_tile& tile) {
  return core_.BeginTile(HeaderOf(tile));
}

void LayerAssembler::EndTile(const cairn::lcmt_grid_tile& tile, bool decoded) {
  core_.EndTile(HeaderOf(tile), decoded);
}

bool LayerAssembler::OnManifest(const cairn::lcmt_grid_manifest& manifest) {
  auto core = FromLcm(manifest);
  return core.ok() && core_.OnManifest(*core);
}

std::vector<std::string> LayerAssembler::layers() const { return core_.layers(); }

bool LayerAssembler::Complete(const std::string& layer) const { return core_.Complete(layer); }

int64_t LayerAssembler::version(const std::string& layer) const { return core_.version(layer); }

std::vector<std::pair<int, int>> LayerAssembler::Missing(const std::string& layer) const {
  return core_.Missing(layer);
}

std::optional<cairn::lcmt_tile_resend_request> LayerAssembler::MakeResendRequest(
    const std::string& layer, const std::string& requester, int64_t utime) const {
  auto request = core_.MissingRequest(layer);
  if (!request) return std::nullopt;
  return ToLcm(*request, requester, utime);
}

std::optional<common::GridMap> LayerAssembler::Layer(const std::string& layer) const {
  return core_.Layer(layer);
}

std::optional<common::GridMap> LayerAssembler::TakeLayer(const std::string& layer) {
  return core_.TakeLayer(layer);
}

std::optional<uint32_t> LayerAssembler::HeldChecksum(const std::string& layer, int tile_ix,
                                                     int tile_iy) const {
  return core_.HeldChecksum(layer, tile_ix, tile_iy);
}

std::optional<common::GridGeometry> LayerAssembler::Geometry(const std::string& layer) const {
  return core_.Geometry(layer);
}

}  // namespace cairn::runtime
