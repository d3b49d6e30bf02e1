#include "planner/lcm/lcm_map_client.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "common/channels.h"

namespace cairn::planner {

LcmMapClient::LcmMapClient(runtime::Node& node, LcmMapClientParams params,
                           std::vector<common::Vector2> footprint_m)
    : node_(node), params_(std::move(params)), policy_(params_.snapshot, std::move(footprint_m)) {
  if (params_.own_thread) thread_ = std::thread([this] { ThreadLoop(); });
  if (params_.snapshot.encoding == MapEncoding::kOccupancy) {
    node_.Subscribe<cairn::lcmt_occupancy_tile>(
        channels::ForRobot(params_.robot, channels::kMapOccupancy),
        [this](const cairn::lcmt_occupancy_tile& t) { Deliver(t); });
  } else {
    node_.Subscribe<cairn::lcmt_grid_tile>(channels::ForRobot(params_.robot, channels::kMapTiles),
                                           [this](const cairn::lcmt_grid_tile& t) { Deliver(t); });
  }
  node_.Subscribe<cairn::lcmt_grid_manifest>(
      channels::ForRobot(params_.robot, channels::kMapManifest),
      [this](const cairn::lcmt_grid_manifest& m) { Deliver(m); });
}

LcmMapClient::~LcmMapClient() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    stop_ = true;
  }
  queue_cv_.notify_one();
  thread_.join();
}

void LcmMapClient::Deliver(Message message) {
  if (!params_.own_thread) return Handle(message);
  bool dropped = false;
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (queue_.size() >= std::max<size_t>(1, params_.max_queued_messages)) {
      queue_.pop_front();
      dropped = true;
    }
    queue_.push_back(std::move(message));
  }
  queue_cv_.notify_one();
  if (dropped) {
    node_.Count("map_queue_drops");
    node_.Warn("map_queue",
               "map messages arrive faster than they are assembled: dropped the "
               "oldest (missing tiles are asked for again)");
  }
}

void LcmMapClient::Handle(const Message& message) {
  std::visit(
      [this](const auto& m) {
        if constexpr (std::is_same_v<std::decay_t<decltype(m)>, cairn::lcmt_grid_manifest>) {
          OnManifest(m);
        } else {
          OnTile(m);
        }
      },
      message);
}

void LcmMapClient::ThreadLoop() {
  std::deque<Message> batch;
  for (;;) {
    bool poll = false;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_cv_.wait(lock, [this] { return stop_ || poll_requested_ || !queue_.empty(); });
      if (stop_) return;
      batch.swap(queue_);
      poll = poll_requested_;
      poll_requested_ = false;
    }
    for (const Message& m : batch) Handle(m);
    batch.clear();
    if (poll) PollNow();
  }
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
  if (layer != params_.layer &&
      (params_.directed_layer.empty() || layer != params_.directed_layer)) {
    return false;
  }
  if (!params_.map_name.empty() && map_name != params_.map_name) return false;
  return robot.empty() || robot == params_.robot;
}

void LcmMapClient::OnTile(const cairn::lcmt_grid_tile& tile) {
  // A float tile of our layer name while we read occupancy (or the reverse) is not ours.
  if (params_.snapshot.encoding != MapEncoding::kCost) return;
  OnTileImpl(tile);
}

void LcmMapClient::OnTile(const cairn::lcmt_occupancy_tile& tile) {
  if (params_.snapshot.encoding != MapEncoding::kOccupancy) return;
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
  Heard();
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
  // A refused manifest (a grid over the cell cap, tiles outside it) changes nothing, not even
  // when the layer was last heard of.
  if (!assembler_.OnManifest(manifest)) {
    node_.CountDropped("bad_map_manifests");
    node_.Warn("map_manifest", "manifest for " + manifest.layer +
                                   " refused: a grid or version no sender could have");
    return;
  }
  if (manifest.layer == params_.layer) tile_size_ = manifest.tile_size;
  Heard();
}

void LcmMapClient::Heard() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    heard_utime_ = node_.NowUtime();
  }
  Carry(
      policy_.OnLayerChanged(assembler_.version(params_.layer), PairComplete(), node_.NowUtime()));
  RefreshDirected();
}

bool LcmMapClient::DirectedPending() const {
  return !params_.directed_layer.empty() && assembler_.version(params_.directed_layer) > 0 &&
         !assembler_.Complete(params_.directed_layer);
}

bool LcmMapClient::PairComplete() const {
  // A cost version is whole only with the directed tiles announced beside it: without them its
  // one-way cells would read as lethal walls (a lost directed tile is asked for again).
  return assembler_.Complete(params_.layer) && !DirectedPending();
}

void LcmMapClient::Poll() {
  if (!params_.own_thread) return PollNow();
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    poll_requested_ = true;
  }
  queue_cv_.notify_one();
}

void LcmMapClient::PollNow() {
  const int64_t now = node_.NowUtime();
  const int64_t version = assembler_.version(params_.layer);
  const bool complete = assembler_.Complete(params_.layer);
  if (now - last_resend_utime_ >= static_cast<int64_t>(params_.resend_interval_s * 1e6)) {
    if (policy_.WantsMissingTiles(version, complete)) AskForMissing(params_.layer, now);
    if (!params_.directed_layer.empty() && assembler_.version(params_.directed_layer) > 0 &&
        !assembler_.Complete(params_.directed_layer)) {
      AskForMissing(params_.directed_layer, now);
    }
  }
  Carry(policy_.OnPoll(version, complete && !DirectedPending(), now));
  RefreshDirected();
}

void LcmMapClient::AskForMissing(const std::string& layer, int64_t now) {
  if (auto request = assembler_.MakeResendRequest(layer, params_.requester, now)) {
    node_.Publish(channels::ForRobot(params_.robot, channels::kMapTileResend), *request);
    node_.Count("tile_resend_requests");
    last_resend_utime_ = now;
  }
}

// The directed layer held now, when it has the cost layer's grid.
void LcmMapClient::AttachDirected(AssembledLayer* assembled) {
  if (params_.directed_layer.empty()) return;
  // What was considered (attached or not), so RefreshDirected does not try it again.
  built_directed_version_ = assembler_.version(params_.directed_layer);
  built_directed_complete_ = assembler_.Complete(params_.directed_layer);
  const auto geometry = assembler_.Geometry(params_.directed_layer);
  if (!geometry || *geometry != assembled->geometry) return;
  auto directed = assembler_.Layer(params_.directed_layer);
  if (!directed) return;
  assembled->directed = std::move(directed->at(params_.directed_layer));
  assembled->directed_missing_tiles = assembler_.Missing(params_.directed_layer);
}

// A directed version that changed, or completed, under the cost version in use: that cost
// version again with it.
void LcmMapClient::RefreshDirected() {
  if (params_.directed_layer.empty() || policy_.built_version() < 0 || policy_.built_incomplete() ||
      assembler_.version(params_.layer) != policy_.built_version()) {
    return;
  }
  const int64_t version = assembler_.version(params_.directed_layer);
  if (version == 0) return;
  const bool complete = assembler_.Complete(params_.directed_layer);
  // A pair still missing tiles on either side waits for them (a lost tile is asked for
  // again): the snapshot in use keeps the pair it was built with, and the policy builds the
  // next cost version without the missing directed tiles once its wait for them is over. New
  // directed cells beside cost cells of the version before would make walls of one-way cells,
  // or of cells that were one-way and are free now.
  if (!complete || !assembler_.Complete(params_.layer)) return;
  if (version == built_directed_version_ && built_directed_complete_) return;
  Carry(SnapshotAction::kBuild);
}

// Hands the assembled layer to the policy when it asks for a snapshot.
void LcmMapClient::Carry(SnapshotAction action) {
  if (action == SnapshotAction::kWait) return;
  auto layer = assembler_.Layer(params_.layer);
  if (!layer) return;
  AssembledLayer assembled;
  assembled.version = assembler_.version(params_.layer);
  assembled.geometry = layer->geometry();
  assembled.cells = std::move(layer->at(params_.layer));
  assembled.tile_size_cells = tile_size_;
  if (action == SnapshotAction::kBuildIncomplete) {
    assembled.missing_tiles = assembler_.Missing(params_.layer);
  }
  AttachDirected(&assembled);
  const size_t missing = assembled.missing_tiles.size();
  auto map = policy_.Build(std::move(assembled), node_.NowUtime());
  if (map.ok()) {
    std::lock_guard<std::mutex> lock(mutex_);
    latest_ = std::move(map).value();
    ++snapshots_;
  } else {
    node_.CountDropped("bad_map_layers");
    node_.Warn("map_layer", "layer " + params_.layer + " refused: " + map.status().message());
  }
  node_.Count("map_snapshots");
  if (missing == 0) return;
  node_.Count("incomplete_map_snapshots");
  node_.Warn("map_incomplete", "layer " + params_.layer + " is incomplete (" +
                                   std::to_string(missing) +
                                   " tiles missing, asked again): the navigator waits for them");
}

}  // namespace cairn::planner
