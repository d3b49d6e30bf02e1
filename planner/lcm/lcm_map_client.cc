#include "planner/lcm/lcm_map_client.h"

#include <algorithm>
#include <cmath>

#include "common/channels.h"
#include "common/check.h"

namespace cairn::planner {

LcmMapClient::LcmMapClient(runtime::Node& node, LcmMapClientParams params,
                           std::vector<common::Vector2> footprint_m, CostMapParams cost_params)
    : node_(node),
      params_(std::move(params)),
      footprint_m_(std::move(footprint_m)),
      cost_params_(cost_params) {
  cost_params_.Validate();
  if (params_.encoding == MapEncoding::kOccupancy) params_.occupancy.Validate();
  FootprintRasterizer check(footprint_m_);  // throws on a bad footprint
  if (params_.encoding == MapEncoding::kOccupancy) {
    node_.Subscribe<cairn::lcmt_occupancy_tile>(
        channels::ForRobot(params_.robot, channels::kMapOccupancy),
        [this](const cairn::lcmt_occupancy_tile& t) { OnTile(t); });
  } else {
    node_.Subscribe<cairn::lcmt_grid_tile>(channels::ForRobot(params_.robot, channels::kMapTiles),
                                           [this](const cairn::lcmt_grid_tile& t) { OnTile(t); });
  }
  node_.Subscribe<cairn::lcmt_grid_manifest>(
      channels::ForRobot(params_.robot, channels::kMapManifest),
      [this](const cairn::lcmt_grid_manifest& m) { OnManifest(m); });
}

std::shared_ptr<const CostMap> LcmMapClient::Latest() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

int64_t LcmMapClient::last_heard_utime() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return heard_utime_;
}

bool LcmMapClient::Accepts(const std::string& robot, const std::string& map_name,
                           const std::string& layer) const {
  if (layer != params_.layer) return false;
  if (!params_.map_name.empty() && map_name != params_.map_name) return false;
  return robot.empty() || robot == params_.robot;
}

void LcmMapClient::OnTile(const cairn::lcmt_grid_tile& tile) {
  // A float tile of our layer name while we read occupancy (or the reverse) is not ours.
  if (params_.encoding != MapEncoding::kCost) return;
  OnTileImpl(tile);
}

void LcmMapClient::OnTile(const cairn::lcmt_occupancy_tile& tile) {
  if (params_.encoding != MapEncoding::kOccupancy) return;
  OnTileImpl(tile);
}

template <typename TileMsg>
void LcmMapClient::OnTileImpl(const TileMsg& tile) {
  if (!Accepts(tile.robot, tile.map_name, tile.layer)) return;
  if (!assembler_.OnTile(tile)) {
    node_.CountDropped("bad_map_tiles");
    node_.Warn("map_tile", "map tile (" + std::to_string(tile.tile_ix) + ", " +
                               std::to_string(tile.tile_iy) + ") of " + tile.layer +
                               " refused (bad checksum or geometry)");
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    heard_utime_ = node_.NowUtime();
  }
  MaybeBuild(false);
}

void LcmMapClient::OnManifest(const cairn::lcmt_grid_manifest& manifest) {
  if (!Accepts(manifest.robot, manifest.map_name, manifest.layer)) return;
  if (manifest.num_tiles < 0 || static_cast<int>(manifest.tile_ix.size()) != manifest.num_tiles ||
      !(manifest.resolution_m > 0.0) || !std::isfinite(manifest.resolution_m) ||
      manifest.layer_size_x <= 0 || manifest.layer_size_y <= 0 || manifest.tile_size <= 0) {
    node_.CountDropped("bad_map_manifests");
    node_.Warn("map_manifest", "malformed manifest for " + manifest.layer + " refused");
    return;
  }
  assembler_.OnManifest(manifest);
  tile_size_ = manifest.tile_size;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    heard_utime_ = node_.NowUtime();
  }
  MaybeBuild(false);
}

void LcmMapClient::Poll() {
  const int64_t now = node_.NowUtime();
  const int64_t version = assembler_.version(params_.layer);
  if (version == 0 || (version == built_version_ && !built_incomplete_)) return;
  if (!assembler_.Complete(params_.layer)) {
    if (now - last_resend_utime_ >= static_cast<int64_t>(params_.resend_interval_s * 1e6)) {
      if (auto request = assembler_.MakeResendRequest(params_.layer, params_.requester, now)) {
        node_.Publish(channels::ForRobot(params_.robot, channels::kMapTileResend), *request);
        node_.Count("tile_resend_requests");
        last_resend_utime_ = now;
      }
    }
    if (pending_since_utime_ > 0 &&
        now - pending_since_utime_ >= static_cast<int64_t>(params_.incomplete_timeout_s * 1e6)) {
      MaybeBuild(true);
    }
  } else if (built_incomplete_) {
    MaybeBuild(false);  // the missing tiles of the version in use came in
  }
}

void LcmMapClient::MaybeBuild(bool allow_incomplete) {
  const int64_t version = assembler_.version(params_.layer);
  if (version == 0) return;
  // A version built with holes is built again once complete, never again with holes.
  if (version == built_version_ && (!built_incomplete_ || allow_incomplete)) return;
  if (pending_since_utime_ == 0) pending_since_utime_ = node_.NowUtime();
  if (!allow_incomplete && !assembler_.Complete(params_.layer)) return;
  auto layer = assembler_.Layer(params_.layer);
  if (!layer) return;
  common::Layer& cells = layer->at(params_.layer);
  if (params_.encoding == MapEncoding::kOccupancy) {
    cells = OccupancyToCostLayer(cells, params_.occupancy, cost_params_.lethal_cost);
  }
  const auto missing =
      allow_incomplete ? assembler_.Missing(params_.layer) : std::vector<std::pair<int, int>>{};
  if (tile_size_ > 0) {
    // Tiles the mapper announced but we never got: block them rather than read them as
    // unexplored (which the planners may be allowed to cross).
    for (const auto& [tx, ty] : missing) {
      for (int iy = ty * tile_size_; iy < std::min<int>((ty + 1) * tile_size_, cells.cols());
           ++iy) {
        for (int ix = tx * tile_size_; ix < std::min<int>((tx + 1) * tile_size_, cells.rows());
             ++ix) {
          if (ix >= 0 && iy >= 0) cells(ix, iy) = cost_params_.lethal_cost;
        }
      }
    }
  }
  try {
    auto map = std::make_shared<CostMap>(layer->geometry(), cells, footprint_m_, cost_params_);
    map->set_stamp(version, node_.NowUtime());
    map->set_missing_tiles(static_cast<int>(missing.size()));
    std::lock_guard<std::mutex> lock(mutex_);
    latest_ = std::move(map);
    built_version_ = version;
    built_incomplete_ = !missing.empty();
    pending_since_utime_ = 0;
    ++snapshots_;
  } catch (const std::exception& e) {
    node_.CountDropped("bad_map_layers");
    node_.Warn("map_layer", "layer " + params_.layer + " refused: " + e.what());
    built_version_ = version;  // do not retry the same bad version
    built_incomplete_ = false;
    pending_since_utime_ = 0;
  }
  node_.Count("map_snapshots");
  if (missing.empty()) return;
  node_.Count("incomplete_map_snapshots");
  node_.Warn("map_incomplete", "layer " + params_.layer + " is incomplete (" +
                                   std::to_string(missing.size()) +
                                   " tiles missing, asked again): the navigator waits for them");
}

}  // namespace cairn::planner
