#include "mapstore/lcm/map_server_service.h"

#include <thread>
#include <utility>

#include "cairn/lcmt_obstacle_registry.hpp"

#include "common/channels.h"
#include "common/check.h"
#include "common/log.h"
#include "services/runtime/conversions.h"

namespace cairn::mapstore {
namespace {

std::string Ch(const std::string& robot, const char* stream) {
  return channels::ForRobot(robot, stream);
}

std::string Label(const MapInfo& info) {
  return info.site + "/" + info.name + " v" + std::to_string(info.version);
}

}  // namespace

MapServerService::MapServerService(runtime::Node& node, MapServerParams params,
                                   const ProfileDeriver* deriver, StoreOpener open_store)
    : node_(node),
      params_((params.Validate(), std::move(params))),
      deriver_(deriver),
      open_store_(std::move(open_store)),
      map_name_(ServedMapName(params_.ref)),
      tiler_(params_.robot, map_name_),
      waiter_(params_.wait_s) {
  CAIRN_THROW_UNLESS(static_cast<bool>(open_store_), "the map server needs a store opener");
  CAIRN_THROW_UNLESS(deriver_ != nullptr && deriver_->valid(),
                     "the map server needs a profile derivation (built without cairn::mapping?)");
  node_.Subscribe<cairn::lcmt_tile_resend_request>(
      Ch(params_.robot, channels::kMapTileResend),
      [this](const cairn::lcmt_tile_resend_request& r) { OnResend(r); });
  node_.AddTimer(0.05, [this] { Tick(); });
  node_.AddTimer(params_.announce_period_s, [this] { Announce(); });
  node_.AddTimer(params_.registry_period_s, [this] { PublishRegistry(); });
  StartLoad();
}

MapServerService::~MapServerService() {
  // A derivation cannot be interrupted; wait for it rather than leave a thread behind.
  if (job_.valid()) job_.wait();
}

double MapServerService::SinceFirstAttempt() const {
  if (!first_attempt_) return 0.0;
  return std::chrono::duration<double>(Clock::now() - *first_attempt_).count();
}

void MapServerService::StartLoad() {
  if (!first_attempt_) first_attempt_ = Clock::now();
  const int64_t current = served_ ? served_->info.version : 0;
  const MapRef ref = params_.ref;
  const std::string profile = params_.profile;
  const ProfileDeriver* deriver = deriver_;
  StoreOpener open = open_store_;
  job_ = std::async(std::launch::async, [=]() -> Outcome {
    auto store = open();
    if (!store.ok()) return store.status();
    // Following: only a version other than the one served is loaded.
    auto info = (*store)->GetMapInfo(ref);
    if (!info.ok()) return info.status();
    if (current != 0 && info->version == current) return std::optional<ServedMap>();
    auto served = LoadServedMap(**store, deriver, {info->site, info->name, info->version}, profile);
    if (!served.ok()) return served.status();
    return std::optional<ServedMap>(std::move(served).value());
  });
}

void MapServerService::Tick() {
  if (job_.valid()) {
    if (job_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    OnOutcome(job_.get());
  }
  if (state_ == State::kFailed || Clock::now() < next_load_) return;
  if (state_ == State::kServing && !(params_.follow_latest && params_.ref.version == 0)) return;
  StartLoad();
}

void MapServerService::OnOutcome(Outcome outcome) {
  node_.Count("loads");
  // Following a served map: a newer version replaces it, a failure keeps the old one.
  if (state_ == State::kServing) {
    next_load_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(params_.follow_period_s));
    if (!outcome.ok()) {
      node_.Warn("follow", "could not look for a newer map: " + outcome.status().ToString());
    } else if (outcome->has_value()) {
      node_.Event("a newer version was saved: %s replaces v%lld",
                  Label((*outcome)->info).c_str(),
                  static_cast<long long>(served_->info.version));
      Serve(std::move(**outcome));
    }
    return;
  }
  const common::Status status = outcome.ok() ? common::Status::Ok() : outcome.status();
  const MapWaiter::Decision decision = waiter_.OnAttempt(SinceFirstAttempt(), status);
  switch (decision.action) {
    case MapWaiter::Action::kServe:
      if (decision.log) node_.Event("%s", decision.log->c_str());
      next_load_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(params_.follow_period_s));
      Serve(std::move(**outcome));
      break;
    case MapWaiter::Action::kWait:
      if (decision.log) {
        // Waiting is this process's job until the map is saved: it is healthy meanwhile (a
        // launcher would otherwise kill it for not becoming ready).
        node_.SetState(runtime::HealthState::kReady, "waiting for " + map_name_);
        node_.Event("%s", decision.log->c_str());
      }
      state_ = State::kWaiting;
      next_load_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(params_.poll_period_s));
      break;
    case MapWaiter::Action::kGiveUp:
      state_ = State::kFailed;
      CAIRN_LOG_ERROR("%s", decision.log ? decision.log->c_str() : "cannot serve the map");
      node_.SetState(runtime::HealthState::kStopping, decision.log.value_or(""));
      node_.Stop();
      break;
  }
}

void MapServerService::Serve(ServedMap map) {
  const int64_t utime = node_.NowUtime();
  size_t tiles = 0;
  std::map<std::string, cairn::lcmt_grid_manifest> manifests;
  for (const std::string& layer : ServedLayers(params_.profile)) {
    if (!map.layers.HasLayer(layer)) continue;
    // As a mapper sends it: a sonar's occupancy in percent on MAP.OCCUPANCY, the rest as floats.
    const bool occupancy = ServedAsOccupancy(layer);
    runtime::LayerTiler::Batch batch = tiler_.Update(
        map.layers, layer,
        occupancy ? runtime::TileEncoding::kOccupancy : runtime::TileEncoding::kFloat, utime);
    Send(Ch(params_.robot, channels::kMapTiles), batch.tiles);
    Send(Ch(params_.robot, channels::kMapOccupancy), batch.occupancy_tiles);
    const size_t sent = batch.tiles.size() + batch.occupancy_tiles.size();
    tiles += sent;
    node_.Count("tiles_sent", static_cast<int64_t>(sent));
    manifests[layer] = std::move(batch.manifest);
  }
  // A layer the new version lacks is announced once more, empty, so receivers drop it.
  for (auto& [layer, manifest] : manifests_) {
    if (manifests.count(layer)) continue;
    manifest.layer_version += 1;
    manifest.num_tiles = 0;
    manifest.tile_ix.clear();
    manifest.tile_iy.clear();
    manifest.tile_version.clear();
    manifest.checksum.clear();
    node_.Publish(Ch(params_.robot, channels::kMapManifest), manifest);
  }
  manifests_ = std::move(manifests);
  served_ = std::move(map);
  state_ = State::kServing;
  Announce();
  PublishRegistry();
  char how[64];
  std::snprintf(how, sizeof(how), "derived in %.0f ms", served_->derive_ms);
  node_.SetState(runtime::HealthState::kReady, "serving " + Label(served_->info));
  node_.Event("serving %s for profile %s on %s.MAP.* as '%s': %zu layers, %zu tiles, %zu "
              "obstacles, %s",
              Label(served_->info).c_str(), params_.profile.c_str(), params_.robot.c_str(),
              map_name_.c_str(), manifests_.size(), tiles, served_->obstacles.obstacles.size(),
              served_->from_cache ? "profile layers from the store's cache" : how);
}

void MapServerService::Announce() {
  if (manifests_.empty()) return;
  const int64_t utime = node_.NowUtime();
  for (auto& [layer, manifest] : manifests_) {
    manifest.utime = utime;
    node_.Publish(Ch(params_.robot, channels::kMapManifest), manifest);
  }
  node_.Count("manifests_sent", static_cast<int64_t>(manifests_.size()));
}

void MapServerService::PublishRegistry() {
  if (!served_) return;
  cairn::lcmt_obstacle_registry msg =
      runtime::ToLcm(served_->obstacles, node_.NowUtime(), params_.robot, map_name_);
  if (runtime::FitRegistryToMessageLimit(&msg)) {
    node_.Warn("registry_size", "the obstacle registry exceeds 256 KB; outlines are left out");
  }
  node_.Publish(Ch(params_.robot, channels::kMapObstacles), msg);
}

void MapServerService::OnResend(const cairn::lcmt_tile_resend_request& request) {
  // Requests for another map on these channels (a mapper's) are not ours to answer.
  if (!request.robot.empty() && request.robot != params_.robot) return;
  if (!request.map_name.empty() && request.map_name != map_name_) return;
  if (manifests_.count(request.layer) == 0) return;
  node_.Count("resend_requests");
  runtime::LayerTiler::Batch batch = tiler_.Resend(request);
  Send(Ch(params_.robot, channels::kMapTiles), batch.tiles);
  Send(Ch(params_.robot, channels::kMapOccupancy), batch.occupancy_tiles);
  node_.Count("tiles_resent",
              static_cast<int64_t>(batch.tiles.size() + batch.occupancy_tiles.size()));
  cairn::lcmt_grid_manifest manifest = manifests_.at(request.layer);
  manifest.utime = node_.NowUtime();
  node_.Publish(Ch(params_.robot, channels::kMapManifest), manifest);
}

template <typename Msg>
void MapServerService::Send(const std::string& channel, const std::vector<Msg>& messages) {
  node_.PublishPaced(channel, messages, params_.tiles_per_burst, params_.burst_pause_ms);
}

}  // namespace cairn::mapstore
