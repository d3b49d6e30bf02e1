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
  critics_.push_back(std::make_unique<ClearanceCritic>(params_.clearance_scale, clearance));
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
  // Best among samples rejected by the oscillation critic alone (the fallback).
  double best_oscillating = std::numeric_limits<double>::infinity();
  Trajectory oscillating;
  for (const Velocity& v : samples) {
    generator_.Simulate(input.pose, v, &scratch_);
    double total = 0.0;
    bool valid = true;
    bool only_oscillation = true;
    for (size_t i = 0; i < critics_.size(); ++i) {
      const Score s = critics_[i]->Evaluate(scratch_);
      if (!s.valid) {
        valid = false;
        ++result.rejections[i];
        if (critics_[i].get() != oscillation_) only_oscillation = false;
        continue;
      }
      total += critics_[i]->scale() * s.value;
    }
    if (valid) {
      ++result.valid;
      if (total < best) {
        best = total;
        result.best = scratch_;
      }
    } else if (only_oscillation && total < best_oscillating) {
      best_oscillating = total;
      oscillating = scratch_;
    }
  }
  for (size_t i = 0; i < critics_.size(); ++i) rejections_[i] += result.rejections[i];

  if (result.valid > 0) {
    result.found = true;
    result.command = result.best.velocity;
    result.score = best;
  } else if (std::isfinite(best_oscillating)) {
    oscillation_->Reset();
    result.oscillation_reset = true;
    result.found = true;
    result.best = oscillating;
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
