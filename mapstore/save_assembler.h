#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/layers.h"
#include "common/obstacle.h"
#include "common/status.h"
#include "mapstore/map_store.h"
#include "mapstore/octomap_chunks.h"
#include "common/tile_assembler.h"

/// @file
/// SaveAssembler: how the map store puts a save together from pieces that arrive one by one
/// (the domain half of OP_SAVE; cairn-mapstore's MapstoreService only converts messages and
/// moves them). No LCM: it works on core tiles, manifests and chunks, and on a MapStore.
///
/// Saves come two ways:
/// - push: the client stages a manifest and the tiles of every layer, the obstacles and the
///   OctoMap under the name "<request_id>/<map>" (StageTile, StageManifest, StageObstacles,
///   StageOctomapChunk), then asks to save naming the layers (Start). A save finishes the moment
///   its last piece arrives (OnPushed), or when Poll finds it complete; the store is handed the
///   pushed compressed tiles as they came (checked on receipt), so it keeps their bytes without
///   reading the cells again.
/// - pull: a save request naming a robot. The assembler follows that robot's live map (the
///   Mirror* calls feed it), asks its mapper to publish everything (SaveProgress::publish_all)
///   and saves its robot-agnostic layers (cost and geometric profile layers are left out: the
///   store derives them per profile) once every wanted layer is complete in a manifest newer
///   than the request. A mapper's layers on another grid become companion maps
///   "<map>-<layer>". A pull naming no layers wants every robot-agnostic layer the mapper's
///   answer to that request lists (OnMapperLayers): it asks again with the same request id every
///   resend round until the answer comes, then asks for each listed layer still missing, so a
///   manifest lost on the link is waited for rather than silently left out. A mapper that never
///   answers (an older one) gets 4 x pull_settle_s; then every robot-agnostic layer announced is
///   taken (the rule before mappers listed their layers).
///
/// Missing pieces are asked for again every resend_interval_s (SaveProgress::resends); a save
/// still incomplete after save_timeout_s fails with kUnavailable naming what is missing. Staged
/// data nobody asks to save are dropped after staging_timeout_s. What pushes make the store hold
/// is bounded by max_staged_bytes, every push together: each layer's canvas (its whole grid, as
/// its first tile allocates it), the compressed tiles kept as they came, manifests, obstacles
/// and OctoMap chunks; and by max_pushes names staged at once. Time is passed in (`now`), so
/// tests need no clock.
///
/// Not thread-safe: one caller at a time.

namespace cairn::mapstore {

using common::CheckedTile;
using common::TileAssembler;
using common::TileHeader;
using common::TileManifest;
using common::TileRequest;

/// Pseudo layer names a push client (or, for obstacles, a mapper) is asked to send again.
using layers::kResendObstacles;
using layers::kResendOctomap;

struct SaveAssemblerParams {
  double save_timeout_s{20.0};            ///< a save gives up waiting for its data after this
  double resend_interval_s{0.05};         ///< asks again for missing data this often
  double staging_timeout_s{30.0};         ///< pushed data no save asked for are dropped after this
  double pull_settle_s{0.5};              ///< pull naming no layers: 4 x this for the mapper's list
  int64_t max_staged_bytes{512LL << 20};  ///< pushed data held at once, every push together
  int max_pushes{64};                      ///< push names staged at once

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// OP_SAVE in core terms.
struct SaveRequest {
  std::string requester;  ///< "" is "unknown" in the audit log
  int64_t request_id{0};
  std::string site;                 ///< "" = kDefaultSite
  std::string map_name;             ///< the map saved
  std::string robot;                ///< set: a pull save from this robot's mapper
  std::vector<std::string> layers;  ///< push: required; pull: "" = every robot-agnostic layer
  std::string profile;              ///< the profile the map was made with (provenance)
  std::string code_version;         ///< provenance
  std::string parameters;           ///< provenance
  bool expect_obstacles{false};     ///< push: wait for pushed obstacles
  bool expect_octomap{false};       ///< push: wait for a pushed OctoMap
};

/// A mapper's answer (<robot>.MAP.CONTROL_REPLY) to the OP_PUBLISH_ALL a pull save sent.
struct MapperLayers {
  int64_t request_id{0};
  bool ok{true};                    ///< the mapper did it (STATUS_OK)
  std::vector<std::string> layers;  ///< every layer whose manifest its publication sent
};

/// "<requester>#<request_id>": what identifies a request (and its replays).
std::string SaveKey(const SaveRequest& request);
/// "<request_id>/<map>": the name pushed data are staged under.
std::string PushName(const SaveRequest& request);

/// How a save ended: the reply's content.
struct SaveOutcome {
  SaveRequest request;  ///< site filled in
  std::string key;      ///< SaveKey(request)
  std::chrono::steady_clock::time_point started;
  common::Status status;
  int64_t version{0};               ///< the map's new version (0 on failure)
  std::vector<std::string> layers;  ///< the map's layers
  std::vector<MapInfo> maps;        ///< the map, then its companion maps
  std::string message;              ///< "" on failure (the status says why)
  std::vector<std::string> events;  ///< log lines: one per stored map
  int saved_maps{0};                ///< maps stored (the map and its companions)
  bool timed_out{false};
};

/// Something a pending save needs sent: a request for missing tiles of a push
/// (MAPSTORE.PUSH.TILE_RESEND) or of a robot's live map (<robot>.MAP.TILE_RESEND).
struct ResendAsk {
  std::string pull_robot;  ///< set: ask this robot's mapper; empty: ask the pusher
  TileRequest tiles;
};

/// OP_PUBLISH_ALL to send to a robot's mapper; a save sends the same request id every time, so
/// the mapper publishes everything once and answers the others from its reply cache.
struct PublishAllAsk {
  std::string robot;
  int64_t request_id{0};
};

/// What the caller must do after a call: reply to finished saves, send resend requests, and ask
/// mappers to publish everything.
struct SaveProgress {
  std::vector<SaveOutcome> finished;
  std::vector<ResendAsk> resends;
  std::vector<PublishAllAsk> publish_all;  ///< mappers that must publish every layer
  std::vector<std::string> new_robots;     ///< robots followed from now on (feed Mirror*)
  int abandoned_pushes{0};                 ///< staged pushes dropped (nobody asked to save them)
  std::vector<std::string> warnings;       ///< unexpected failures (also in their outcome)
};

class SaveAssembler {
 public:
  using Clock = std::chrono::steady_clock;

  /// `store` must outlive the assembler.
  SaveAssembler(MapStore& store, SaveAssemblerParams params);
  ~SaveAssembler();
  SaveAssembler(const SaveAssembler&) = delete;
  SaveAssembler& operator=(const SaveAssembler&) = delete;

  // ---- Pushed data, by map name "<request_id>/<map>" ----
  enum class Intake {
    kHeld,         ///< kept
    kRefused,      ///< bad data (or a name without '/'): count it as a dropped input
    kStagingFull,  ///< beyond max_staged_bytes or max_pushes: dropped
  };
  /// A pushed tile. `codec` and `bytes`: a compressed tile's codec (mapstore::Codec) and bytes
  /// as they came; the store keeps them instead of compressing the cells again.
  Intake StageTile(const CheckedTile& tile, std::optional<int> codec, std::string bytes,
                   Clock::time_point now);
  Intake StageManifest(const TileManifest& manifest, Clock::time_point now);
  /// Pushed obstacles, or why they could not be read (the save then fails as invalid).
  Intake StageObstacles(const std::string& map_name,
                        common::Result<common::ObstacleRegistry> registry, Clock::time_point now);
  Intake StageOctomapChunk(const std::string& map_name, const OctomapChunk& chunk,
                           Clock::time_point now);

  // ---- Live maps of robots pulled from (only robots in SaveProgress::new_robots) ----
  /// False when the tile was refused (or the robot is not followed).
  bool MirrorTile(const std::string& robot, const CheckedTile& tile);
  void MirrorManifest(const std::string& robot, const TileManifest& manifest,
                      Clock::time_point now);
  void MirrorObstacles(const std::string& robot, common::ObstacleRegistry registry,
                       Clock::time_point now);
  /// False for an inconsistent chunk.
  bool MirrorOctomapChunk(const std::string& robot, const OctomapChunk& chunk);
  /// The mapper of `robot` answered a control request: the pull save whose OP_PUBLISH_ALL has
  /// this request id learns the layers the mapper has (the first answer counts; replays and
  /// answers to other requests are ignored). The save finishes now when nothing is missing.
  SaveProgress OnMapperLayers(const std::string& robot, const MapperLayers& reply,
                              Clock::time_point now);
  /// OP_PUBLISH_ALL request ids start above `base` (a process passes its wall-clock start, so
  /// that ids stay unique across restarts: a mapper answers a known id from its reply cache).
  void set_publish_all_id_base(int64_t base) { next_publish_all_id_ = base; }

  // ---- Saves ----
  /// Starts a save. A bad request, or one the audit log says was saved already (a replay after
  /// a restart), finishes at once; so does a push whose data all arrived already.
  SaveProgress Start(SaveRequest request, Clock::time_point now);
  /// Pushed data for `map_name` arrived: the save waiting for them finishes now when nothing is
  /// missing any more.
  SaveProgress OnPushed(const std::string& map_name, Clock::time_point now);
  /// Finishes, asks again for, or gives up on every pending save; drops abandoned pushes.
  SaveProgress Poll(Clock::time_point now);

  /// Whether a save with this key (SaveKey) is waiting for data.
  bool IsPending(const std::string& key) const;
  int64_t pending_saves() const;
  /// Bytes staged by every push together (as max_staged_bytes counts them).
  int64_t staged_bytes() const;

 private:
  struct Staging;
  struct PendingSave;
  struct LiveMirror;
  struct Gathered;

  /// Tries to finish a pending save (erasing it when it ends); appends to `progress`.
  void TryFinish(const std::string& key, bool timed_out, Clock::time_point now,
                 SaveProgress* progress);
  void TryFinishGuarded(const std::string& key, bool timed_out, Clock::time_point now,
                        SaveProgress* progress);
  /// What a pull or push save has and lacks now.
  Gathered GatherPull(PendingSave& save, Clock::time_point now);
  Gathered GatherPush(PendingSave& save);
  /// Stores the gathered layers: the map, and a companion map per other grid.
  void Store(const PendingSave& save, Gathered& gathered, Clock::time_point now,
             SaveOutcome* outcome);
  /// Stores one grid's layers (the map itself, or a companion map); `event` gets its log line.
  common::Result<MapInfo> StoreGroup(const PendingSave& save, Gathered& gathered,
                                     const std::vector<std::string>& group, bool companion,
                                     Clock::time_point now, std::string* event);
  Provenance ProvenanceOf(const PendingSave& save, const std::string& push_robot) const;
  /// The compressed tiles pushed for `group` that are the tiles the assembler holds (same CRC,
  /// checked when each was decoded on receipt): the store keeps them as they came. They move
  /// out of the staging.
  static std::vector<StoredLayer> TakeEncodedLayers(Staging* staging,
                                                    const TileAssembler& assembler,
                                                    const std::vector<std::string>& group);
  /// Ends a save: its staging goes, its outcome is appended.
  void End(const std::string& key, SaveOutcome outcome, SaveProgress* progress);
  SaveOutcome OutcomeOf(const PendingSave& save) const;
  /// The staging of a push name, made if new; null when a new one would exceed max_pushes.
  Staging* StagingFor(const std::string& map_name, Clock::time_point now);
  /// Whether `more` bytes fit the staging budget.
  bool Fits(int64_t more) const;
  LiveMirror* MirrorOf(const std::string& robot);
  void DropAbandoned(Clock::time_point now, SaveProgress* progress);

  MapStore& store_;
  SaveAssemblerParams params_;
  std::map<std::string, std::unique_ptr<Staging>> staging_;      // by push name
  std::map<std::string, std::unique_ptr<PendingSave>> pending_;  // by SaveKey
  std::map<std::string, std::unique_ptr<LiveMirror>> mirrors_;   // by robot
  int64_t next_publish_all_id_{0};
};

}  // namespace cairn::mapstore
