#include "services/mapping/lcm/mapper_service.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "cairn/lcmt_mapstore_request.hpp"
#include "cairn/lcmt_sonar_detection.hpp"

#include "common/channels.h"
#include "common/check.h"
#include "common/layers.h"
#include "common/log.h"
#include "services/mapping/derive.h"
#include "services/mapping/sonar_mapper_layer.h"
#include "services/runtime/conversions.h"

namespace cairn::mapping {
namespace {

using Clock = std::chrono::steady_clock;
using cairn::lcmt_map_control_reply;
using cairn::lcmt_map_control_request;

constexpr size_t kMaxReplies = 256;

std::string Ch(const std::string& robot, const char* stream) {
  return channels::ForRobot(robot, stream);
}

Clock::duration Period(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

MapperService::MapperService(runtime::Node& node, MapperParams params,
                             const std::vector<common::RobotProfile>& profiles,
                             ProfileResolver resolver, Mode mode,
                             std::vector<std::unique_ptr<MapperLayer>> extra_layers,
                             std::vector<StreamConverter> extra_streams)
    : node_(node),
      params_((params.Validate(), std::move(params))),
      resolver_(std::move(resolver)),
      mode_(mode),
      core_(params_.core),
      inputs_(params_.inputs) {
  params_.core.dynamic.long_term_restore.reset();  // the core took it; do not keep a copy
  resend_limits_ = common::TokenBuckets(params_.resend_limits);
  for (auto& layer : extra_layers) core_.AddLayer(std::move(layer));
  // The converters of the sensor streams the layers take.
  for (const std::string& stream : core_.ReadingStreams()) {
    auto has = [&](const StreamConverter& c) { return c.stream == stream; };
    auto extra = std::find_if(extra_streams.begin(), extra_streams.end(), has);
    auto registered = std::find_if(RegisteredStreams().begin(), RegisteredStreams().end(), has);
    CAIRN_THROW_UNLESS(extra != extra_streams.end() || registered != RegisteredStreams().end(),
                       "a mapper layer takes the stream " << stream << ", which has no converter");
    streams_.push_back(extra != extra_streams.end() ? *extra : *registered);
  }
  if (!profiles.empty()) {
    CAIRN_THROW_UNLESS(core_.terrain() != nullptr, "profiles need the terrain layer");
    for (const auto& p : profiles) core_.terrain()->AddProfile(p);
  }
  // Versions from the wall clock: a restarted mapper's layers supersede its predecessor's at
  // every receiver (the navigator, the store's mirror for pull saves).
  MapPublisher::Options options;
  options.robot = params_.robot;
  options.map_name = params_.map_name;
  options.tiles_per_burst = params_.tiles_per_burst;
  options.burst_pause_ms = params_.burst_pause_ms;
  options.version_base = mode == Mode::kLive ? runtime::LayerTiler::StartVersionBase() : 0;
  publisher_ = std::make_unique<MapPublisher>(
      node_, core_, options, [this](const MapperLayer& layer) { return LockLayer(layer); });
  next_long_term_save_ = Clock::now() + Period(params_.long_term_save_period_s);
  next_save_request_id_ = runtime::Node::WallUtime();  // unique across restarts
  if (mode_ == Mode::kLive) {
    // Layers that run on a thread of their own get one; the core leaves them to us.
    core_.set_defer_own_thread_layers(true);
    for (const auto& layer : core_.layers()) {
      if (!layer->schedule().own_thread) continue;
      auto worker = std::make_unique<LayerWorker>();
      worker->layer = layer.get();
      LayerWorker* w = worker.get();
      worker->thread = std::thread([this, w] { LayerWorkerLoop(w); });
      layer_workers_.push_back(std::move(worker));
    }
    Subscribe();
    worker_ = std::thread([this] { WorkerLoop(); });
  }
  std::string names;
  if (core_.terrain() != nullptr) {
    for (const auto& p : core_.terrain()->profiles()) names += (names.empty() ? "" : ",") + p.name;
  }
  std::string layer_names;
  for (const auto& layer : core_.layers()) {
    layer_names += (layer_names.empty() ? "" : ",") + layer->name();
  }
  node_.Event("mapping %s for profiles [%s], layers [%s], poses from %s", params_.robot.c_str(),
              names.c_str(), layer_names.c_str(),
              params_.inputs.pose_source == PoseSource::kGroundTruth ? "ground truth" : "odometry");
  if (!core_.long_term_restore_status().ok()) {
    node_.Warn("long_term_restore", "the stored long-term layer was not used: " +
                                        core_.long_term_restore_status().message());
  }
  if (!params_.long_term_store.empty()) {
    node_.Event("saving the long-term layer to %s every %.0f s", params_.long_term_store.c_str(),
                params_.long_term_save_period_s);
  }
  node_.SetState(runtime::HealthState::kReady);
}

MapperService::~MapperService() { Stop(); }

void MapperService::Stop() {
  if (stop_.exchange(true)) return;
  queue_cv_.notify_all();
  for (auto& w : layer_workers_) w->cv.notify_all();
  if (worker_.joinable()) worker_.join();
  for (auto& w : layer_workers_) {
    if (w->thread.joinable()) w->thread.join();
  }
}

int64_t MapperService::Now() const { return node_.NowUtime(); }

std::unique_lock<std::mutex> MapperService::LockLayer(const MapperLayer& layer) {
  for (auto& w : layer_workers_) {
    if (w->layer == &layer) return std::unique_lock<std::mutex>(w->layer_mutex);
  }
  return {};
}

std::vector<std::unique_lock<std::mutex>> MapperService::LockAllLayers() {
  std::vector<std::unique_lock<std::mutex>> locks;
  for (auto& w : layer_workers_) locks.emplace_back(w->layer_mutex);
  return locks;
}

// --- LCM-thread side ---------------------------------------------------------------------------

void MapperService::Subscribe() {
  const std::string& r = params_.robot;
  node_.Subscribe<cairn::lcmt_point_cloud_slice>(
      Ch(r, channels::kLidar), [this](const auto& m) { OnSlice(runtime::FromLcm(m)); });
  node_.Subscribe<cairn::lcmt_lidar_ranges>(
      Ch(r, channels::kLidarRanges), [this](const auto& m) { OnSlice(runtime::FromLcm(m)); });
  node_.Subscribe<cairn::lcmt_laser_scan>(Ch(r, channels::kScan),
                                          [this](const auto& m) { OnScan(m); });
  node_.Subscribe<cairn::lcmt_pose>(Ch(r, channels::kPose), [this](const auto& m) { OnPose(m); });
  node_.Subscribe<cairn::lcmt_odometry>(Ch(r, channels::kOdom),
                                        [this](const auto& m) { OnOdometry(m); });
  node_.Subscribe<cairn::lcmt_imu>(Ch(r, channels::kImu), [this](const auto& m) { OnImu(m); });
  node_.Subscribe<lcmt_map_control_request>(Ch(r, channels::kMapControl),
                                            [this](const auto& m) { OnControl(m); });
  node_.Subscribe<cairn::lcmt_tile_resend_request>(Ch(r, channels::kMapTileResend),
                                                   [this](const auto& m) { OnResend(m); });
  if (!params_.long_term_store.empty()) {
    node_.Subscribe<cairn::lcmt_mapstore_reply>(channels::kMapstoreReply,
                                                [this](const auto& m) { OnMapstoreReply(m); });
  }
  for (const StreamConverter& c : streams_) {
    node_.SubscribeRaw(Ch(r, c.stream.c_str()),
                       [this, &c](const std::string&, const void* data, int size, int64_t) {
                         OnStreamMessage(c, data, size);
                       });
  }
}

void MapperService::HandleLogged(const std::string& channel, const void* data, int size) {
  const std::string& r = params_.robot;
  auto decode = [&](auto& msg) {
    if (msg.decode(data, 0, size) < 0) {
      node_.CountDropped("undecodable_messages");
      return false;
    }
    return true;
  };
  if (channel == Ch(r, channels::kLidar)) {
    cairn::lcmt_point_cloud_slice m{};
    if (decode(m)) OnSlice(runtime::FromLcm(m));
  } else if (channel == Ch(r, channels::kLidarRanges)) {
    cairn::lcmt_lidar_ranges m{};
    if (decode(m)) OnSlice(runtime::FromLcm(m));
  } else if (channel == Ch(r, channels::kScan)) {
    cairn::lcmt_laser_scan m{};
    if (decode(m)) OnScan(m);
  } else if (channel == Ch(r, channels::kPose)) {
    cairn::lcmt_pose m{};
    if (decode(m)) OnPose(m);
  } else if (channel == Ch(r, channels::kOdom)) {
    cairn::lcmt_odometry m{};
    if (decode(m)) OnOdometry(m);
  } else if (channel == Ch(r, channels::kImu)) {
    cairn::lcmt_imu m{};
    if (decode(m)) OnImu(m);
  } else if (channel == Ch(r, channels::kMapControl)) {
    lcmt_map_control_request m{};
    if (decode(m)) OnControl(m);
  } else {
    for (const StreamConverter& c : streams_) {
      if (channel == Ch(r, c.stream.c_str())) OnStreamMessage(c, data, size);
    }
  }
}

void MapperService::OnPose(const cairn::lcmt_pose& msg) {
  auto pose = runtime::FromLcm(msg);
  if (!pose.ok()) {
    node_.CountDropped("bad_poses");
    node_.Warn("bad_pose", "dropped a pose: " + pose.status().message());
    return;
  }
  inputs_.AddGroundTruth(msg.utime, *pose);
}

void MapperService::OnOdometry(const cairn::lcmt_odometry& msg) {
  auto pose = runtime::FromLcm(msg);
  if (!pose.ok()) {
    node_.CountDropped("bad_odometry");
    node_.Warn("bad_odometry", "dropped odometry: " + pose.status().message());
    return;
  }
  inputs_.AddOdometry(msg.utime, *pose);
}

void MapperService::OnImu(const cairn::lcmt_imu& msg) {
  const double zero[3] = {0, 0, 0};
  auto pose = runtime::PoseFromArrays(zero, msg.orientation_wxyz);
  if (!pose.ok()) {
    node_.CountDropped("bad_imu");
    node_.Warn("bad_imu", "dropped an IMU message: " + pose.status().message());
    return;
  }
  inputs_.AddImu(msg.utime, *pose);
}

void MapperService::LogNewMounts() {
  for (const auto& [sensor, mount] : inputs_.TakeNewMounts()) {
    node_.Event("%s mount: (%.3f, %.3f, %.3f) m from the base", sensor.c_str(),
                mount.position_m.x(), mount.position_m.y(), mount.position_m.z());
  }
}

void MapperService::OnSlice(common::Result<common::LidarSlice> slice) {
  if (!slice.ok()) {
    node_.CountDropped("bad_lidar_slices");
    node_.Warn("bad_slice", "dropped a lidar slice: " + slice.status().message());
    return;
  }
  if (!slice->robot.empty() && slice->robot != params_.robot) {
    node_.CountDropped("foreign_slices");
    node_.Warn("foreign_slice", "dropped a lidar slice of robot '" + slice->robot + "'");
    return;
  }
  const int64_t refused = assembler_.refused_slices();
  const int64_t expired = assembler_.expired_revolutions();
  auto revolutions = assembler_.OnSlice(std::move(slice.value()), runtime::Node::SteadyUtime());
  if (assembler_.refused_slices() > refused) {
    node_.CountDropped("refused_slices");
    node_.Warn("refused_slice",
               "refused a lidar slice: a count beyond the assembler's limits, or one that "
               "disagrees with its revolution's other slices");
  }
  if (assembler_.expired_revolutions() > expired) {
    node_.Count("expired_revolutions", assembler_.expired_revolutions() - expired);
  }
  for (auto& revolution : revolutions) OnRevolution(std::move(revolution));
}

void MapperService::OnRevolution(common::LidarRevolution revolution) {
  RevolutionDrops drops;
  std::optional<PreparedRevolution> prepared =
      inputs_.PrepareRevolution(std::move(revolution), &drops);
  LogNewMounts();
  if (drops.incomplete) node_.Count("incomplete_revolutions");
  if (drops.bad_points > 0) {
    node_.CountDropped("bad_points", drops.bad_points);
    node_.Warn("bad_points", "dropped lidar points that are not finite or beyond the sensor range");
  }
  if (drops.slices_without_pose > 0) {
    node_.CountDropped("slices_without_pose", drops.slices_without_pose);
    node_.Warn("no_pose", "dropped lidar slices with no pose within " +
                              std::to_string(params_.inputs.max_pose_gap_s) + " s of their time");
  }
  if (!prepared) return;
  Job j;
  j.kind = Job::Kind::kRevolution;
  j.revolution = std::move(*prepared);
  Enqueue(std::move(j));
}

void MapperService::OnScan(const cairn::lcmt_laser_scan& msg) {
  auto scan = runtime::FromLcm(msg);
  if (!scan.ok()) {
    node_.CountDropped("bad_scans");
    node_.Warn("bad_scan", "dropped a laser scan: " + scan.status().message());
    return;
  }
  std::optional<common::LaserScan> prepared = inputs_.PrepareScan(std::move(scan.value()));
  LogNewMounts();
  if (!prepared) {
    node_.CountDropped("scans_without_pose");
    node_.Warn("no_pose_scan", "dropped a laser scan with no pose near its time");
    return;
  }
  Job j;
  j.kind = Job::Kind::kScan;
  j.scan = std::move(*prepared);
  Enqueue(std::move(j));
}

void MapperService::OnStreamMessage(const StreamConverter& converter, const void* data, int size) {
  std::string counter = converter.stream;
  std::transform(counter.begin(), counter.end(), counter.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  auto reading = converter.convert(data, size);
  if (!reading.ok()) {
    node_.CountDropped("bad_" + counter);
    node_.Warn("bad_" + counter,
               "dropped a " + converter.stream + " message: " + reading.status().message());
    return;
  }
  std::unique_ptr<SensorReading> r = std::move(reading.value());
  r->stream = converter.stream;
  const bool posed = inputs_.PrepareReading(r.get());
  LogNewMounts();
  if (!posed) {
    node_.CountDropped(counter + "_without_pose");
    node_.Warn("no_pose_" + counter,
               "dropped a " + converter.stream + " reading with no pose near its time");
    return;
  }
  Job j;
  j.kind = Job::Kind::kReading;
  j.reading = std::move(r);
  Enqueue(std::move(j));
}

void MapperService::OnControl(const lcmt_map_control_request& msg) {
  Job j;
  j.kind = Job::Kind::kControl;
  j.control = msg;
  Enqueue(std::move(j));
}

void MapperService::OnMapstoreReply(const cairn::lcmt_mapstore_reply& msg) {
  {
    std::lock_guard<std::mutex> lock(save_mutex_);
    if (saves_in_flight_.erase(msg.request_id) == 0) return;  // not one of ours
  }
  if (msg.status == cairn::lcmt_mapstore_reply::STATUS_OK) {
    node_.Count("long_term_saves");
  } else {
    node_.Count("long_term_save_failures");
    node_.Warn("long_term_save", "saving the long-term layer to " + params_.long_term_store +
                                     " failed: " + msg.message);
  }
}

void MapperService::OnResend(const cairn::lcmt_tile_resend_request& msg) {
  if (msg.robot != params_.robot || msg.map_name != params_.map_name) return;
  // The registry ("#obstacles") is one message: it counts as one tile.
  const double tiles = msg.layer == layers::kResendObstacles ? 1.0
                       : msg.num_tiles > 0                  ? msg.num_tiles
                                                            : kWholeLayerResendTiles;
  if (!resend_limits_.Allow(msg.requester, tiles, runtime::Node::SteadyUtime() * 1e-6)) {
    node_.CountDropped("resend_rate_limited");
    node_.Warn("resend_rate", "dropped a resend request of '" + msg.requester +
                                  "': beyond the resend rate (resend_tiles_per_s)");
    return;
  }
  Job j;
  j.kind = Job::Kind::kResend;
  j.resend = msg;
  Enqueue(std::move(j));
}

void MapperService::Enqueue(Job job) {
  if (mode_ == Mode::kReplay) {
    Process(job);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    if (job.kind == Job::Kind::kRevolution) {
      // Keep the newest revolutions when the worker falls behind.
      while (pending_revolutions_ >= params_.max_pending_revolutions) {
        auto it = std::find_if(queue_.begin(), queue_.end(),
                               [](const Job& q) { return q.kind == Job::Kind::kRevolution; });
        if (it == queue_.end()) break;
        queue_.erase(it);
        --pending_revolutions_;
        node_.Count("revolutions_skipped");
        node_.Warn("behind", "mapping falls behind the lidar: skipped a revolution");
      }
      ++pending_revolutions_;
    } else if (static_cast<int>(queue_.size() - pending_revolutions_) >= params_.max_queued_jobs) {
      // Full: the oldest job of this kind makes room, else the new one is dropped.
      auto it = std::find_if(queue_.begin(), queue_.end(),
                             [&](const Job& q) { return q.kind == job.kind; });
      node_.Count("queue_drops");
      node_.Warn("queue_full", "the mapper's worker falls behind its inputs: dropped a job");
      if (it == queue_.end()) return;
      queue_.erase(it);
    }
    queue_.push_back(std::move(job));
  }
  queue_cv_.notify_one();
}

// --- worker side -------------------------------------------------------------------------------

void MapperService::WorkerLoop() {
  while (!stop_) {
    std::deque<Job> jobs;
    {
      std::unique_lock<std::mutex> lock(queue_mutex_);
      queue_cv_.wait_for(lock, std::chrono::milliseconds(20),
                         [this] { return stop_ || !queue_.empty(); });
      jobs.swap(queue_);
      pending_revolutions_ = 0;
    }
    for (Job& job : jobs) {
      if (stop_) break;
      try {
        Process(job);
      } catch (const std::exception& e) {
        node_.Count("processing_errors");
        node_.Warn("processing", std::string("processing failed: ") + e.what());
      }
    }
    try {
      PublishDue(false);
    } catch (const std::exception& e) {
      node_.Count("processing_errors");
      node_.Warn("publishing", std::string("publishing failed: ") + e.what());
    }
  }
}

void MapperService::LayerWorkerLoop(LayerWorker* w) {
  while (!stop_) {
    PreparedRevolution job;
    {
      std::unique_lock<std::mutex> lock(w->slot_mutex);
      w->cv.wait_for(lock, std::chrono::milliseconds(100),
                     [&] { return stop_ || w->pending.has_value(); });
      if (stop_ || !w->pending) continue;
      job = std::move(*w->pending);
      w->pending.reset();
    }
    std::lock_guard<std::mutex> layer_lock(w->layer_mutex);
    try {
      MapperCore::FeedDeferred(w->layer, job.revolution, job.robot, job.time_s);
    } catch (const std::exception& e) {
      node_.Count("processing_errors");
      node_.Warn("processing", w->layer->name() + " failed: " + e.what());
    }
  }
}

void MapperService::PublishDetections(SonarMapperLayer* layer) {
  for (const SonarDetection& d : layer->TakeDetections()) {
    cairn::lcmt_sonar_detection msg{};
    msg.utime = d.utime;
    msg.robot = params_.robot;
    msg.pan_rad = d.pan_rad;
    for (int i = 0; i < 3; ++i) msg.sensor_position_m[i] = d.head_m[i];
    msg.beam_yaw_rad = d.beam_yaw_rad;
    msg.range_max_m = d.range_max_m;
    msg.clear_to_range = d.bins.empty();
    msg.num_obstacles = static_cast<int32_t>(d.bins.size());
    for (size_t i = 0; i < d.bins.size(); ++i) {
      msg.bins.push_back(static_cast<int16_t>(d.bins[i]));
      msg.x_m.push_back(d.points[i].x());
      msg.y_m.push_back(d.points[i].y());
    }
    node_.Publish(channels::ForRobot(params_.robot, channels::kSonarDetections), msg);
    node_.Count("sonar_detections");
  }
}

void MapperService::Process(Job& job) {
  switch (job.kind) {
    case Job::Kind::kRevolution:
      ProcessRevolution(job.revolution);
      break;
    case Job::Kind::kScan:
      core_.ProcessScan(job.scan);
      break;
    case Job::Kind::kReading:
      core_.ProcessReading(*job.reading);
      for (const auto& layer : core_.layers()) {
        if (auto* sonar = dynamic_cast<SonarMapperLayer*>(layer.get())) PublishDetections(sonar);
        for (const std::string& e : layer->TakeEvents()) {
          node_.Event("%s: %s", layer->name().c_str(), e.c_str());
        }
      }
      break;
    case Job::Kind::kControl:
      ProcessControl(job.control);
      break;
    case Job::Kind::kResend:
      publisher_->Resend(job.resend);
      break;
  }
}

void MapperService::ProcessRevolution(PreparedRevolution& job) {
  const RevolutionReport report = core_.ProcessRevolution(job.revolution, job.robot, job.time_s);
  if (report.terrain.out_of_range > 0)
    node_.Count("points_outside_mapping_range", report.terrain.out_of_range);
  ++revolutions_;
  if (!announced_first_revolution_) {
    announced_first_revolution_ = true;
    node_.Event("first revolution mapped: %lld points, %lld used",
                static_cast<long long>(report.terrain.points),
                static_cast<long long>(report.terrain.used));
  }
  // Layers on threads of their own: the newest due revolution waits in their slot.
  for (MapperLayer* layer : report.deferred) {
    for (auto& w : layer_workers_) {
      if (w->layer != layer) continue;
      {
        std::lock_guard<std::mutex> lock(w->slot_mutex);
        if (w->pending) node_.Count(layer->name() + "_revolutions_skipped");
        if (report.deferred.size() == 1) {
          w->pending = std::move(job);
        } else {
          w->pending = job;
        }
      }
      w->cv.notify_one();
    }
  }
  const TerrainMap* terrain = core_.terrain();
  if (terrain == nullptr) return;
  const common::GridGeometry extent = terrain->Bounds();
  if (extent.size_x > announced_extent_.size_x || extent.size_y > announced_extent_.size_y) {
    announced_extent_ = extent;
    node_.Event("terrain map now spans %.0f x %.0f m (%zu tiles)", extent.length_x_m(),
                extent.length_y_m(), terrain->Tiles().size());
  }
}

void MapperService::ProcessControl(const lcmt_map_control_request& request) {
  const auto key = std::make_pair(request.requester, request.request_id);
  auto cached = replies_.find(key);
  if (cached != replies_.end()) {
    node_.Publish(Ch(params_.robot, channels::kMapControlReply), cached->second);
    return;
  }
  lcmt_map_control_reply reply{};
  reply.utime = Now();
  reply.request_id = request.request_id;
  reply.status = lcmt_map_control_reply::STATUS_OK;
  switch (request.op) {
    case lcmt_map_control_request::OP_ADD_PROFILE:
      AddProfile(request, &reply);
      break;
    case lcmt_map_control_request::OP_REMOVE_PROFILE:
      RemoveProfile(request, &reply);
      break;
    case lcmt_map_control_request::OP_PUBLISH_ALL:
      if (mode_ == Mode::kLive) {
        PublishDue(/*force=*/true);
        // What went out: a pull save naming no layers waits for every one of them.
        for (const std::string& layer : publisher_->announced()) {
          if (static_cast<int32_t>(reply.layers.size()) >= lcmt_map_control_reply::MAX_LAYERS) {
            node_.Warn("control_reply", "more layers than a control reply lists: some left out");
            break;
          }
          if (std::find(reply.layers.begin(), reply.layers.end(), layer) == reply.layers.end()) {
            reply.layers.push_back(layer);
          }
        }
        reply.num_layers = static_cast<int32_t>(reply.layers.size());
      }
      reply.message = "published everything (" + std::to_string(reply.num_layers) + " layers)";
      break;
    case lcmt_map_control_request::OP_CLEAR_SHORT_TERM:
      ClearShortTerm(request, &reply);
      break;
    case lcmt_map_control_request::OP_RESET:
      if (Allowed(request, "OP_RESET", "allow_reset", params_.allow_reset, &reply)) {
        ResetMaps(request, &reply);
      }
      break;
    case lcmt_map_control_request::OP_SNAPSHOT:
      if (Allowed(request, "OP_SNAPSHOT", "allow_snapshot", params_.allow_snapshot, &reply)) {
        Snapshot(&reply);
      }
      break;
    default:
      reply.status = lcmt_map_control_reply::STATUS_INVALID;
      reply.message = "unknown op " + std::to_string(request.op);
      node_.CountDropped("bad_control_requests");
      break;
  }
  reply.map_version = revolutions_;
  replies_[key] = reply;
  reply_order_.push_back(key);
  while (reply_order_.size() > kMaxReplies) {
    replies_.erase(reply_order_.front());
    reply_order_.pop_front();
  }
  node_.Publish(Ch(params_.robot, channels::kMapControlReply), reply);
}

bool MapperService::Allowed(const lcmt_map_control_request& request, const char* op,
                            const char* key, bool allowed, lcmt_map_control_reply* reply) {
  // The audit line of a destructive request, done or refused.
  node_.Event("%s from %s (request %lld): %s", op, request.requester.c_str(),
              static_cast<long long>(request.request_id),
              allowed ? "allowed" : (std::string("refused, ") + key + " is off").c_str());
  if (allowed) return true;
  reply->status = lcmt_map_control_reply::STATUS_FORBIDDEN;
  reply->message = std::string(op) + " is off in this mapper's configuration (" + key + ")";
  node_.CountDropped("forbidden_requests");
  return false;
}

void MapperService::AddProfile(const lcmt_map_control_request& request,
                               lcmt_map_control_reply* reply) {
  common::Result<common::RobotProfile> profile =
      common::NotFoundError("no profile named '" + request.profile + "'");
  if (request.has_profile) {
    profile = runtime::FromLcm(request.profile_data);
  } else if (resolver_) {
    profile = resolver_(request.profile);
  }
  if (profile.ok() && core_.terrain() == nullptr) {
    profile = common::NotFoundError("this mapper keeps no terrain layer: no cost layers");
  }
  if (!profile.ok()) {
    reply->status = profile.status().code() == common::StatusCode::kNotFound
                        ? lcmt_map_control_reply::STATUS_NOT_FOUND
                        : lcmt_map_control_reply::STATUS_INVALID;
    reply->message = profile.status().message();
    node_.CountDropped("refused_profiles");
    node_.Warn("profile", "refused a profile: " + reply->message);
    return;
  }
  try {
    core_.terrain()->AddProfile(*profile);
    publisher_->UnretireLayer(layers::DirectedLayer(profile->name));
    publisher_->UnretireLayer(layers::CostLayer(profile->name));
    reply->message = "profile '" + profile->name + "' added";
    node_.Event("profile %s added", profile->name.c_str());
  } catch (const std::exception& e) {
    reply->status = lcmt_map_control_reply::STATUS_INVALID;
    reply->message = e.what();
    node_.CountDropped("refused_profiles");
  }
}

void MapperService::RemoveProfile(const lcmt_map_control_request& request,
                                  lcmt_map_control_reply* reply) {
  if (core_.terrain() != nullptr && core_.terrain()->RemoveProfile(request.profile)) {
    publisher_->RetireLayer(layers::DirectedLayer(request.profile));
    publisher_->RetireLayer(layers::CostLayer(request.profile));
    reply->message = "profile '" + request.profile + "' removed";
    node_.Event("profile %s removed", request.profile.c_str());
    return;
  }
  reply->status = lcmt_map_control_reply::STATUS_NOT_FOUND;
  reply->message = "no profile named '" + request.profile + "'";
  node_.CountDropped("refused_profiles");
}

void MapperService::ClearShortTerm(const lcmt_map_control_request& request,
                                   lcmt_map_control_reply* reply) {
  auto* dynamic = dynamic_cast<DynamicMapperLayer*>(core_.FindLayer(kDynamicLayerName));
  if (dynamic == nullptr) {
    reply->status = lcmt_map_control_reply::STATUS_NOT_FOUND;
    reply->message = "this mapper keeps no short-term layer (dynamic layers are off)";
    return;
  }
  dynamic->ClearShortTerm();  // a new version: published at the next period
  reply->message = "short-term layer cleared";
  node_.Event("short-term layer cleared on request of %s", request.requester.c_str());
}

void MapperService::ResetMaps(const lcmt_map_control_request& request,
                              lcmt_map_control_reply* reply) {
  {
    std::vector<std::unique_lock<std::mutex>> locks = LockAllLayers();
    for (auto& w : layer_workers_) {
      std::lock_guard<std::mutex> slot(w->slot_mutex);
      w->pending.reset();
    }
    core_.Reset();
  }
  publisher_->AfterReset(/*send=*/mode_ == Mode::kLive);
  announced_extent_ = common::GridGeometry();
  reply->message = "maps cleared";
  node_.Event("maps cleared on request of %s", request.requester.c_str());
}

void MapperService::Snapshot(lcmt_map_control_reply* reply) {
  const std::string dir =
      params_.snapshot_dir + "/" + params_.robot + "-" + std::to_string(reply->utime);
  const common::Status status = WriteOutputs(dir);
  if (status.ok()) {
    reply->message = dir;
    node_.Event("snapshot written to %s", dir.c_str());
  } else {
    reply->status = lcmt_map_control_reply::STATUS_ERROR;
    reply->message = status.message();
  }
}

void MapperService::PublishDue(bool force) {
  publisher_->PublishDue(force, revolutions_);
  if (mode_ == Mode::kLive && !params_.long_term_store.empty() &&
      Clock::now() >= next_long_term_save_) {
    next_long_term_save_ = Clock::now() + Period(params_.long_term_save_period_s);
    RequestLongTermSave();
  }
}

void MapperService::RequestLongTermSave() {
  const auto slash = params_.long_term_store.find('/');
  cairn::lcmt_mapstore_request r{};
  r.utime = Now();
  r.requester = "cairn-mapper-" + params_.robot;  // request ids are per requester
  r.op = cairn::lcmt_mapstore_request::OP_SAVE;
  r.site = params_.long_term_store.substr(0, slash);
  r.map_name = params_.long_term_store.substr(slash + 1);
  r.robot = params_.robot;  // a pull: the store fetches the layer from our tiles
  r.layers = {layers::kLongTerm};
  r.num_layers = 1;
  r.code_version = kMappingCodeVersion;
  {
    std::lock_guard<std::mutex> lock(save_mutex_);
    r.request_id = ++next_save_request_id_;
    // A save the store never answered (it was down) is forgotten after a few periods.
    const auto now = Clock::now();
    for (auto it = saves_in_flight_.begin(); it != saves_in_flight_.end();) {
      if (now - it->second > Period(4 * params_.long_term_save_period_s)) {
        node_.Count("long_term_save_failures");
        node_.Warn("long_term_save", "cairn-mapstore did not answer a save of the long-term layer");
        it = saves_in_flight_.erase(it);
      } else {
        ++it;
      }
    }
    saves_in_flight_[r.request_id] = now;
  }
  node_.Publish(channels::kMapstoreRequest, r);
  node_.Count("long_term_save_requests");
}

common::Status MapperService::WriteOutputs(const std::string& dir) {
  std::vector<std::unique_lock<std::mutex>> locks = LockAllLayers();
  return core_.WriteOutputs(dir, params_.robot, revolutions_);
}

}  // namespace cairn::mapping
