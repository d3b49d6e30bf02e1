// MapstoreService's saves: pushed pieces and robots' live maps go to the SaveAssembler as core
// tiles, manifests and chunks; what it asks for (resends, a mapper's full publication) and the
// saves it finishes go back on the bus.

#include "cairn/lcmt_map_control_reply.hpp"
#include "cairn/lcmt_map_control_request.hpp"
#include "cairn/lcmt_occupancy_tile.hpp"

#include "common/channels.h"
#include "common/log.h"
#include "mapstore/blob_codec.h"
#include "mapstore/lcm/mapstore_conversions.h"
#include "mapstore/lcm/mapstore_service.h"
#include "mapstore/lcm/tile_wire.h"
#include "services/runtime/conversions.h"

namespace cairn::mapstore {

using Reply = cairn::lcmt_mapstore_reply;
using Request = cairn::lcmt_mapstore_request;
using Intake = SaveAssembler::Intake;

namespace {

constexpr char kActor[] = "cairn-mapstore";

}  // namespace

template <typename Msg>
void MapstoreService::SubscribePush(const std::string& channel,
                                    void (MapstoreService::*handler)(const Msg&)) {
  node_.Subscribe<Msg>(channel, [this, handler](const Msg& m) {
    (this->*handler)(m);
    std::lock_guard<std::mutex> lock(mutex_);
    Apply(saves_.OnPushed(m.map_name, Clock::now()));
  });
}

void MapstoreService::SubscribeSaves() {
  // A save waiting for pushed data finishes as soon as its last piece arrives.
  SubscribePush(channels::kMapstorePushTiles, &MapstoreService::OnPushTile);
  SubscribePush(channels::kMapstorePushTileBatches, &MapstoreService::OnPushTileBatch);
  SubscribePush(channels::kMapstorePushManifest, &MapstoreService::OnPushManifest);
  SubscribePush(channels::kMapstorePushObstacles, &MapstoreService::OnPushObstacles);
  SubscribePush(channels::kMapstorePushOctomap, &MapstoreService::OnPushOctomap);
}

void MapstoreService::Poll() {
  std::lock_guard<std::mutex> lock(mutex_);
  Apply(saves_.Poll(Clock::now()));
}

void MapstoreService::StartSave(const Request& request, Reply* reply, Clock::time_point started) {
  common::Status s;
  if (request.num_layers < 0 || request.layers.size() != static_cast<size_t>(request.num_layers)) {
    s = common::InvalidArgumentError("layers disagree with num_layers");
  }
  if (!s.ok()) {
    SetStatus(s, reply);
    Finish(request, std::move(*reply), started);
    return;
  }
  Apply(saves_.Start(SaveRequestOf(request), started), reply);
}

void MapstoreService::Apply(SaveProgress progress, const Reply* first_reply) {
  for (const std::string& robot : progress.new_robots) FollowRobot(robot);
  for (const PublishAllAsk& ask : progress.publish_all) {
    cairn::lcmt_map_control_request control{};
    control.utime = node_.NowUtime();
    control.requester = kActor;
    control.op = cairn::lcmt_map_control_request::OP_PUBLISH_ALL;
    control.has_profile = false;
    control.request_id = ask.request_id;
    node_.Publish(channels::ForRobot(ask.robot, channels::kMapControl), control);
  }
  const int64_t utime = node_.NowUtime();
  for (const ResendAsk& ask : progress.resends) {
    const std::string channel = ask.pull_robot.empty()
                                    ? std::string(channels::kMapstorePushTileResend)
                                    : channels::ForRobot(ask.pull_robot, channels::kMapTileResend);
    node_.Publish(channel, ToLcm(ask.tiles, kActor, utime));
  }
  if (progress.abandoned_pushes > 0)
    node_.CountDropped("abandoned_pushes", progress.abandoned_pushes);
  for (const std::string& warning : progress.warnings) node_.Warn("save", warning);
  for (SaveOutcome& outcome : progress.finished) FinishSave(std::move(outcome), first_reply);
}

void MapstoreService::FinishSave(SaveOutcome outcome, const Reply* first_reply) {
  // A save that ends at once answers with the reply its request started; a later one with a
  // reply of its own.
  Reply reply{};
  if (first_reply != nullptr) {
    reply = *first_reply;
  } else {
    reply.utime = node_.NowUtime();
    reply.request_id = outcome.request.request_id;
    reply.op = Request::OP_SAVE;
    reply.status = Reply::STATUS_OK;
    reply.site = outcome.request.site;
    reply.map_name = outcome.request.map_name;
  }
  if (outcome.version != 0 || first_reply == nullptr) reply.version = outcome.version;
  reply.layers = outcome.layers;
  for (const MapInfo& info : outcome.maps) reply.maps.push_back(ToLcm(info));
  if (!outcome.message.empty()) reply.message = outcome.message;
  const common::StatusCode code = outcome.status.code();
  if (!outcome.status.ok() && code != common::StatusCode::kInvalidArgument &&
      code != common::StatusCode::kNotFound && code != common::StatusCode::kUnavailable) {
    // The store could not keep a map (disk full, read-only or damaged file): every one is
    // logged, with the file and the reason the store gave; the service goes on.
    node_.Count("failed_saves");
    node_.Count("failed_requests");
    CAIRN_LOG_ERROR("save of %s/%s failed: %s", outcome.request.site.c_str(),
                    outcome.request.map_name.c_str(), outcome.status.ToString().c_str());
    reply.status = ReplyStatus(outcome.status);
    reply.message = outcome.status.message();
  } else {
    SetStatus(outcome.status, &reply);
  }
  if (outcome.timed_out) node_.Count("save_timeouts");
  if (outcome.saved_maps > 0) node_.Count("saves", outcome.saved_maps);
  for (const std::string& event : outcome.events) node_.Event("%s", event.c_str());
  Request request{};
  request.requester = outcome.request.requester;
  request.request_id = outcome.request.request_id;
  Finish(request, std::move(reply), outcome.started);
}

void MapstoreService::CountIntake(Intake intake, const char* counter) {
  if (intake == Intake::kRefused) {
    node_.CountDropped(counter);
  } else if (intake == Intake::kStagingFull) {
    node_.CountDropped("staging_full");
    node_.Warn("staging_full", "pushed tiles dropped: too much staged data");
  }
}

void MapstoreService::OnPushTile(const cairn::lcmt_grid_tile& pushed) {
  // A compressed tile is decoded (and checked by zstd) before the lock is taken.
  std::vector<float> cells;
  if (pushed.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32 &&
      !DecodeTileCells(pushed, &cells).ok()) {
    node_.CountDropped("bad_push_tiles");
    return;
  }
  StagePushTile(pushed, cells);
}

void MapstoreService::OnPushTileBatch(const cairn::lcmt_grid_tile_batch& batch) {
  if (batch.num_tiles < 0 || static_cast<size_t>(batch.num_tiles) != batch.tiles.size()) {
    node_.CountDropped("bad_push_tiles");
    return;
  }
  thread_local std::vector<std::vector<float>> cells;  // buffers kept between batches
  std::vector<char> ok;
  DecodeTiles(batch.tiles, batch.map_name, params_.decode_threads, &cells, &ok);
  for (size_t i = 0; i < batch.tiles.size(); ++i) {
    if (ok[i]) {
      StagePushTile(batch.tiles[i], cells[i]);
    } else {
      node_.CountDropped("bad_push_tiles");
    }
  }
}

void MapstoreService::StagePushTile(const cairn::lcmt_grid_tile& pushed,
                                    const std::vector<float>& cells) {
  const bool compressed = pushed.encoding != cairn::lcmt_grid_tile::ENCODING_FLOAT32;
  common::Result<CheckedTile> tile =
      compressed ? DecodedTile(pushed, cells) : CheckFloatTile(pushed);
  if (!tile.ok()) {
    node_.CountDropped("bad_push_tiles");
    return;
  }
  std::optional<int> codec;
  std::string bytes;
  if (const std::optional<Codec> c = CodecOfEncoding(pushed.encoding)) {
    codec = static_cast<int>(*c);
    bytes.assign(pushed.bytes.begin(), pushed.bytes.end());
  }
  std::lock_guard<std::mutex> lock(mutex_);
  CountIntake(saves_.StageTile(*tile, codec, std::move(bytes), Clock::now()), "bad_push_tiles");
}

void MapstoreService::OnPushManifest(const cairn::lcmt_grid_manifest& msg) {
  auto manifest = FromLcm(msg);
  if (!manifest.ok()) {
    node_.CountDropped("bad_push_manifests");
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  CountIntake(saves_.StageManifest(*manifest, Clock::now()), "bad_push_manifests");
}

void MapstoreService::OnPushObstacles(const cairn::lcmt_obstacle_registry& msg) {
  auto registry = runtime::FromLcm(msg);
  std::lock_guard<std::mutex> lock(mutex_);
  CountIntake(saves_.StageObstacles(msg.map_name, std::move(registry), Clock::now()),
              "bad_push_obstacles");
}

void MapstoreService::OnPushOctomap(const cairn::lcmt_octomap& msg) {
  auto chunk = FromLcm(msg);
  std::lock_guard<std::mutex> lock(mutex_);
  if (!chunk.ok()) {
    node_.CountDropped("bad_push_octomap");
    return;
  }
  CountIntake(saves_.StageOctomapChunk(msg.map_name, *chunk, Clock::now()), "bad_push_octomap");
}

void MapstoreService::FollowRobot(const std::string& robot) {
  // Handlers run on the node's thread, as do the save assembler's other callers; the lock
  // guards it against the worker threads' bookkeeping.
  node_.Subscribe<cairn::lcmt_grid_tile>(channels::ForRobot(robot, channels::kMapTiles),
                                         [this, robot](const cairn::lcmt_grid_tile& t) {
                                           auto tile = CheckFloatTile(t);
                                           std::lock_guard<std::mutex> lock(mutex_);
                                           if (!tile.ok() || !saves_.MirrorTile(robot, *tile))
                                             node_.CountDropped("bad_mapper_tiles");
                                         });
  node_.Subscribe<cairn::lcmt_occupancy_tile>(channels::ForRobot(robot, channels::kMapOccupancy),
                                              [this, robot](const cairn::lcmt_occupancy_tile& t) {
                                                std::vector<float> cells;
                                                auto tile = CheckOccupancyTile(t, &cells);
                                                std::lock_guard<std::mutex> lock(mutex_);
                                                if (!tile.ok() || !saves_.MirrorTile(robot, *tile))
                                                  node_.CountDropped("bad_mapper_tiles");
                                              });
  node_.Subscribe<cairn::lcmt_grid_manifest>(channels::ForRobot(robot, channels::kMapManifest),
                                             [this, robot](const cairn::lcmt_grid_manifest& m) {
                                               auto manifest = FromLcm(m);
                                               std::lock_guard<std::mutex> lock(mutex_);
                                               if (!manifest.ok()) {
                                                 node_.CountDropped("bad_mapper_manifests");
                                                 return;
                                               }
                                               saves_.MirrorManifest(robot, *manifest,
                                                                     Clock::now());
                                             });
  node_.Subscribe<cairn::lcmt_obstacle_registry>(
      channels::ForRobot(robot, channels::kMapObstacles),
      [this, robot](const cairn::lcmt_obstacle_registry& r) {
        auto registry = runtime::FromLcm(r);
        std::lock_guard<std::mutex> lock(mutex_);
        if (!registry.ok()) {
          node_.CountDropped("bad_mapper_obstacles");
          return;
        }
        saves_.MirrorObstacles(robot, std::move(registry).value(), Clock::now());
      });
  node_.Subscribe<cairn::lcmt_octomap>(
      channels::ForRobot(robot, channels::kMapOctomap),
      [this, robot](const cairn::lcmt_octomap& c) {
        auto chunk = FromLcm(c);
        std::lock_guard<std::mutex> lock(mutex_);
        if (!chunk.ok() || !saves_.MirrorOctomapChunk(robot, *chunk)) {
          node_.CountDropped("bad_mapper_octomap");
        }
      });
  // The mapper's answer to OP_PUBLISH_ALL lists its layers: a pull save naming none waits for
  // each of them.
  node_.Subscribe<cairn::lcmt_map_control_reply>(
      channels::ForRobot(robot, channels::kMapControlReply),
      [this, robot](const cairn::lcmt_map_control_reply& r) {
        auto reply = FromLcm(r);
        std::lock_guard<std::mutex> lock(mutex_);
        if (!reply.ok()) {
          node_.CountDropped("bad_mapper_replies");
          return;
        }
        Apply(saves_.OnMapperLayers(robot, *reply, Clock::now()));
      });
  node_.Event("following the live map of %s for pull saves", robot.c_str());
}

}  // namespace cairn::mapstore
