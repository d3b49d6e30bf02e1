#include "services/mission/lcm/demo_mission.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <utility>
#include <sstream>

#include "cairn/lcmt_goal.hpp"
#include "cairn/lcmt_mapstore_reply.hpp"
#include "cairn/lcmt_mapstore_request.hpp"
#include "cairn/lcmt_nav_status.hpp"
#include "cairn/lcmt_odometry.hpp"
#include "cairn/lcmt_path.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sonar_ping.hpp"

#include "common/channels.h"
#include "common/layers.h"
#include "common/robot_profile.h"
#include "mapstore/lcm/mapstore_client.h"
#include "mapstore/map_io.h"
#include "services/runtime/conversions.h"

namespace cairn::mission {
namespace {

using Clock = std::chrono::steady_clock;
using NavStatus = cairn::lcmt_nav_status;
using Request = cairn::lcmt_mapstore_request;

double SecondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

const char* StateName(int8_t state) {
  switch (state) {
    case NavStatus::STATE_IDLE:
      return "idle";
    case NavStatus::STATE_PLANNING:
      return "planning";
    case NavStatus::STATE_DRIVING:
      return "driving";
    case NavStatus::STATE_RECOVERING:
      return "recovering";
    case NavStatus::STATE_REACHED:
      return "reached";
    case NavStatus::STATE_FAILED:
      return "failed";
    case NavStatus::STATE_CANCELLED:
      return "cancelled";
    case NavStatus::STATE_STOPPED:
      return "stopped";
  }
  return "?";
}

// The part of a map that holds known cells of `layer`, plus a margin: stored maps grow in
// large blocks, and a render of mostly unknown space shows nothing. With a focus (world min and
// max corners), only known cells inside it count: a sonar sees 50 m round every point of a
// drive, and the rocks it passed would be specks in a render of all it saw.
common::GridMap CropToKnown(const common::GridMap& map, const std::string& layer,
                            int margin_cells,
                            std::optional<std::pair<common::Vector2, common::Vector2>> focus = {}) {
  if (!map.HasLayer(layer)) return map;
  const common::Layer& values = map.at(layer);
  int min_x = map.size_x(), min_y = map.size_y(), max_x = -1, max_y = -1;
  for (int iy = 0; iy < map.size_y(); ++iy) {
    for (int ix = 0; ix < map.size_x(); ++ix) {
      if (std::isnan(values(ix, iy))) continue;
      if (focus) {
        const common::Vector2 c = map.CenterOf({ix, iy});
        if ((c.array() < focus->first.array()).any() || (c.array() > focus->second.array()).any())
          continue;
      }
      min_x = std::min(min_x, ix);
      max_x = std::max(max_x, ix);
      min_y = std::min(min_y, iy);
      max_y = std::max(max_y, iy);
    }
  }
  if (max_x < 0) return map;
  min_x = std::max(0, min_x - margin_cells);
  min_y = std::max(0, min_y - margin_cells);
  max_x = std::min(map.size_x() - 1, max_x + margin_cells);
  max_y = std::min(map.size_y() - 1, max_y + margin_cells);
  common::GridGeometry g = map.geometry();
  g.origin = map.geometry().origin.Compose({min_x * g.resolution_m, min_y * g.resolution_m, 0.0});
  g.size_x = max_x - min_x + 1;
  g.size_y = max_y - min_y + 1;
  common::GridMap out(g);
  for (const auto& name : map.layer_names()) {
    out.AddLayer(name) = map.at(name).block(min_x, min_y, g.size_x, g.size_y);
  }
  return out;
}

}  // namespace

DemoMission::DemoMission(runtime::Node* node, MissionParams params)
    : node_(node), params_(std::move(params)) {}

MissionReport DemoMission::Run() {
  MissionReport report;
  try {
    if (!WaitForGraph(&report)) return report;
    const bool arrived = Drive(&report);
    // The map is stored and rendered even when the drive failed: it shows why.
    const std::string drive_error = report.error;
    report.error.clear();
    StoreAndShare(&report);
    if (!arrived) report.error = drive_error + (report.error.empty() ? "" : "; " + report.error);
  } catch (const std::exception& e) {
    report.error = std::string("internal error: ") + e.what();
  }
  return report;
}

bool DemoMission::WaitForGraph(MissionReport* report) {
  // The robot's pose and a ready navigator heartbeat mean the graph is working.
  bool have_pose = false, navigator_ready = false, mapstore_ready = false;
  auto pose_sub = node_->lcm().subscribeFunction<bool*>(
      channels::ForRobot(params_.robot, channels::kPose),
      [](const lcm::ReceiveBuffer*, const std::string&, bool* flag) { *flag = true; }, &have_pose);
  struct Flags {
    std::string robot;
    bool* navigator;
    bool* mapstore;
  } flags{params_.robot, &navigator_ready, &mapstore_ready};
  auto health_sub = node_->lcm().subscribeFunction<Flags*>(
      channels::kHealth,
      [](const lcm::ReceiveBuffer* rbuf, const std::string&, Flags* f) {
        cairn::lcmt_health h{};
        if (h.decode(rbuf->data, 0, rbuf->data_size) < 0) return;
        const bool ready = h.state == cairn::lcmt_health::STATE_READY;
        if (h.process == "cairn-navigator" && h.robot == f->robot && ready) *f->navigator = true;
        if (h.process == "cairn-mapstore" && ready) *f->mapstore = true;
      },
      &flags);
  const auto start = Clock::now();
  while (!(have_pose && navigator_ready && mapstore_ready) &&
         SecondsSince(start) < params_.ready_timeout_s && !node_->stopping()) {
    node_->SpinOnce(50);
  }
  node_->lcm().unsubscribe(pose_sub);
  node_->lcm().unsubscribe(health_sub);
  if (!(have_pose && navigator_ready && mapstore_ready)) {
    report->error = std::string("the graph is not working after ") +
                    std::to_string(static_cast<int>(params_.ready_timeout_s)) +
                    " s: " + (!have_pose ? "no pose from " + params_.robot + "; " : "") +
                    (!navigator_ready ? "no ready cairn-navigator; " : "") +
                    (!mapstore_ready ? "no ready cairn-mapstore" : "");
    return false;
  }
  node_->Event("graph ready: %s has a pose, the navigator and the map store are ready",
               params_.robot.c_str());
  return true;
}

// What the drive has seen on the bus: the robot's ground-truth track and the navigator's
// status for our goal.
struct DemoMission::DriveState {
  bool have_pose{false};
  common::Vector2 last{common::Vector2::Zero()};
  int64_t first_utime{0};
  int64_t last_utime{0};
  double distance_m{0.0};
  std::vector<common::Vector2>* path{nullptr};
  TrackLog* track{nullptr};
  SonarFan* fan{nullptr};
  SonarFan* first_fan{nullptr};
  int64_t* bad{nullptr};
  std::optional<NavStatus> status;
  Clock::time_point status_time;
  int64_t goal_id{0};

  // A new pose: the track grows by steps of more than 5 cm.
  void OnPose(const cairn::lcmt_pose& m) {
    const common::Vector2 p(m.position_m[0], m.position_m[1]);
    if (!p.allFinite()) return;
    if (!have_pose) {
      have_pose = true;
      first_utime = m.utime;
      last = p;
      path->push_back(p);
    }
    const double step = (p - last).norm();
    if (step > 0.05) {
      distance_m += step;
      last = p;
      path->push_back(p);
    }
    last_utime = m.utime;
    track->OnTruth(m.utime, p);
  }

  // The navigator's latest plan (checked: a count that disagrees with its arrays, or over
  // 100,000 poses, is dropped).
  void OnPath(const cairn::lcmt_path& m) {
    const size_t n = static_cast<size_t>(std::max(0, m.num_poses));
    if (m.num_poses < 0 || m.num_poses > 100000 || m.x_m.size() != n || m.y_m.size() != n) {
      ++*bad;
      return;
    }
    std::vector<common::Vector2> points;
    points.reserve(n);
    for (size_t i = 0; i < n; ++i) points.emplace_back(m.x_m[i], m.y_m[i]);
    if (!track->OnPath(points).ok()) ++*bad;
  }

  void OnPing(const cairn::lcmt_sonar_ping& m) {
    if (m.num_bins < 0 || static_cast<size_t>(m.num_bins) != m.intensities.size()) {
      ++*bad;
      return;
    }
    FanPing ping;
    ping.pan_rad = m.pan_rad;
    ping.range_min_m = m.range_min_m;
    ping.range_max_m = m.range_max_m;
    ping.bins.assign(m.intensities.begin(), m.intensities.end());
    if (!fan->Add(ping).ok()) {
      ++*bad;
      return;
    }
    if (fan->reversals() < 2) first_fan->Add(ping);
  }
};

bool DemoMission::Drive(MissionReport* report) {
  DriveState state;
  state.path = &driven_m_;
  state.track = &track_;
  state.fan = &fan_;
  state.first_fan = &first_fan_;
  state.bad = &bad_messages_;
  state.goal_id = runtime::Node::WallUtime();
  auto pose_sub = node_->lcm().subscribeFunction<DriveState*>(
      channels::ForRobot(params_.robot, channels::kPose),
      [](const lcm::ReceiveBuffer* rbuf, const std::string&, DriveState* s) {
        cairn::lcmt_pose m{};
        if (m.decode(rbuf->data, 0, rbuf->data_size) >= 0) s->OnPose(m);
      },
      &state);
  auto status_sub = node_->lcm().subscribeFunction<DriveState*>(
      channels::ForRobot(params_.robot, channels::kNavStatus),
      [](const lcm::ReceiveBuffer* rbuf, const std::string&, DriveState* s) {
        NavStatus m;
        if (m.decode(rbuf->data, 0, rbuf->data_size) < 0 || m.goal_id != s->goal_id) return;
        s->status = m;
        s->status_time = Clock::now();
      },
      &state);
  auto path_sub = node_->lcm().subscribeFunction<DriveState*>(
      channels::ForRobot(params_.robot, channels::kPath),
      [](const lcm::ReceiveBuffer* rbuf, const std::string&, DriveState* s) {
        cairn::lcmt_path m;
        if (m.decode(rbuf->data, 0, rbuf->data_size) < 0) {
          ++*s->bad;
          return;
        }
        s->OnPath(m);
      },
      &state);
  auto odom_sub = node_->lcm().subscribeFunction<DriveState*>(
      channels::ForRobot(params_.robot, channels::kOdom),
      [](const lcm::ReceiveBuffer* rbuf, const std::string&, DriveState* s) {
        cairn::lcmt_odometry m{};
        if (m.decode(rbuf->data, 0, rbuf->data_size) < 0) return;
        s->track->OnOdometry({m.position_m[0], m.position_m[1]});
      },
      &state);
  auto sonar_sub = node_->lcm().subscribeFunction<DriveState*>(
      channels::ForRobot(params_.robot, channels::kSonar),
      [](const lcm::ReceiveBuffer* rbuf, const std::string&, DriveState* s) {
        cairn::lcmt_sonar_ping m;
        if (m.decode(rbuf->data, 0, rbuf->data_size) < 0) {
          ++*s->bad;
          return;
        }
        s->OnPing(m);
      },
      &state);
  cairn::lcmt_goal goal = MakeGoal(state.goal_id);
  const auto start = Clock::now();
  const bool done = FollowGoal(&goal, &state, report);
  for (auto* sub : {pose_sub, status_sub, path_sub, odom_sub, sonar_sub}) {
    node_->lcm().unsubscribe(sub);
  }
  if (bad_messages_ > 0) node_->Count("bad_messages", bad_messages_);
  report->wall_time_s = SecondsSince(start);
  report->distance_m = state.distance_m;
  report->sim_time_s = (state.last_utime - state.first_utime) * 1e-6;
  report->real_time_factor = report->wall_time_s > 0 ? report->sim_time_s / report->wall_time_s : 0;
  if (!done) {
    report->nav_outcome = node_->stopping() ? "interrupted" : "timed out";
    report->error = "the robot did not reach the goal within " +
                    std::to_string(static_cast<int>(params_.timeout_s)) + " s (" +
                    (state.status ? StateName(state.status->state) : "no navigation status") + ")";
    // Stop the robot: cancel the goal.
    goal.kind = cairn::lcmt_goal::KIND_CANCEL;
    node_->Publish(channels::ForRobot(params_.robot, channels::kGoal), goal);
    return false;
  }
  if (!report->reached) {
    report->error = "navigation " + report->nav_outcome;
    return false;
  }
  return true;
}

cairn::lcmt_goal DemoMission::MakeGoal(int64_t goal_id) const {
  cairn::lcmt_goal goal{};
  goal.robot = params_.robot;
  goal.goal_id = goal_id;
  goal.kind = cairn::lcmt_goal::KIND_POSE;
  goal.x_m = params_.goal.x_m;
  goal.y_m = params_.goal.y_m;
  goal.yaw_rad = params_.goal.yaw_rad;
  goal.use_yaw = params_.goal_has_yaw;
  node_->Event("goal %lld: %s to (%.2f, %.2f)", static_cast<long long>(goal.goal_id),
               params_.robot.c_str(), goal.x_m, goal.y_m);
  return goal;
}

bool DemoMission::FollowGoal(cairn::lcmt_goal* goal, DriveState* state, MissionReport* report) {
  const auto start = Clock::now();
  auto last_goal = Clock::now() - std::chrono::seconds(10);
  int8_t last_state = -1;
  while (SecondsSince(start) < params_.timeout_s && !node_->stopping()) {
    // Publish the goal until the navigator answers for it, and again whenever its status for
    // the goal stops (a restarted navigator starts idle; re-sends of a goal id are idempotent).
    const bool unanswered = !state->status || SecondsSince(state->status_time) > 3.0;
    if (unanswered && SecondsSince(last_goal) > 1.0) {
      if (state->status)
        node_->Event("goal %lld: no status for 3 s, sending it again",
                     static_cast<long long>(goal->goal_id));
      goal->utime = node_->NowUtime();
      node_->Publish(channels::ForRobot(params_.robot, channels::kGoal), *goal);
      last_goal = Clock::now();
    }
    node_->SpinOnce(50);
    if (!state->status) continue;
    const NavStatus& s = *state->status;
    if (s.state != last_state) {
      last_state = s.state;
      node_->Event("navigation %s%s%s (%.0f %% of the path, %.1f m to go)", StateName(s.state),
                   s.message.empty() ? "" : ": ", s.message.c_str(), 100.0 * s.progress,
                   s.distance_remaining_m);
    }
    report->replans = s.replans;
    report->recoveries = s.recoveries;
    if (s.state == NavStatus::STATE_REACHED) {
      report->reached = true;
      report->nav_outcome = "reached";
      return true;
    }
    if (s.state == NavStatus::STATE_FAILED || s.state == NavStatus::STATE_CANCELLED) {
      report->nav_outcome = std::string(StateName(s.state)) + ": " + s.message;
      return true;
    }
  }
  return false;
}

bool DemoMission::StoreAndShare(MissionReport* report) {
  mapstore::MapstoreClientOptions options;
  options.total_timeout_s = 120.0;
  mapstore::MapstoreClient client(node_->lcm(), "cairn-mission", options);
  std::vector<std::string> profiles = {params_.source_profile};
  profiles.insert(profiles.end(), params_.share_profiles.begin(), params_.share_profiles.end());
  return WriteTrackAndSonar(report) && PutProfiles(&client, profiles, report) &&
         SaveMap(&client, report) && ShareMap(&client, report) &&
         RenderAndList(&client, profiles, report);
}

namespace {

// The reply's failure as text, or the empty string for an OK reply.
std::string CallError(const common::Result<cairn::lcmt_mapstore_reply>& reply) {
  if (!reply.ok()) return reply.status().ToString();
  return reply->status == cairn::lcmt_mapstore_reply::STATUS_OK ? "" : reply->message;
}

// "0.30 m", or "unmeasured" (a sonar contact).
std::string HeightText(double height_m) {
  if (std::isnan(height_m)) return "unmeasured";
  char text[32];
  std::snprintf(text, sizeof(text), "%5.2f m", height_m);
  return text;
}

// "crossable", or "one-way (reason)" / "blocked (reason)".
std::string VerdictText(const common::ObstacleVerdict& v) {
  return v.crossable ? std::string("crossable")
                     : std::string(common::VerdictWord(v)) + " (" + v.reason + ")";
}

}  // namespace

bool DemoMission::PutProfiles(mapstore::MapstoreClient* client,
                              const std::vector<std::string>& profiles, MissionReport* report) {
  // Profiles the store needs to label the map for each robot.
  for (const auto& name : profiles) {
    const common::RobotProfile profile =
        common::LoadRobotProfileFile(params_.profiles_dir + "/" + name + ".yaml");
    Request put{};
    put.op = Request::OP_PUT_PROFILE;
    put.has_profile = true;
    put.profile_data = runtime::ToLcm(profile);
    const std::string error = CallError(client->Call(put));
    if (!error.empty()) {
      report->error = "storing profile " + name + " failed: " + error;
      return false;
    }
  }
  return true;
}

bool DemoMission::SaveMap(mapstore::MapstoreClient* client, MissionReport* report) {
  // Save: the store pulls the mapper's live layers.
  Request save{};
  save.op = Request::OP_SAVE;
  save.site = params_.site;
  save.map_name = params_.map_name;
  save.robot = params_.robot;
  save.profile = params_.source_profile;
  auto saved = client->Call(save);
  const std::string error = CallError(saved);
  if (!error.empty()) {
    report->error = "saving the map failed: " + error;
    return false;
  }
  report->map_version = saved->version;
  node_->Event("map saved as %s/%s version %lld (%s)", params_.site.c_str(),
               params_.map_name.c_str(), static_cast<long long>(saved->version),
               saved->message.c_str());
  return true;
}

bool DemoMission::ShareMap(mapstore::MapstoreClient* client, MissionReport* report) {
  // Share with every other profile: the store derives their layers and verdicts.
  for (const auto& target : params_.share_profiles) {
    Request share{};
    share.op = Request::OP_SHARE;
    share.site = params_.site;
    share.map_name = params_.map_name;
    share.version = report->map_version;
    share.profile = target;
    auto shared = client->Call(share);
    const std::string error = CallError(shared);
    if (!error.empty()) {
      report->error = "sharing with " + target + " failed: " + error;
      return false;
    }
    node_->Event("shared with %s: %d obstacle verdicts differ from %s", target.c_str(),
                 shared->num_obstacles, params_.source_profile.c_str());
  }
  return true;
}

bool DemoMission::Render(const std::string& name, const common::GridMap& map,
                         const std::string& layer, const mapstore::io::PngOverlay& overlay,
                         MissionReport* report) {
  // A map other than a terrain's (a sonar's) is shown round the path and the obstacles.
  std::optional<std::pair<common::Vector2, common::Vector2>> focus;
  if (params_.map_layer != layers::kElevation && !driven_m_.empty()) {
    common::Vector2 lo = driven_m_.front(), hi = driven_m_.front();
    auto grow = [&](const common::Vector2& p) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    };
    for (const auto& p : driven_m_) grow(p);
    for (const auto& o : overlay.obstacles) grow(o.centroid_m);
    const common::Vector2 margin(8.0, 8.0);
    focus = std::make_pair(common::Vector2(lo - margin), common::Vector2(hi + margin));
  }
  auto png = mapstore::io::WritePng(params_.out_dir, name,
                                    CropToKnown(map, params_.map_layer, 5, focus), layer, overlay);
  if (!png.ok()) {
    report->error = "rendering " + name + " failed: " + png.status().ToString();
    return false;
  }
  report->renders.push_back(*png);
  return true;
}

bool DemoMission::WriteTrackAndSonar(MissionReport* report) {
  std::error_code ec;
  std::filesystem::create_directories(params_.out_dir, ec);
  const std::string csv = params_.out_dir + "/track.csv";
  const common::Status written = track_.WriteCsv(csv);
  if (!written.ok()) {
    report->error = "writing the track failed: " + written.ToString();
    return false;
  }
  report->renders.push_back(std::filesystem::absolute(csv, ec).string());
  const struct {
    const SonarFan* fan;
    const char* stem;
    const char* which;
  } fans[] = {{&first_fan_, "sonar_fan_first", "FIRST WHOLE SWEEP"},
              {&fan_, "sonar_fan_last", "LAST SWEEP"}};
  for (const auto& f : fans) {
    if (f.fan->bearings() == 0) continue;
    mapstore::io::PngOverlay overlay;
    char caption[160];
    std::snprintf(caption, sizeof(caption), "%s OF THE SONAR OF %s, %.0f TO %.0f DEG, X FORWARD",
                  f.which, params_.robot.c_str(), f.fan->min_pan_rad() * 180.0 / M_PI,
                  f.fan->max_pan_rad() * 180.0 / M_PI);
    overlay.caption = caption;
    overlay.markers.push_back({{0.0, 0.0}, "HEAD"});
    auto png = mapstore::io::WritePng(params_.out_dir, f.stem, f.fan->Image(0.1),
                                      SonarFan::kIntensityLayer, overlay);
    if (!png.ok()) {
      report->error = std::string("rendering the sonar fan failed: ") + png.status().ToString();
      return false;
    }
    report->renders.push_back(*png);
  }
  return true;
}

bool DemoMission::RenderAndList(mapstore::MapstoreClient* client,
                                const std::vector<std::string>& profiles, MissionReport* report) {
  // Load the map under each profile and render it.
  std::error_code ec;
  std::filesystem::create_directories(params_.out_dir, ec);
  std::map<int, std::map<std::string, std::string>> verdicts;  // obstacle id -> profile -> text
  std::map<int, common::Obstacle> obstacles;
  bool base_done = false;
  for (const auto& name : profiles) {
    auto loaded = client->Load(params_.site, params_.map_name, report->map_version, name,
                               {params_.map_layer, layers::CostLayer(name)});
    if (!loaded.ok()) {
      report->error = "loading the map for " + name + " failed: " + loaded.status().ToString();
      return false;
    }
    for (const auto& o : loaded->obstacles.obstacles) {
      auto [it, fresh] = obstacles.emplace(o.id, o);
      if (!fresh && it->second.parts.size() == o.parts.size()) {
        for (size_t k = 0; k < o.parts.size(); ++k) {
          auto& kept = it->second.parts[k].verdicts;
          kept.insert(kept.end(), o.parts[k].verdicts.begin(), o.parts[k].verdicts.end());
        }
      }
      const auto* v = o.VerdictFor(name);
      verdicts[o.id][name] = v == nullptr ? "?" : VerdictText(*v);
    }
    if (!base_done && loaded->layers.HasLayer(params_.map_layer)) {
      // The stored base layer, with the path and the obstacles (a sonar map's contacts).
      mapstore::io::PngOverlay overlay;
      overlay.obstacles = loaded->obstacles.obstacles;
      overlay.verdict_profile = name;
      if (params_.map_layer != layers::kElevation) overlay.path_m = driven_m_;
      std::string title = params_.map_layer;
      std::transform(title.begin(), title.end(), title.begin(), ::toupper);
      overlay.caption = title + " OF " + params_.site + "/" + params_.map_name + " V" +
                        std::to_string(report->map_version) + " MAPPED BY " + params_.robot;
      std::string stem = params_.map_layer;
      std::replace(stem.begin(), stem.end(), '/', '_');
      if (!Render(stem, loaded->layers, params_.map_layer, overlay, report)) return false;
      base_done = true;
    }
    mapstore::io::PngOverlay overlay;
    overlay.path_m = driven_m_;
    overlay.obstacles = loaded->obstacles.obstacles;
    overlay.verdict_profile = name;
    overlay.caption = "COST FOR " + name + " WITH THE PATH " + params_.robot + " DROVE";
    if (!Render("cost_" + name, loaded->layers, layers::CostLayer(name), overlay, report))
      return false;
  }
  for (const auto& [id, o] : obstacles) {
    std::ostringstream line;
    char head[160];
    std::snprintf(head, sizeof(head),
                  "#%-3d %-14s at (%5.1f, %5.1f)  slope %4.1f deg  height %s  width %4.2f m",
                  id, common::ObstacleKindName(o.kind), o.centroid_m.x(), o.centroid_m.y(),
                  o.slope_rad * 180.0 / M_PI, HeightText(o.height_m).c_str(), o.width_m);
    line << head;
    for (const auto& name : profiles) line << "  " << name << ": " << verdicts[id][name];
    report->obstacle_lines.push_back(line.str());
    // A terrace's parts, each with every profile's verdict.
    for (size_t k = 0; k < o.parts.size(); ++k) {
      const common::ObstaclePart& p = o.parts[k];
      std::ostringstream part;
      std::snprintf(head, sizeof(head),
                    "  #%d.%zu %-10s at (%5.1f, %5.1f)  slope %4.1f deg  height %5.2f m  onto it "
                    "heading %3.0f deg",
                    id, k + 1, common::ObstacleKindName(p.kind), p.centroid_m.x(), p.centroid_m.y(),
                    p.slope_rad * 180.0 / M_PI, p.height_m,
                    std::fmod(p.heading_in_rad * 180.0 / M_PI + 360.0, 360.0));
      part << head;
      for (const auto& v : p.verdicts) {
        part << "  " << v.profile << ": " << VerdictText(v);
      }
      report->obstacle_lines.push_back(part.str());
    }
  }
  return true;
}

std::string FormatReport(const MissionParams& params, const MissionReport& r) {
  std::ostringstream out;
  char line[256];
  out << "\n=== cairn demo mission ===\n";
  std::snprintf(line, sizeof(line), "robot          %s (profile %s), goal (%.2f, %.2f)\n",
                params.robot.c_str(), params.source_profile.c_str(), params.goal.x_m,
                params.goal.y_m);
  out << line;
  out << "outcome        " << (r.ok() ? "SUCCESS" : "FAILED") << " (navigation " << r.nav_outcome
      << ")\n";
  if (!r.error.empty()) out << "error          " << r.error << "\n";
  std::snprintf(line, sizeof(line),
                "distance       %.1f m\nsim time       %.1f s\nwall time      %.1f s\n"
                "real-time      %.2fx\nreplans        %d\nrecoveries     %d\n",
                r.distance_m, r.sim_time_s, r.wall_time_s, r.real_time_factor, r.replans,
                r.recoveries);
  out << line;
  if (r.map_version > 0) {
    out << "stored map     " << params.site << "/" << params.map_name << " version "
        << r.map_version << ", shared with";
    for (const auto& p : params.share_profiles) out << " " << p;
    out << "\n";
  }
  if (!r.obstacle_lines.empty()) {
    out << "obstacles (" << r.obstacle_lines.size() << "):\n";
    for (const auto& l : r.obstacle_lines) out << "  " << l << "\n";
  }
  if (!r.renders.empty()) {
    out << "renders:\n";
    for (const auto& p : r.renders) out << "  " << p << "\n";
  }
  return out.str();
}

}  // namespace cairn::mission
