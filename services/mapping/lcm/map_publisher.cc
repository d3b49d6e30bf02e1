#include "services/mapping/lcm/map_publisher.h"

#include <algorithm>

#include "cairn/lcmt_octomap.hpp"

#include "common/channels.h"
#include "common/crc32.h"
#include "common/layers.h"
#include "services/mapping/octomap_mapper_layer.h"
#include "services/runtime/conversions.h"

namespace cairn::mapping {
namespace {

constexpr size_t kOctomapChunkBytes = 192 * 1024;

std::chrono::steady_clock::duration Period(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

runtime::TileEncoding WireEncoding(GridEncoding encoding) {
  return encoding == GridEncoding::kOccupancy ? runtime::TileEncoding::kOccupancy
                                              : runtime::TileEncoding::kFloat;
}

}  // namespace

MapPublisher::MapPublisher(runtime::Node& node, MapperCore& core, Options options, LayerLock lock)
    : node_(node),
      core_(core),
      options_(std::move(options)),
      lock_(std::move(lock)),
      terrain_publisher_(options_.robot, options_.map_name, /*extent_tiles=*/4,
                         options_.version_base),
      grid_tiler_(options_.robot, options_.map_name, runtime::kDefaultTileSize,
                  options_.version_base) {
  const auto now = Clock::now();
  for (const auto& layer : core_.layers()) {
    layers_.push_back({layer.get(), now + Period(layer->schedule().publish_period_s), -1});
    if (auto* terrain = dynamic_cast<TerrainMapperLayer*>(layer.get())) terrain_ = terrain;
  }
  if (terrain_ != nullptr) {
    next_slow_ = now + Period(terrain_->params().slow_publish_period_s);
    next_registry_ = now + Period(terrain_->params().registry_period_s);
  }
}

template <typename Msg>
void MapPublisher::Send(const std::string& stream, const std::vector<Msg>& messages) {
  node_.PublishPaced(channels::ForRobot(options_.robot, stream.c_str()), messages,
                     options_.tiles_per_burst, options_.burst_pause_ms);
}

void MapPublisher::PublishDue(bool force, int64_t map_version) {
  const auto now = Clock::now();
  last_map_version_ = map_version;
  announced_.clear();
  for (LayerState& state : layers_) {
    if (state.layer == terrain_) {
      const TerrainMapperLayerParams& p = terrain_->params();
      const bool slow = force || now >= next_slow_;
      if (slow) next_slow_ = now + Period(p.slow_publish_period_s);
      if (map_version != last_data_version_) {
        last_data_version_ = map_version;
        last_data_ = now;
      }
      // Manifests of the fast layers go out every period, changed or not: they tell receivers
      // (the navigator's staleness check) that the layer is current. That holds only while
      // data comes in: a mapper starved of revolutions stops saying it.
      const bool data_flows = now - last_data_ <= Period(p.max_announce_without_data_s);
      if (data_flows != announcing_ && map_version > 0) {
        announcing_ = data_flows;
        if (data_flows) {
          node_.Event("revolutions again: the terrain layers are announced as current");
        } else {
          node_.Event(
              "no lidar revolution integrated for %.1f s: the terrain layers are no longer "
              "announced as current (a navigator's map goes stale)",
              p.max_announce_without_data_s);
        }
      }
      if (force || ((slow || now >= state.next) && data_flows)) {
        state.next = now + Period(p.publish_period_s);
        PublishTerrain(FastLayers(), force);
      }
      if (slow) PublishTerrain(SlowLayers(), force);
      if (force || slow || now >= next_registry_) {
        next_registry_ = now + Period(p.registry_period_s);
        PublishRegistry(force || slow, map_version);
      }
      continue;
    }
    if (!force && now < state.next) continue;
    state.next = now + Period(state.layer->schedule().publish_period_s);
    if (dynamic_cast<const OctomapMapperLayer*>(state.layer) != nullptr) {
      PublishOctomap(&state, force);
    } else {
      PublishGrids(&state, force);
    }
  }
}

std::vector<std::string> MapPublisher::FastLayers() const {
  std::vector<std::string> names{layers::kElevation, layers::kSlope, layers::kStepMax,
                                 layers::kRoughness};
  // Each profile's directed layer before its cost layer: a navigator pairs a cost version with
  // the directed data it holds (planner/README.md, "One-way steps").
  for (const auto& p : terrain_->map().profiles()) {
    names.push_back(layers::DirectedLayer(p.name));
    names.push_back(layers::CostLayer(p.name));
  }
  return names;
}

std::vector<std::string> MapPublisher::SlowLayers() {
  return {layers::kElevationVariance, layers::kObservationCount, layers::kLastSeen,
          layers::kGroundBound,       layers::kDitchDepth,       layers::kDitchWidth};
}

void MapPublisher::PublishTerrain(const std::vector<std::string>& names, bool force) {
  std::vector<std::string> all = names;
  for (const auto& r : retired_layers_) all.push_back(r);
  const std::vector<std::string> retired = std::move(retired_layers_);
  retired_layers_.clear();
  const auto batch = terrain_publisher_.Update(terrain_->map(), all, node_.NowUtime(), force);
  Send(channels::kMapTiles, batch.tiles);
  std::vector<cairn::lcmt_grid_manifest> out = batch.manifests;
  for (const auto& name : all) {
    const bool sent =
        std::any_of(out.begin(), out.end(), [&](const auto& m) { return m.layer == name; });
    if (sent) continue;
    if (auto m = terrain_publisher_.Manifest(name)) out.push_back(*m);
  }
  Send(channels::kMapManifest, out);
  for (const auto& m : out) {
    if (std::find(retired.begin(), retired.end(), m.layer) == retired.end()) {
      announced_.push_back(m.layer);
    }
  }
}

void MapPublisher::PublishRegistry(bool force, int64_t map_version) {
  common::ObstacleRegistry registry = terrain_->map().BuildRegistry();
  registry.map_version = map_version;
  cairn::lcmt_obstacle_registry msg =
      runtime::ToLcm(registry, 0, options_.robot, options_.map_name);
  msg.map_version = 0;
  std::string bytes(static_cast<size_t>(msg.getEncodedSize()), '\0');
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  if (!force && bytes == last_registry_bytes_) return;
  last_registry_bytes_ = std::move(bytes);
  msg.utime = node_.NowUtime();
  msg.map_version = map_version;
  if (runtime::FitRegistryToMessageLimit(&msg)) {
    node_.Warn("registry_size", "the obstacle registry exceeds 256 KB; outlines are left out");
  }
  node_.Publish(channels::ForRobot(options_.robot, channels::kMapObstacles), msg);
}

void MapPublisher::PublishGrids(LayerState* state, bool force) {
  const std::vector<GridOutput> outputs = state->layer->GridOutputs();
  if (outputs.empty()) return;
  std::optional<common::GridMap> map;
  {
    std::unique_lock<std::mutex> lock = lock_(*state->layer);
    const int64_t version = state->layer->version();
    if (!force && version == state->published_version) return;
    state->published_version = version;
    map = state->layer->ExportGrids();
  }
  if (!map) return;
  const int64_t utime = node_.NowUtime();
  std::vector<cairn::lcmt_grid_manifest> manifests;
  for (const GridOutput& out : outputs) {
    if (!out.published) continue;
    auto batch = grid_tiler_.Update(*map, out.name, WireEncoding(out.encoding), utime, force);
    if (out.encoding == GridEncoding::kOccupancy) {
      Send(channels::kMapOccupancy, batch.occupancy_tiles);
    } else {
      Send(channels::kMapTiles, batch.tiles);
    }
    // Every manifest goes out, changed or not: receivers (the navigator's staleness check
    // when it plans on the final layer) read it as "the layer is current".
    manifests.push_back(batch.manifest);
    announced_.push_back(batch.manifest.layer);
  }
  Send(channels::kMapManifest, manifests);
}

void MapPublisher::PublishOctomap(LayerState* state, bool force) {
  std::string blob;
  double resolution = 0;
  {
    std::unique_lock<std::mutex> lock = lock_(*state->layer);
    const auto* octomap = static_cast<const OctomapMapperLayer*>(state->layer);
    if (!force && octomap->version() == state->published_version) return;
    state->published_version = octomap->version();
    blob = octomap->tree().ToBinary();
    resolution = octomap->tree().params().resolution_m;
  }
  const uint32_t crc = common::Crc32(blob.data(), blob.size());
  const int count =
      std::max(1, static_cast<int>((blob.size() + kOctomapChunkBytes - 1) / kOctomapChunkBytes));
  ++octomap_chunk_version_;
  std::vector<cairn::lcmt_octomap> chunks;
  for (int i = 0; i < count; ++i) {
    cairn::lcmt_octomap m{};
    m.utime = node_.NowUtime();
    m.robot = options_.robot;
    m.map_name = options_.map_name;
    m.resolution_m = resolution;
    m.binary = true;
    m.version = octomap_chunk_version_;
    m.chunk_index = i;
    m.chunk_count = count;
    m.total_bytes = static_cast<int64_t>(blob.size());
    m.checksum = crc;
    const size_t begin = i * kOctomapChunkBytes;
    const size_t end = std::min(blob.size(), begin + kOctomapChunkBytes);
    m.data.assign(blob.begin() + begin, blob.begin() + end);
    m.num_bytes = static_cast<int32_t>(m.data.size());
    chunks.push_back(std::move(m));
  }
  Send(channels::kMapOctomap, chunks);
}

void MapPublisher::Resend(const cairn::lcmt_tile_resend_request& request) {
  if (request.layer == layers::kResendObstacles) {
    // A pull save that missed the registry (one message, lost whole on a lossy link).
    if (terrain_ != nullptr) PublishRegistry(/*force=*/true, last_map_version_);
    return;
  }
  if (terrain_publisher_.Has(request.layer)) {
    const auto batch = terrain_publisher_.Resend(request);
    Send(channels::kMapTiles, batch.tiles);
    Send(channels::kMapManifest, batch.manifests);
    node_.Count("tiles_resent", static_cast<int64_t>(batch.tiles.size()));
    return;
  }
  const auto batch = grid_tiler_.Resend(request);
  Send(channels::kMapOccupancy, batch.occupancy_tiles);
  Send(channels::kMapTiles, batch.tiles);
  if (batch.manifest.num_tiles > 0 || batch.changed) {
    Send(channels::kMapManifest, std::vector<cairn::lcmt_grid_manifest>{batch.manifest});
  }
  node_.Count("tiles_resent",
              static_cast<int64_t>(batch.tiles.size() + batch.occupancy_tiles.size()));
}

void MapPublisher::AfterReset(bool send) {
  const auto batch = terrain_publisher_.Reset(node_.NowUtime());
  if (send) Send(channels::kMapManifest, batch.manifests);
}

void MapPublisher::RetireLayer(const std::string& layer) { retired_layers_.push_back(layer); }

void MapPublisher::UnretireLayer(const std::string& layer) {
  retired_layers_.erase(std::remove(retired_layers_.begin(), retired_layers_.end(), layer),
                        retired_layers_.end());
}

}  // namespace cairn::mapping
