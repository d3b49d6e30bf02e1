#include "planner/local/dwa_planner.h"

#include <cmath>
#include <limits>

#include "common/check.h"

namespace cairn::planner {

void DwaParams::Validate() const {
  generator.Validate();
  for (const double s :
       {path_align_scale, goal_dist_scale, clearance_scale, speed_scale, oscillation_scale}) {
    CAIRN_THROW_UNLESS(std::isfinite(s) && s >= 0.0, "critic scales must be finite and >= 0");
  }
  CAIRN_THROW_UNLESS(braking_margin_s >= 0.0, "braking_margin_s must not be negative");
  CAIRN_THROW_UNLESS(clearance_inflation_m >= 0.0, "clearance_inflation_m must not be negative");
  CAIRN_THROW_UNLESS(forward_point_distance_m >= 0.0, "forward_point_distance_m must be >= 0");
  for (const double l : tracking_lookaheads_m) {
    CAIRN_THROW_UNLESS(std::isfinite(l) && l > 0.0, "tracking_lookaheads_m must be positive");
  }
  CAIRN_THROW_UNLESS(tracking_turn_in_place_rad > 0.0 && tracking_turn_in_place_rad <= M_PI,
                     "tracking_turn_in_place_rad must lie in (0, pi]");
  CAIRN_THROW_UNLESS(tracking_min_radius_m > 0.0, "tracking_min_radius_m must be positive");
  CAIRN_THROW_UNLESS(stall_speed_mps >= 0.0, "stall_speed_mps must not be negative");
  CAIRN_THROW_UNLESS(tracking_slow_distance_m >= 0.0,
                     "tracking_slow_distance_m must not be negative");
  CAIRN_THROW_UNLESS(oscillation_reset_dist_m > 0.0, "oscillation_reset_dist_m must be positive");
  CAIRN_THROW_UNLESS(oscillation_reset_angle_rad > 0.0,
                     "oscillation_reset_angle_rad must be positive");
}

DwaPlanner::DwaPlanner(const VelocityLimits& limits, const DwaParams& params)
    : params_(params), generator_(limits, params.generator) {
  params_.Validate();
  // Cheap critics first; clearance (footprint rasterisation) last.
  critics_.push_back(std::make_unique<SpeedCritic>(params_.speed_scale, limits.max_vel_x_mps));
  auto oscillation = std::make_unique<OscillationCritic>(params_.oscillation_scale,
                                                         params_.oscillation_reset_dist_m,
                                                         params_.oscillation_reset_angle_rad);
  oscillation_ = oscillation.get();
  critics_.push_back(std::move(oscillation));
  critics_.push_back(std::make_unique<GoalDistCritic>(params_.goal_dist_scale));
  critics_.push_back(std::make_unique<PathAlignCritic>(params_.path_align_scale,
                                                       params_.forward_point_distance_m));
  ClearanceCritic::Params clearance;
  clearance.admissible_braking = params_.admissible_braking;
  clearance.sim_step_s = params_.generator.sim_step_s;
  clearance.margin_s = params_.braking_margin_s;
  clearance.inflation_m = params_.clearance_inflation_m;
  clearance.acc_lim_x_mps2 = limits.acc_lim_x_mps2;
  clearance.acc_lim_theta_radps2 = limits.acc_lim_theta_radps2;
  // As far as the fastest sample goes over the horizon, plus the footprint's reach.
  clearance.path_reach_m = limits.max_vel_x_mps * params_.generator.sim_time_s + 0.3;
  auto clearance_critic = std::make_unique<ClearanceCritic>(params_.clearance_scale, clearance);
  clearance_ = clearance_critic.get();
  critics_.push_back(std::move(clearance_critic));
  for (const auto& c : critics_) names_.push_back(c->name());
  rejections_.assign(critics_.size(), 0);
}

DwaResult DwaPlanner::Compute(const DwaInput& input) {
  CAIRN_DEMAND(input.map != nullptr);
  CriticContext context;
  context.map = input.map;
  context.pose = input.pose;
  context.last_command = input.last_command;
  context.path = input.path;
  context.segment_begin = input.segment_begin;
  context.segment_end = input.segment_end;
  context.local_goal = input.local_goal;
  for (auto& c : critics_) c->Prepare(context);

  DwaResult result;
  result.rejections.assign(critics_.size(), 0);
  const std::vector<Velocity> samples = generator_.Samples(input.last_command);
  result.samples = static_cast<int>(samples.size());
  double best = std::numeric_limits<double>::infinity();
  double best_forward = std::numeric_limits<double>::infinity();
  // Best among samples rejected by the oscillation critic alone (the fallback).
  double best_oscillating = std::numeric_limits<double>::infinity();
  Trajectory oscillating;
  std::vector<double> values(critics_.size(), 0.0), oscillating_values;
  // Scores scratch_ with every critic and keeps it when it is the best so far.
  double best_tracking = std::numeric_limits<double>::infinity();
  Trajectory tracking_trajectory;
  std::vector<double> tracking_values;
  auto consider = [&](bool tracking) {
    double total = 0.0;
    bool valid = true;
    bool only_oscillation = true;
    for (size_t i = 0; i < critics_.size(); ++i) {
      const Score s = critics_[i]->Evaluate(scratch_);
      values[i] = 0.0;
      if (!s.valid) {
        valid = false;
        ++result.rejections[i];
        if (critics_[i].get() != oscillation_) only_oscillation = false;
        continue;
      }
      values[i] = critics_[i]->scale() * s.value;
      total += values[i];
    }
    if (valid) {
      ++result.valid;
      if (total < best) {
        best = total;
        result.best = scratch_;
        result.best_values = values;
        result.tracking_chosen = tracking;
      }
      // The best tracking trajectory that is clear over its whole horizon (the fallback below).
      if (tracking && values.back() < 2.0 * critics_.back()->scale() && total < best_tracking) {
        best_tracking = total;
        tracking_trajectory = scratch_;
        tracking_values = values;
      }
      if (scratch_.target.linear_mps > 1e-6 && total < best_forward) {
        best_forward = total;
        result.has_best_forward = true;
        result.best_forward = scratch_.target;
        result.best_forward_values = values;
      }
    } else if (only_oscillation && total < best_oscillating) {
      best_oscillating = total;
      oscillating = scratch_;
      oscillating_values = values;
    }
  };
  for (const Velocity& v : samples) {
    generator_.Simulate(input.pose, v, &scratch_);
    consider(false);
  }
  // More candidates: the robot tracking the global path itself.
  if (params_.path_tracking && input.path != nullptr) {
    TrajectoryGenerator::TrackingParams tracking;
    tracking.turn_in_place_rad = params_.tracking_turn_in_place_rad;
    tracking.min_radius_m = params_.tracking_min_radius_m;
    tracking.slow_distance_m = params_.tracking_slow_distance_m;
    for (const double lookahead_m : params_.tracking_lookaheads_m) {
      tracking.lookahead_m = lookahead_m;
      if (!generator_.TrackPath(input.pose, input.last_command, *input.path, input.segment_begin,
                                tracking, input.map, &scratch_)) {
        break;
      }
      ++result.samples;
      consider(true);
    }
  }
  for (size_t i = 0; i < critics_.size(); ++i) rejections_[i] += result.rejections[i];

  // A stall the path can break: the critics' sum picked standing still or creeping, while
  // tracking the global path is clear and drives on. Near an obstacle the path bends past (a
  // door beside a wall, a table leg) every constant arc that gains ground clips the obstacle or
  // costs more than it gains, and the dynamic window alone would stand there for ever.
  // And where the path itself runs within the clearance inflation of a blocking cell (a door,
  // a gap between table legs) it is the local plan: samples that score better by leaving it
  // take the robot off a line with centimetres to spare.
  const bool stalled = std::abs(result.best.target.linear_mps) < params_.stall_speed_mps &&
                       tracking_trajectory.target.linear_mps >= params_.stall_speed_mps;
  const bool tight = clearance_->path_proximity() > 0.0;
  if (result.valid > 0 && !result.tracking_chosen && std::isfinite(best_tracking) &&
      (stalled || tight)) {
    result.best = tracking_trajectory;
    result.best_values = tracking_values;
    result.tracking_chosen = true;
    result.tracking_broke_stall = stalled;
    best = best_tracking;
  }
  if (result.valid > 0) {
    result.found = true;
    result.command = result.best.velocity;
    result.score = best;
  } else if (std::isfinite(best_oscillating)) {
    oscillation_->Reset();
    result.oscillation_reset = true;
    result.found = true;
    result.best = oscillating;
    result.best_values = oscillating_values;
    result.command = oscillating.velocity;
    result.score = best_oscillating;
  } else {
    result.command = generator_.Brake(input.last_command);
  }
  return result;
}

void DwaPlanner::Commit(const Velocity& sent, const common::Pose2& pose) {
  for (auto& c : critics_) c->Commit(sent, pose);
}

void DwaPlanner::Reset() {
  for (auto& c : critics_) c->Reset();
  rejections_.assign(critics_.size(), 0);
}

}  // namespace cairn::planner
