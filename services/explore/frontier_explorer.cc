#include "services/explore/frontier_explorer.h"

#include <cmath>
#include <cstdio>

namespace cairn::explore {
namespace {

// Frontiers on a cost layer: free below 0.5 (cost 0), occupied above 99.5 (lethal).
FrontierParams OnCostLayer(FrontierParams p) {
  p.free_threshold = 0.5f;
  p.occupied_threshold = 99.5f;
  return p;
}

std::string Format(const char* format, double a, double b, double c = 0.0) {
  char line[200];
  std::snprintf(line, sizeof(line), format, a, b, c);
  return line;
}

}  // namespace

FrontierExplorer::FrontierExplorer(const FrontierModeParams& params) : params_(params) {
  params_.Validate();
}

FrontierAction FrontierExplorer::Send(const Frontier& f, double now_s, const std::string& why) {
  FrontierAction a;
  a.kind = FrontierAction::Kind::kSendGoal;
  a.goal_id = next_id_++;
  a.goal_m = f.goal_m;
  a.why = why;
  active_id_ = a.goal_id;
  active_goal_ = f.goal_m;
  active_cost_ = f.cost;
  best_distance_m_ = f.distance_m;
  progress_time_s_ = now_s;
  ++goals_sent_;
  return a;
}

FrontierAction FrontierExplorer::Tick(const common::GridMap* map, const std::string& layer,
                                      const common::Vector2& robot_m, double now_s) {
  if (finished_ || map == nullptr) return {};
  if (active_id_) {
    // Progress: the straight-line distance to the goal must shrink by 0.25 m now and then.
    const double d = (active_goal_ - robot_m).norm();
    if (d < best_distance_m_ - 0.25) {
      best_distance_m_ = d;
      progress_time_s_ = now_s;
    }
    if (now_s - progress_time_s_ > params_.progress_timeout_s) {
      FrontierAction a;
      a.kind = FrontierAction::Kind::kCancelGoal;
      a.goal_id = *active_id_;
      a.goal_m = active_goal_;
      a.why = Format("goal (%.2f, %.2f) given up: no progress for %.0f s", active_goal_.x(),
                     active_goal_.y(), params_.progress_timeout_s);
      failed_.push_back(active_goal_);
      ++goals_failed_;
      active_id_.reset();
      return a;
    }
    if (last_choice_s_ && now_s - *last_choice_s_ < params_.choose_period_s) return {};
  }
  last_choice_s_ = now_s;
  // The robot's own surroundings read as free where unknown (see free_around_robot_m).
  common::GridMap local = *map;
  common::Layer& cells = local.at(layer);
  const double r = params_.free_around_robot_m;
  const double res = local.resolution_m();
  const int reach = static_cast<int>(std::ceil(r / res));
  if (const auto centre = local.IndexOf(robot_m)) {
    for (int dy = -reach; dy <= reach; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const common::CellIndex c{centre->ix + dx, centre->iy + dy};
        if (!local.Contains(c) || (dx * dx + dy * dy) * res * res > r * r) continue;
        if (std::isnan(cells(c.ix, c.iy))) cells(c.ix, c.iy) = 0.f;
      }
    }
  }
  const std::vector<Frontier> all =
      FindFrontiers(local, layer, robot_m, OnCostLayer(params_.frontier));
  frontiers_ = static_cast<int>(all.size());
  const std::optional<Frontier> best =
      ChooseFrontierGoal(all, failed_, OnCostLayer(params_.frontier));
  if (!best) {
    if (active_id_) return {};  // let the navigator finish the last goal
    if (!empty_since_s_) empty_since_s_ = now_s;
    if (now_s - *empty_since_s_ >= params_.finish_wait_s) {
      finished_ = true;
      FrontierAction a;
      a.kind = FrontierAction::Kind::kFinished;
      a.why = Format("no frontier left (%.0f found, %.0f blacklisted): exploration done",
                     static_cast<double>(all.size()), static_cast<double>(failed_.size()));
      return a;
    }
    return {};
  }
  empty_since_s_.reset();
  if (!active_id_) {
    char line[200];
    std::snprintf(line, sizeof(line), "frontier of %.1f m, %.1f m away: goal (%.2f, %.2f)",
                  best->size_m, best->distance_m, best->goal_m.x(), best->goal_m.y());
    return Send(*best, now_s, line);
  }
  // Driving: is the current goal still on a frontier (within 1 m of one of its goal cells: the
  // goal may be a later candidate than the first, after a failure), and is another much cheaper?
  bool still_frontier = false;
  for (const Frontier& f : all) {
    // The candidates begin with the frontier's own goal.
    for (const FrontierGoalCandidate& c : f.candidates) {
      if ((c.position_m - active_goal_).norm() < 1.0) {
        still_frontier = true;
        active_cost_ = FrontierCost(params_.frontier, c.distance_m, f.size_m);
        break;
      }
    }
    if (still_frontier) break;
  }
  if (!still_frontier || best->cost < active_cost_ - params_.switch_margin) {
    const std::string why = still_frontier ? "a cheaper frontier" : "its frontier is explored";
    return Send(*best, now_s,
                "goal switched (" + why + "): " +
                    Format("(%.2f, %.2f), frontier of %.1f m", best->goal_m.x(), best->goal_m.y(),
                           best->size_m));
  }
  return {};
}

void FrontierExplorer::OnGoalResult(int64_t goal_id, bool reached, double now_s, bool blacklist) {
  if (!active_id_ || goal_id != *active_id_) return;
  if (reached) {
    ++goals_reached_;
  } else {
    if (blacklist) failed_.push_back(active_goal_);
    ++goals_failed_;
  }
  active_id_.reset();
  last_choice_s_.reset();
  (void)now_s;
}

}  // namespace cairn::explore
