#include "mapstore/save_assembler.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <utility>

#include "common/check.h"
#include "common/layers.h"
#include "mapstore/names.h"

namespace cairn::mapstore {

using common::Result;
using common::Status;
using Clock = SaveAssembler::Clock;

namespace {

double SecondsBetween(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

Clock::time_point After(Clock::time_point t, double seconds) {
  return t + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// Profile-specific layers the store never saves: it derives them per profile itself.
bool IsDerivedLayer(const std::string& name) {
  return layers::IsCostLayer(name) || layers::IsDirectedLayer(name) || name == layers::kSlope ||
         name == layers::kStepMax || name == layers::kRoughness || name == layers::kDitchDepth ||
         name == layers::kDitchWidth;
}

bool IsPushName(const std::string& map_name) { return map_name.find('/') != std::string::npos; }

Status ValidateSaveRequest(const SaveRequest& request) {
  Status s = ValidateName("site name", request.site);
  if (s.ok()) s = ValidateName("map name", request.map_name);
  if (s.ok() && !request.robot.empty()) s = ValidateName("robot name", request.robot);
  for (const std::string& layer : request.layers) {
    if (s.ok()) s = ValidateLayerName(layer);
  }
  if (s.ok() && request.robot.empty() && request.layers.empty()) {
    s = common::InvalidArgumentError("a pushed save must name its layers");
  }
  return s;
}

// Layers of an assembler as one map; every layer must share one geometry. `take` moves the
// layers out of the assembler (which forgets them) instead of copying them.
Result<common::GridMap> CollectLayers(TileAssembler* assembler,
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

// The wanted layers by grid. The group holding the elevation comes first: it is the map itself;
// the others become companion maps.
std::vector<std::vector<std::string>> GroupByGeometry(const TileAssembler& assembler,
                                                      const std::vector<std::string>& wanted) {
  std::vector<std::vector<std::string>> groups;
  std::vector<common::GridGeometry> group_geometry;
  for (const std::string& layer : wanted) {
    const std::optional<common::GridGeometry> geometry = assembler.Geometry(layer);
    if (!geometry) continue;
    size_t g = 0;
    while (g < groups.size() && group_geometry[g] != *geometry) ++g;
    if (g == groups.size()) {
      groups.emplace_back();
      group_geometry.push_back(*geometry);
    }
    groups[g].push_back(layer);
  }
  for (size_t g = 1; g < groups.size(); ++g) {
    if (std::find(groups[g].begin(), groups[g].end(), layers::kElevation) != groups[g].end()) {
      std::swap(groups[0], groups[g]);
    }
  }
  return groups;
}

std::string JoinList(const std::vector<std::string>& items) {
  std::string list;
  for (const std::string& item : items) list += (list.empty() ? "" : ", ") + item;
  return list;
}

}  // namespace

void SaveAssemblerParams::Validate() const {
  CAIRN_THROW_UNLESS(save_timeout_s > 0, "save_timeout_s must be positive");
  CAIRN_THROW_UNLESS(resend_interval_s > 0, "resend_interval_s must be positive");
  CAIRN_THROW_UNLESS(staging_timeout_s > 0, "staging_timeout_s must be positive");
  CAIRN_THROW_UNLESS(pull_settle_s >= 0, "pull_settle_s must not be negative");
  CAIRN_THROW_UNLESS(max_staged_bytes > 0, "max_staged_bytes must be positive");
  CAIRN_THROW_UNLESS(max_pushes > 0, "max_pushes must be positive");
}

std::string SaveKey(const SaveRequest& request) {
  return request.requester + "#" + std::to_string(request.request_id);
}

std::string PushName(const SaveRequest& request) {
  return std::to_string(request.request_id) + "/" + request.map_name;
}

// Pushed data of one save, by push name.
struct SaveAssembler::Staging {
  std::string invalid;  // why pushed data were refused (the save fails with kInvalidArgument)
  TileAssembler assembler;
  // Compressed tiles as they came, by layer and (tile_ix, tile_iy): the store keeps these bytes
  // rather than compressing the cells again (checked against the cells' CRC when stored).
  struct EncodedLayer {
    int tile_size{0};
    std::map<std::pair<int, int>, StoredTile> tiles;
  };
  std::map<std::string, EncodedLayer> encoded;
  std::set<std::string> manifests;
  std::optional<common::ObstacleRegistry> obstacles;
  OctomapAssembler octomap;
  std::string robot;
  Clock::time_point last;
  int64_t encoded_bytes{0};   // of `encoded`
  int64_t manifest_bytes{0};  // of the manifests staged (the newest of each layer)
  int64_t obstacle_bytes{0};

  // What the staging holds, as max_staged_bytes counts it.
  int64_t Bytes() const {
    constexpr int64_t kOverhead = 1024;
    int64_t canvas = 0;
    for (const std::string& layer : assembler.layers()) {
      if (auto g = assembler.Geometry(layer)) canvas += g->num_cells() * int64_t{sizeof(float)};
    }
    return kOverhead + canvas + encoded_bytes + manifest_bytes + obstacle_bytes +
           octomap.held_bytes();
  }
};

namespace {

// Roughly what a registry takes in memory.
int64_t ApproxBytes(const common::ObstacleRegistry& registry) {
  int64_t bytes = 0;
  for (const common::Obstacle& o : registry.obstacles) {
    bytes += int64_t{sizeof(common::Obstacle)} +
             static_cast<int64_t>(o.outline_m.size() * sizeof(common::Vector2)) +
             static_cast<int64_t>(o.verdicts.size() * (sizeof(common::ObstacleVerdict) + 64)) +
             static_cast<int64_t>(o.parts.size() * sizeof(common::ObstaclePart));
  }
  return bytes;
}

// Bytes a staged manifest takes.
int64_t ManifestBytes(const TileManifest& manifest) {
  return 256 + static_cast<int64_t>(manifest.tiles.size() * sizeof(TileManifest::Entry));
}

}  // namespace

struct SaveAssembler::PendingSave {
  SaveRequest request;  // site filled in
  std::string key;
  std::string map_name;  // push: "<request_id>/<map>"
  bool pull{false};
  Clock::time_point started;
  Clock::time_point next_resend;
  int resend_rounds{0};
  int64_t publish_all_id{0};  // a pull: its OP_PUBLISH_ALL's request id
  // A pull: the layers the mapper's answer to it listed (once it came).
  std::optional<std::vector<std::string>> mapper_layers;
};

// The live map of a robot pulled from.
struct SaveAssembler::LiveMirror {
  std::string map_name{"live"};  // the mapper's map, as its manifests name it
  TileAssembler assembler;
  std::map<std::string, Clock::time_point> manifest_time;
  std::optional<common::ObstacleRegistry> obstacles;
  Clock::time_point obstacles_time;
  OctomapAssembler octomap;
  std::optional<OctomapData> complete_octomap;  // the newest whole tree
};

// What a pending save has and lacks at one moment.
struct SaveAssembler::Gathered {
  bool settling{false};         // a pull without named layers still collects layer names
  bool awaiting_layers{false};  // ... and waits for the mapper's list of them
  std::string invalid;          // pushed data were refused: the save fails
  TileAssembler* assembler{nullptr};
  Staging* push_staging{nullptr};  // a push: its compressed tiles go to the store as they came
  std::vector<std::string> wanted;
  std::vector<std::string> missing;
  std::vector<ResendAsk> resends;
  const common::ObstacleRegistry* obstacles{nullptr};
  const OctomapData* octomap{nullptr};
  std::string push_robot;
};

SaveAssembler::SaveAssembler(MapStore& store, SaveAssemblerParams params)
    : store_(store), params_(params) {
  params_.Validate();
}

SaveAssembler::~SaveAssembler() = default;

bool SaveAssembler::IsPending(const std::string& key) const { return pending_.count(key) > 0; }

int64_t SaveAssembler::pending_saves() const { return static_cast<int64_t>(pending_.size()); }

int64_t SaveAssembler::staged_bytes() const {
  int64_t total = 0;
  for (const auto& [name, staging] : staging_) total += staging->Bytes();
  return total;
}

bool SaveAssembler::Fits(int64_t more) const {
  return staged_bytes() + more <= params_.max_staged_bytes;
}

SaveAssembler::Staging* SaveAssembler::StagingFor(const std::string& map_name,
                                                  Clock::time_point now) {
  auto it = staging_.find(map_name);
  if (it != staging_.end()) return it->second.get();
  if (static_cast<int>(staging_.size()) >= params_.max_pushes) return nullptr;
  auto staging = std::make_unique<Staging>();
  staging->last = now;
  Staging* made = staging.get();
  staging_[map_name] = std::move(staging);
  return made;
}

SaveAssembler::LiveMirror* SaveAssembler::MirrorOf(const std::string& robot) {
  auto it = mirrors_.find(robot);
  return it == mirrors_.end() ? nullptr : it->second.get();
}

SaveAssembler::Intake SaveAssembler::StageTile(const CheckedTile& tile, std::optional<int> codec,
                                               std::string bytes, Clock::time_point now) {
  const TileHeader& h = tile.header;
  if (!IsPushName(h.map_name)) return Intake::kRefused;
  // A tile's first in its layer (or grid) allocates the whole layer's canvas.
  auto it = staging_.find(h.map_name);
  int64_t more = static_cast<int64_t>(bytes.size());
  if (it == staging_.end() || it->second->assembler.Geometry(h.layer) != h.geometry) {
    more += h.geometry.num_cells() * int64_t{sizeof(float)};
  }
  if (!Fits(more)) return Intake::kStagingFull;
  Staging* staging = StagingFor(h.map_name, now);
  if (staging == nullptr) return Intake::kStagingFull;
  if (!staging->assembler.OnTile(tile)) return Intake::kRefused;
  Staging::EncodedLayer& encoded = staging->encoded[h.layer];
  const std::pair<int, int> key{h.tile_ix, h.tile_iy};
  auto old = encoded.tiles.find(key);
  if (old != encoded.tiles.end()) {
    staging->encoded_bytes -= static_cast<int64_t>(old->second.data.size());
    encoded.tiles.erase(old);
  }
  if (codec && (encoded.tiles.empty() || encoded.tile_size == h.tile_size)) {
    encoded.tile_size = h.tile_size;
    staging->encoded_bytes += static_cast<int64_t>(bytes.size());
    encoded.tiles[key] =
        StoredTile{h.tile_ix, h.tile_iy,  h.cells_x,        h.cells_y,
                   *codec,    h.checksum, std::move(bytes), /*stored_crc32=*/std::nullopt};
  }  // else a newer copy came as floats: it is compressed when stored
  staging->robot = h.robot;
  staging->last = now;
  return Intake::kHeld;
}

SaveAssembler::Intake SaveAssembler::StageManifest(const TileManifest& manifest,
                                                   Clock::time_point now) {
  if (!IsPushName(manifest.map_name)) return Intake::kRefused;
  if (!Fits(ManifestBytes(manifest))) return Intake::kStagingFull;
  Staging* staging = StagingFor(manifest.map_name, now);
  if (staging == nullptr) return Intake::kStagingFull;
  if (!staging->assembler.OnManifest(manifest)) return Intake::kRefused;
  if (staging->manifests.insert(manifest.layer).second) {
    staging->manifest_bytes += ManifestBytes(manifest);
  }
  staging->last = now;
  return Intake::kHeld;
}

SaveAssembler::Intake SaveAssembler::StageObstacles(
    const std::string& map_name, common::Result<common::ObstacleRegistry> registry,
    Clock::time_point now) {
  if (!IsPushName(map_name)) return Intake::kRefused;
  Staging* staging = StagingFor(map_name, now);
  if (staging == nullptr) return Intake::kStagingFull;
  if (!registry.ok()) {
    staging->invalid = "pushed obstacles: " + registry.status().message();
    return Intake::kRefused;
  }
  const int64_t bytes = ApproxBytes(*registry);
  if (!Fits(bytes - staging->obstacle_bytes)) return Intake::kStagingFull;
  staging->obstacles = std::move(registry).value();
  staging->obstacle_bytes = bytes;
  staging->last = now;
  return Intake::kHeld;
}

SaveAssembler::Intake SaveAssembler::StageOctomapChunk(const std::string& map_name,
                                                       const OctomapChunk& chunk,
                                                       Clock::time_point now) {
  if (!IsPushName(map_name)) return Intake::kRefused;
  // The chunk, and the whole tree once its last chunk completes it.
  if (!Fits(2 * static_cast<int64_t>(chunk.size))) return Intake::kStagingFull;
  Staging* staging = StagingFor(map_name, now);
  if (staging == nullptr) return Intake::kStagingFull;
  const bool held = staging->octomap.Add(chunk);
  staging->last = now;
  return held ? Intake::kHeld : Intake::kRefused;
}

bool SaveAssembler::MirrorTile(const std::string& robot, const CheckedTile& tile) {
  LiveMirror* mirror = MirrorOf(robot);
  return mirror != nullptr && mirror->assembler.OnTile(tile);
}

void SaveAssembler::MirrorManifest(const std::string& robot, const TileManifest& manifest,
                                   Clock::time_point now) {
  LiveMirror* mirror = MirrorOf(robot);
  if (mirror == nullptr) return;
  mirror->assembler.OnManifest(manifest);
  mirror->manifest_time[manifest.layer] = now;
  if (!manifest.map_name.empty()) mirror->map_name = manifest.map_name;
}

void SaveAssembler::MirrorObstacles(const std::string& robot, common::ObstacleRegistry registry,
                                    Clock::time_point now) {
  LiveMirror* mirror = MirrorOf(robot);
  if (mirror == nullptr) return;
  mirror->obstacles = std::move(registry);
  mirror->obstacles_time = now;
}

bool SaveAssembler::MirrorOctomapChunk(const std::string& robot, const OctomapChunk& chunk) {
  LiveMirror* mirror = MirrorOf(robot);
  if (mirror == nullptr || !mirror->octomap.Add(chunk)) return false;
  if (mirror->octomap.complete()) mirror->complete_octomap = mirror->octomap.complete();
  return true;
}

SaveProgress SaveAssembler::Start(SaveRequest request, Clock::time_point now) {
  SaveProgress progress;
  if (request.site.empty()) request.site = kDefaultSite;
  SaveOutcome outcome;
  outcome.request = request;
  outcome.key = SaveKey(request);
  outcome.started = now;
  outcome.status = ValidateSaveRequest(request);
  if (!outcome.status.ok()) {
    progress.finished.push_back(std::move(outcome));
    return progress;
  }
  // A save replayed after a restart: the audit log knows the version it made.
  if (!request.requester.empty()) {
    auto earlier = store_.FindRequest(request.requester, request.request_id);
    if (earlier.ok() && earlier->has_value() && (*earlier)->op == "save" &&
        (*earlier)->map == request.map_name) {
      outcome.version = (*earlier)->version;
      outcome.message = "already saved as version " + std::to_string((*earlier)->version);
      progress.finished.push_back(std::move(outcome));
      return progress;
    }
  }
  auto save = std::make_unique<PendingSave>();
  save->key = outcome.key;
  save->pull = !request.robot.empty();
  save->map_name = PushName(request);
  save->started = now;
  save->next_resend = now;
  if (save->pull) {
    if (!mirrors_.count(request.robot)) {
      mirrors_[request.robot] = std::make_unique<LiveMirror>();
      progress.new_robots.push_back(request.robot);
    }
    save->publish_all_id = ++next_publish_all_id_;
    progress.publish_all.push_back({request.robot, save->publish_all_id});
    save->next_resend = After(now, params_.pull_settle_s);
  }
  save->request = std::move(request);
  const std::string key = save->key;
  pending_[key] = std::move(save);
  TryFinishGuarded(key, false, now, &progress);  // finishes now when everything arrived already
  return progress;
}

SaveProgress SaveAssembler::OnMapperLayers(const std::string& robot, const MapperLayers& reply,
                                           Clock::time_point now) {
  SaveProgress progress;
  for (const auto& [key, save] : pending_) {
    if (!save->pull || save->request.robot != robot || save->publish_all_id != reply.request_id ||
        save->mapper_layers) {
      continue;
    }
    // A refusal lists nothing: the save keeps the rule of mappers that do not list.
    save->mapper_layers = reply.ok ? reply.layers : std::vector<std::string>{};
    const std::string pending_key = key;  // TryFinish may erase the entry
    TryFinishGuarded(pending_key, false, now, &progress);
    break;
  }
  return progress;
}

SaveProgress SaveAssembler::OnPushed(const std::string& map_name, Clock::time_point now) {
  SaveProgress progress;
  for (const auto& [key, save] : pending_) {
    if (save->pull || save->map_name != map_name) continue;
    const std::string pending_key = key;  // TryFinish may erase the entry
    TryFinishGuarded(pending_key, false, now, &progress);
    break;
  }
  return progress;
}

SaveProgress SaveAssembler::Poll(Clock::time_point now) {
  SaveProgress progress;
  std::vector<std::string> keys;
  for (const auto& [key, save] : pending_) keys.push_back(key);
  for (const std::string& key : keys) {
    auto it = pending_.find(key);
    if (it == pending_.end()) continue;
    const bool timed_out = SecondsBetween(it->second->started, now) > params_.save_timeout_s;
    TryFinishGuarded(key, timed_out, now, &progress);
  }
  DropAbandoned(now, &progress);
  return progress;
}

void SaveAssembler::DropAbandoned(Clock::time_point now, SaveProgress* progress) {
  for (auto it = staging_.begin(); it != staging_.end();) {
    bool wanted = false;
    for (const auto& [key, save] : pending_) wanted |= save->map_name == it->first;
    if (!wanted && SecondsBetween(it->second->last, now) > params_.staging_timeout_s) {
      ++progress->abandoned_pushes;
      it = staging_.erase(it);
    } else {
      ++it;
    }
  }
}

SaveOutcome SaveAssembler::OutcomeOf(const PendingSave& save) const {
  SaveOutcome outcome;
  outcome.request = save.request;
  outcome.key = save.key;
  outcome.started = save.started;
  return outcome;
}

void SaveAssembler::End(const std::string& key, SaveOutcome outcome, SaveProgress* progress) {
  auto it = pending_.find(key);
  if (it != pending_.end()) {
    if (!it->second->pull) staging_.erase(it->second->map_name);
    pending_.erase(it);
  }
  progress->finished.push_back(std::move(outcome));
}

void SaveAssembler::TryFinishGuarded(const std::string& key, bool timed_out, Clock::time_point now,
                                     SaveProgress* progress) {
  try {
    TryFinish(key, timed_out, now, progress);
  } catch (const std::exception& e) {
    // A bug or memory exhaustion: the save ends with an error reply rather than silence.
    progress->warnings.push_back(std::string("save failed: ") + e.what());
    auto it = pending_.find(key);
    if (it == pending_.end()) return;
    SaveOutcome outcome = OutcomeOf(*it->second);
    outcome.status = common::InternalError(std::string("internal error: ") + e.what());
    End(key, std::move(outcome), progress);
  }
}

void SaveAssembler::TryFinish(const std::string& key, bool timed_out, Clock::time_point now,
                              SaveProgress* progress) {
  auto it = pending_.find(key);
  if (it == pending_.end()) return;
  PendingSave& save = *it->second;
  Gathered gathered = save.pull ? GatherPull(save, now) : GatherPush(save);
  if (gathered.awaiting_layers && now >= save.next_resend) {
    // The request or its answer was lost (or the mapper is still publishing): the same request
    // id again; a mapper that has done it answers from its reply cache.
    progress->publish_all.push_back({save.request.robot, save.publish_all_id});
    save.next_resend = After(now, params_.resend_interval_s);
  }
  if (gathered.settling) return;
  SaveOutcome outcome = OutcomeOf(save);
  if (!gathered.invalid.empty()) {
    outcome.status = common::InvalidArgumentError(gathered.invalid);
    End(key, std::move(outcome), progress);
    return;
  }
  if (!gathered.missing.empty()) {
    if (timed_out) {
      outcome.status = common::UnavailableError(
          "timed out after " + std::to_string(static_cast<int>(params_.save_timeout_s)) +
          " s waiting for: " + JoinList(gathered.missing));
      outcome.timed_out = true;
      End(key, std::move(outcome), progress);
    } else if (now >= save.next_resend) {
      for (ResendAsk& ask : gathered.resends) progress->resends.push_back(std::move(ask));
      if (!gathered.resends.empty()) ++save.resend_rounds;
      save.next_resend = After(now, params_.resend_interval_s);
    }
    return;
  }
  Store(save, gathered, now, &outcome);
  End(key, std::move(outcome), progress);
}

SaveAssembler::Gathered SaveAssembler::GatherPull(PendingSave& save, Clock::time_point now) {
  const SaveRequest& request = save.request;
  LiveMirror& mirror = *mirrors_.at(request.robot);
  Gathered g;
  g.assembler = &mirror.assembler;
  g.wanted = request.layers;
  if (g.wanted.empty()) {
    // Every robot-agnostic layer the mapper lists in its answer to the request: each is waited
    // for (and asked for again) like a named layer.
    const double waited_s = SecondsBetween(save.started, now);
    if (save.mapper_layers) {
      for (const std::string& layer : *save.mapper_layers) {
        if (!IsDerivedLayer(layer)) g.wanted.push_back(layer);
      }
    } else if (waited_s < 4 * params_.pull_settle_s) {
      g.settling = true;
      g.awaiting_layers = true;
      return g;
    }
    if (g.wanted.empty()) {
      // No list (a mapper that does not answer, or lists nothing robot-agnostic): every
      // robot-agnostic layer announced; wait until none is new.
      for (const auto& [layer, when] : mirror.manifest_time) {
        if (!IsDerivedLayer(layer)) g.wanted.push_back(layer);
      }
      if (waited_s < params_.pull_settle_s) {
        g.settling = true;
        return g;
      }
    }
  }
  if (g.wanted.empty()) {
    g.missing.push_back("any layer (is the mapper of '" + request.robot + "' running?)");
  }
  for (const std::string& layer : g.wanted) {
    auto it = mirror.manifest_time.find(layer);
    const bool fresh = it != mirror.manifest_time.end() && it->second >= save.started;
    if (fresh && mirror.assembler.Complete(layer)) continue;
    g.missing.push_back(layer);
    std::optional<TileRequest> r;
    if (fresh) r = mirror.assembler.MissingRequest(layer);
    if (!r) {
      r = TileRequest();  // no current manifest: the whole layer (its manifest comes with it)
      r->layer = layer;
    }
    // Mappers answer requests naming their robot and map.
    r->robot = request.robot;
    r->map_name = mirror.map_name;
    g.resends.push_back({request.robot, std::move(*r)});
  }
  // Obstacles published after the request. The registry travels as one message, lost whole on a
  // lossy link, so it is asked for again ("#obstacles") every round until a fresh one arrives.
  // A mapper known to keep one (a registry arrived before the request) is waited for until the
  // save times out: saving without it would lose its obstacles without a word. A mapper never
  // heard to have one (no terrain layer) gets 4 x pull_settle_s.
  const bool obstacles_fresh = mirror.obstacles && mirror.obstacles_time >= save.started;
  const bool keeps_registry = mirror.obstacles.has_value();
  if (!obstacles_fresh &&
      (keeps_registry || SecondsBetween(save.started, now) < 4 * params_.pull_settle_s)) {
    g.missing.push_back("obstacles");
    TileRequest r;
    r.layer = kResendObstacles;
    r.robot = request.robot;
    r.map_name = mirror.map_name;
    g.resends.push_back({request.robot, std::move(r)});
  }
  if (mirror.obstacles) g.obstacles = &*mirror.obstacles;
  if (mirror.complete_octomap) g.octomap = &*mirror.complete_octomap;
  return g;
}

SaveAssembler::Gathered SaveAssembler::GatherPush(PendingSave& save) {
  const SaveRequest& request = save.request;
  Gathered g;
  g.wanted = request.layers;
  auto it = staging_.find(save.map_name);
  Staging* staging = it == staging_.end() ? nullptr : it->second.get();
  if (staging == nullptr) {
    g.missing = g.wanted;
    if (request.expect_obstacles) g.missing.push_back(kResendObstacles);
    if (request.expect_octomap) g.missing.push_back(kResendOctomap);
  } else {
    if (!staging->invalid.empty()) {
      g.invalid = staging->invalid;
      return g;
    }
    g.assembler = &staging->assembler;
    g.push_staging = staging;
    g.push_robot = staging->robot;
    for (const std::string& layer : g.wanted) {
      if (!staging->manifests.count(layer) || !staging->assembler.Complete(layer)) {
        g.missing.push_back(layer);
      }
    }
    if (staging->obstacles) g.obstacles = &*staging->obstacles;
    if (staging->octomap.complete()) g.octomap = &*staging->octomap.complete();
    if (request.expect_obstacles && !g.obstacles) g.missing.push_back(kResendObstacles);
    if (request.expect_octomap && !g.octomap) g.missing.push_back(kResendOctomap);
  }
  for (const std::string& layer : g.missing) {
    std::optional<TileRequest> r;
    if (staging != nullptr && staging->manifests.count(layer)) {
      r = staging->assembler.MissingRequest(layer);
    }
    if (!r) {
      r = TileRequest();
      r->layer = layer;
    }
    r->map_name = save.map_name;
    g.resends.push_back({"", std::move(*r)});
  }
  return g;
}

void SaveAssembler::Store(const PendingSave& save, Gathered& gathered, Clock::time_point now,
                          SaveOutcome* outcome) {
  // A map holds layers of one grid; layers of another grid (a mapper's finer 2-D occupancy)
  // become companion maps "<map>-<first layer>".
  const std::vector<std::vector<std::string>> groups =
      GroupByGeometry(*gathered.assembler, gathered.wanted);
  std::string companions;
  Status failed;
  for (size_t g = 0; g < groups.size(); ++g) {
    std::string event;
    auto info = StoreGroup(save, gathered, groups[g], g > 0, now, &event);
    if (!info.ok()) {
      failed = info.status();
      break;
    }
    ++outcome->saved_maps;
    outcome->events.push_back(std::move(event));
    if (g == 0) {
      outcome->version = info->version;
      outcome->layers = info->layers;
    } else {
      companions += (companions.empty() ? "" : ", ") + info->name + " v" +
                    std::to_string(info->version) + " (" + std::to_string(info->layers.size()) +
                    " layers of another grid)";
    }
    outcome->maps.push_back(std::move(info).value());
  }
  if (!failed.ok()) {
    outcome->status = failed;
  } else if (groups.empty()) {
    outcome->status = common::InternalError("no layer to save");
  } else {
    outcome->message = "saved version " + std::to_string(outcome->version) +
                       (companions.empty() ? "" : "; also " + companions);
  }
}

std::vector<StoredLayer> SaveAssembler::TakeEncodedLayers(Staging* staging,
                                                          const TileAssembler& assembler,
                                                          const std::vector<std::string>& group) {
  std::vector<StoredLayer> out;
  for (const std::string& layer : group) {
    auto e = staging->encoded.find(layer);
    if (e == staging->encoded.end() || e->second.tiles.empty()) continue;
    StoredLayer stored;
    stored.name = layer;
    stored.tile_size = e->second.tile_size;
    for (auto& [key, tile] : e->second.tiles) {
      if (assembler.HeldChecksum(layer, key.first, key.second) == tile.raw_crc32) {
        stored.tiles.push_back(std::move(tile));
      }
    }
    e->second.tiles.clear();
    out.push_back(std::move(stored));
  }
  return out;
}

Provenance SaveAssembler::ProvenanceOf(const PendingSave& save,
                                       const std::string& push_robot) const {
  const SaveRequest& request = save.request;
  Provenance p;
  p.source_robot =
      save.pull ? request.robot : (push_robot.empty() ? request.requester : push_robot);
  p.source_profile = request.profile;
  p.code_version = request.code_version;
  p.parameters = request.parameters;
  if (!request.profile.empty()) {
    auto profile = store_.GetProfile(request.profile);
    if (profile.ok()) p.source_profile_hash = profile->content_hash;
  }
  if (!ValidateName("robot", p.source_robot).ok()) p.source_robot.clear();
  return p;
}

Result<MapInfo> SaveAssembler::StoreGroup(const PendingSave& save, Gathered& gathered,
                                          const std::vector<std::string>& group, bool companion,
                                          Clock::time_point now, std::string* event) {
  const SaveRequest& request = save.request;
  MapSnapshot snapshot;
  Staging* staging = gathered.push_staging;
  if (staging != nullptr) {
    snapshot.encoded_layers = TakeEncodedLayers(staging, *gathered.assembler, group);
    snapshot.encoded_layers_checked = true;
  }
  // A push's staging goes once this save ends: its layers move out of it.
  auto base = CollectLayers(gathered.assembler, group, /*take=*/staging != nullptr);
  if (!base.ok()) return base.status();
  snapshot.base = std::move(base).value();
  snapshot.site = request.site;
  snapshot.name = request.map_name;
  if (companion) {
    std::string suffix = group.front();
    std::replace(suffix.begin(), suffix.end(), '/', '_');
    snapshot.name += "-" + suffix;
  }
  snapshot.provenance = ProvenanceOf(save, gathered.push_robot);
  if (!companion && gathered.obstacles) snapshot.obstacles = *gathered.obstacles;
  if (!companion && gathered.octomap) snapshot.octomap = *gathered.octomap;
  // Companion maps are not request replays: only the main save carries the request id.
  const WriteContext ctx{request.requester.empty() ? "unknown" : request.requester,
                         companion ? 0 : request.request_id, 0};
  const auto t0 = Clock::now();
  auto info = store_.SaveMap(snapshot, ctx);
  if (!info.ok()) return info.status();
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "saved %s/%s v%lld from %s (%zu layers, %zu obstacles%s): waited %.0f ms for data "
                "(%d resend rounds), stored in %.0f ms",
                request.site.c_str(), snapshot.name.c_str(), static_cast<long long>(info->version),
                save.pull ? ("mapper of " + request.robot).c_str() : "a push", info->layers.size(),
                snapshot.obstacles.obstacles.size(), snapshot.octomap ? ", octomap" : "",
                SecondsBetween(save.started, now) * 1e3, save.resend_rounds,
                SecondsBetween(t0, Clock::now()) * 1e3);
  *event = buf;
  return info;
}

}  // namespace cairn::mapstore
