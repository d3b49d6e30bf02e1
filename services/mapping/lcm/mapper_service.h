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
#include "cairn/lcmt_lidar_ranges.hpp"
#include "cairn/lcmt_map_control_reply.hpp"
#include "cairn/lcmt_map_control_request.hpp"
#include "cairn/lcmt_mapstore_reply.hpp"
#include "cairn/lcmt_odometry.hpp"
#include "cairn/lcmt_point_cloud_slice.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_tile_resend_request.hpp"

#include "common/robot_profile.h"
#include "common/status.h"
#include "services/mapping/lcm/map_publisher.h"
#include "services/mapping/lcm/mapper_streams.h"
#include "services/mapping/mapper_config.h"
#include "services/mapping/mapper_core.h"
#include "services/mapping/mapper_inputs.h"
#include "services/runtime/node.h"
#include "services/runtime/revolution_assembler.h"

/// @file
/// MapperService: one robot's mapper on the bus (the process is cairn-mapper). It only converts
/// and moves messages: MapperInputs resolves poses and drops bad points, MapperCore maps,
/// MapPublisher sends the layers.
///
/// Reads <robot>.LIDAR_RANGES and <robot>.LIDAR (slices as ranges or as points, assembled into
/// revolutions), <robot>.SCAN, <robot>.POSE or
/// <robot>.ODOM (per pose_source), <robot>.IMU, <robot>.MAP.TILE_RESEND and
/// <robot>.MAP.CONTROL. Writes, with map_name "live", what MapPublisher lists (the layers'
/// tiles, manifests, registry and OctoMap), and:
/// - <robot>.MAP.CONTROL_REPLY: answers (a replayed request id gets the first answer again);
/// - MAPSTORE.REQUEST, with long_term_store set: every long_term_save_period_s a pull save of
///   the long-term layer (OP_SAVE naming this robot and the layer; cairn-mapstore then fetches
///   the tiles from <robot>.MAP.OCCUPANCY). Replies are read on MAPSTORE.REPLY and counted
///   (long_term_saves, long_term_save_failures). This is seed 001's periodic map_saver; the
///   main restores the stored layer at start (DynamicMapperLayerParams::long_term_restore).
///
/// Work happens off the LCM thread: handlers only decode, check and queue; a worker thread
/// maps revolutions (at most max_pending_revolutions wait; older ones are dropped and counted)
/// and publishes; a layer that runs on a thread of its own (the OctoMap) gets one, fed its due
/// revolutions. In replay mode everything runs inline, in log order, so the same log always gives
/// the same maps.

namespace cairn::mapping {

/// Looks a profile up by name (the main reads config/profiles); NOT_FOUND when unknown.
using ProfileResolver = std::function<common::Result<common::RobotProfile>(const std::string&)>;

class SonarMapperLayer;

class MapperService {
 public:
  enum class Mode { kLive, kReplay };

  /// Live mode subscribes on `node` and starts the worker threads; replay mode subscribes to
  /// nothing (feed it with HandleLogged). `extra_layers` join the configured ones (after them);
  /// `extra_streams` join RegisteredStreams(). `node` must outlive the service.
  /// @throws std::invalid_argument for invalid params or profiles, or a stream a layer takes
  /// with no converter.
  MapperService(runtime::Node& node, MapperParams params,
                const std::vector<common::RobotProfile>& profiles, ProfileResolver resolver,
                Mode mode = Mode::kLive,
                std::vector<std::unique_ptr<MapperLayer>> extra_layers = {},
                std::vector<StreamConverter> extra_streams = {});
  ~MapperService();
  MapperService(const MapperService&) = delete;
  MapperService& operator=(const MapperService&) = delete;

  /// Replay: handles one logged message of any channel (others are ignored), in log order.
  void HandleLogged(const std::string& channel, const void* data, int size);
  /// Writes every layer under `dir` (MapperCore::WriteOutputs). Call from the replay thread or
  /// after the worker stopped.
  common::Status WriteOutputs(const std::string& dir);

  /// Stops the worker threads (idempotent; the destructor does it).
  void Stop();
  int64_t revolutions() const { return revolutions_.load(); }
  const MapperParams& params() const { return params_; }

 private:
  struct Job {
    enum class Kind { kRevolution, kScan, kReading, kControl, kResend } kind;
    PreparedRevolution revolution;
    common::LaserScan scan;
    std::unique_ptr<SensorReading> reading;
    cairn::lcmt_map_control_request control{};
    cairn::lcmt_tile_resend_request resend{};
  };
  /// A layer fed on a thread of its own: a single slot, the newest revolution wins.
  struct LayerWorker {
    MapperLayer* layer{nullptr};
    std::mutex layer_mutex;  // guards the layer itself (inputs, reads, reset)
    std::mutex slot_mutex;   // guards pending
    std::condition_variable cv;
    std::optional<PreparedRevolution> pending;
    std::thread thread;
  };

  // LCM-thread side (or the replay thread): decode, check, resolve poses, queue.
  void Subscribe();
  /// A lidar slice decoded from either message (points or ranges), or why it was refused.
  void OnSlice(common::Result<common::LidarSlice> slice);
  void OnScan(const cairn::lcmt_laser_scan& msg);
  void OnPose(const cairn::lcmt_pose& msg);
  void OnOdometry(const cairn::lcmt_odometry& msg);
  void OnImu(const cairn::lcmt_imu& msg);
  void OnControl(const cairn::lcmt_map_control_request& msg);
  void OnResend(const cairn::lcmt_tile_resend_request& msg);
  void OnMapstoreReply(const cairn::lcmt_mapstore_reply& msg);
  void OnRevolution(common::LidarRevolution revolution);
  void OnStreamMessage(const StreamConverter& converter, const void* data, int size);
  void LogNewMounts();
  void Enqueue(Job job);

  // Worker side.
  void WorkerLoop();
  void LayerWorkerLoop(LayerWorker* worker);
  void Process(Job& job);
  /// Each ping's obstacles on <robot>.SONAR_DETECTIONS (lcmt_sonar_detection).
  void PublishDetections(SonarMapperLayer* layer);
  void ProcessRevolution(PreparedRevolution& job);
  /// Whether a destructive request is allowed by `allowed` (the config key `key`); logs the
  /// audit line, and fills the FORBIDDEN reply when it is not.
  bool Allowed(const cairn::lcmt_map_control_request& request, const char* op, const char* key,
               bool allowed, cairn::lcmt_map_control_reply* reply);
  void ProcessControl(const cairn::lcmt_map_control_request& request);
  void AddProfile(const cairn::lcmt_map_control_request& request,
                  cairn::lcmt_map_control_reply* reply);
  void RemoveProfile(const cairn::lcmt_map_control_request& request,
                     cairn::lcmt_map_control_reply* reply);
  void ClearShortTerm(const cairn::lcmt_map_control_request& request,
                      cairn::lcmt_map_control_reply* reply);
  void ResetMaps(const cairn::lcmt_map_control_request& request,
                 cairn::lcmt_map_control_reply* reply);
  void Snapshot(cairn::lcmt_map_control_reply* reply);
  void PublishDue(bool force);
  /// Asks cairn-mapstore to pull-save the long-term layer (worker thread).
  void RequestLongTermSave();
  /// Locks of the layers on threads of their own, all of them (reset, writing).
  std::vector<std::unique_lock<std::mutex>> LockAllLayers();
  std::unique_lock<std::mutex> LockLayer(const MapperLayer& layer);
  int64_t Now() const;

  runtime::Node& node_;
  MapperParams params_;
  ProfileResolver resolver_;
  Mode mode_;
  MapperCore core_;

  // LCM-thread state.
  runtime::RevolutionAssembler assembler_;
  MapperInputs inputs_;
  std::vector<StreamConverter> streams_;  // those of the streams the layers take

  // Work queue.
  std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<Job> queue_;
  common::TokenBuckets resend_limits_{common::TokenBucketsParams{}};  // LCM thread only
  int pending_revolutions_{0};
  std::atomic<bool> stop_{false};
  std::thread worker_;
  std::atomic<int64_t> revolutions_{0};
  std::vector<std::unique_ptr<LayerWorker>> layer_workers_;

  // Worker state.
  std::unique_ptr<MapPublisher> publisher_;
  std::chrono::steady_clock::time_point next_long_term_save_;
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
