#include "services/mapping/lcm/mapper_service.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cairn/lcmt_mapstore_request.hpp"
#include "cairn/lcmt_octomap.hpp"

#include "common/crc32.h"
#include "common/channels.h"
#include "common/check.h"
#include "common/layers.h"
#include "common/log.h"
#include "services/mapping/derive.h"
#include "services/runtime/conversions.h"

namespace cairn::mapping {
namespace {

using Clock = std::chrono::steady_clock;
using cairn::lcmt_map_control_reply;
using cairn::lcmt_map_control_request;

constexpr size_t kOctomapChunkBytes = 192 * 1024;
constexpr size_t kMaxReplies = 256;

std::string Ch(const std::string& robot, const char* stream) {
  return channels::ForRobot(robot, stream);
}

Clock::duration Period(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

common::Pose3 Compose(const common::Pose3& a, const common::Pose3& b) {
  common::Pose3 p;
  p.position_m = a.position_m + a.orientation * b.position_m;
  p.orientation = (a.orientation * b.orientation).normalized();
  return p;
}

common::Pose3 Inverse(const common::Pose3& a) {
  common::Pose3 p;
  p.orientation = a.orientation.conjugate();
  p.position_m = -(p.orientation * a.position_m);
  return p;
}

// A sensor point is bad input when not finite or beyond what the sensor can measure.
bool BadPoint(const common::LidarPoint& p, double max_range_m) {
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.z_m)) return true;
  if (max_range_m > 0) {
    const double r2 = double(p.x_m) * p.x_m + double(p.y_m) * p.y_m + double(p.z_m) * p.z_m;
    if (r2 > max_range_m * max_range_m * 1.0001) return true;
  }
  return false;
}

std::string FileNameOf(const std::string& layer) {
  std::string s = layer;
  std::replace(s.begin(), s.end(), '/', '_');
  return s + ".f32";
}

common::Status WriteLayer(const std::string& path, const common::Layer& layer) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return common::UnavailableError("cannot write " + path);
  out.write(reinterpret_cast<const char*>(layer.data()),
            static_cast<std::streamsize>(layer.size() * sizeof(float)));
  return out ? common::Status::Ok() : common::UnavailableError("write failed: " + path);
}

std::string Num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

}  // namespace

void MapperParams::Validate() const {
  CAIRN_THROW_UNLESS(!robot.empty(), "the mapper needs a robot name");
  CAIRN_THROW_UNLESS(!map_name.empty(), "map_name must not be empty");
  CAIRN_THROW_UNLESS(max_pose_gap_s > 0, "max_pose_gap_s must be positive");
  CAIRN_THROW_UNLESS(max_imu_gap_s > 0, "max_imu_gap_s must be positive");
  for (double p : {publish_period_s, slow_publish_period_s, registry_period_s, occupancy_period_s,
                   octomap_period_s}) {
    CAIRN_THROW_UNLESS(p > 0, "publish periods must be positive, got " << p);
  }
  CAIRN_THROW_UNLESS(octomap_every_revolutions >= 1, "octomap_every_revolutions must be >= 1");
  CAIRN_THROW_UNLESS(max_pending_revolutions >= 1, "max_pending_revolutions must be >= 1");
  CAIRN_THROW_UNLESS(tiles_per_burst >= 1, "tiles_per_burst must be >= 1");
  CAIRN_THROW_UNLESS(burst_pause_ms >= 0, "burst_pause_ms must be >= 0");
  if (!long_term_store.empty()) {
    const auto slash = long_term_store.find('/');
    CAIRN_THROW_UNLESS(slash != std::string::npos && slash > 0 &&
                           slash + 1 < long_term_store.size() &&
                           long_term_store.find('/', slash + 1) == std::string::npos,
                       "long_term_store must be SITE/MAP, got '" << long_term_store << "'");
    CAIRN_THROW_UNLESS(core.dynamic_enabled,
                       "long_term_store needs the dynamic layers (a static map)");
    CAIRN_THROW_UNLESS(long_term_save_period_s > 0, "long_term_save_period_s must be positive");
  }
  core.Validate();
}

MapperService::MapperService(runtime::Node& node, MapperParams params,
                             const std::vector<common::RobotProfile>& profiles,
                             ProfileResolver resolver, Mode mode)
    : node_(node),
      params_((params.Validate(), std::move(params))),
      resolver_(std::move(resolver)),
      mode_(mode),
      core_(params_.core),
      // Versions from the wall clock: a restarted mapper's layers supersede its predecessor's
      // at every receiver (the navigator, the store's mirror for pull saves).
      terrain_publisher_(params_.robot, params_.map_name, /*extent_tiles=*/4,
                         mode == Mode::kLive ? runtime::LayerTiler::StartVersionBase() : 0),
      occupancy_tiler_(params_.robot, params_.map_name, runtime::kDefaultTileSize,
                       mode == Mode::kLive ? runtime::LayerTiler::StartVersionBase() : 0) {
  for (const auto& p : profiles) core_.terrain().AddProfile(p);
  const auto now = Clock::now();
  next_fast_ = now + Period(params_.publish_period_s);
  next_slow_ = now + Period(params_.slow_publish_period_s);
  next_registry_ = now + Period(params_.registry_period_s);
  next_occupancy_ = now + Period(params_.occupancy_period_s);
  next_octomap_ = now + Period(params_.octomap_period_s);
  next_long_term_save_ = now + Period(params_.long_term_save_period_s);
  next_save_request_id_ = runtime::Node::WallUtime();  // unique across restarts
  if (mode_ == Mode::kLive) {
    const std::string& r = params_.robot;
    node_.Subscribe<cairn::lcmt_point_cloud_slice>(Ch(r, channels::kLidar),
                                                   [this](const auto& m) { OnSlice(m); });
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
    worker_ = std::thread([this] { WorkerLoop(); });
    if (core_.octomap() != nullptr) octomap_worker_ = std::thread([this] { OctomapLoop(); });
  }
  std::string names;
  for (const auto& p : core_.terrain().profiles()) names += (names.empty() ? "" : ",") + p.name;
  node_.Event("mapping %s for profiles [%s], poses from %s", params_.robot.c_str(), names.c_str(),
              params_.pose_source == PoseSource::kGroundTruth ? "ground truth" : "odometry");
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
  octomap_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
  if (octomap_worker_.joinable()) octomap_worker_.join();
}

int64_t MapperService::Now() const { return node_.NowUtime(); }

// --- LCM-thread side ---------------------------------------------------------------------------

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
    if (decode(m)) OnSlice(m);
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
  }
}

void MapperService::OnPose(const cairn::lcmt_pose& msg) {
  auto pose = runtime::FromLcm(msg);
  if (!pose.ok()) {
    node_.CountDropped("bad_poses");
    node_.Warn("bad_pose", "dropped a pose: " + pose.status().message());
    return;
  }
  ground_truth_.Add(msg.utime, *pose);
}

void MapperService::OnOdometry(const cairn::lcmt_odometry& msg) {
  auto pose = runtime::FromLcm(msg);
  if (!pose.ok()) {
    node_.CountDropped("bad_odometry");
    node_.Warn("bad_odometry", "dropped odometry: " + pose.status().message());
    return;
  }
  odometry_.Add(msg.utime, *pose);
}

void MapperService::OnImu(const cairn::lcmt_imu& msg) {
  const double zero[3] = {0, 0, 0};
  auto pose = runtime::PoseFromArrays(zero, msg.orientation_wxyz);
  if (!pose.ok()) {
    node_.CountDropped("bad_imu");
    node_.Warn("bad_imu", "dropped an IMU message: " + pose.status().message());
    return;
  }
  imu_.Add(msg.utime, *pose);
}

std::optional<common::Pose3> MapperService::BasePose(int64_t utime) {
  if (params_.pose_source == PoseSource::kGroundTruth) {
    return ground_truth_.At(utime, params_.max_pose_gap_s);
  }
  auto base = odometry_.At(utime, params_.max_pose_gap_s);
  if (!base) return std::nullopt;
  if (params_.imu_attitude) {
    // Heading and position from odometry, roll and pitch from the IMU.
    if (auto imu = imu_.At(utime, params_.max_imu_gap_s)) {
      const double dyaw = base->yaw_rad() - imu->yaw_rad();
      base->orientation =
          (Eigen::AngleAxisd(dyaw, Eigen::Vector3d::UnitZ()) * imu->orientation).normalized();
    }
  }
  return base;
}

std::optional<common::Pose3> MapperService::SensorPose(const std::string& sensor, int64_t utime,
                                                       const common::Pose3& reported) {
  if (params_.pose_source == PoseSource::kGroundTruth) {
    if (!ground_truth_.At(utime, params_.max_pose_gap_s)) return std::nullopt;
    return reported;
  }
  auto base = BasePose(utime);
  if (!base) return std::nullopt;
  auto it = mounts_.find(sensor);
  if (it == mounts_.end()) {
    // The mount: configured for the lidar, else measured once against the producer's pose.
    common::Pose3 mount = (sensor == "lidar" && params_.lidar_mount)
                              ? *params_.lidar_mount
                              : Compose(Inverse(*base), reported);
    it = mounts_.emplace(sensor, mount).first;
    node_.Event("%s mount: (%.3f, %.3f, %.3f) m from the base", sensor.c_str(),
                mount.position_m.x(), mount.position_m.y(), mount.position_m.z());
  }
  return Compose(*base, it->second);
}

void MapperService::OnSlice(const cairn::lcmt_point_cloud_slice& msg) {
  auto slice = runtime::FromLcm(msg);
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
  for (auto& revolution : assembler_.OnSlice(std::move(slice.value()))) {
    OnRevolution(std::move(revolution));
  }
}

void MapperService::OnRevolution(common::LidarRevolution revolution) {
  if (!revolution.complete()) node_.Count("incomplete_revolutions");
  // Resolve each slice's sensor pose; drop bad points (not finite, beyond the sensor's range).
  std::vector<common::LidarSlice> kept;
  int64_t bad_points = 0, no_pose = 0;
  for (auto& slice : revolution.slices) {
    auto pose = SensorPose("lidar", slice.utime, slice.sensor_pose);
    if (!pose) {
      ++no_pose;
      continue;
    }
    slice.sensor_pose = *pose;
    const size_t before = slice.points.size();
    slice.points.erase(
        std::remove_if(slice.points.begin(), slice.points.end(),
                       [&](const common::LidarPoint& p) { return BadPoint(p, slice.max_range_m); }),
        slice.points.end());
    bad_points += static_cast<int64_t>(before - slice.points.size());
    kept.push_back(std::move(slice));
  }
  if (bad_points > 0) {
    node_.CountDropped("bad_points", bad_points);
    node_.Warn("bad_points", "dropped lidar points that are not finite or beyond the sensor range");
  }
  if (no_pose > 0) {
    node_.CountDropped("slices_without_pose", no_pose);
    node_.Warn("no_pose", "dropped lidar slices with no pose within " +
                              std::to_string(params_.max_pose_gap_s) + " s of their time");
  }
  if (kept.empty()) return;
  revolution.slices = std::move(kept);
  const int64_t utime = revolution.slices.back().utime;
  RevolutionJob job;
  job.time_s = utime * 1e-6;
  if (auto base = BasePose(utime)) {
    job.robot.xy_m = common::Vector2(base->position_m.x(), base->position_m.y());
    job.robot.yaw_rad = base->yaw_rad();
    job.robot.pitch_rad = base->pitch_rad();
    if (auto imu = imu_.At(utime, params_.max_imu_gap_s)) job.robot.pitch_rad = imu->pitch_rad();
  }
  job.revolution = std::move(revolution);
  Job j;
  j.kind = Job::Kind::kRevolution;
  j.revolution = std::move(job);
  Enqueue(std::move(j));
}

void MapperService::OnScan(const cairn::lcmt_laser_scan& msg) {
  auto scan = runtime::FromLcm(msg);
  if (!scan.ok()) {
    node_.CountDropped("bad_scans");
    node_.Warn("bad_scan", "dropped a laser scan: " + scan.status().message());
    return;
  }
  auto pose = SensorPose("scan", scan->utime, scan->sensor_pose);
  if (!pose) {
    node_.CountDropped("scans_without_pose");
    node_.Warn("no_pose_scan", "dropped a laser scan with no pose near its time");
    return;
  }
  Job j;
  j.kind = Job::Kind::kScan;
  j.scan = std::move(scan.value());
  j.scan.sensor_pose = *pose;
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

void MapperService::OctomapLoop() {
  while (!stop_) {
    common::LidarRevolution revolution;
    {
      std::unique_lock<std::mutex> lock(octomap_mutex_);
      octomap_cv_.wait_for(lock, std::chrono::milliseconds(100),
                           [this] { return stop_ || octomap_pending_.has_value(); });
      if (stop_ || !octomap_pending_) continue;
      revolution = std::move(*octomap_pending_);
      octomap_pending_.reset();
    }
    std::lock_guard<std::mutex> tree_lock(tree_mutex_);
    core_.InsertOctomap(revolution);
  }
}

void MapperService::Process(Job& job) {
  switch (job.kind) {
    case Job::Kind::kRevolution:
      ProcessRevolution(job.revolution);
      break;
    case Job::Kind::kScan:
      core_.ProcessScan(job.scan);
      StepDynamicUpTo(job.scan.utime);
      break;
    case Job::Kind::kControl:
      ProcessControl(job.control);
      break;
    case Job::Kind::kResend:
      ProcessResend(job.resend);
      break;
  }
}

void MapperService::ProcessRevolution(RevolutionJob& job) {
  const RevolutionReport report = core_.ProcessRevolution(job.revolution, job.robot, job.time_s);
  StepDynamicUpTo(job.revolution.slices.back().utime);
  if (report.terrain.out_of_range > 0)
    node_.Count("points_outside_mapping_range", report.terrain.out_of_range);
  const int64_t n = ++revolutions_;
  if (!announced_first_revolution_) {
    announced_first_revolution_ = true;
    node_.Event("first revolution mapped: %lld points, %lld used",
                static_cast<long long>(report.terrain.points),
                static_cast<long long>(report.terrain.used));
  }
  if (core_.octomap() != nullptr && n % params_.octomap_every_revolutions == 0) {
    if (mode_ == Mode::kReplay) {
      core_.InsertOctomap(job.revolution);
    } else {
      {
        std::lock_guard<std::mutex> lock(octomap_mutex_);
        if (octomap_pending_) node_.Count("octomap_revolutions_skipped");
        octomap_pending_ = std::move(job.revolution);
      }
      octomap_cv_.notify_one();
    }
  }
  const common::GridGeometry extent = core_.terrain().Bounds();
  if (extent.size_x > announced_extent_.size_x || extent.size_y > announced_extent_.size_y) {
    announced_extent_ = extent;
    node_.Event("terrain map now spans %.0f x %.0f m (%zu tiles)", extent.length_x_m(),
                extent.length_y_m(), core_.terrain().Tiles().size());
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
    case lcmt_map_control_request::OP_ADD_PROFILE: {
      common::Result<common::RobotProfile> profile =
          common::NotFoundError("no profile named '" + request.profile + "'");
      if (request.has_profile) {
        profile = runtime::FromLcm(request.profile_data);
      } else if (resolver_) {
        profile = resolver_(request.profile);
      }
      if (!profile.ok()) {
        reply.status = profile.status().code() == common::StatusCode::kNotFound
                           ? lcmt_map_control_reply::STATUS_NOT_FOUND
                           : lcmt_map_control_reply::STATUS_INVALID;
        reply.message = profile.status().message();
        node_.CountDropped("refused_profiles");
        node_.Warn("profile", "refused a profile: " + reply.message);
        break;
      }
      try {
        core_.terrain().AddProfile(*profile);
        retired_layers_.erase(std::remove(retired_layers_.begin(), retired_layers_.end(),
                                          layers::CostLayer(profile->name)),
                              retired_layers_.end());
        reply.message = "profile '" + profile->name + "' added";
        node_.Event("profile %s added", profile->name.c_str());
      } catch (const std::exception& e) {
        reply.status = lcmt_map_control_reply::STATUS_INVALID;
        reply.message = e.what();
        node_.CountDropped("refused_profiles");
      }
      break;
    }
    case lcmt_map_control_request::OP_REMOVE_PROFILE:
      if (core_.terrain().RemoveProfile(request.profile)) {
        retired_layers_.push_back(layers::CostLayer(request.profile));
        reply.message = "profile '" + request.profile + "' removed";
        node_.Event("profile %s removed", request.profile.c_str());
      } else {
        reply.status = lcmt_map_control_reply::STATUS_NOT_FOUND;
        reply.message = "no profile named '" + request.profile + "'";
        node_.CountDropped("refused_profiles");
      }
      break;
    case lcmt_map_control_request::OP_PUBLISH_ALL:
      if (mode_ == Mode::kLive) PublishDue(/*force=*/true);
      reply.message = "published everything";
      break;
    case lcmt_map_control_request::OP_CLEAR_SHORT_TERM:
      if (core_.dynamic() != nullptr) {
        core_.ClearShortTerm();
        dynamic_published_updates_ = -1;
        reply.message = "short-term layer cleared";
        node_.Event("short-term layer cleared on request of %s", request.requester.c_str());
      } else {
        reply.status = lcmt_map_control_reply::STATUS_NOT_FOUND;
        reply.message = "this mapper keeps no short-term layer (dynamic layers are off)";
      }
      break;
    case lcmt_map_control_request::OP_RESET: {
      {
        std::lock_guard<std::mutex> tree_lock(tree_mutex_);
        std::lock_guard<std::mutex> lock(octomap_mutex_);
        core_.Reset();
        octomap_pending_.reset();
      }
      const auto batch = terrain_publisher_.Reset(Now());
      if (mode_ == Mode::kLive) Send(Ch(params_.robot, channels::kMapManifest), batch.manifests);
      announced_extent_ = common::GridGeometry();
      reply.message = "maps cleared";
      node_.Event("maps cleared on request of %s", request.requester.c_str());
      break;
    }
    case lcmt_map_control_request::OP_SNAPSHOT: {
      const std::string dir =
          params_.snapshot_dir + "/" + params_.robot + "-" + std::to_string(reply.utime);
      const common::Status status = WriteOutputs(dir);
      if (status.ok()) {
        reply.message = dir;
        node_.Event("snapshot written to %s", dir.c_str());
      } else {
        reply.status = lcmt_map_control_reply::STATUS_ERROR;
        reply.message = status.message();
      }
      break;
    }
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

void MapperService::ProcessResend(const cairn::lcmt_tile_resend_request& request) {
  if (terrain_publisher_.Has(request.layer)) {
    const auto batch = terrain_publisher_.Resend(request);
    Send(Ch(params_.robot, channels::kMapTiles), batch.tiles);
    Send(Ch(params_.robot, channels::kMapManifest), batch.manifests);
    node_.Count("tiles_resent", static_cast<int64_t>(batch.tiles.size()));
    return;
  }
  const auto batch = occupancy_tiler_.Resend(request);
  Send(Ch(params_.robot, channels::kMapOccupancy), batch.occupancy_tiles);
  Send(Ch(params_.robot, channels::kMapTiles), batch.tiles);
  if (batch.manifest.num_tiles > 0 || batch.changed) {
    Send(Ch(params_.robot, channels::kMapManifest),
         std::vector<cairn::lcmt_grid_manifest>{batch.manifest});
  }
  node_.Count("tiles_resent",
              static_cast<int64_t>(batch.tiles.size() + batch.occupancy_tiles.size()));
}

std::vector<std::string> MapperService::FastLayers() const {
  std::vector<std::string> names{layers::kElevation, layers::kSlope, layers::kStepMax,
                                 layers::kRoughness};
  for (const auto& p : core_.terrain().profiles()) names.push_back(layers::CostLayer(p.name));
  return names;
}

std::vector<std::string> MapperService::SlowLayers() const {
  return {layers::kElevationVariance, layers::kObservationCount, layers::kLastSeen,
          layers::kGroundBound,       layers::kDitchDepth,       layers::kDitchWidth};
}

template <typename Msg>
void MapperService::Send(const std::string& channel, const std::vector<Msg>& messages) {
  node_.PublishPaced(channel, messages, params_.tiles_per_burst, params_.burst_pause_ms);
}

void MapperService::PublishTerrain(const std::vector<std::string>& names, bool force,
                                   bool manifests) {
  std::vector<std::string> all = names;
  for (const auto& r : retired_layers_) all.push_back(r);
  retired_layers_.clear();
  const auto batch = terrain_publisher_.Update(core_.terrain(), all, Now(), force);
  Send(Ch(params_.robot, channels::kMapTiles), batch.tiles);
  std::vector<cairn::lcmt_grid_manifest> out = batch.manifests;
  if (manifests) {
    for (const auto& name : all) {
      const bool sent =
          std::any_of(out.begin(), out.end(), [&](const auto& m) { return m.layer == name; });
      if (sent) continue;
      if (auto m = terrain_publisher_.Manifest(name)) out.push_back(*m);
    }
  }
  Send(Ch(params_.robot, channels::kMapManifest), out);
}

void MapperService::PublishRegistry(bool force) {
  common::ObstacleRegistry registry = core_.terrain().BuildRegistry();
  registry.map_version = revolutions_;
  cairn::lcmt_obstacle_registry msg = runtime::ToLcm(registry, 0, params_.robot, params_.map_name);
  msg.map_version = 0;
  std::string bytes(static_cast<size_t>(msg.getEncodedSize()), '\0');
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  if (!force && bytes == last_registry_bytes_) return;
  last_registry_bytes_ = std::move(bytes);
  msg.utime = Now();
  msg.map_version = revolutions_;
  if (runtime::FitRegistryToMessageLimit(&msg)) {
    node_.Warn("registry_size", "the obstacle registry exceeds 256 KB; outlines are left out");
  }
  node_.Publish(Ch(params_.robot, channels::kMapObstacles), msg);
}

void MapperService::PublishOccupancy(bool force) {
  if (const DynamicLayers* dynamic = core_.dynamic()) {
    if (force || dynamic->updates() != dynamic_published_updates_) {
      dynamic_published_updates_ = dynamic->updates();
      const common::GridMap layers_map = dynamic->ToGridMap();
      const int64_t utime = Now();
      std::vector<cairn::lcmt_grid_manifest> manifests;
      for (const char* name : {layers::kShortTerm, layers::kLongTerm, layers::kFinal}) {
        auto batch = occupancy_tiler_.Update(layers_map, name, runtime::TileEncoding::kOccupancy,
                                             utime, force);
        Send(Ch(params_.robot, channels::kMapOccupancy), batch.occupancy_tiles);
        // Every step's manifests go out, changed or not: they tell receivers (the navigator's
        // staleness check when it plans on the final layer) that the layer is current.
        manifests.push_back(batch.manifest);
      }
      Send(Ch(params_.robot, channels::kMapManifest), manifests);
    }
  }
  const OccupancyGrid* grid = core_.occupancy();
  if (grid == nullptr) return;
  if (!force && grid->version() == occupancy_published_version_) return;
  occupancy_published_version_ = grid->version();
  const common::GridGeometry bounds = grid->ObservedBounds();
  if (bounds.size_x <= 0 || bounds.size_y <= 0) return;
  const common::GridMap map = grid->Export(bounds);
  const int64_t utime = Now();
  auto occ = occupancy_tiler_.Update(map, layers::kOccupancy, runtime::TileEncoding::kOccupancy,
                                     utime, force);
  Send(Ch(params_.robot, channels::kMapOccupancy), occ.occupancy_tiles);
  auto logodds = occupancy_tiler_.Update(map, layers::kOccupancyLogOdds,
                                         runtime::TileEncoding::kFloat, utime, force);
  Send(Ch(params_.robot, channels::kMapTiles), logodds.tiles);
  Send(Ch(params_.robot, channels::kMapManifest),
       std::vector<cairn::lcmt_grid_manifest>{occ.manifest, logodds.manifest});
}

void MapperService::StepDynamicUpTo(int64_t utime) {
  const DynamicLayers* dynamic = core_.dynamic();
  if (dynamic == nullptr || utime <= 0) return;
  const int64_t period = static_cast<int64_t>(std::llround(dynamic->update_period_s() * 1e6));
  if (next_dynamic_utime_ == 0) next_dynamic_utime_ = utime + period;
  if (utime < next_dynamic_utime_) return;
  core_.StepDynamic();
  // One step per period of sensor time; after a gap, one step and a fresh start.
  next_dynamic_utime_ += period;
  if (next_dynamic_utime_ <= utime) next_dynamic_utime_ = utime + period;
}

void MapperService::PublishOctomap(bool force) {
  std::string blob;
  double resolution = 0;
  {
    std::lock_guard<std::mutex> lock(tree_mutex_);
    const OctomapLayer* octomap = core_.octomap();
    if (octomap == nullptr) return;
    if (!force && octomap->version() == octomap_published_version_) return;
    octomap_published_version_ = octomap->version();
    blob = octomap->ToBinary();
    resolution = octomap->params().resolution_m;
  }
  const uint32_t crc = common::Crc32(blob.data(), blob.size());
  const int count = static_cast<int>((blob.size() + kOctomapChunkBytes - 1) / kOctomapChunkBytes);
  ++octomap_chunk_version_;
  std::vector<cairn::lcmt_octomap> chunks;
  for (int i = 0; i < std::max(1, count); ++i) {
    cairn::lcmt_octomap m{};
    m.utime = Now();
    m.robot = params_.robot;
    m.map_name = params_.map_name;
    m.resolution_m = resolution;
    m.binary = true;
    m.version = octomap_chunk_version_;
    m.chunk_index = i;
    m.chunk_count = std::max(1, count);
    m.total_bytes = static_cast<int64_t>(blob.size());
    m.checksum = crc;
    const size_t begin = i * kOctomapChunkBytes;
    const size_t end = std::min(blob.size(), begin + kOctomapChunkBytes);
    m.data.assign(blob.begin() + begin, blob.begin() + end);
    m.num_bytes = static_cast<int32_t>(m.data.size());
    chunks.push_back(std::move(m));
  }
  Send(Ch(params_.robot, channels::kMapOctomap), chunks);
}

void MapperService::PublishDue(bool force) {
  const auto now = Clock::now();
  const bool slow = force || now >= next_slow_;
  if (slow) next_slow_ = now + Period(params_.slow_publish_period_s);
  if (force || slow || now >= next_fast_) {
    next_fast_ = now + Period(params_.publish_period_s);
    // Manifests of the fast layers go out every period, changed or not: they tell receivers
    // (the navigator's staleness check) that the layer is current.
    PublishTerrain(FastLayers(), force, /*manifests=*/true);
  }
  if (slow) PublishTerrain(SlowLayers(), force, true);
  if (force || slow || now >= next_registry_) {
    next_registry_ = now + Period(params_.registry_period_s);
    PublishRegistry(force || slow);
  }
  if (force || now >= next_occupancy_) {
    next_occupancy_ = now + Period(params_.occupancy_period_s);
    PublishOccupancy(force);
  }
  if (force || now >= next_octomap_) {
    next_octomap_ = now + Period(params_.octomap_period_s);
    PublishOctomap(force);
  }
  if (mode_ == Mode::kLive && !params_.long_term_store.empty() && now >= next_long_term_save_) {
    next_long_term_save_ = now + Period(params_.long_term_save_period_s);
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
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return common::UnavailableError("cannot create " + dir + ": " + ec.message());
  std::ostringstream yaml;
  yaml << "# cairn-mapper layers: raw little-endian float32, x fastest from the minimum corner\n";
  yaml << "robot: " << params_.robot << "\n";
  yaml << "code_version: " << kMappingCodeVersion << "\n";
  yaml << "revolutions: " << revolutions_ << "\n";
  const TerrainMap& terrain = core_.terrain();
  auto geometry = [&](const common::GridGeometry& g, const std::string& indent) {
    yaml << indent << "resolution_m: " << Num(g.resolution_m) << "\n"
         << indent << "size_x: " << g.size_x << "\n"
         << indent << "size_y: " << g.size_y << "\n"
         << indent << "origin: [" << Num(g.origin.x_m) << ", " << Num(g.origin.y_m) << ", "
         << Num(g.origin.yaw_rad) << "]\n";
  };
  yaml << "terrain:\n";
  if (!terrain.empty()) {
    std::vector<std::string> names = TerrainMap::BaseLayers();
    for (const auto& n : terrain.DerivedLayers()) names.push_back(n);
    const common::GridMap map = terrain.Export(names);
    geometry(map.geometry(), "  ");
    yaml << "  layers:\n";
    for (const auto& name : names) {
      const common::Status s = WriteLayer(dir + "/" + FileNameOf(name), map.at(name));
      if (!s.ok()) return s;
      yaml << "    - {name: \"" << name << "\", file: " << FileNameOf(name) << "}\n";
    }
  }
  if (const OccupancyGrid* grid = core_.occupancy()) {
    const common::GridGeometry bounds = grid->ObservedBounds();
    if (bounds.size_x > 0 && bounds.size_y > 0) {
      const common::GridMap map = grid->Export(bounds);
      yaml << "occupancy:\n";
      geometry(map.geometry(), "  ");
      const common::Status s = WriteLayer(dir + "/" + FileNameOf(layers::kOccupancyLogOdds),
                                          map.at(layers::kOccupancyLogOdds));
      if (!s.ok()) return s;
      yaml << "  layers:\n    - {name: \"" << layers::kOccupancyLogOdds
           << "\", file: " << FileNameOf(layers::kOccupancyLogOdds) << "}\n";
    }
  }
  if (const DynamicLayers* dynamic = core_.dynamic()) {
    const common::GridMap map = dynamic->ToGridMap();
    yaml << "dynamic:\n";
    geometry(map.geometry(), "  ");
    yaml << "  layers:\n";
    for (const char* name :
         {layers::kStaticMap, layers::kShortTerm, layers::kLongTerm, layers::kFinal}) {
      const common::Status s = WriteLayer(dir + "/" + FileNameOf(name), map.at(name));
      if (!s.ok()) return s;
      yaml << "    - {name: \"" << name << "\", file: " << FileNameOf(name) << "}\n";
    }
  }
  {
    std::lock_guard<std::mutex> lock(tree_mutex_);
    if (const OctomapLayer* octomap = core_.octomap()) {
      const common::Status s = octomap->WriteBinaryFile(dir + "/octomap.bt");
      if (!s.ok()) return s;
      yaml << "octomap: octomap.bt\n";
    }
  }
  // The registry, in a stable text form.
  const common::ObstacleRegistry registry = terrain.BuildRegistry();
  std::ostringstream obs;
  obs << "obstacles:\n";
  for (const auto& o : registry.obstacles) {
    obs << "  - id: " << o.id << "\n    kind: " << common::ObstacleKindName(o.kind)
        << "\n    centroid_m: [" << Num(o.centroid_m.x()) << ", " << Num(o.centroid_m.y())
        << "]\n    slope_rad: " << Num(o.slope_rad) << "\n    height_m: " << Num(o.height_m)
        << "\n    width_m: " << Num(o.width_m) << "\n    length_m: " << Num(o.length_m)
        << "\n    depth_m: " << Num(o.depth_m) << "\n    area_m2: " << Num(o.area_m2)
        << "\n    num_cells: " << o.num_cells << "\n    outline_m: [";
    for (size_t k = 0; k < o.outline_m.size(); ++k) {
      obs << (k ? ", " : "") << "[" << Num(o.outline_m[k].x()) << ", " << Num(o.outline_m[k].y())
          << "]";
    }
    obs << "]\n    verdicts:\n";
    for (const auto& v : o.verdicts) {
      obs << "      - {profile: " << v.profile
          << ", crossable: " << (v.crossable ? "true" : "false") << ", reason: \"" << v.reason
          << "\"}\n";
    }
  }
  std::ofstream(dir + "/obstacles.yaml", std::ios::trunc) << obs.str();
  yaml << "obstacles: obstacles.yaml\n";
  std::ofstream out(dir + "/map.yaml", std::ios::trunc);
  out << yaml.str();
  if (!out) return common::UnavailableError("cannot write " + dir + "/map.yaml");
  return common::Status::Ok();
}

}  // namespace cairn::mapping
