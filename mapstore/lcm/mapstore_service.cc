#include "mapstore/lcm/mapstore_service.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <thread>

#include "cairn/lcmt_grid_tile_batch.hpp"
#include "cairn/lcmt_map_control_request.hpp"

#include "common/crc32.h"
#include "common/channels.h"
#include "common/layers.h"
#include "mapstore/blob_codec.h"
#include "mapstore/map_operations.h"
#include "mapstore/map_transfer.h"
#include "mapstore/lcm/mapstore_conversions.h"
#include "mapstore/names.h"
#include "mapstore/lcm/tile_wire.h"
#include "services/runtime/conversions.h"

namespace cairn::mapstore {

namespace fs = std::filesystem;
using common::Result;
using common::Status;
using Reply = cairn::lcmt_mapstore_reply;
using Request = cairn::lcmt_mapstore_request;

namespace {

constexpr char kActor[] = "cairn-mapstore";
// Pseudo layers a push client is asked to send again (they cannot be layer names).
constexpr char kResendObstacles[] = "#obstacles";
constexpr char kResendOctomap[] = "#octomap";
constexpr size_t kOctomapChunkBytes = 192 * 1024;

double SecondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Profile-specific layers the store never saves: it derives them per profile itself.
bool IsDerivedLayer(const std::string& name) {
  return layers::IsCostLayer(name) || name == layers::kSlope || name == layers::kStepMax ||
         name == layers::kRoughness || name == layers::kDitchDepth || name == layers::kDitchWidth;
}

// Chunks of one OctoMap version being reassembled.
struct OctomapChunks {
  int64_t version{0};
  int32_t chunk_count{0};
  int64_t total_bytes{0};
  int64_t checksum{0};
  bool binary{true};
  double resolution_m{0.0};
  std::map<int32_t, std::string> chunks;

  // Adds a chunk; returns false for an inconsistent one.
  bool Add(const cairn::lcmt_octomap& c) {
    if (c.chunk_count <= 0 || c.chunk_index < 0 || c.chunk_index >= c.chunk_count ||
        c.num_bytes != static_cast<int32_t>(c.data.size()) || c.total_bytes < 0 ||
        c.total_bytes > (int64_t{1} << 31)) {
      return false;
    }
    if (chunks.empty() || c.version != version || c.chunk_count != chunk_count) {
      chunks.clear();
      version = c.version;
      chunk_count = c.chunk_count;
      total_bytes = c.total_bytes;
      checksum = c.checksum;
      binary = c.binary;
      resolution_m = c.resolution_m;
    }
    chunks[c.chunk_index].assign(c.data.begin(), c.data.end());
    return true;
  }
  // The whole tree once every chunk arrived and the checksum holds.
  std::optional<OctomapData> Complete() const {
    if (chunk_count == 0 || static_cast<int32_t>(chunks.size()) != chunk_count) return std::nullopt;
    OctomapData out;
    out.binary = binary;
    out.resolution_m = resolution_m;
    for (const auto& [index, bytes] : chunks) out.bytes += bytes;
    if (static_cast<int64_t>(out.bytes.size()) != total_bytes ||
        common::Crc32(out.bytes.data(), out.bytes.size()) != static_cast<uint32_t>(checksum)) {
      return std::nullopt;
    }
    return out;
  }
};

std::vector<cairn::lcmt_octomap> OctomapChunksOf(const OctomapData& octomap,
                                                 const std::string& robot,
                                                 const std::string& map_name, int64_t utime) {
  std::vector<cairn::lcmt_octomap> out;
  const size_t total = octomap.bytes.size();
  const int32_t count = static_cast<int32_t>(
      std::max<size_t>(1, (total + kOctomapChunkBytes - 1) / kOctomapChunkBytes));
  const int64_t crc = common::Crc32(octomap.bytes.data(), total);
  for (int32_t i = 0; i < count; ++i) {
    cairn::lcmt_octomap c{};
    c.utime = utime;
    c.robot = robot;
    c.map_name = map_name;
    c.resolution_m = octomap.resolution_m;
    c.binary = octomap.binary;
    c.version = 1;
    c.chunk_index = i;
    c.chunk_count = count;
    c.total_bytes = static_cast<int64_t>(total);
    c.checksum = crc;
    const size_t begin = i * kOctomapChunkBytes, end = std::min(total, begin + kOctomapChunkBytes);
    c.data.assign(octomap.bytes.begin() + begin, octomap.bytes.begin() + end);
    c.num_bytes = static_cast<int32_t>(c.data.size());
    out.push_back(std::move(c));
  }
  return out;
}

// Layers of an assembler as one map; every layer must share one geometry. `take` moves the
// layers out of the assembler (which forgets them) instead of copying them.
Result<common::GridMap> CollectLayers(runtime::LayerAssembler* assembler,
                                      const std::vector<std::string>& names, bool take) {
  common::GridMap map;
  bool first = true;
  for (const std::string& name : names) {
    auto layer = take ? assembler->TakeLayer(name) : assembler->Layer(name);
    if (!layer) return common::NotFoundError("no layer '" + name + "' arrived");
    if (first) {
      map = common::GridMap(layer->geometry());
      first = false;
    } else if (layer->geometry() != map.geometry()) {
      return common::InvalidArgumentError("layer '" + name +
                                          "' has another geometry than the other layers");
    }
    map.AddLayer(name, std::move(layer->at(name)));
  }
  return map;
}

}  // namespace

int8_t ReplyStatus(const Status& status) {
  switch (status.code()) {
    case common::StatusCode::kOk:
      return Reply::STATUS_OK;
    case common::StatusCode::kNotFound:
      return Reply::STATUS_NOT_FOUND;
    case common::StatusCode::kInvalidArgument:
      return Reply::STATUS_INVALID;
    case common::StatusCode::kCorrupt:
      return Reply::STATUS_CORRUPT;
    case common::StatusCode::kUnavailable:
      return Reply::STATUS_BUSY;
    case common::StatusCode::kAlreadyExists:
      return Reply::STATUS_CONFLICT;
    default:
      return Reply::STATUS_ERROR;
  }
}

struct MapstoreService::Outgoing {
  std::mutex sending;  // one send of this payload at a time
  std::string map_name;
  std::string robot;
  std::unique_ptr<runtime::LayerTiler> tiler;
  std::vector<runtime::LayerTiler::Batch> first_send;  // sent once with the reply, then dropped
  std::vector<std::string> layers;
  std::optional<OctomapData> octomap;
  int64_t cells{0};
  double tile_ms{0.0};      // cutting the layers into tiles
  double compress_ms{0.0};  // compressing the tiles
  int64_t bytes{0};         // of the first send's tiles
};

struct MapstoreService::Staging {
  std::string invalid;  // why pushed data were refused (the save fails with INVALID)
  runtime::LayerAssembler assembler;
  // Compressed tiles as they came, by layer and (tile_ix, tile_iy): the store keeps these bytes
  // rather than compressing the cells again (SaveMap checks each against the cells' CRC).
  struct EncodedLayer {
    int tile_size{0};
    std::map<std::pair<int, int>, StoredTile> tiles;
  };
  std::map<std::string, EncodedLayer> encoded;
  std::set<std::string> manifests;
  std::optional<common::ObstacleRegistry> obstacles;
  OctomapChunks octomap;
  std::string robot;
  Clock::time_point last{Clock::now()};
  int64_t cells{0};
};

struct MapstoreService::PendingSave {
  Request request;
  std::string key;
  std::string map_name;  // push: "<request_id>/<map>"
  bool pull{false};
  Clock::time_point started{Clock::now()};
  Clock::time_point next_resend{Clock::now()};
  int resend_rounds{0};
};

struct MapstoreService::LiveMirror {
  std::string map_name{"live"};  // the mapper's map, as its manifests name it
  runtime::LayerAssembler assembler;
  std::map<std::string, Clock::time_point> manifest_time;
  std::optional<common::ObstacleRegistry> obstacles;
  Clock::time_point obstacles_time;
  OctomapChunks octomap;
  std::optional<OctomapData> complete_octomap;
};

MapstoreService::MapstoreService(runtime::Node& node, MapStore& store, ProfileDeriver deriver,
                                 MapstoreServiceParams params)
    : node_(node), store_(store), deriver_(std::move(deriver)), params_(std::move(params)) {
  node_.Subscribe<Request>(channels::kMapstoreRequest, [this](const Request& r) { OnRequest(r); });
  // A save waiting for pushed data finishes as soon as its last piece arrives (OnPushed).
  SubscribePush(channels::kMapstorePushTiles, &MapstoreService::OnPushTile);
  SubscribePush(channels::kMapstorePushTileBatches, &MapstoreService::OnPushTileBatch);
  SubscribePush(channels::kMapstorePushManifest, &MapstoreService::OnPushManifest);
  SubscribePush(channels::kMapstorePushObstacles, &MapstoreService::OnPushObstacles);
  SubscribePush(channels::kMapstorePushOctomap, &MapstoreService::OnPushOctomap);
  node_.Subscribe<cairn::lcmt_tile_resend_request>(
      channels::kMapstoreTileResend,
      [this](const cairn::lcmt_tile_resend_request& r) { OnResend(r); });
  node_.AddTimer(params_.poll_period_s, [this] { Poll(); });
  for (int i = 0; i < std::max(1, params_.worker_threads); ++i) {
    workers_.emplace_back([this] { WorkerLoop(); });
  }
}

MapstoreService::~MapstoreService() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  work_ready_.notify_all();
  for (auto& w : workers_) w.join();
}

int64_t MapstoreService::pending_saves() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int64_t>(pending_.size());
}

int64_t MapstoreService::running_jobs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int64_t>(busy_keys_.size());
}

std::string MapstoreService::RequestKey(const Request& request) const {
  return request.requester + "#" + std::to_string(request.request_id);
}

void MapstoreService::SetStatus(const Status& status, Reply* reply) {
  reply->status = ReplyStatus(status);
  reply->message = status.ok() ? reply->message : status.message();
  if (status.code() == common::StatusCode::kInvalidArgument) {
    node_.CountDropped("invalid_requests");
  } else if (status.code() == common::StatusCode::kNotFound) {
    node_.Count("not_found");
  } else if (!status.ok()) {
    node_.Count("failed_requests");
    node_.Warn("request_error", status.ToString());
  }
}

void MapstoreService::Publish(const Reply& reply) {
  node_.Publish(channels::kMapstoreReply, reply);
}

void MapstoreService::OnRequest(const Request& request) {
  std::unique_lock<std::mutex> lock(mutex_);
  const std::string key = RequestKey(request);
  auto cached = replies_.find(key);
  if (cached != replies_.end()) {
    // A replay: the first reply again, and its payload if still kept.
    node_.Count("replayed_requests");
    Publish(cached->second);
    auto out = outgoing_.find(std::to_string(request.request_id) + "/" + request.map_name);
    if (out != outgoing_.end()) {
      std::shared_ptr<Outgoing> payload = out->second;
      lock.unlock();
      Resend(*payload, nullptr);
    }
    return;
  }
  if (pending_.count(key) || busy_keys_.count(key)) return;  // still working on it

  const auto started = Clock::now();
  Reply reply{};
  reply.utime = node_.NowUtime();
  reply.request_id = request.request_id;
  reply.op = request.op;
  reply.status = Reply::STATUS_OK;
  reply.site = request.site.empty() ? kDefaultSite : request.site;
  reply.map_name = request.map_name;
  reply.version = request.version;
  reply.num_maps = reply.num_profiles = reply.num_places = reply.num_obstacles = 0;
  reply.num_tiles = reply.num_layers = 0;
  reply.duration_us = 0;
  bool done = true;
  try {
    done = Handle(request, &reply);
  } catch (const std::exception& e) {
    SetStatus(common::InternalError(std::string("internal error: ") + e.what()), &reply);
  }
  if (done) Finish(request, std::move(reply), started);
}

void MapstoreService::CacheReply(const Request& request, Reply* reply, Clock::time_point started) {
  reply->duration_us = static_cast<int64_t>(SecondsSince(started) * 1e6);
  reply->num_maps = static_cast<int32_t>(reply->maps.size());
  reply->num_profiles = static_cast<int32_t>(reply->profiles.size());
  reply->num_places = static_cast<int32_t>(reply->places.size());
  reply->num_obstacles = static_cast<int32_t>(reply->obstacles.size());
  reply->num_layers = static_cast<int32_t>(reply->layers.size());
  const std::string key = RequestKey(request);
  replies_[key] = *reply;
  reply_order_.push_back(key);
  while (static_cast<int>(reply_order_.size()) > params_.reply_cache_size) {
    replies_.erase(reply_order_.front());
    reply_order_.pop_front();
  }
}

void MapstoreService::Finish(const Request& request, Reply reply, Clock::time_point started) {
  CacheReply(request, &reply, started);
  Publish(reply);
}

bool MapstoreService::Handle(const Request& request, Reply* reply) {
  const std::string site = request.site.empty() ? kDefaultSite : request.site;
  const MapRef ref{site, request.map_name, request.version};
  const WriteContext ctx{request.requester.empty() ? "unknown" : request.requester,
                         request.request_id, 0};
  Status s;
  switch (request.op) {
    case Request::OP_SAVE:
      return StartSave(request, reply);
    case Request::OP_LOAD:
    case Request::OP_SHARE:
    case Request::OP_EXPORT:
    case Request::OP_IMPORT:
    case Request::OP_LOAD_OBSTACLES: {
      if (request.num_layers < 0 ||
          request.layers.size() != static_cast<size_t>(request.num_layers)) {
        SetStatus(common::InvalidArgumentError("layers disagree with num_layers"), reply);
        return true;
      }
      auto job = std::make_unique<Job>();
      job->request = request;
      job->started = Clock::now();
      job->reply = *reply;
      busy_keys_.insert(RequestKey(request));
      queue_.push_back(std::move(job));
      work_ready_.notify_one();
      return false;
    }
    case Request::OP_LIST_MAPS: {
      MapFilter filter;
      filter.site = request.site;
      filter.name = request.map_name;
      filter.all_versions = !request.map_name.empty();
      auto maps = store_.ListMaps(filter);
      if (!maps.ok()) {
        SetStatus(maps.status(), reply);
        return true;
      }
      for (const MapInfo& info : *maps) reply->maps.push_back(ToLcm(info));
      reply->message = std::to_string(maps->size()) + " maps";
      return true;
    }
    case Request::OP_LIST_PROFILES: {
      auto profiles = store_.ListProfiles();
      if (!profiles.ok()) {
        SetStatus(profiles.status(), reply);
        return true;
      }
      for (const StoredProfile& p : *profiles) reply->profiles.push_back(runtime::ToLcm(p.profile));
      reply->message = std::to_string(profiles->size()) + " profiles";
      return true;
    }
    case Request::OP_LIST_PLACES: {
      auto places = store_.ListPlaces(site);
      if (!places.ok()) {
        SetStatus(places.status(), reply);
        return true;
      }
      for (const Place& p : *places) reply->places.push_back(ToLcm(p));
      reply->message = std::to_string(places->size()) + " places";
      return true;
    }
    case Request::OP_PUT_PROFILE: {
      if (!request.has_profile) {
        SetStatus(common::InvalidArgumentError("OP_PUT_PROFILE without profile_data"), reply);
        return true;
      }
      auto profile = runtime::FromLcm(request.profile_data);
      if (!profile.ok()) {
        SetStatus(common::InvalidArgumentError(profile.status().message()), reply);
        return true;
      }
      s = store_.PutProfile(*profile, ctx);
      SetStatus(s, reply);
      if (s.ok()) {
        reply->message = "profile '" + profile->name + "' stored (" + profile->ContentHash() + ")";
        reply->profiles.push_back(runtime::ToLcm(*profile));
        node_.Event("stored profile %s (%s) for %s", profile->name.c_str(),
                    profile->ContentHash().c_str(), ctx.actor.c_str());
      }
      return true;
    }
    case Request::OP_GET_PROFILE: {
      auto profile = store_.GetProfile(request.profile);
      if (!profile.ok()) {
        SetStatus(profile.status(), reply);
        return true;
      }
      reply->profiles.push_back(runtime::ToLcm(profile->profile));
      return true;
    }
    case Request::OP_DELETE:
      s = store_.DeleteMap(ref, ctx);
      SetStatus(s, reply);
      if (s.ok()) {
        reply->message = request.version == 0 ? "map deleted" : "version deleted";
        node_.Event("deleted %s/%s%s for %s", site.c_str(), request.map_name.c_str(),
                    request.version == 0 ? "" : (" v" + std::to_string(request.version)).c_str(),
                    ctx.actor.c_str());
      }
      return true;
    case Request::OP_PUT_PLACE: {
      if (request.num_places <= 0 ||
          request.places.size() != static_cast<size_t>(request.num_places)) {
        SetStatus(common::InvalidArgumentError("OP_PUT_PLACE needs places (num_places > 0)"),
                  reply);
        return true;
      }
      std::vector<Place> places;
      for (const auto& m : request.places) {
        auto p = FromLcm(m);
        if (!p.ok()) {
          SetStatus(p.status(), reply);
          return true;
        }
        places.push_back(std::move(p).value());
      }
      s = store_.PutPlaces(site, places, ctx);
      SetStatus(s, reply);
      if (s.ok()) reply->message = std::to_string(places.size()) + " places stored";
      return true;
    }
    default:
      SetStatus(common::InvalidArgumentError("unknown op " + std::to_string(request.op)), reply);
      return true;
  }
}

MapstoreService::JobResult MapstoreService::RunJob(const Request& request, Reply reply) const {
  JobResult out;
  out.reply = std::move(reply);
  try {
    switch (request.op) {
      case Request::OP_LOAD:
        JobLoad(request, &out);
        break;
      case Request::OP_SHARE:
        JobShare(request, &out);
        break;
      case Request::OP_LOAD_OBSTACLES:
        JobLoadObstacles(request, &out);
        break;
      case Request::OP_EXPORT:
        JobExport(request, &out);
        break;
      case Request::OP_IMPORT:
        JobImport(request, &out);
        break;
      default:
        out.status = common::InternalError("not a worker request");
        break;
    }
  } catch (const std::exception& e) {
    out.status = common::InternalError(std::string("internal error: ") + e.what());
  }
  return out;
}

void MapstoreService::JobLoad(const Request& request, JobResult* out) const {
  Reply* reply = &out->reply;
  out->counter = "loads";
  const std::string site = request.site.empty() ? kDefaultSite : request.site;
  std::vector<std::string> wanted;
  bool want_octomap = false;
  for (const std::string& l : request.layers) {
    if (l == "octomap") {
      want_octomap = true;
    } else {
      wanted.push_back(l);
    }
  }
  const bool only_octomap = want_octomap && wanted.empty();
  // A load without a profile, of base layers only, sends the stored blobs as they are, neither
  // decoded nor tiled nor compressed again (each is still checked). A derived layer's name goes
  // to LoadForProfile, which explains why it cannot be had.
  const bool may_send_stored =
      !only_octomap && request.profile.empty() && params_.compress_reply_tiles;
  ProfileView view;
  bool stored = false;
  if (only_octomap || may_send_stored) {
    auto info = store_.GetMapInfo({site, request.map_name, request.version});
    if (!info.ok()) {
      out->status = info.status();
      return;
    }
    view.info = *info;
    const std::set<std::string> base(info->layers.begin(), info->layers.end());
    if (may_send_stored && std::all_of(wanted.begin(), wanted.end(),
                                       [&](const std::string& l) { return base.count(l) > 0; })) {
      const MapRef exact{info->site, info->name, info->version};
      auto tiles = store_.LoadStoredTiles(exact, wanted, params_.reply_tile_size);
      if (!tiles.ok()) {
        out->status = tiles.status();
        return;
      }
      auto obstacles = store_.LoadObstacles(exact);
      if (!obstacles.ok()) {
        out->status = obstacles.status();
        return;
      }
      view.obstacles = std::move(obstacles).value();
      out->stored_layers = std::move(tiles).value();
      out->stored_geometry = info->geometry;
      stored = true;
    }
  }
  // A load of cached derived layers alone for a profile sends the cache's blobs as they are too.
  if (!only_octomap && !stored && !request.profile.empty() && params_.compress_reply_tiles &&
      !wanted.empty() && deriver_.valid()) {
    auto info = store_.GetMapInfo({site, request.map_name, request.version});
    if (!info.ok()) {
      out->status = info.status();
      return;
    }
    const std::set<std::string> base(info->layers.begin(), info->layers.end());
    if (std::none_of(wanted.begin(), wanted.end(),
                     [&](const std::string& l) { return base.count(l) > 0; })) {
      auto profile_hash = store_.GetProfileHash(request.profile);
      if (!profile_hash.ok()) {
        out->status = profile_hash.status();
        return;
      }
      const MapRef exact{info->site, info->name, info->version};
      auto cached = store_.FindDerivedTiles(exact, *profile_hash, deriver_.code_version, wanted,
                                            params_.reply_tile_size);
      if (!cached.ok()) {
        out->status = cached.status();
        return;
      }
      if (cached->has_value()) {
        view.info = *info;
        view.obstacles = std::move((*cached)->registry);
        view.from_cache = true;
        out->stored_layers = std::move((*cached)->layers);
        out->stored_geometry = info->geometry;
        stored = true;
      }
    }
  }
  if (!only_octomap && !stored) {
    auto loaded = LoadForProfile(store_, &deriver_, {site, request.map_name, request.version},
                                 request.profile, {wanted, std::nullopt});
    if (!loaded.ok()) {
      out->status = loaded.status();
      return;
    }
    view = std::move(loaded).value();
  }
  if (want_octomap) {
    auto o = store_.LoadOctomap({view.info.site, view.info.name, view.info.version});
    if (!o.ok()) {
      out->status = o.status();
      return;
    }
    out->octomap = std::move(o).value();
  }
  reply->version = view.info.version;
  reply->maps.push_back(ToLcm(view.info));
  out->robot = view.info.provenance.source_robot;
  if (stored) {
    for (const auto& layer : out->stored_layers) reply->layers.push_back(layer.name);
  } else if (!only_octomap) {
    reply->layers = view.layers.layer_names();
    out->layers = std::move(view.layers);
  }
  for (const auto& o : view.obstacles.obstacles) {
    if (static_cast<int>(reply->obstacles.size()) >= params_.max_reply_obstacles) break;
    reply->obstacles.push_back(runtime::ToLcm(o));
  }
  reply->message = std::to_string(reply->layers.size()) + " layers" +
                   (request.profile.empty() ? std::string()
                    : view.from_cache       ? ", derived layers from the cache"
                                            : ", derived now (not cached)") +
                   (out->octomap ? ", OctoMap follows" : "");
}

void MapstoreService::JobShare(const Request& request, JobResult* out) const {
  Reply* reply = &out->reply;
  const std::string site = request.site.empty() ? kDefaultSite : request.site;
  if (!deriver_.valid()) {
    out->status = common::UnavailableError("this store cannot derive profile layers");
    return;
  }
  const auto t0 = Clock::now();
  auto shared =
      ShareMap(store_, deriver_, {site, request.map_name, request.version}, request.profile,
               {request.requester.empty() ? "unknown" : request.requester, request.request_id, 0});
  if (!shared.ok()) {
    out->status = shared.status();
    return;
  }
  reply->version = shared->info.version;
  reply->maps.push_back(ToLcm(shared->info));
  reply->layers = shared->derived.layers.layer_names();
  for (const auto& o : shared->changed) {
    if (static_cast<int>(reply->obstacles.size()) >= params_.max_reply_obstacles) break;
    reply->obstacles.push_back(runtime::ToLcm(o));
  }
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%zu obstacles change verdict from %s to %s; layers %s",
                shared->changed.size(),
                shared->source_profile.empty() ? "(unknown)" : shared->source_profile.c_str(),
                request.profile.c_str(), shared->was_cached ? "from the cache" : "derived");
  reply->message = buf;
  if (!shared->was_cached) {
    std::snprintf(
        buf, sizeof(buf), "shared %s/%s v%lld with %s: derived in %.0f ms, %zu verdicts differ",
        site.c_str(), request.map_name.c_str(), static_cast<long long>(shared->info.version),
        request.profile.c_str(), SecondsSince(t0) * 1e3, shared->changed.size());
    out->event = buf;
  }
}

void MapstoreService::JobLoadObstacles(const Request& request, JobResult* out) const {
  Reply* reply = &out->reply;
  const std::string site = request.site.empty() ? kDefaultSite : request.site;
  const MapRef ref{site, request.map_name, request.version};
  auto info = store_.GetMapInfo(ref);
  if (!info.ok()) {
    out->status = info.status();
    return;
  }
  common::ObstacleRegistry registry;
  if (request.profile.empty()) {
    auto stored = store_.LoadObstacles(ref);
    if (!stored.ok()) {
      out->status = stored.status();
      return;
    }
    registry = std::move(stored).value();
  } else {
    auto view = LoadForProfile(store_, &deriver_, ref, request.profile,
                               {{layers::CostLayer(request.profile)}, std::nullopt});
    if (!view.ok()) {
      out->status = view.status();
      return;
    }
    registry = std::move(view->obstacles);
  }
  reply->version = info->version;
  reply->maps.push_back(ToLcm(*info));
  for (const auto& o : registry.obstacles) {
    if (static_cast<int>(reply->obstacles.size()) >= params_.max_reply_obstacles) break;
    reply->obstacles.push_back(runtime::ToLcm(o));
  }
  reply->message = std::to_string(registry.obstacles.size()) + " obstacles";
  if (static_cast<int>(registry.obstacles.size()) > params_.max_reply_obstacles) {
    reply->message += " (first " + std::to_string(params_.max_reply_obstacles) +
                      " in this reply; export csv for all)";
  }
}

Result<std::string> MapstoreService::FilesPath(const std::string& relative) const {
  std::error_code ec;
  fs::create_directories(params_.files_root, ec);
  const fs::path root = fs::weakly_canonical(params_.files_root, ec);
  if (ec) return common::UnavailableError("files root '" + params_.files_root + "' is unusable");
  if (relative.find('\0') != std::string::npos) {
    return common::InvalidArgumentError("path holds a NUL byte");
  }
  const fs::path candidate = fs::weakly_canonical(root / relative, ec);
  if (ec) return common::InvalidArgumentError("cannot resolve path '" + relative + "'");
  const fs::path rel = candidate.lexically_relative(root);
  if (rel.empty() || *rel.begin() == "..") {
    return common::InvalidArgumentError("path '" + relative + "' leaves the store's files folder");
  }
  return candidate.string();
}

void MapstoreService::JobExport(const Request& request, JobResult* out) const {
  Reply* reply = &out->reply;
  ExportOptions options;
  options.ref = {request.site.empty() ? kDefaultSite : request.site, request.map_name,
                 request.version};
  options.format = request.format.empty() ? "ros" : request.format;
  if (options.format.rfind("ros-", 0) == 0) {
    auto mode = io::PgmModeFromName(options.format.substr(4));
    if (!mode.ok()) {
      out->status = mode.status();
      return;
    }
    options.ros.mode = *mode;
    options.format = "ros";
  }
  auto folder = FilesPath(request.path.empty() ? "." : request.path);
  if (!folder.ok()) {
    out->status = folder.status();
    return;
  }
  options.folder = *folder;
  options.profile = request.profile;
  if (!request.layers.empty()) options.layer = request.layers.front();
  auto files = ExportMap(store_, &deriver_, options);
  if (!files.ok()) {
    out->status = files.status();
    return;
  }
  std::string list;
  for (const std::string& f : *files) list += (list.empty() ? "" : ", ") + f;
  reply->message = "wrote " + list;
  out->event = "exported " + options.ref.site + "/" + request.map_name + " as " + options.format +
               ": " + list;
}

void MapstoreService::JobImport(const Request& request, JobResult* out) const {
  Reply* reply = &out->reply;
  ImportOptions options;
  options.site = request.site.empty() ? kDefaultSite : request.site;
  options.name = request.map_name;
  if (!request.layers.empty()) options.layer = request.layers.front();
  auto path = FilesPath(request.path);
  if (!path.ok()) {
    out->status = path.status();
    return;
  }
  options.path = *path;
  options.provenance.source_robot = request.robot;
  options.provenance.source_profile = request.profile;
  auto info =
      ImportMap(store_, options,
                {request.requester.empty() ? "unknown" : request.requester, request.request_id, 0});
  if (!info.ok()) {
    out->status = info.status();
    return;
  }
  reply->version = info->version;
  reply->maps.push_back(ToLcm(*info));
  reply->layers = info->layers;
  reply->message = "imported as version " + std::to_string(info->version);
  out->event = "imported " + request.path + " into " + options.site + "/" + options.name + " v" +
               std::to_string(info->version);
}

void MapstoreService::WorkerLoop() {
  while (true) {
    std::unique_ptr<Job> job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_ready_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      job = std::move(queue_.front());
      queue_.pop_front();
    }
    // The work and the tiling of the payload run without the lock ...
    const auto work_started = Clock::now();
    JobResult result = RunJob(job->request, job->reply);
    const double work_ms = SecondsSince(work_started) * 1e3;
    Reply reply = std::move(result.reply);
    std::shared_ptr<Outgoing> payload;
    if (result.status.ok() && (result.layers || result.octomap || !result.stored_layers.empty())) {
      try {
        payload = MakeOutgoing(
            std::to_string(job->request.request_id) + "/" + job->request.map_name, result);
        for (const auto& batch : payload->first_send) {
          reply.num_tiles += static_cast<int32_t>(batch.tiles.size());
        }
      } catch (const std::exception& e) {
        payload.reset();
        result.status = common::InternalError(std::string("preparing the reply: ") + e.what());
      }
    }
    SetStatus(result.status, &reply);
    if (!result.counter.empty()) node_.Count(result.counter);
    {
      // ... the bookkeeping with it ...
      std::lock_guard<std::mutex> lock(mutex_);
      if (payload) KeepOutgoing(payload);
      CacheReply(job->request, &reply, job->started);
      busy_keys_.erase(RequestKey(job->request));
    }
    // ... and the sending after it: the reply, then the payload it announces.
    Publish(reply);
    const auto send_started = Clock::now();
    if (payload) Resend(*payload, nullptr);
    if (result.status.ok() && payload && payload->cells > 0) {
      // Where a load's time goes, one line per load.
      node_.Event(
          "%s '%s' v%lld: %d tiles%s, %.1f MB; read %.0f ms, tiled %.0f ms, compressed %.0f ms, "
          "sent %.0f ms",
          result.counter == "loads" ? "load of" : "reply with", job->request.map_name.c_str(),
          static_cast<long long>(reply.version), reply.num_tiles,
          result.stored_layers.empty() ? "" : " as stored", payload->bytes / 1e6, work_ms,
          payload->tile_ms, payload->compress_ms, SecondsSince(send_started) * 1e3);
    }
    if (result.status.ok() && !result.event.empty()) node_.Event("%s", result.event.c_str());
  }
}

std::shared_ptr<MapstoreService::Outgoing> MapstoreService::MakeOutgoing(
    const std::string& map_name, const JobResult& result) const {
  auto out = std::make_shared<Outgoing>();
  out->map_name = map_name;
  out->robot = result.robot;
  out->octomap = result.octomap;
  if (!result.stored_layers.empty()) {
    const auto tile_started = Clock::now();
    out->tiler = std::make_unique<runtime::LayerTiler>(result.robot, map_name,
                                                       result.stored_layers.front().tile_size);
    const int64_t utime = node_.NowUtime();
    for (const StoredLayer& layer : result.stored_layers) {
      std::vector<runtime::LayerTiler::EncodedTile> tiles;
      tiles.reserve(layer.tiles.size());
      for (const StoredTile& t : layer.tiles) {
        runtime::LayerTiler::EncodedTile e;
        e.tile_ix = t.tile_ix;
        e.tile_iy = t.tile_iy;
        e.cells_x = t.cells_x;
        e.cells_y = t.cells_y;
        e.checksum = t.raw_crc32;
        e.encoding = WireEncoding(static_cast<Codec>(t.codec));
        if (e.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32) {
          e.bytes.assign(t.data.begin(), t.data.end());
        } else {
          // Another codec (raw, plain zstd): the cells travel as floats.
          e.encoding = cairn::lcmt_grid_tile::ENCODING_FLOAT32;
          e.data.resize(static_cast<size_t>(t.cells_x) * t.cells_y);
          const Status s = DecodeBlobTo(static_cast<Codec>(t.codec), t.data.data(), t.data.size(),
                                        static_cast<int64_t>(e.data.size() * sizeof(float)),
                                        t.raw_crc32, reinterpret_cast<uint8_t*>(e.data.data()));
          if (!s.ok()) throw std::runtime_error(s.message());  // checked when loaded
        }
        tiles.push_back(std::move(e));
      }
      out->first_send.push_back(
          out->tiler->Adopt(layer.name, result.stored_geometry, std::move(tiles), utime));
      out->layers.push_back(layer.name);
      out->cells += result.stored_geometry.num_cells();
    }
    out->tile_ms = SecondsSince(tile_started) * 1e3;
  } else if (result.layers) {
    out->tiler =
        std::make_unique<runtime::LayerTiler>(result.robot, map_name, params_.reply_tile_size);
    const int64_t utime = node_.NowUtime();
    const auto tile_started = Clock::now();
    for (const std::string& name : result.layers->layer_names()) {
      out->first_send.push_back(
          out->tiler->Update(*result.layers, name, runtime::TileEncoding::kFloat, utime, true));
      out->layers.push_back(name);
      out->cells += result.layers->geometry().num_cells();
    }
    if (params_.compress_reply_tiles) {
      std::vector<cairn::lcmt_grid_tile*> tiles;
      for (auto& batch : out->first_send) {
        for (auto& tile : batch.tiles) tiles.push_back(&tile);
      }
      out->tile_ms = SecondsSince(tile_started) * 1e3;
      const auto compress_started = Clock::now();
      ParallelFor(tiles.size(), std::max(1, params_.worker_threads),
                  [&](size_t i) { CompressTile(tiles[i]); });
      out->compress_ms = SecondsSince(compress_started) * 1e3;
    } else {
      out->tile_ms = SecondsSince(tile_started) * 1e3;
    }
  }
  for (const auto& batch : out->first_send) {
    for (const auto& tile : batch.tiles) out->bytes += TilePayloadBytes(tile);
  }
  return out;
}

void MapstoreService::KeepOutgoing(std::shared_ptr<Outgoing> out) {
  // Kept for resends; the oldest payloads go first when memory runs short.
  outgoing_cells_ += out->cells;
  auto existing = outgoing_.find(out->map_name);
  if (existing != outgoing_.end()) {
    outgoing_cells_ -= existing->second->cells;
    existing->second = std::move(out);
  } else {
    outgoing_order_.push_back(out->map_name);
    outgoing_[out->map_name] = std::move(out);
  }
  while (outgoing_cells_ > params_.max_kept_reply_cells && outgoing_order_.size() > 1) {
    auto victim = outgoing_.find(outgoing_order_.front());
    if (victim != outgoing_.end()) {
      outgoing_cells_ -= victim->second->cells;
      outgoing_.erase(victim);
    }
    outgoing_order_.pop_front();
  }
}

void MapstoreService::Resend(Outgoing& out, const cairn::lcmt_tile_resend_request* request) {
  // A null request sends the whole payload: every layer's manifest and tiles, then the OctoMap.
  std::lock_guard<std::mutex> sending(out.sending);
  // Compressed tiles travel several to a message, up to batch_bytes, with a pause after each
  // message; float tiles (resends) travel singly, in bursts of tiles_per_burst.
  auto pause = [&] { PacingPause(params_.burst_pause_ms); };
  cairn::lcmt_grid_tile_batch pending{};
  int64_t pending_bytes = 0;
  auto flush = [&] {
    if (pending.tiles.empty()) return;
    pending.utime = node_.NowUtime();
    pending.map_name = out.map_name;
    pending.num_tiles = static_cast<int32_t>(pending.tiles.size());
    node_.Publish(channels::kMapstoreTileBatches, pending);
    node_.Count("tiles_sent", pending.num_tiles);
    pending.tiles.clear();
    pending_bytes = 0;
    pause();
  };
  int burst_tiles = 0;
  auto publish_batch = [&](const runtime::LayerTiler::Batch& batch) {
    node_.Publish(channels::kMapstoreManifest, batch.manifest);
    for (const auto& tile : batch.tiles) {
      if (tile.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32 && params_.batch_bytes > 0) {
        const int64_t bytes = TilePayloadBytes(tile);
        if (!pending.tiles.empty() && pending_bytes + bytes > params_.batch_bytes) flush();
        pending.tiles.push_back(tile);
        pending_bytes += bytes;
        continue;
      }
      flush();
      if (!PublishTile(node_.lcm(), channels::kMapstoreTiles, tile)) {
        node_.Warn("publish_tiles", "could not publish reply tiles");
      }
      node_.Count("tiles_sent");
      if (++burst_tiles >= params_.tiles_per_burst) {
        pause();
        burst_tiles = 0;
      }
    }
    flush();
  };
  if (request == nullptr && !out.first_send.empty()) {
    // The first send of a reply: the batches made when the payload was tiled.
    for (const auto& batch : out.first_send) publish_batch(batch);
    out.first_send.clear();
  } else if (out.tiler) {
    if (request != nullptr) {
      if (request->layer == kResendOctomap) {
        // handled below
      } else {
        publish_batch(out.tiler->Resend(*request));
      }
    } else {
      for (const std::string& layer : out.layers) {
        cairn::lcmt_tile_resend_request all{};
        all.layer = layer;
        all.num_tiles = 0;
        publish_batch(out.tiler->Resend(all));
      }
    }
  }
  if (out.octomap && (request == nullptr || request->layer == kResendOctomap)) {
    for (const auto& chunk :
         OctomapChunksOf(*out.octomap, out.robot, out.map_name, node_.NowUtime())) {
      node_.Publish(channels::kMapstoreOctomap, chunk);
    }
  }
}

void MapstoreService::OnResend(const cairn::lcmt_tile_resend_request& request) {
  std::shared_ptr<Outgoing> payload;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = outgoing_.find(request.map_name);
    if (it == outgoing_.end()) return;  // not ours, or forgotten
    payload = it->second;
  }
  node_.Count("tile_resend_requests");
  Resend(*payload, &request);
}

bool MapstoreService::StartSave(const Request& request, Reply* reply) {
  const std::string site = request.site.empty() ? kDefaultSite : request.site;
  Status s = ValidateName("site name", site);
  if (s.ok()) s = ValidateName("map name", request.map_name);
  if (s.ok() && !request.robot.empty()) s = ValidateName("robot name", request.robot);
  if (s.ok() && (request.num_layers < 0 ||
                 request.layers.size() != static_cast<size_t>(request.num_layers))) {
    s = common::InvalidArgumentError("layers disagree with num_layers");
  }
  for (const std::string& layer : request.layers) {
    if (s.ok()) s = ValidateLayerName(layer);
  }
  if (s.ok() && request.robot.empty() && request.layers.empty()) {
    s = common::InvalidArgumentError("a pushed save must name its layers");
  }
  if (!s.ok()) {
    SetStatus(s, reply);
    return true;
  }
  // A save replayed after a restart: the audit log knows the version it made.
  if (!request.requester.empty()) {
    auto earlier = store_.FindRequest(request.requester, request.request_id);
    if (earlier.ok() && earlier->has_value() && (*earlier)->op == "save" &&
        (*earlier)->map == request.map_name) {
      reply->version = (*earlier)->version;
      reply->message = "already saved as version " + std::to_string((*earlier)->version);
      return true;
    }
  }
  auto save = std::make_unique<PendingSave>();
  save->request = request;
  save->request.site = site;
  save->key = RequestKey(request);
  save->pull = !request.robot.empty();
  save->map_name = std::to_string(request.request_id) + "/" + request.map_name;
  if (save->pull) {
    EnsureMirror(request.robot);
    cairn::lcmt_map_control_request control{};
    control.utime = node_.NowUtime();
    control.request_id = request.request_id;
    control.requester = kActor;
    control.op = cairn::lcmt_map_control_request::OP_PUBLISH_ALL;
    control.has_profile = false;
    node_.Publish(channels::ForRobot(request.robot, channels::kMapControl), control);
    save->next_resend = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(params_.pull_settle_s));
  }
  PendingSave& pending = *save;
  pending_[save->key] = std::move(save);
  TryFinishSave(pending, false);  // replies now when everything already arrived
  return false;
}

bool MapstoreService::TryFinishSave(PendingSave& save, bool timed_out) {
  const Request& request = save.request;
  Reply reply{};
  reply.utime = node_.NowUtime();
  reply.request_id = request.request_id;
  reply.op = request.op;
  reply.status = Reply::STATUS_OK;
  reply.site = request.site;
  reply.map_name = request.map_name;
  reply.version = 0;
  reply.num_tiles = 0;

  // What must be there, and what is missing.
  runtime::LayerAssembler* assembler = nullptr;
  Staging* push_staging = nullptr;  // a push: its compressed tiles go to the store as they are
  std::vector<std::string> wanted(request.layers.begin(), request.layers.end());
  std::vector<std::string> missing;
  std::optional<common::ObstacleRegistry> obstacles;
  std::optional<OctomapData> octomap;
  std::string push_robot;
  std::vector<cairn::lcmt_tile_resend_request> resends;
  const int64_t utime = node_.NowUtime();
  if (save.pull) {
    LiveMirror& mirror = *mirrors_.at(request.robot);
    assembler = &mirror.assembler;
    if (wanted.empty()) {
      // Every robot-agnostic layer announced since the request; wait until none is new.
      for (const auto& [layer, when] : mirror.manifest_time) {
        if (!IsDerivedLayer(layer)) wanted.push_back(layer);
      }
      if (SecondsSince(save.started) < params_.pull_settle_s) return false;
    }
    if (wanted.empty())
      missing.push_back("any layer (is the mapper of '" + request.robot + "' running?)");
    for (const std::string& layer : wanted) {
      auto it = mirror.manifest_time.find(layer);
      const bool fresh = it != mirror.manifest_time.end() && it->second >= save.started;
      if (fresh && assembler->Complete(layer)) continue;
      missing.push_back(layer);
      std::optional<cairn::lcmt_tile_resend_request> r;
      if (fresh) r = assembler->MakeResendRequest(layer, kActor, utime);
      if (!r) {
        // No current manifest: ask for the whole layer (its manifest comes with it).
        cairn::lcmt_tile_resend_request all{};
        all.utime = utime;
        all.requester = kActor;
        all.layer = layer;
        r = all;
      }
      // Mappers answer requests naming their robot and map.
      r->robot = request.robot;
      r->map_name = mirror.map_name;
      resends.push_back(*r);
    }
    // Obstacles published after the request, or (a mapper without any) none after a while.
    const bool obstacles_fresh = mirror.obstacles && mirror.obstacles_time >= save.started;
    if (!obstacles_fresh && SecondsSince(save.started) < 4 * params_.pull_settle_s) {
      missing.push_back("obstacles");
    }
    if (mirror.obstacles) obstacles = mirror.obstacles;
    octomap = mirror.complete_octomap;
  } else {
    auto it = staging_.find(save.map_name);
    if (it == staging_.end()) {
      for (const auto& layer : wanted) missing.push_back(layer);
      if (request.expect_obstacles) missing.push_back(kResendObstacles);
      if (request.expect_octomap) missing.push_back(kResendOctomap);
    } else {
      Staging& staging = *it->second;
      if (!staging.invalid.empty()) {
        SetStatus(common::InvalidArgumentError(staging.invalid), &reply);
        staging_.erase(it);
        const Request done_request = request;
        const Clock::time_point started = save.started;
        pending_.erase(save.key);
        Finish(done_request, std::move(reply), started);
        return true;
      }
      assembler = &staging.assembler;
      push_staging = &staging;
      push_robot = staging.robot;
      for (const std::string& layer : wanted) {
        if (!staging.manifests.count(layer) || !assembler->Complete(layer))
          missing.push_back(layer);
      }
      obstacles = staging.obstacles;
      octomap = staging.octomap.Complete();
      if (request.expect_obstacles && !obstacles) missing.push_back(kResendObstacles);
      if (request.expect_octomap && !octomap) missing.push_back(kResendOctomap);
    }
    for (const std::string& layer : missing) {
      std::optional<cairn::lcmt_tile_resend_request> r;
      if (assembler != nullptr && it != staging_.end() && it->second->manifests.count(layer)) {
        r = assembler->MakeResendRequest(layer, kActor, utime);
      }
      if (!r) {
        cairn::lcmt_tile_resend_request all{};
        all.utime = utime;
        all.requester = kActor;
        all.layer = layer;
        all.layer_version = 0;
        all.num_tiles = 0;
        r = all;
      }
      r->map_name = save.map_name;
      resends.push_back(*r);
    }
  }

  if (!missing.empty()) {
    if (timed_out) {
      std::string list;
      for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
      SetStatus(common::UnavailableError("timed out after " +
                                         std::to_string(static_cast<int>(params_.save_timeout_s)) +
                                         " s waiting for: " + list),
                &reply);
      node_.Count("save_timeouts");
    } else {
      if (Clock::now() >= save.next_resend) {
        const std::string channel =
            save.pull ? channels::ForRobot(request.robot, channels::kMapTileResend)
                      : std::string(channels::kMapstorePushTileResend);
        for (const auto& r : resends) node_.Publish(channel, r);
        if (!resends.empty()) ++save.resend_rounds;
        save.next_resend =
            Clock::now() + std::chrono::duration_cast<Clock::duration>(
                               std::chrono::duration<double>(params_.resend_interval_s));
      }
      return false;
    }
  } else {
    // Everything is here: store it. A map holds layers of one grid; layers of another grid
    // (a mapper's finer 2-D occupancy) become companion maps "<map>-<first layer>".
    const double waited_ms = SecondsSince(save.started) * 1e3;
    std::vector<std::vector<std::string>> groups;
    std::vector<common::GridGeometry> group_geometry;
    for (const std::string& layer : wanted) {
      const std::optional<common::GridGeometry> geometry = assembler->Geometry(layer);
      if (!geometry) continue;
      size_t g = 0;
      while (g < groups.size() && group_geometry[g] != *geometry) ++g;
      if (g == groups.size()) {
        groups.emplace_back();
        group_geometry.push_back(*geometry);
      }
      groups[g].push_back(layer);
    }
    // The group holding the elevation is the map itself.
    for (size_t g = 1; g < groups.size(); ++g) {
      if (std::find(groups[g].begin(), groups[g].end(), layers::kElevation) != groups[g].end()) {
        std::swap(groups[0], groups[g]);
      }
    }
    const WriteContext ctx{request.requester.empty() ? "unknown" : request.requester,
                           request.request_id, 0};
    std::string companions;
    Status failed;
    for (size_t g = 0; g < groups.size() && failed.ok(); ++g) {
      // A pushed save's compressed tiles are kept as they came when they are the tiles the
      // assembler holds (same CRC, checked when each was decoded on receipt).
      std::vector<StoredLayer> encoded_layers;
      if (push_staging != nullptr) {
        for (const std::string& layer : groups[g]) {
          auto e = push_staging->encoded.find(layer);
          if (e == push_staging->encoded.end() || e->second.tiles.empty()) continue;
          StoredLayer stored;
          stored.name = layer;
          stored.tile_size = e->second.tile_size;
          for (auto& [key, t] : e->second.tiles) {
            if (assembler->HeldChecksum(layer, key.first, key.second) == t.raw_crc32) {
              stored.tiles.push_back(std::move(t));
            }
          }
          e->second.tiles.clear();
          encoded_layers.push_back(std::move(stored));
        }
      }
      // A push's staging goes once this save ends: its layers move out of it.
      auto base = CollectLayers(assembler, groups[g], /*take=*/push_staging != nullptr);
      if (!base.ok()) {
        failed = base.status();
        break;
      }
      MapSnapshot snapshot;
      snapshot.site = request.site;
      snapshot.name = request.map_name;
      if (g > 0) {
        std::string suffix = groups[g].front();
        std::replace(suffix.begin(), suffix.end(), '/', '_');
        snapshot.name = request.map_name + "-" + suffix;
      }
      snapshot.base = std::move(base).value();
      snapshot.encoded_layers = std::move(encoded_layers);
      snapshot.encoded_layers_checked = push_staging != nullptr;
      snapshot.provenance.source_robot =
          save.pull ? request.robot : (push_robot.empty() ? request.requester : push_robot);
      snapshot.provenance.source_profile = request.profile;
      snapshot.provenance.code_version = request.code_version;
      snapshot.provenance.parameters = request.parameters;
      if (!request.profile.empty()) {
        auto p = store_.GetProfile(request.profile);
        if (p.ok()) snapshot.provenance.source_profile_hash = p->content_hash;
      }
      if (ValidateName("robot", snapshot.provenance.source_robot).code() !=
          common::StatusCode::kOk) {
        snapshot.provenance.source_robot.clear();
      }
      if (g == 0 && obstacles) snapshot.obstacles = *obstacles;
      if (g == 0 && octomap) snapshot.octomap = *octomap;
      const auto t0 = Clock::now();
      // Companion maps are not request replays: only the main save carries the request id.
      auto info = store_.SaveMap(snapshot, g == 0 ? ctx : WriteContext{ctx.actor, 0, 0});
      if (!info.ok()) {
        failed = info.status();
        break;
      }
      node_.Count("saves");
      node_.Event(
          "saved %s/%s v%lld from %s (%zu layers, %zu obstacles%s): waited %.0f ms "
          "for data (%d resend rounds), stored in %.0f ms",
          request.site.c_str(), snapshot.name.c_str(), static_cast<long long>(info->version),
          save.pull ? ("mapper of " + request.robot).c_str() : "a push", info->layers.size(),
          snapshot.obstacles.obstacles.size(), snapshot.octomap ? ", octomap" : "", waited_ms,
          save.resend_rounds, SecondsSince(t0) * 1e3);
      if (g == 0) {
        reply.version = info->version;
        reply.layers = info->layers;
      } else {
        companions += (companions.empty() ? "" : ", ") + snapshot.name + " v" +
                      std::to_string(info->version) + " (" + std::to_string(info->layers.size()) +
                      " layers of another grid)";
      }
      reply.maps.push_back(ToLcm(*info));
    }
    if (!failed.ok()) {
      SetStatus(failed, &reply);
    } else if (groups.empty()) {
      SetStatus(common::InternalError("no layer to save"), &reply);
    } else {
      reply.message = "saved version " + std::to_string(reply.version) +
                      (companions.empty() ? "" : "; also " + companions);
    }
  }
  if (!save.pull) staging_.erase(save.map_name);
  const Request done_request = request;
  const Clock::time_point started = save.started;
  pending_.erase(save.key);  // `save` is gone from here on
  Finish(done_request, std::move(reply), started);
  return true;
}

void MapstoreService::OnPushed(const std::string& map_name) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [key, save] : pending_) {
    if (save->pull || save->map_name != map_name) continue;
    const std::string pending_key = key;  // TryFinishSave may erase the entry
    try {
      TryFinishSave(*save, false);
    } catch (const std::exception& e) {
      node_.Warn("save", std::string("save failed: ") + e.what());
      pending_.erase(pending_key);
    }
    return;
  }
}

void MapstoreService::Poll() {
  std::lock_guard<std::mutex> lock(mutex_);
  // Pending saves: finish, ask again, or give up.
  std::vector<std::string> keys;
  for (const auto& [key, save] : pending_) keys.push_back(key);
  for (const std::string& key : keys) {
    auto it = pending_.find(key);
    if (it == pending_.end()) continue;
    const bool timed_out = SecondsSince(it->second->started) > params_.save_timeout_s;
    try {
      TryFinishSave(*it->second, timed_out);
    } catch (const std::exception& e) {
      node_.Warn("save", std::string("save failed: ") + e.what());
      pending_.erase(key);
    }
  }
  // Pushed data nobody asked to save.
  for (auto it = staging_.begin(); it != staging_.end();) {
    bool wanted = false;
    for (const auto& [key, save] : pending_) wanted |= save->map_name == it->first;
    if (!wanted && SecondsSince(it->second->last) > params_.staging_timeout_s) {
      node_.CountDropped("abandoned_pushes");
      it = staging_.erase(it);
    } else {
      ++it;
    }
  }
}

namespace {

// Total cells held by staging areas.
template <typename Map>
int64_t StagedCells(const Map& staging) {
  int64_t total = 0;
  for (const auto& [name, s] : staging) total += s->cells;
  return total;
}

}  // namespace

void MapstoreService::OnPushTile(const cairn::lcmt_grid_tile& pushed) {
  // A compressed tile is decoded (and checked by zstd) before the lock is taken.
  std::vector<float> cells;
  if (pushed.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32 &&
      !DecodeTileCells(pushed, &cells).ok()) {
    node_.CountDropped("bad_push_tiles");
    return;
  }
  StagePushTile(pushed, std::move(cells));
}

void MapstoreService::OnPushTileBatch(const cairn::lcmt_grid_tile_batch& batch) {
  if (batch.num_tiles < 0 || static_cast<size_t>(batch.num_tiles) != batch.tiles.size()) {
    node_.CountDropped("bad_push_tiles");
    return;
  }
  std::vector<std::vector<float>> cells;
  std::vector<char> ok;
  DecodeTiles(batch.tiles, batch.map_name, params_.decode_threads, &cells, &ok);
  for (size_t i = 0; i < batch.tiles.size(); ++i) {
    if (ok[i]) {
      StagePushTile(batch.tiles[i], std::move(cells[i]));
    } else {
      node_.CountDropped("bad_push_tiles");
    }
  }
}

void MapstoreService::StagePushTile(const cairn::lcmt_grid_tile& pushed, std::vector<float> cells) {
  const bool compressed = pushed.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32;
  const int64_t num_cells = static_cast<int64_t>(compressed ? cells.size() : pushed.data.size());
  std::lock_guard<std::mutex> lock(mutex_);
  if (pushed.map_name.find('/') == std::string::npos) {
    node_.CountDropped("bad_push_tiles");
    return;
  }
  auto it = staging_.find(pushed.map_name);
  if (it == staging_.end()) {
    if (StagedCells(staging_) + num_cells > params_.max_staged_cells) {
      node_.CountDropped("staging_full");
      node_.Warn("staging_full", "pushed tiles dropped: too much staged data");
      return;
    }
    it = staging_.emplace(pushed.map_name, std::make_unique<Staging>()).first;
  }
  Staging& staging = *it->second;
  // The store compares a kept blob's declared CRC with the cells it saves (SaveMap).
  const bool held = compressed ? staging.assembler.OnDecodedTile(pushed, std::move(cells))
                               : staging.assembler.OnTile(pushed);
  if (!held) {
    node_.CountDropped("bad_push_tiles");
    return;
  }
  Staging::EncodedLayer& encoded = staging.encoded[pushed.layer];
  const std::pair<int, int> key{pushed.tile_ix, pushed.tile_iy};
  const std::optional<Codec> codec = CodecOfEncoding(pushed.encoding);
  if (codec && (encoded.tiles.empty() || encoded.tile_size == pushed.tile_size)) {
    encoded.tile_size = pushed.tile_size;
    encoded.tiles[key] = StoredTile{pushed.tile_ix,
                                    pushed.tile_iy,
                                    pushed.cells_x,
                                    pushed.cells_y,
                                    static_cast<int>(*codec),
                                    static_cast<uint32_t>(pushed.checksum),
                                    std::string(pushed.bytes.begin(), pushed.bytes.end()),
                                    /*stored_crc32=*/std::nullopt};
  } else {
    encoded.tiles.erase(key);  // a newer copy came as floats: it is compressed when stored
  }
  staging.robot = pushed.robot;
  staging.cells += num_cells;
  staging.last = Clock::now();
}

void MapstoreService::OnPushManifest(const cairn::lcmt_grid_manifest& manifest) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (manifest.map_name.find('/') == std::string::npos || manifest.num_tiles < 0 ||
      manifest.tile_ix.size() != static_cast<size_t>(manifest.num_tiles) ||
      manifest.tile_iy.size() != static_cast<size_t>(manifest.num_tiles) ||
      manifest.checksum.size() != static_cast<size_t>(manifest.num_tiles) ||
      manifest.tile_version.size() != static_cast<size_t>(manifest.num_tiles)) {
    node_.CountDropped("bad_push_manifests");
    return;
  }
  auto& staging = staging_[manifest.map_name];
  if (!staging) staging = std::make_unique<Staging>();
  staging->assembler.OnManifest(manifest);
  staging->manifests.insert(manifest.layer);
  staging->last = Clock::now();
}

void MapstoreService::OnPushObstacles(const cairn::lcmt_obstacle_registry& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (msg.map_name.find('/') == std::string::npos) {
    node_.CountDropped("bad_push_obstacles");
    return;
  }
  auto& staging = staging_[msg.map_name];
  if (!staging) staging = std::make_unique<Staging>();
  auto registry = runtime::FromLcm(msg);
  if (!registry.ok()) {
    node_.CountDropped("bad_push_obstacles");
    staging->invalid = "pushed obstacles: " + registry.status().message();
    return;
  }
  staging->obstacles = std::move(registry).value();
  staging->last = Clock::now();
}

void MapstoreService::OnPushOctomap(const cairn::lcmt_octomap& chunk) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (chunk.map_name.find('/') == std::string::npos) {
    node_.CountDropped("bad_push_octomap");
    return;
  }
  auto& staging = staging_[chunk.map_name];
  if (!staging) staging = std::make_unique<Staging>();
  if (!staging->octomap.Add(chunk)) node_.CountDropped("bad_push_octomap");
  staging->last = Clock::now();
}

void MapstoreService::EnsureMirror(const std::string& robot) {
  if (mirrors_.count(robot)) return;
  auto mirror = std::make_unique<LiveMirror>();
  LiveMirror* m = mirror.get();
  mirrors_[robot] = std::move(mirror);
  node_.Subscribe<cairn::lcmt_grid_tile>(channels::ForRobot(robot, channels::kMapTiles),
                                         [this, m](const cairn::lcmt_grid_tile& t) {
                                           if (!m->assembler.OnTile(t))
                                             node_.CountDropped("bad_mapper_tiles");
                                         });
  node_.Subscribe<cairn::lcmt_occupancy_tile>(channels::ForRobot(robot, channels::kMapOccupancy),
                                              [this, m](const cairn::lcmt_occupancy_tile& t) {
                                                if (!m->assembler.OnTile(t))
                                                  node_.CountDropped("bad_mapper_tiles");
                                              });
  node_.Subscribe<cairn::lcmt_grid_manifest>(channels::ForRobot(robot, channels::kMapManifest),
                                             [m](const cairn::lcmt_grid_manifest& g) {
                                               m->assembler.OnManifest(g);
                                               m->manifest_time[g.layer] = Clock::now();
                                               if (!g.map_name.empty()) m->map_name = g.map_name;
                                             });
  node_.Subscribe<cairn::lcmt_obstacle_registry>(channels::ForRobot(robot, channels::kMapObstacles),
                                                 [this, m](const cairn::lcmt_obstacle_registry& r) {
                                                   auto registry = runtime::FromLcm(r);
                                                   if (registry.ok()) {
                                                     m->obstacles = std::move(registry).value();
                                                     m->obstacles_time = Clock::now();
                                                   } else {
                                                     node_.CountDropped("bad_mapper_obstacles");
                                                   }
                                                 });
  node_.Subscribe<cairn::lcmt_octomap>(channels::ForRobot(robot, channels::kMapOctomap),
                                       [this, m](const cairn::lcmt_octomap& c) {
                                         if (!m->octomap.Add(c)) {
                                           node_.CountDropped("bad_mapper_octomap");
                                           return;
                                         }
                                         if (auto whole = m->octomap.Complete())
                                           m->complete_octomap = std::move(whole);
                                       });
  node_.Event("following the live map of %s for pull saves", robot.c_str());
}

}  // namespace cairn::mapstore
