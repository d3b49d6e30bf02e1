#include "mapstore/lcm/mapstore_client.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include <unistd.h>

#include "cairn/lcmt_obstacle_registry.hpp"

#include "common/channels.h"
#include "common/crc32.h"
#include "mapstore/blob_codec.h"
#include "mapstore/lcm/mapstore_conversions.h"
#include "mapstore/lcm/tile_wire.h"
#include "mapstore/octomap_chunks.h"
#include "mapstore/save_assembler.h"
#include "services/runtime/conversions.h"

namespace cairn::mapstore {

using common::Result;
using common::Status;
using Clock = std::chrono::steady_clock;

namespace {

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

int64_t WallUtimeNow() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

Status StatusOfReply(const cairn::lcmt_mapstore_reply& reply) {
  using R = cairn::lcmt_mapstore_reply;
  switch (reply.status) {
    case R::STATUS_OK:
      return Status::Ok();
    case R::STATUS_NOT_FOUND:
      return common::NotFoundError(reply.message);
    case R::STATUS_INVALID:
      return common::InvalidArgumentError(reply.message);
    case R::STATUS_CORRUPT:
      return common::CorruptError(reply.message);
    case R::STATUS_BUSY:
      return common::UnavailableError(reply.message);
    case R::STATUS_CONFLICT:
      return common::AlreadyExistsError(reply.message);
    case R::STATUS_FORBIDDEN:
      return common::PermissionDeniedError(reply.message);
    default:
      return common::InternalError(reply.message);
  }
}

struct MapstoreClient::Incoming {
  std::string map_name;
  runtime::LayerAssembler assembler;
  std::set<std::string> manifests;
  std::map<int32_t, std::string> octomap_chunks;
  cairn::lcmt_octomap octomap_head{};
  bool has_octomap_head{false};
  Clock::time_point last_progress{Clock::now()};
};

struct MapstoreClient::Push {
  std::string map_name;
  std::string robot;
  std::map<std::string, std::unique_ptr<runtime::LayerTiler>> tilers;  // one per layer
  std::optional<cairn::lcmt_obstacle_registry> obstacles;
  std::vector<cairn::lcmt_octomap> octomap;
};

template <typename Msg, void (MapstoreClient::*Handler)(const lcm::ReceiveBuffer*,
                                                        const std::string&, const Msg*)>
void MapstoreClient::Guarded(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                             MapstoreClient* self) {
  try {
    Msg m;
    if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) {
      ++self->dropped_messages_;
      return;
    }
    (self->*Handler)(rbuf, channel, &m);
  } catch (const std::exception&) {
    ++self->dropped_messages_;
  }
}

template <typename Msg, void (MapstoreClient::*Handler)(const lcm::ReceiveBuffer*,
                                                        const std::string&, const Msg*)>
void MapstoreClient::Subscribe(const char* channel) {
  subscriptions_.push_back(
      lcm_.subscribeFunction<MapstoreClient*>(channel, &Guarded<Msg, Handler>, this));
}

MapstoreClient::MapstoreClient(lcm::LCM& lcm, std::string requester, MapstoreClientOptions options)
    : lcm_(lcm), requester_(std::move(requester)), options_(options) {
  // Through Guarded, not liblcm's typed subscribe: a handler's exception would unwind through
  // its C dispatch.
  Subscribe<cairn::lcmt_mapstore_reply, &MapstoreClient::OnReply>(channels::kMapstoreReply);
  Subscribe<cairn::lcmt_grid_tile, &MapstoreClient::OnTile>(channels::kMapstoreTiles);
  Subscribe<cairn::lcmt_grid_tile_batch, &MapstoreClient::OnTileBatch>(
      channels::kMapstoreTileBatches);
  Subscribe<cairn::lcmt_grid_manifest, &MapstoreClient::OnManifest>(channels::kMapstoreManifest);
  Subscribe<cairn::lcmt_octomap, &MapstoreClient::OnOctomap>(channels::kMapstoreOctomap);
  Subscribe<cairn::lcmt_tile_resend_request, &MapstoreClient::OnPushResend>(
      channels::kMapstorePushTileResend);
  counter_ = ((WallUtimeNow() / 1000000) & 0x7fffff) << 40 |
             (static_cast<int64_t>(getpid()) & 0xfffff) << 20;
}

MapstoreClient::~MapstoreClient() {
  for (lcm::Subscription* s : subscriptions_) lcm_.unsubscribe(s);
}

int64_t MapstoreClient::NextRequestId() { return ++counter_; }

void MapstoreClient::OnReply(const lcm::ReceiveBuffer*, const std::string&,
                             const cairn::lcmt_mapstore_reply* m) {
  if (m->request_id == active_id_ && !reply_) reply_ = *m;
}

void MapstoreClient::OnTile(const lcm::ReceiveBuffer*, const std::string&,
                            const cairn::lcmt_grid_tile* m) {
  HoldTile(*m);
}

void MapstoreClient::OnTileBatch(const lcm::ReceiveBuffer*, const std::string&,
                                 const cairn::lcmt_grid_tile_batch* m) {
  if (!incoming_ || m->map_name != incoming_->map_name) return;
  // The compressed tiles of a batch decode on decode_threads threads straight into the layers.
  if (AssembleTiles(m->tiles, incoming_->map_name, options_.decode_threads, &incoming_->assembler) >
      0) {
    incoming_->last_progress = Clock::now();
  }
}

void MapstoreClient::HoldTile(const cairn::lcmt_grid_tile& tile) {
  if (!incoming_ || tile.map_name != incoming_->map_name) return;
  // A compressed tile that does not decode is dropped: the resend asks for it again. One that
  // does was checked by zstd against the bytes the store compressed, whose CRC it declares.
  // It decodes straight into its place in the layer.
  if (AssembleTile(tile, incoming_->map_name, &incoming_->assembler)) {
    incoming_->last_progress = Clock::now();
  }
}

void MapstoreClient::OnManifest(const lcm::ReceiveBuffer*, const std::string&,
                                const cairn::lcmt_grid_manifest* m) {
  if (!incoming_ || m->map_name != incoming_->map_name) return;
  incoming_->assembler.OnManifest(*m);
  incoming_->manifests.insert(m->layer);
  incoming_->last_progress = Clock::now();
}

void MapstoreClient::OnOctomap(const lcm::ReceiveBuffer*, const std::string&,
                               const cairn::lcmt_octomap* m) {
  if (!incoming_ || m->map_name != incoming_->map_name) return;
  if (m->chunk_index < 0 || m->chunk_index >= m->chunk_count) return;
  incoming_->octomap_head = *m;
  incoming_->has_octomap_head = true;
  incoming_->octomap_chunks[m->chunk_index].assign(m->data.begin(), m->data.end());
  incoming_->last_progress = Clock::now();
}

void MapstoreClient::OnPushResend(const lcm::ReceiveBuffer*, const std::string&,
                                  const cairn::lcmt_tile_resend_request* m) {
  if (!push_ || m->map_name != push_->map_name) return;
  if (m->layer == kResendObstacles) {
    if (push_->obstacles) lcm_.publish(channels::kMapstorePushObstacles, &*push_->obstacles);
    return;
  }
  if (m->layer == kResendOctomap) {
    for (const auto& c : push_->octomap) lcm_.publish(channels::kMapstorePushOctomap, &c);
    return;
  }
  auto tiler = push_->tilers.find(m->layer);
  if (tiler == push_->tilers.end()) return;
  const auto batch = tiler->second->Resend(*m);
  lcm_.publish(channels::kMapstorePushManifest, &batch.manifest);
  PublishPushed(push_->map_name, batch.tiles);
}

void MapstoreClient::PublishPaced(const cairn::lcmt_grid_tile& tile) {
  PublishTile(lcm_, channels::kMapstorePushTiles, tile);
  if (++paced_ % std::max(1, options_.tiles_per_burst) == 0) PacingPause(options_.burst_pause_ms);
}

void MapstoreClient::PublishPushed(const std::string& map_name,
                                   const std::vector<cairn::lcmt_grid_tile>& tiles) {
  cairn::lcmt_grid_tile_batch pending{};
  int64_t pending_bytes = 0;
  auto flush = [&] {
    if (pending.tiles.empty()) return;
    pending.utime = WallUtimeNow();
    pending.map_name = map_name;
    pending.num_tiles = static_cast<int32_t>(pending.tiles.size());
    lcm_.publish(channels::kMapstorePushTileBatches, &pending);
    pending.tiles.clear();
    pending_bytes = 0;
    PacingPause(options_.burst_pause_ms);
  };
  for (const auto& tile : tiles) {
    if (tile.encoding == cairn::lcmt_grid_tile::ENCODING_FLOAT32 || options_.batch_bytes <= 0) {
      flush();
      PublishPaced(tile);
      continue;
    }
    const int64_t bytes = TilePayloadBytes(tile);
    if (!pending.tiles.empty() && pending_bytes + bytes > options_.batch_bytes) flush();
    pending.tiles.push_back(tile);
    pending_bytes += bytes;
  }
  flush();
}

Result<cairn::lcmt_mapstore_reply> MapstoreClient::Call(cairn::lcmt_mapstore_request request) {
  if (request.request_id == 0) request.request_id = NextRequestId();
  if (request.requester.empty()) request.requester = requester_;
  request.num_layers = static_cast<int32_t>(request.layers.size());
  request.num_places = static_cast<int32_t>(request.places.size());
  if (request.utime == 0) request.utime = WallUtimeNow();
  active_id_ = request.request_id;
  reply_.reset();
  const auto start = Clock::now();
  auto sent = Clock::now();
  lcm_.publish(channels::kMapstoreRequest, &request);
  while (!reply_) {
    if (Since(start) > options_.total_timeout_s) {
      active_id_ = 0;
      return common::UnavailableError("no reply from cairn-mapstore to request " +
                                      std::to_string(request.request_id));
    }
    if (Since(sent) > options_.reply_timeout_s) {
      lcm_.publish(channels::kMapstoreRequest, &request);  // same id: replays are idempotent
      sent = Clock::now();
    }
    lcm_.handleTimeout(10);
  }
  active_id_ = 0;
  return *reply_;
}

namespace {

cairn::lcmt_mapstore_request SaveRequestOf(const MapSnapshot& snapshot) {
  cairn::lcmt_mapstore_request request{};
  request.op = cairn::lcmt_mapstore_request::OP_SAVE;
  request.site = snapshot.site;
  request.map_name = snapshot.name;
  request.profile = snapshot.provenance.source_profile;
  request.code_version = snapshot.provenance.code_version;
  request.parameters = snapshot.provenance.parameters;
  request.layers = snapshot.base.layer_names();
  request.has_profile = false;
  request.expect_obstacles = !snapshot.obstacles.obstacles.empty();
  request.expect_octomap = snapshot.octomap.has_value();
  return request;
}

}  // namespace

Status MapstoreClient::PushLayers(const std::vector<std::string>& layers,
                                  const MapSnapshot& snapshot, int64_t utime) {
  for (const std::string& layer : layers) {
    push_->tilers[layer] =
        std::make_unique<runtime::LayerTiler>(push_->robot, push_->map_name, options_.tile_size);
  }
  // Layers are tiled and compressed on compression_threads threads, in order, while this
  // thread publishes each one as soon as it is ready (its pauses leave the cores to them).
  const size_t num_layers = layers.size();
  std::vector<runtime::LayerTiler::Batch> batches(num_layers);
  std::vector<char> ready(num_layers, 0);
  bool failed = false;
  std::string failure;
  std::mutex ready_mutex;
  std::condition_variable ready_cv;
  std::thread producer([&] {
    try {
      ParallelFor(num_layers, std::max(1, options_.compression_threads), [&](size_t l) {
        runtime::LayerTiler::Batch batch = push_->tilers.at(layers[l])->Update(
            snapshot.base, layers[l], runtime::TileEncoding::kFloat, utime, true);
        if (options_.compress_tiles) {
          for (auto& tile : batch.tiles) CompressTile(&tile);
        }
        std::lock_guard<std::mutex> lock(ready_mutex);
        batches[l] = std::move(batch);
        ready[l] = 1;
        ready_cv.notify_all();
      });
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(ready_mutex);
      failed = true;
      failure = e.what();
      ready_cv.notify_all();
    }
  });
  for (size_t l = 0; l < num_layers; ++l) {
    runtime::LayerTiler::Batch batch;
    {
      std::unique_lock<std::mutex> lock(ready_mutex);
      ready_cv.wait(lock, [&] { return ready[l] != 0 || failed; });
      if (!ready[l]) break;
      batch = std::move(batches[l]);
    }
    lcm_.publish(channels::kMapstorePushManifest, &batch.manifest);
    PublishPushed(push_->map_name, batch.tiles);
  }
  producer.join();
  if (failed) return common::InternalError("tiling the map to push it: " + failure);
  return Status::Ok();
}

void MapstoreClient::PushOctomap(const OctomapData& octomap, int64_t utime) {
  for (const OctomapChunk& chunk : SplitOctomap(octomap)) {
    cairn::lcmt_octomap c = ToLcm(chunk, push_->robot, push_->map_name, utime);
    lcm_.publish(channels::kMapstorePushOctomap, &c);
    push_->octomap.push_back(std::move(c));
  }
}

Result<cairn::lcmt_mapstore_reply> MapstoreClient::Save(const MapSnapshot& snapshot) {
  cairn::lcmt_mapstore_request request = SaveRequestOf(snapshot);
  request.request_id = NextRequestId();
  request.requester = requester_;
  const int64_t utime = WallUtimeNow();
  // Everything goes out before the request; the store asks for what it missed.
  push_ = std::make_unique<Push>();
  push_->map_name = std::to_string(request.request_id) + "/" + snapshot.name;
  push_->robot = snapshot.provenance.source_robot;
  const Status pushed = PushLayers(request.layers, snapshot, utime);
  if (!pushed.ok()) {
    push_.reset();
    return pushed;
  }
  if (request.expect_obstacles) {
    push_->obstacles = runtime::ToLcm(snapshot.obstacles, utime, push_->robot, push_->map_name);
    lcm_.publish(channels::kMapstorePushObstacles, &*push_->obstacles);
  }
  if (snapshot.octomap) PushOctomap(*snapshot.octomap, utime);
  auto reply = Call(request);
  push_.reset();
  return reply;
}

bool MapstoreClient::PayloadComplete(const cairn::lcmt_mapstore_reply& reply,
                                     bool want_octomap) const {
  for (const std::string& layer : reply.layers) {
    if (!incoming_->manifests.count(layer) || !incoming_->assembler.Complete(layer)) return false;
  }
  return !want_octomap || OctomapComplete();
}

bool MapstoreClient::OctomapComplete() const {
  return incoming_->has_octomap_head && static_cast<int32_t>(incoming_->octomap_chunks.size()) ==
                                            incoming_->octomap_head.chunk_count;
}

int MapstoreClient::AskForMissing(const cairn::lcmt_mapstore_reply& reply, bool want_octomap,
                                  bool long_quiet) {
  // A layer whose manifest never came is asked for whole, after a longer silence.
  int asked = 0;
  for (const std::string& layer : reply.layers) {
    std::optional<cairn::lcmt_tile_resend_request> r;
    if (incoming_->manifests.count(layer)) {
      r = incoming_->assembler.MakeResendRequest(layer, requester_, WallUtimeNow());
    } else if (long_quiet) {
      cairn::lcmt_tile_resend_request all{};
      all.utime = WallUtimeNow();
      all.requester = requester_;
      all.layer = layer;
      r = all;
    }
    if (!r) continue;
    r->map_name = incoming_->map_name;
    lcm_.publish(channels::kMapstoreTileResend, &*r);
    ++asked;
  }
  if (want_octomap && long_quiet && !OctomapComplete()) {
    cairn::lcmt_tile_resend_request r{};
    r.utime = WallUtimeNow();
    r.requester = requester_;
    r.map_name = incoming_->map_name;
    r.layer = kResendOctomap;
    lcm_.publish(channels::kMapstoreTileResend, &r);
    ++asked;
  }
  return asked;
}

Status MapstoreClient::AwaitPayload(const cairn::lcmt_mapstore_reply& reply, bool want_octomap,
                                    Clock::time_point start, Loaded* loaded) {
  incoming_->last_progress = Clock::now();  // the tiles follow the reply
  // Collect the tiles, asking again for what does not arrive.
  auto last_ask = Clock::now();
  while (!PayloadComplete(reply, want_octomap)) {
    if (Since(start) > options_.total_timeout_s) {
      return common::UnavailableError("tiles of '" + reply.map_name + "' did not all arrive");
    }
    const double quiet = Since(incoming_->last_progress);
    if (quiet > options_.resend_interval_s && Since(last_ask) > options_.resend_interval_s) {
      loaded->resend_requests +=
          AskForMissing(reply, want_octomap, quiet > 5 * options_.resend_interval_s);
      last_ask = Clock::now();
    }
    lcm_.handleTimeout(5);
  }
  return Status::Ok();
}

Status MapstoreClient::CollectPayload(const cairn::lcmt_mapstore_reply& reply, bool want_octomap,
                                      Loaded* loaded) {
  bool first = true;
  for (const std::string& layer : reply.layers) {
    auto grid = incoming_->assembler.TakeLayer(layer);
    if (!grid) continue;
    if (first) {
      loaded->layers = common::GridMap(grid->geometry());
      first = false;
    }
    if (grid->geometry() == loaded->layers.geometry()) {
      loaded->layers.AddLayer(layer, std::move(grid->at(layer)));
    }
  }
  for (const auto& m : reply.obstacles) {
    auto o = runtime::FromLcm(m);
    if (o.ok()) loaded->obstacles.obstacles.push_back(std::move(o).value());
  }
  loaded->obstacles.map_version = reply.version;
  if (!want_octomap) return Status::Ok();
  OctomapData octomap;
  octomap.binary = incoming_->octomap_head.binary;
  octomap.resolution_m = incoming_->octomap_head.resolution_m;
  for (const auto& [i, bytes] : incoming_->octomap_chunks) octomap.bytes += bytes;
  if (common::Crc32(octomap.bytes.data(), octomap.bytes.size()) !=
      static_cast<uint32_t>(incoming_->octomap_head.checksum)) {
    return common::CorruptError("the OctoMap arrived damaged");
  }
  loaded->octomap = std::move(octomap);
  return Status::Ok();
}

Result<MapstoreClient::Loaded> MapstoreClient::Load(const std::string& site, const std::string& map,
                                                    int64_t version, const std::string& profile,
                                                    const std::vector<std::string>& layers) {
  cairn::lcmt_mapstore_request request{};
  request.request_id = NextRequestId();
  request.requester = requester_;
  request.op = cairn::lcmt_mapstore_request::OP_LOAD;
  request.site = site;
  request.map_name = map;
  request.version = version;
  request.profile = profile;
  request.layers = layers;
  request.has_profile = false;
  const bool want_octomap = std::find(layers.begin(), layers.end(), "octomap") != layers.end();
  incoming_ = std::make_unique<Incoming>();
  incoming_->map_name = std::to_string(request.request_id) + "/" + map;
  const auto start = Clock::now();
  auto reply = Call(request);
  Status status = reply.ok() ? StatusOfReply(*reply) : reply.status();
  Loaded loaded;
  if (status.ok()) status = AwaitPayload(*reply, want_octomap, start, &loaded);
  if (status.ok()) status = CollectPayload(*reply, want_octomap, &loaded);
  incoming_.reset();
  if (!status.ok()) return status;
  loaded.reply = *reply;
  return loaded;
}

}  // namespace cairn::mapstore
