#include "services/explore/nbv_mission.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "common/check.h"

namespace cairn::explore {

void NbvMissionParams::Validate() const {
  nbv.Validate();
  mesh.Validate();
  analysis.Validate();
  info.Validate();
  turret.Validate();
  work_area.Validate();
  CAIRN_THROW_UNLESS(max_scans >= 1, "max_scans must be >= 1 (got " << max_scans << ")");
  CAIRN_THROW_UNLESS(std::isfinite(goal_timeout_s) && goal_timeout_s > 0.0,
                     "goal_timeout_s must be > 0");
  CAIRN_THROW_UNLESS(max_scan_retries >= 0, "max_scan_retries must be >= 0");
  CAIRN_THROW_UNLESS(max_skipped_views >= 0, "max_skipped_views must be >= 0");
  CAIRN_THROW_UNLESS(max_goal_failures >= 1, "max_goal_failures must be >= 1");
  CAIRN_THROW_UNLESS(max_zones >= 0 && max_zones <= 100000, "max_zones must be in [0, 100000]");
}

namespace {

const NbvMissionParams& Validated(const NbvMissionParams& p) {
  p.Validate();
  return p;
}

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::string Fixed(double v, int digits) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

}  // namespace

NbvMission::NbvMission(const NbvMissionParams& params)
    : params_(Validated(params)),
      info_(params.work_area, params.info),
      planner_(params.nbv),
      assembler_(params.turret),
      missed_(info_.num_cells()) {}

const char* NbvMission::state_name() const {
  switch (state_) {
    case State::kIdle:
      return "idle";
    case State::kScanning:
      return "scanning";
    case State::kDriving:
      return "driving";
    case State::kDone:
      return "done";
  }
  return "?";
}

NbvAction NbvMission::Start(double now_s) {
  if (state_ != State::kIdle) return {};
  scan_retries_ = 0;
  return RequestScan(now_s, "first scan requested");
}

NbvAction NbvMission::RequestScan(double now_s, const std::string& event) {
  state_ = State::kScanning;
  assembler_.Request(now_s);
  NbvAction a;
  a.request_scan = true;
  a.event = event;
  return a;
}

void NbvMission::OnPosition(const common::Vector2& xy_m) {
  if (!std::isfinite(xy_m.x()) || !std::isfinite(xy_m.y())) return;
  if (!path_m_.empty()) {
    const double step = (xy_m - path_m_.back()).norm();
    if (step < 0.05) return;  // keep the path light: a point every 5 cm
    distance_m_ += step;
  }
  path_m_.push_back(xy_m);
}

NbvAction NbvMission::OnTurretLine(const common::LaserScan& line, double pan_rad, double now_s) {
  if (state_ != State::kScanning) return {};
  std::string event;
  const int restarts = assembler_.restarts();
  std::optional<OrderedScan> scan = assembler_.Add(line, pan_rad, now_s, &event);
  if (!scan) {
    if (assembler_.restarts() != restarts) {
      // The sweep broke (lines lost, the robot moved): a turret that sweeps on request will
      // not come back to pan 0 by itself, so ask again now.
      if (++scan_retries_ > params_.max_scan_retries) return ScanFailed(event, now_s);
      return RequestScan(now_s, event + "; asking again");
    }
    NbvAction a;
    a.event = event;
    return a;
  }
  NbvAction a = OnScan(*scan, now_s);
  if (!event.empty()) a.event = event + "; " + a.event;
  return a;
}

NbvAction NbvMission::OnScan(const OrderedScan& scan, double now_s) {
  scan_retries_ = 0;
  skipped_in_row_ = 0;
  ViewPoint view;
  const IntegratedScan integrated = IntegrateScan(scan, params_.Integration(), &info_, &mesh_);
  const ScanFeatures& features = integrated.features;
  view.mesh_ms = integrated.mesh_ms;
  view.analysis_ms = integrated.analysis_ms;
  const auto t0 = std::chrono::steady_clock::now();
  view.position_m = common::Vector2(scan.sensor_origin_m.x(), scan.sensor_origin_m.y());
  view.time_s = now_s;
  view.points_used = integrated.points_used;
  // The ground under the scanner: it picks the level the robot stands on (a deck or the road
  // below it) for the next decision.
  ground_z_m_ = scan.sensor_origin_m.z() - static_cast<float>(params_.nbv.scanner_height_m);

  // Zones this view has seen into leave the list; the scan's own zones join it.
  if (const auto cell = info_.geometry().IndexOf(view.position_m)) {
    ViewEvaluator evaluator(info_, params_.nbv);
    const int64_t node = info_.NearestLevel(info_.Linear(*cell), ground_z_m_);
    view.node = node;
    view.ground_z_m = ground_z_m_;
    ViewGains gains = evaluator.Evaluate(node, zones_, true);
    // Cells this scan should have seen and did not count in A only for nearer views.
    RecordMissedView(info_, node, gains.unexplored, &missed_);
    std::vector<size_t>& seen = gains.zones_seen;
    std::sort(seen.rbegin(), seen.rend());
    for (size_t z : seen) {
      if (z < zones_.size()) zones_.erase(zones_.begin() + static_cast<std::ptrdiff_t>(z));
    }
  }
  zones_.insert(zones_.end(), features.zones.begin(), features.zones.end());
  std::stable_sort(zones_.begin(), zones_.end(), [](const InterestZone& a, const InterestZone& b) {
    return a.area_m2 > b.area_m2;
  });
  if (zones_.size() > static_cast<size_t>(params_.max_zones)) zones_.resize(params_.max_zones);

  view.map_ms = integrated.map_ms + MsSince(t0);
  view.coverage = info_.Coverage();
  view.mean_quality = info_.MeanQuality();
  view.zones = static_cast<int>(zones_.size());
  view_points_.push_back(view);
  const std::string scanned = "scan " + std::to_string(view_points_.size()) + " at (" +
                              Fixed(view.position_m.x(), 1) + ", " + Fixed(view.position_m.y(), 1) +
                              "): " + std::to_string(view.points_used) + " points, coverage " +
                              Fixed(100.0 * view.coverage, 1) + " %, quality " +
                              Fixed(view.mean_quality, 2) + ", " + std::to_string(view.zones) +
                              " zones, " + Fixed(distance_m_, 1) + " m driven";
  if (scans() >= params_.max_scans) {
    NbvAction a = Finish("the scan limit (" + std::to_string(params_.max_scans) + ") is reached");
    a.event = scanned + "; " + a.event;
    return a;
  }
  double decision_ms = 0.0;
  NbvAction a = DecideNext(view.position_m, now_s, &decision_ms);
  view_points_.back().decision_ms = decision_ms;
  if (a.done) {
    a.event = scanned + "; " + a.event;
    return a;
  }
  const ViewPoint& v = view_points_.back();
  a.event = scanned + " (mesh " + Fixed(v.mesh_ms, 0) + " ms, analysis " + Fixed(v.analysis_ms, 0) +
            " ms, map " + Fixed(v.map_ms, 0) + " ms, decision " + Fixed(v.decision_ms, 0) +
            " ms over " + std::to_string(last_decision_->candidates.size()) + " candidates); " +
            a.event;
  return a;
}

NbvAction NbvMission::DecideNext(const common::Vector2& from_m, double now_s, double* decision_ms) {
  const auto t0 = std::chrono::steady_clock::now();
  try {
    std::vector<common::Vector2> visited = skipped_;
    visited.reserve(view_points_.size() + skipped_.size());
    for (const ViewPoint& v : view_points_) visited.push_back(v.position_m);
    last_decision_ = planner_.Decide(info_, zones_, from_m, &missed_, visited, ground_z_m_);
    *decision_ms = MsSince(t0);
  } catch (const std::invalid_argument& e) {
    return Finish(std::string("no decision: ") + e.what());
  }
  if (last_decision_->outcome != NbvDecision::Outcome::kGoTo || !last_decision_->best) {
    return Finish(std::string(OutcomeName(last_decision_->outcome)) + ": " +
                  last_decision_->reason);
  }
  goal_ = last_decision_->best;
  NbvLeg leg;
  leg.nodes = goal_->path_nodes;
  float ground = ground_z_m_;
  for (int64_t node : leg.nodes) {
    const bool explored = info_.Explored(node);
    leg.cnc_when_chosen.push_back(explored ? info_.Navigability(node)
                                           : std::numeric_limits<float>::quiet_NaN());
    if (explored && !std::isnan(info_.GroundHeight(node))) ground = info_.GroundHeight(node);
    leg.ground_z_m.push_back(ground);
  }
  legs_.push_back(std::move(leg));
  goal_sent_s_ = now_s;
  ++goals_sent_;
  state_ = State::kDriving;
  NbvAction a;
  a.goal = goal_;
  a.event = "next view (" + Fixed(goal_->position_m.x(), 1) + ", " +
            Fixed(goal_->position_m.y(), 1) + "): u " + Fixed(goal_->utility, 3) + ", A " +
            Fixed(goal_->info_gain, 2) + ", Q " + Fixed(goal_->quality_gain, 2) + ", O " +
            Fixed(goal_->zone_gain, 2) + ", path " + Fixed(goal_->path_cost, 1);
  return a;
}

NbvAction NbvMission::ScanFailed(const std::string& why, double now_s) {
  // At a view point (not the first scan) a sweep that never completes (the robot rocks on a
  // kerb's edge, lines keep getting lost) leaves that view point out: the next view is decided
  // from the map as it is, and only max_skipped_views of them in a row end the mission.
  if (view_points_.empty() || !goal_ || skipped_in_row_ >= params_.max_skipped_views) {
    return Finish(
        "no whole scan after " + std::to_string(scan_retries_) + " requests (" + why + ")", true);
  }
  ++skipped_in_row_;
  // Where the robot stands (its last position; the view point when none came).
  const common::Vector2 here = path_m_.empty() ? goal_->position_m : path_m_.back();
  skipped_.push_back(here);
  const std::string skipped = "no whole scan at (" + Fixed(here.x(), 1) + ", " +
                              Fixed(here.y(), 1) + ") after " + std::to_string(scan_retries_) +
                              " requests (" + why + "): view point skipped";
  scan_retries_ = 0;
  double decision_ms = 0.0;
  NbvAction a = DecideNext(here, now_s, &decision_ms);
  a.event = skipped + "; " + a.event;
  return a;
}

NbvAction NbvMission::OnGoalResult(bool reached, const std::string& reason, double now_s) {
  if (state_ != State::kDriving) return {};
  if (reached) {
    ++goals_reached_;
    failures_in_a_row_ = 0;
    scan_retries_ = 0;
    return RequestScan(now_s, "view point reached; scanning");
  }
  ++goals_failed_;
  if (++failures_in_a_row_ >= params_.max_goal_failures) {
    return Finish(
        std::to_string(failures_in_a_row_) + " goals in a row failed (last: " + reason + ")", true);
  }
  // Scan where the robot stopped: it has moved, and the new view decides again.
  scan_retries_ = 0;
  return RequestScan(now_s, "goal failed (" + reason + "); scanning where the robot stands");
}

NbvAction NbvMission::Tick(double now_s) {
  if (state_ == State::kScanning) {
    std::string event;
    if (assembler_.CheckTimeout(now_s, &event)) {
      if (++scan_retries_ > params_.max_scan_retries) return ScanFailed(event, now_s);
      return RequestScan(now_s, event + "; asking again");
    }
  } else if (state_ == State::kDriving && now_s - goal_sent_s_ > params_.goal_timeout_s) {
    return OnGoalResult(false, "no result in " + Fixed(params_.goal_timeout_s, 0) + " s", now_s);
  }
  return {};
}

void NbvMission::Stop(const std::string& why) {
  if (state_ != State::kDone) Finish(why);
}

NbvAction NbvMission::Finish(const std::string& why, bool failed) {
  state_ = State::kDone;
  failed_ = failed;
  end_reason_ = why;
  NbvAction a;
  a.done = true;
  a.event = "exploration done: " + why;
  return a;
}

}  // namespace cairn::explore
