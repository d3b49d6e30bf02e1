// MapstoreService's worker jobs: loads, shares, obstacle loads, exports and imports run on
// worker threads (a long derivation never stalls other requests); the core answers, these turn
// the answers into replies and payloads.

#include <cstdio>

#include "mapstore/io/files.h"
#include "mapstore/lcm/mapstore_conversions.h"
#include "mapstore/lcm/mapstore_service.h"
#include "mapstore/load_answers.h"
#include "mapstore/map_operations.h"
#include "mapstore/map_transfer.h"
#include "services/runtime/conversions.h"

namespace cairn::mapstore {

using Reply = cairn::lcmt_mapstore_reply;
using Request = cairn::lcmt_mapstore_request;

namespace {

// Obstacles into a reply, at most `max` (a bus message stays under its size limit).
void AddObstacles(const std::vector<common::Obstacle>& obstacles, int max, Reply* reply) {
  for (const auto& o : obstacles) {
    if (static_cast<int>(reply->obstacles.size()) >= max) break;
    reply->obstacles.push_back(runtime::ToLcm(o));
  }
}

}  // namespace

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
    RunQueued(*job);
  }
}

void MapstoreService::RunQueued(Job& job) {
  // The work and the tiling of the payload run without the lock ...
  const auto work_started = Clock::now();
  JobResult result = RunJob(job.request, job.reply);
  const double work_ms = SecondsSince(work_started) * 1e3;
  Reply reply = std::move(result.reply);
  std::shared_ptr<ReplyPayloads::Payload> payload;
  if (result.status.ok() && !result.payload.empty()) {
    try {
      payload = payloads_.Make(std::to_string(job.request.request_id) + "/" + job.request.map_name,
                               result.payload);
      reply.num_tiles += payload->num_tiles;
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
    if (payload) payloads_.Keep(payload);
    CacheReply(job.request, &reply, job.started);
    busy_keys_.erase(RequestKey(job.request));
  }
  // ... and the sending after it: the reply, then the payload it announces.
  Publish(reply);
  const auto send_started = Clock::now();
  if (payload) payloads_.Send(*payload, nullptr);
  if (result.status.ok() && payload && payload->cells > 0) {
    // Where a load's time goes, one line per load.
    node_.Event(
        "%s '%s' v%lld: %d tiles%s, %.1f MB; read %.0f ms, tiled %.0f ms, compressed %.0f ms, "
        "sent %.0f ms",
        result.counter == "loads" ? "load of" : "reply with", job.request.map_name.c_str(),
        static_cast<long long>(reply.version), reply.num_tiles,
        payload->as_stored ? " as stored" : "", payload->bytes / 1e6, work_ms, payload->tile_ms,
        payload->compress_ms, SecondsSince(send_started) * 1e3);
  }
  if (result.status.ok() && !result.event.empty()) node_.Event("%s", result.event.c_str());
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
  out->counter = "loads";
  LoadRequest load;
  load.ref = RefOf(request);
  load.profile = request.profile;
  load.layers = request.layers;
  load.may_send_stored = params_.compress_reply_tiles;
  load.tile_size = params_.reply_tile_size;
  auto answer = AnswerLoad(store_, deriver_, load);
  if (!answer.ok()) {
    out->status = answer.status();
    return;
  }
  Reply* reply = &out->reply;
  const MapInfo& info = answer->view.info;
  reply->version = info.version;
  reply->maps.push_back(ToLcm(info));
  reply->layers = answer->layer_names();
  reply->message = answer->Summary(!request.profile.empty());
  AddObstacles(answer->view.obstacles.obstacles, params_.max_reply_obstacles, reply);
  out->payload.robot = info.provenance.source_robot;
  out->payload.octomap = std::move(answer->octomap);
  if (answer->stored) {
    out->payload.stored_layers = std::move(answer->stored_layers);
    out->payload.stored_geometry = info.geometry;
  } else if (!answer->only_octomap) {
    out->payload.layers = std::move(answer->view.layers);
  }
}

void MapstoreService::JobShare(const Request& request, JobResult* out) const {
  Reply* reply = &out->reply;
  if (!deriver_.valid()) {
    out->status = common::UnavailableError("this store cannot derive profile layers");
    return;
  }
  const auto t0 = Clock::now();
  auto shared = ShareMap(store_, deriver_, RefOf(request), request.profile, ContextOf(request));
  if (!shared.ok()) {
    out->status = shared.status();
    return;
  }
  reply->version = shared->info.version;
  reply->maps.push_back(ToLcm(shared->info));
  reply->layers = shared->derived.layers.layer_names();
  AddObstacles(shared->changed, params_.max_reply_obstacles, reply);
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%zu obstacles change verdict from %s to %s; layers %s",
                shared->changed.size(),
                shared->source_profile.empty() ? "(unknown)" : shared->source_profile.c_str(),
                request.profile.c_str(), shared->was_cached ? "from the cache" : "derived");
  reply->message = buf;
  if (!shared->was_cached) {
    std::snprintf(buf, sizeof(buf),
                  "shared %s/%s v%lld with %s: derived in %.0f ms, %zu verdicts differ",
                  shared->info.site.c_str(), request.map_name.c_str(),
                  static_cast<long long>(shared->info.version), request.profile.c_str(),
                  SecondsSince(t0) * 1e3, shared->changed.size());
    out->event = buf;
  }
}

void MapstoreService::JobLoadObstacles(const Request& request, JobResult* out) const {
  auto answer = AnswerObstacles(store_, deriver_, RefOf(request), request.profile);
  if (!answer.ok()) {
    out->status = answer.status();
    return;
  }
  Reply* reply = &out->reply;
  const std::vector<common::Obstacle>& obstacles = answer->registry.obstacles;
  reply->version = answer->info.version;
  reply->maps.push_back(ToLcm(answer->info));
  AddObstacles(obstacles, params_.max_reply_obstacles, reply);
  reply->message = std::to_string(obstacles.size()) + " obstacles";
  if (static_cast<int>(obstacles.size()) > params_.max_reply_obstacles) {
    reply->message += " (first " + std::to_string(params_.max_reply_obstacles) +
                      " in this reply; export csv for all)";
  }
}

void MapstoreService::JobExport(const Request& request, JobResult* out) const {
  ExportOptions options;
  options.ref = RefOf(request);
  options.format = request.format.empty() ? "ros" : request.format;
  auto folder = io::PathBelow(params_.files_root, request.path.empty() ? "." : request.path);
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
  out->reply.message = "wrote " + list;
  out->event = "exported " + options.ref.site + "/" + request.map_name + " as " + options.format +
               ": " + list;
}

void MapstoreService::JobImport(const Request& request, JobResult* out) const {
  ImportOptions options;
  options.site = SiteOf(request);
  options.name = request.map_name;
  if (!request.layers.empty()) options.layer = request.layers.front();
  auto path = io::PathBelow(params_.files_root, request.path);
  if (!path.ok()) {
    out->status = path.status();
    return;
  }
  options.path = *path;
  options.provenance.source_robot = request.robot;
  options.provenance.source_profile = request.profile;
  auto info = ImportMap(store_, options, ContextOf(request));
  if (!info.ok()) {
    out->status = info.status();
    return;
  }
  Reply* reply = &out->reply;
  reply->version = info->version;
  reply->maps.push_back(ToLcm(*info));
  reply->layers = info->layers;
  reply->message = "imported as version " + std::to_string(info->version);
  out->event = "imported " + request.path + " into " + options.site + "/" + options.name + " v" +
               std::to_string(info->version);
}

}  // namespace cairn::mapstore
