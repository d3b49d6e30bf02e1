#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/grid_map.h"
#include "services/explore/explorer_config.h"
#include "services/explore/frontier.h"

/// @file
/// The frontier strategy's decisions (explore_lite's loop): choose the cheapest frontier, send
/// its goal, reconsider every choose_period_s while driving (switch when another frontier is
/// cheaper by switch_margin or the goal's frontier is gone), blacklist a goal the navigator
/// failed or that brought no progress for progress_timeout_s, and finish when no frontier has
/// been left for finish_wait_s. Pure: the caller brings the map, the pose, the navigator's
/// results and the time, and carries out the actions.

namespace cairn::explore {

struct FrontierAction {
  enum class Kind { kNone, kSendGoal, kCancelGoal, kFinished };
  Kind kind{Kind::kNone};
  int64_t goal_id{0};
  common::Vector2 goal_m{0.0, 0.0};
  std::string why;  ///< one line for the log (empty for kNone)
};

class FrontierExplorer {
 public:
  /// @throws std::invalid_argument for invalid params.
  explicit FrontierExplorer(const FrontierModeParams& params);

  /// One decision. `map` holds the occupancy as a cost layer named `layer` (0 free .. 100
  /// lethal, NaN unknown; nullptr: no map yet). Returns what to do now.
  FrontierAction Tick(const common::GridMap* map, const std::string& layer,
                      const common::Vector2& robot_m, double now_s);
  /// The navigator's final word on a goal (other ids are ignored). A goal that failed for a
  /// reason of its own (no path, occupied) is blacklisted; one that failed for a passing reason
  /// (a stale map or pose) is not, and may be chosen again.
  void OnGoalResult(int64_t goal_id, bool reached, double now_s, bool blacklist = true);

  std::optional<int64_t> active_goal() const { return active_id_; }
  int goals_sent() const { return goals_sent_; }
  int goals_reached() const { return goals_reached_; }
  int goals_failed() const { return goals_failed_; }
  int frontiers() const { return frontiers_; }
  bool finished() const { return finished_; }
  const std::vector<common::Vector2>& failed_goals() const { return failed_; }

 private:
  FrontierAction Send(const Frontier& f, double now_s, const std::string& why);

  FrontierModeParams params_;
  std::optional<int64_t> active_id_;
  common::Vector2 active_goal_{0.0, 0.0};
  double active_cost_{0.0};
  double best_distance_m_{0.0};
  double progress_time_s_{0.0};
  std::optional<double> last_choice_s_;
  std::optional<double> empty_since_s_;
  int64_t next_id_{1};
  int goals_sent_{0};
  int goals_reached_{0};
  int goals_failed_{0};
  int frontiers_{0};
  bool finished_{false};
  std::vector<common::Vector2> failed_;
};

}  // namespace cairn::explore
