#include "mapstore/lcm/mapstore_service.h"

#include <algorithm>
#include <stdexcept>

#include "common/channels.h"
#include "mapstore/lcm/mapstore_conversions.h"
#include "services/runtime/conversions.h"

namespace cairn::mapstore {

using common::Status;
using Reply = cairn::lcmt_mapstore_reply;
using Request = cairn::lcmt_mapstore_request;

namespace {

ReplyPayloadParams PayloadParamsOf(const MapstoreServiceParams& p) {
  ReplyPayloadParams out;
  out.tile_size = p.reply_tile_size;
  out.compress_tiles = p.compress_reply_tiles;
  out.compress_threads = p.worker_threads;
  out.batch_bytes = p.batch_bytes;
  out.tiles_per_burst = p.tiles_per_burst;
  out.burst_pause_ms = p.burst_pause_ms;
  out.max_kept_cells = p.max_kept_reply_cells;
  return out;
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
    case common::StatusCode::kPermissionDenied:
      return Reply::STATUS_FORBIDDEN;
    default:
      return Reply::STATUS_ERROR;
  }
}

MapstoreService::MapstoreService(runtime::Node& node, MapStore& store, ProfileDeriver deriver,
                                 MapstoreServiceParams params)
    : node_(node),
      store_(store),
      deriver_(std::move(deriver)),
      params_(std::move(params)),
      payloads_(node, PayloadParamsOf(params_)),
      saves_(store, params_.save()),
      resend_limits_(params_.resend_limits) {
  params_.Validate();
  // A mapper caches its control replies by request id: ids unique across restarts.
  saves_.set_publish_all_id_base(runtime::Node::WallUtime());
  node_.Subscribe<Request>(channels::kMapstoreRequest, [this](const Request& r) { OnRequest(r); });
  node_.Subscribe<cairn::lcmt_tile_resend_request>(
      channels::kMapstoreTileResend,
      [this](const cairn::lcmt_tile_resend_request& r) { OnResend(r); });
  SubscribeSaves();
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
  return saves_.pending_saves();
}

int64_t MapstoreService::running_jobs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int64_t>(busy_keys_.size());
}

double MapstoreService::SecondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
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
    auto payload = payloads_.Find(std::to_string(request.request_id) + "/" + request.map_name);
    lock.unlock();
    if (payload) payloads_.Send(*payload, nullptr);
    return;
  }
  if (saves_.IsPending(key) || busy_keys_.count(key)) return;  // still working on it

  const auto started = Clock::now();
  Reply reply{};
  reply.utime = node_.NowUtime();
  reply.request_id = request.request_id;
  reply.op = request.op;
  reply.status = Reply::STATUS_OK;
  reply.site = SiteOf(request);
  reply.map_name = request.map_name;
  reply.version = request.version;
  reply.num_maps = reply.num_profiles = reply.num_places = reply.num_obstacles = 0;
  reply.num_tiles = reply.num_layers = 0;
  reply.duration_us = 0;
  bool done = true;
  try {
    if (request.op == Request::OP_SAVE) {
      StartSave(request, &reply, started);
      done = false;  // StartSave replies itself, now or later
    } else {
      done = Handle(request, &reply);
    }
  } catch (const std::exception& e) {
    SetStatus(common::InternalError(std::string("internal error: ") + e.what()), &reply);
    done = true;
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
  switch (request.op) {
    case Request::OP_LOAD:
    case Request::OP_SHARE:
    case Request::OP_EXPORT:
    case Request::OP_IMPORT:
    case Request::OP_LOAD_OBSTACLES:
      return QueueJob(request, reply);
    case Request::OP_LIST_MAPS:
    case Request::OP_LIST_PROFILES:
    case Request::OP_LIST_PLACES:
      HandleList(request, reply);
      return true;
    case Request::OP_PUT_PROFILE:
      HandlePutProfile(request, reply);
      return true;
    case Request::OP_GET_PROFILE: {
      auto profile = store_.GetProfile(request.profile);
      if (!profile.ok()) {
        SetStatus(profile.status(), reply);
      } else {
        reply->profiles.push_back(runtime::ToLcm(profile->profile));
      }
      return true;
    }
    case Request::OP_DELETE:
      HandleDelete(request, reply);
      return true;
    case Request::OP_PUT_PLACE:
      HandlePutPlaces(request, reply);
      return true;
    default:
      SetStatus(common::InvalidArgumentError("unknown op " + std::to_string(request.op)), reply);
      return true;
  }
}

bool MapstoreService::QueueJob(const Request& request, Reply* reply) {
  if (request.num_layers < 0 || request.layers.size() != static_cast<size_t>(request.num_layers)) {
    SetStatus(common::InvalidArgumentError("layers disagree with num_layers"), reply);
    return true;
  }
  if (static_cast<int>(queue_.size()) >= params_.max_queued_jobs) {
    node_.CountDropped("queue_full");
    node_.Warn("queue_full", "request refused: " + std::to_string(queue_.size()) +
                                 " loads, shares, exports and imports already wait");
    SetStatus(common::UnavailableError("the store is busy: " + std::to_string(queue_.size()) +
                                       " requests wait (service.max_queued_jobs); ask again later"),
              reply);
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

void MapstoreService::HandleList(const Request& request, Reply* reply) {
  if (request.op == Request::OP_LIST_MAPS) {
    MapFilter filter;
    filter.site = request.site;
    filter.name = request.map_name;
    filter.all_versions = !request.map_name.empty();
    auto maps = store_.ListMaps(filter);
    if (!maps.ok()) return SetStatus(maps.status(), reply);
    for (const MapInfo& info : *maps) reply->maps.push_back(ToLcm(info));
    reply->message = std::to_string(maps->size()) + " maps";
  } else if (request.op == Request::OP_LIST_PROFILES) {
    auto profiles = store_.ListProfiles();
    if (!profiles.ok()) return SetStatus(profiles.status(), reply);
    for (const StoredProfile& p : *profiles) reply->profiles.push_back(runtime::ToLcm(p.profile));
    reply->message = std::to_string(profiles->size()) + " profiles";
  } else {
    auto places = store_.ListPlaces(SiteOf(request));
    if (!places.ok()) return SetStatus(places.status(), reply);
    for (const Place& p : *places) reply->places.push_back(ToLcm(p));
    reply->message = std::to_string(places->size()) + " places";
  }
}

void MapstoreService::HandlePutProfile(const Request& request, Reply* reply) {
  if (!request.has_profile) {
    return SetStatus(common::InvalidArgumentError("OP_PUT_PROFILE without profile_data"), reply);
  }
  auto profile = runtime::FromLcm(request.profile_data);
  if (!profile.ok()) {
    return SetStatus(common::InvalidArgumentError(profile.status().message()), reply);
  }
  const WriteContext ctx = ContextOf(request);
  const Status s = store_.PutProfile(*profile, ctx);
  SetStatus(s, reply);
  if (!s.ok()) return;
  reply->message = "profile '" + profile->name + "' stored (" + profile->ContentHash() + ")";
  reply->profiles.push_back(runtime::ToLcm(*profile));
  node_.Event("stored profile %s (%s) for %s", profile->name.c_str(),
              profile->ContentHash().c_str(), ctx.actor.c_str());
}

void MapstoreService::HandleDelete(const Request& request, Reply* reply) {
  const std::string site = SiteOf(request);
  const WriteContext ctx = ContextOf(request);
  const std::string what = site + "/" + request.map_name +
                           (request.version == 0 ? "" : " v" + std::to_string(request.version));
  if (!params_.allow_delete) {
    // The audit line of a refused destructive request.
    node_.Event("refused OP_DELETE of %s for %s (request %lld): allow_delete is off", what.c_str(),
                ctx.actor.c_str(), static_cast<long long>(request.request_id));
    node_.CountDropped("forbidden_requests");
    return SetStatus(common::PermissionDeniedError(
                         "OP_DELETE is off in this store's configuration (service.allow_delete)"),
                     reply);
  }
  const Status s = store_.DeleteMap({site, request.map_name, request.version}, ctx);
  SetStatus(s, reply);
  if (!s.ok()) return;
  reply->message = request.version == 0 ? "map deleted" : "version deleted";
  node_.Event("deleted %s/%s%s for %s", site.c_str(), request.map_name.c_str(),
              request.version == 0 ? "" : (" v" + std::to_string(request.version)).c_str(),
              ctx.actor.c_str());
}

void MapstoreService::HandlePutPlaces(const Request& request, Reply* reply) {
  if (request.num_places <= 0 || request.places.size() != static_cast<size_t>(request.num_places)) {
    return SetStatus(common::InvalidArgumentError("OP_PUT_PLACE needs places (num_places > 0)"),
                     reply);
  }
  std::vector<Place> places;
  for (const auto& m : request.places) {
    auto p = FromLcm(m);
    if (!p.ok()) return SetStatus(p.status(), reply);
    places.push_back(std::move(p).value());
  }
  const Status s = store_.PutPlaces(SiteOf(request), places, ContextOf(request));
  SetStatus(s, reply);
  if (s.ok()) reply->message = std::to_string(places.size()) + " places stored";
}

void MapstoreService::OnResend(const cairn::lcmt_tile_resend_request& request) {
  std::shared_ptr<ReplyPayloads::Payload> payload = payloads_.Find(request.map_name);
  if (!payload) return;  // not ours, or forgotten
  const double tiles = request.num_tiles > 0 ? request.num_tiles : 200.0;
  if (!resend_limits_.Allow(request.requester, tiles, runtime::Node::SteadyUtime() * 1e-6)) {
    node_.CountDropped("resend_rate_limited");
    node_.Warn("resend_rate", "dropped a resend request of '" + request.requester +
                                  "': beyond the resend rate (service.resend_tiles_per_s)");
    return;
  }
  node_.Count("tile_resend_requests");
  payloads_.Send(*payload, &request);
}

}  // namespace cairn::mapstore
