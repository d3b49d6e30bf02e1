#include "planner/local/dwa_planner.h"

#include <cmath>
#include <limits>
#include <set>

#include "common/check.h"

namespace cairn::planner {

CriticConfig* DwaParams::FindCritic(const std::string& name) {
  for (CriticConfig& c : critics) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

const CriticConfig* DwaParams::FindCritic(const std::string& name) const {
  for (const CriticConfig& c : critics) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

void DwaParams::Validate() const {
  generator.Validate();
  CAIRN_THROW_UNLESS(!critics.empty(), "the DWA needs at least one critic");
  std::set<std::string> names;
  for (const CriticConfig& c : critics) {
    CAIRN_THROW_UNLESS(!c.name.empty(), "a critic of the list has no name");
    CAIRN_THROW_UNLESS(names.insert(c.name).second, "critic '" << c.name << "' is listed twice");
    CAIRN_THROW_UNLESS(std::isfinite(c.scale) && c.scale >= 0.0,
                       "critic '" << c.name << "': scale must be finite and >= 0");
  }
  for (const double l : tracking_lookaheads_m) {
    CAIRN_THROW_UNLESS(std::isfinite(l) && l > 0.0, "tracking_lookaheads_m must be positive");
  }
  CAIRN_THROW_UNLESS(tracking_turn_in_place_rad > 0.0 && tracking_turn_in_place_rad <= M_PI,
                     "tracking_turn_in_place_rad must lie in (0, pi]");
  CAIRN_THROW_UNLESS(tracking_min_radius_m > 0.0, "tracking_min_radius_m must be positive");
  CAIRN_THROW_UNLESS(stall_speed_mps >= 0.0, "stall_speed_mps must not be negative");
  CAIRN_THROW_UNLESS(tracking_slow_distance_m >= 0.0,
                     "tracking_slow_distance_m must not be negative");
}

DwaPlanner::DwaPlanner(const VelocityLimits& limits, const DwaParams& params,
                       const CriticRegistry& registry)
    : params_(params), generator_(limits, params.generator) {
  params_.Validate();
  const CriticSetup setup{limits, params_.generator};
  for (const CriticConfig& c : params_.critics) {
    critics_.push_back(registry.Make(c, setup));
    names_.push_back(critics_.back()->name());
    const auto* clearance = dynamic_cast<const ClearanceCritic*>(critics_.back().get());
    if (clearance != nullptr && clearance_ == nullptr) {
      clearance_ = clearance;
      clearance_index_ = critics_.size() - 1;
    }
  }
  rejections_.assign(critics_.size(), 0);
}

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

struct DwaPlanner::Cycle {
  DwaResult result;
  std::vector<double> values;  // scratch: scale × value per critic
  double best{kInf};
  double best_forward{kInf};
  // The best trajectory that only critics rejecting from memory refused (the fallback when
  // nothing is valid).
  double best_released{kInf};
  Trajectory released;
  std::vector<double> released_values;
  // The best tracking trajectory clear over its whole horizon (the stall fallback).
  double best_tracking{kInf};
  Trajectory tracking;
  std::vector<double> tracking_values;
};

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

  Cycle cycle;
  cycle.result.rejections.assign(critics_.size(), 0);
  cycle.values.assign(critics_.size(), 0.0);
  const std::vector<Velocity> samples = generator_.Samples(input.last_command);
  cycle.result.samples = static_cast<int>(samples.size());
  for (const Velocity& v : samples) {
    generator_.Simulate(input.pose, v, &scratch_);
    Consider(false, &cycle);
  }
  ScoreTracking(input, &cycle);
  for (size_t i = 0; i < critics_.size(); ++i) rejections_[i] += cycle.result.rejections[i];
  PreferTracking(&cycle);
  Decide(input, &cycle);
  return std::move(cycle.result);
}

// Scores scratch_ with every critic and keeps it where it is the best so far.
void DwaPlanner::Consider(bool tracking, Cycle* cycle) {
  DwaResult& result = cycle->result;
  std::vector<double>& values = cycle->values;
  double total = 0.0;
  bool valid = true;
  bool only_memory = true;
  bool clear_ahead = clearance_ == nullptr;
  for (size_t i = 0; i < critics_.size(); ++i) {
    const Score s = critics_[i]->Evaluate(scratch_);
    values[i] = 0.0;
    if (!s.valid) {
      valid = false;
      ++result.rejections[i];
      if (!critics_[i]->RejectsByMemory()) only_memory = false;
      continue;
    }
    if (clearance_ != nullptr && i == clearance_index_) {
      clear_ahead = ClearanceCritic::ClearOverHorizon(s);
    }
    values[i] = critics_[i]->scale() * s.value;
    total += values[i];
  }
  if (!valid) {
    if (only_memory && total < cycle->best_released) {
      cycle->best_released = total;
      cycle->released = scratch_;
      cycle->released_values = values;
    }
    return;
  }
  ++result.valid;
  if (total < cycle->best) {
    cycle->best = total;
    result.best = scratch_;
    result.best_values = values;
    result.tracking_chosen = tracking;
  }
  // The best tracking trajectory that is clear over its whole horizon (PreferTracking).
  if (tracking && clear_ahead && total < cycle->best_tracking) {
    cycle->best_tracking = total;
    cycle->tracking = scratch_;
    cycle->tracking_values = values;
  }
  if (scratch_.target.linear_mps > 1e-6 && total < cycle->best_forward) {
    cycle->best_forward = total;
    result.has_best_forward = true;
    result.best_forward = scratch_.target;
    result.best_forward_values = values;
  }
}

// More candidates: the robot tracking the global path itself, one per lookahead.
void DwaPlanner::ScoreTracking(const DwaInput& input, Cycle* cycle) {
  if (!params_.path_tracking || input.path == nullptr) return;
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
    ++cycle->result.samples;
    Consider(true, cycle);
  }
}

// A stall the path can break: the critics' sum picked standing still or creeping, while
// tracking the global path is clear and drives on. Near an obstacle the path bends past (a
// door beside a wall, a table leg) every constant arc that gains ground clips the obstacle or
// costs more than it gains, and the dynamic window alone would stand there for ever.
// And where the path itself runs within the clearance inflation of a blocking cell (a door,
// a gap between table legs) it is the local plan: samples that score better by leaving it
// take the robot off a line with centimetres to spare.
void DwaPlanner::PreferTracking(Cycle* cycle) const {
  DwaResult& result = cycle->result;
  const bool stalled = std::abs(result.best.target.linear_mps) < params_.stall_speed_mps &&
                       cycle->tracking.target.linear_mps >= params_.stall_speed_mps;
  const bool tight = clearance_ != nullptr && clearance_->path_proximity() > 0.0;
  if (result.valid > 0 && !result.tracking_chosen && std::isfinite(cycle->best_tracking) &&
      (stalled || tight)) {
    result.best = cycle->tracking;
    result.best_values = cycle->tracking_values;
    result.tracking_chosen = true;
    result.tracking_broke_stall = stalled;
    cycle->best = cycle->best_tracking;
  }
}

// The command: the best valid trajectory's, else the best one only memory refused (that memory
// cleared), else braking.
void DwaPlanner::Decide(const DwaInput& input, Cycle* cycle) {
  DwaResult& result = cycle->result;
  if (result.valid > 0) {
    result.found = true;
    result.command = result.best.velocity;
    result.score = cycle->best;
  } else if (std::isfinite(cycle->best_released)) {
    for (auto& c : critics_) {
      if (c->RejectsByMemory()) c->Reset();
    }
    result.oscillation_reset = true;
    result.found = true;
    result.best = cycle->released;
    result.best_values = cycle->released_values;
    result.command = cycle->released.velocity;
    result.score = cycle->best_released;
  } else {
    result.command = generator_.Brake(input.last_command);
  }
}

void DwaPlanner::Commit(const Velocity& sent, const common::Pose2& pose) {
  for (auto& c : critics_) c->Commit(sent, pose);
}

void DwaPlanner::Reset() {
  for (auto& c : critics_) c->Reset();
  rejections_.assign(critics_.size(), 0);
}

}  // namespace cairn::planner
