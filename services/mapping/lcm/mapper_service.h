#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cairn/lcmt_imu.hpp"
#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_map_control_reply.hpp"
#include "cairn/lcmt_map_control_request.hpp"
#include "cairn/lcmt_mapstore_reply.hpp"
#include "cairn/lcmt_obstacle_registry.hpp"
#include "cairn/lcmt_odometry.hpp"
#include "cairn/lcmt_point_cloud_slice.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/robot_profile.h"
#include "common/status.h"
#include "services/mapping/mapper_core.h"
#include "services/mapping/pose_buffer.h"
#include "services/mapping/lcm/terrain_publisher.h"
#include "services/runtime/node.h"
#include "services/runtime/revolution_assembler.h"
#include "services/runtime/tiler.h"

/// @file
/// MapperService: one robot's mapper on the bus (the process is cairn-mapper).
///
/// Reads <robot>.LIDAR (slices, assembled into revolutions), <robot>.SCAN, <robot>.POSE or
/// <robot>.ODOM (per pose_source), <robot>.IMU, <robot>.MAP.TILE_RESEND and
/// <robot>.MAP.CONTROL. Writes, with map_name "live":
/// - <robot>.MAP.TILES / .MAP.MANIFEST: the terrain layers (elevation, elevation_variance,
///   observation_count, last_seen_s, ground_bound, slope, step, roughness, ditch_depth,
///   ditch_width and cost/<profile> for every profile) and occupancy_logodds as float tiles,
///   only the tiles that changed, at publish_period_s (slow_publish_period_s for the base
///   statistics), with every manifest again at the slow period;
/// - <robot>.MAP.OCCUPANCY: the 2-D occupancy (0..100, -1 unknown) as int8 tiles, and, when
///   the dynamic layers are on, short_term, long_term and final (seed 001);
/// - <robot>.MAP.OBSTACLES: the obstacle registry, with every profile's verdicts;
/// - <robot>.MAP.OCTOMAP: the OctoMap's .bt stream in chunks;
/// - <robot>.MAP.CONTROL_REPLY: answers (a replayed request id gets the first answer again);
/// - MAPSTORE.REQUEST, with long_term_store set: every long_term_save_period_s a pull save of
///   the long-term layer (OP_SAVE naming this robot and the layer; cairn-mapstore then fetches
///   the tiles from <robot>.MAP.OCCUPANCY). Replies are read on MAPSTORE.REPLY and counted
///   (long_term_saves, long_term_save_failures). This is seed 001's periodic map_saver; the
///   main restores the stored layer at start (MapperCoreParams::long_term_restore).
///
/// Sensor poses. pose_source ground_truth: each slice's own sensor pose, accepted only when a
/// <robot>.POSE sample lies within max_pose_gap_s of the slice. odometry: the odometry pose at
/// the slice time (roll and pitch from the IMU when imu_attitude is on) composed with the
/// lidar mount, which is configured or, if not, measured once from the first slice. A slice
/// with no pose near its time is dropped and counted.
///
/// Work happens off the LCM thread: handlers only decode, check and queue; a worker thread
/// integrates revolutions (at most max_pending_revolutions wait; older ones are dropped and
/// counted) and publishes; the OctoMap has its own thread fed every
/// octomap_every_revolutions-th revolution. In replay mode everything runs inline, in log
/// order, so the same log always gives the same maps.

namespace cairn::mapping {

enum class PoseSource { kGroundTruth, kOdometry };

struct MapperParams {
  std::string robot;
  std::string map_name{"live"};
  PoseSource pose_source{PoseSource::kGroundTruth};
  double max_pose_gap_s{0.15};  ///< a slice needs a pose sample this close to its time
  bool imu_attitude{true};      ///< odometry poses take roll and pitch from the IMU
  double max_imu_gap_s{0.25};
  /// Base-to-lidar transform for odometry poses; without it, measured from the first slice.
  std::optional<common::Pose3> lidar_mount;
  double publish_period_s{0.2};
  double slow_publish_period_s{5.0};
  double registry_period_s{1.0};
  double occupancy_period_s{1.0};
  double octomap_period_s{5.0};
  int octomap_every_revolutions{10};
  int max_pending_revolutions{3};
  int tiles_per_burst{8};  ///< tiles sent back to back before a short pause
  double burst_pause_ms{1.0};
  std::string snapshot_dir{"var/mapper-snapshots"};  ///< OP_SNAPSHOT writes below it
  /// "SITE/MAP" in cairn-mapstore where the long-term layer is remembered across runs
  /// ("" = nowhere). Needs the dynamic layers.
  std::string long_term_store;
  /// How often the long-term layer is saved there (seed 001's "every so often"; 20 s).
  double long_term_save_period_s{20.0};
  /// How long cairn-mapper waits at start for the store to send the stored layer.
  double long_term_load_timeout_s{30.0};
  MapperCoreParams core;

  /// @throws std::invalid_argument naming a bad field.
  void Validate() const;
};

/// Looks a profile up by name (the main reads config/profiles); NOT_FOUND when unknown.
using ProfileResolver = std::function<common::Result<common::RobotProfile>(const std::string&)>;

class MapperService {
 public:
  enum class Mode { kLive, kReplay };

  /// Live mode subscribes on `node` and starts the worker threads; replay mode subscribes to
  /// nothing (feed it with HandleLogged). `node` must outlive the service.
  /// @throws std::invalid_argument for invalid params or profiles.
  MapperService(runtime::Node& node, MapperParams params,
                const std::vector<common::RobotProfile>& profiles, ProfileResolver resolver,
                Mode mode = Mode::kLive);
  ~MapperService();
  MapperService(const MapperService&) = delete;
  MapperService& operator=(const MapperService&) = delete;

  /// Replay: handles one logged message of any channel (others are ignored), in log order.
  void HandleLogged(const std::string& channel, const void* data, int size);
  /// Writes every layer, the registry and the OctoMap under `dir` (created): one raw float32
  /// file per layer (x fastest from the minimum corner), map.yaml with the geometry,
  /// obstacles.yaml, octomap.bt. Call from the replay thread or after the worker stopped.
  common::Status WriteOutputs(const std::string& dir);

  /// Stops the worker threads (idempotent; the destructor does it).
  void Stop();
  int64_t revolutions() const { return revolutions_.load(); }
  const MapperParams& params() const { return params_; }

 private:
  struct RevolutionJob {
    common::LidarRevolution revolution;
    RobotContext robot;
    double time_s{0.0};
  };
  struct Job {
    enum class Kind { kRevolution, kScan, kControl, kResend } kind;
    RevolutionJob revolution;
    common::LaserScan scan;
    cairn::lcmt_map_control_request control{};
    cairn::lcmt_tile_resend_request resend{};
  };

  // LCM-thread side (or the replay thread): decode, check, resolve poses, queue.
  void OnSlice(const cairn::lcmt_point_cloud_slice& msg);
  void OnScan(const cairn::lcmt_laser_scan& msg);
  void OnPose(const cairn::lcmt_pose& msg);
  void OnOdometry(const cairn::lcmt_odometry& msg);
  void OnImu(const cairn::lcmt_imu& msg);
  void OnControl(const cairn::lcmt_map_control_request& msg);
  void OnResend(const cairn::lcmt_tile_resend_request& msg);
  void OnMapstoreReply(const cairn::lcmt_mapstore_reply& msg);
  void OnRevolution(common::LidarRevolution revolution);
  /// The world pose of a sensor at `utime` whose producer reported `reported` (the sensor's
  /// pose by the producer's own localisation), per pose_source; nullopt without a pose near
  /// that time. `sensor` keys the measured mount of odometry poses.
  std::optional<common::Pose3> SensorPose(const std::string& sensor, int64_t utime,
                                          const common::Pose3& reported);
  /// The robot base pose at `utime` per pose_source.
  std::optional<common::Pose3> BasePose(int64_t utime);
  void Enqueue(Job job);

  // Worker side.
  void WorkerLoop();
  void OctomapLoop();
  void Process(Job& job);
  void ProcessRevolution(RevolutionJob& job);
  void ProcessControl(const cairn::lcmt_map_control_request& request);
  void ProcessResend(const cairn::lcmt_tile_resend_request& request);
  void PublishDue(bool force);
  void PublishTerrain(const std::vector<std::string>& layers, bool force, bool manifests);
  void PublishRegistry(bool force);
  void PublishOccupancy(bool force);
  void PublishOctomap(bool force);
  /// Asks cairn-mapstore to pull-save the long-term layer (worker thread).
  void RequestLongTermSave();
  /// Steps the dynamic layers at their rate, on sensor time (so a replay steps alike).
  void StepDynamicUpTo(int64_t utime);
  template <typename Msg>
  void Send(const std::string& channel, const std::vector<Msg>& messages);
  std::vector<std::string> FastLayers() const;
  std::vector<std::string> SlowLayers() const;
  int64_t Now() const;

  runtime::Node& node_;
  MapperParams params_;
  ProfileResolver resolver_;
  Mode mode_;
  MapperCore core_;

  // LCM-thread state.
  runtime::RevolutionAssembler assembler_;
  PoseBuffer ground_truth_;
  PoseBuffer odometry_;
  PoseBuffer imu_;                               // orientation only
  std::map<std::string, common::Pose3> mounts_;  // base -> sensor (odometry poses)
  bool warned_no_pose_{false};

  // Work queue.
  std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<Job> queue_;
  int pending_revolutions_{0};
  std::atomic<bool> stop_{false};
  std::thread worker_;
  std::atomic<int64_t> revolutions_{0};

  // OctoMap thread: a single slot, the newest revolution wins.
  std::mutex octomap_mutex_;  // guards octomap_pending_
  std::mutex tree_mutex_;     // guards the OctoMap itself (inserts, reads, reset)
  std::condition_variable octomap_cv_;
  std::optional<common::LidarRevolution> octomap_pending_;
  std::thread octomap_worker_;

  // Worker state.
  TerrainPublisher terrain_publisher_;
  runtime::LayerTiler occupancy_tiler_;
  std::vector<std::string> retired_layers_;
  std::string last_registry_bytes_;
  int64_t octomap_published_version_{-1};
  int64_t octomap_chunk_version_{0};
  int64_t occupancy_published_version_{-1};
  int64_t dynamic_published_updates_{-1};
  int64_t next_dynamic_utime_{0};
  std::chrono::steady_clock::time_point next_fast_, next_slow_, next_registry_, next_occupancy_,
      next_octomap_, next_long_term_save_;
  // Long-term saves in flight (request ids), shared with the LCM thread.
  std::mutex save_mutex_;
  std::map<int64_t, std::chrono::steady_clock::time_point> saves_in_flight_;
  int64_t next_save_request_id_{0};
  std::map<std::pair<std::string, int64_t>, cairn::lcmt_map_control_reply> replies_;
  std::deque<std::pair<std::string, int64_t>> reply_order_;
  bool announced_first_revolution_{false};
  common::GridGeometry announced_extent_;
};

}  // namespace cairn::mapping
