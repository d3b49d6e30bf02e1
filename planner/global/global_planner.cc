#include "planner/global/global_planner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <vector>

#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/geometric/PathHybridization.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/util/RandomNumbers.h>

#include "common/check.h"
#include "planner/global/coarse_route.h"
#include "planner/global/ompl_problem.h"

namespace cairn::planner {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using common::Pose2;
using common::Vector2;
using internal::OmplProblem;

namespace {

// " (N cells: the nearest at (x, y), lethal|unknown)" for the cells blocking `pose`.
std::string BlockingCellText(const CostMap& map, const common::Pose2& pose) {
  const std::vector<int64_t> cells = map.BlockingCellsUnder(pose);
  if (cells.empty()) return "";
  const common::GridGeometry& g = map.geometry();
  double best = std::numeric_limits<double>::infinity();
  common::Vector2 nearest = pose.position();
  for (const int64_t i : cells) {
    const common::Vector2 c =
        g.CenterOf({static_cast<int>(i % g.size_x), static_cast<int>(i / g.size_x)});
    const double d = (c - pose.position()).norm();
    if (d < best) {
      best = d;
      nearest = c;
    }
  }
  const float cost = map.CostAt(nearest);
  std::ostringstream out;
  out.precision(3);
  out << " (" << cells.size() << " cells; the nearest at (" << nearest.x() << ", " << nearest.y()
      << "), " << (std::isnan(cost) ? std::string("unknown") : "cost " + std::to_string(int(cost)))
      << ")";
  return out.str();
}

using Clock = std::chrono::steady_clock;

// Shortcut attempts per simplification pass: OMPL's default is the number of states, which
// for the few long motions of RRTConnect is far too few.
constexpr unsigned kShortcutSteps = 200;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The valid pose nearest to `pose` within `radius_m` (rings of positions, the pose's heading
// first), or nullopt.
std::optional<Pose2> NearestValidPose(const CostMap& map, const Pose2& pose, double radius_m) {
  const double step = std::max(0.05, 0.5 * map.resolution_m());
  for (double r = step; r <= radius_m + 1e-9; r += step) {
    const int n = std::max(8, static_cast<int>(std::ceil(2.0 * M_PI * r / step)));
    for (int yaw_try = 0; yaw_try < 9; ++yaw_try) {
      const double yaw =
          pose.yaw_rad +
          (yaw_try == 0 ? 0.0 : (yaw_try % 2 ? 1 : -1) * M_PI / 4 * ((yaw_try + 1) / 2));
      for (int k = 0; k < n; ++k) {
        const double a = 2.0 * M_PI * k / n;
        const Pose2 p{pose.x_m + r * std::cos(a), pose.y_m + r * std::sin(a),
                      common::WrapAngle(yaw)};
        if (map.Contains(p.position()) && map.IsValid(p)) return p;
      }
    }
  }
  return std::nullopt;
}

std::mutex& PlanMutex() {
  static std::mutex mutex;
  return mutex;
}

// One plan, stage by stage, the way OMPL's SimpleSetup reads: the cheap outcomes first (a bad
// request, an occupied start or goal, no connection on the grid), then the OMPL problem is set
// up and solved to a first exact solution, refined (simplified, the coarse grid route offered,
// more solutions merged without one) and checked again pose by pose. The time budget bounds
// every stage together. Each stage returns false when it ended the
// plan (End() set the status).
class PlanRun {
 public:
  PlanRun(const GlobalPlannerParams& params, const CostMap& map, const PlanRequest& request,
          const std::atomic<bool>* cancel)
      : params_(params),
        map_(map),
        request_(request),
        cancel_(cancel),
        t0_(Clock::now()),
        budget_s_(request.time_budget_s > 0.0 ? request.time_budget_s : params.time_budget_s),
        start_(request.start),
        goal_(request.goal) {}

  PlanResult Run() {
    if (CheckRequest() && RescueStart() && ShiftGoal() && PickGoalHeadings() && ProveConnected()) {
      std::lock_guard<std::mutex> lock(PlanMutex());
      ompl::RNG::setSeed(params_.seed);
      problem_ =
          internal::SetUpProblem(map_, params_, start_, goal_, request_.goal_has_yaw, goal_yaws_);
      if (Solve() && Refine()) Finish();
      // The OMPL objects go while the plan still holds the lock.
      best_.reset();
      raw_.reset();
      problem_ = OmplProblem{};
    }
    return std::move(result_);
  }

 private:
  bool End(PlanStatus status, std::string message) {
    result_.status = status;
    result_.message = std::move(message);
    result_.total_time_s = SecondsSince(t0_);
    return false;
  }
  bool Cancelled() const { return cancel_ != nullptr && cancel_->load(); }
  // What is left of the plan's time budget (every stage shares it).
  double TimeLeft() const { return budget_s_ - SecondsSince(t0_); }
  ob::PlannerTerminationCondition CancelCondition() const {
    const std::atomic<bool>* cancel = cancel_;
    return ob::PlannerTerminationCondition([cancel] { return cancel->load(); });
  }

  bool CheckRequest();
  bool RescueStart();
  bool ShiftGoal();
  bool PickGoalHeadings();
  bool ProveConnected();
  bool Solve();
  bool Refine();
  bool Improve(og::PathSimplifier& simplifier);
  std::shared_ptr<og::PathGeometric> SolveAgain(double time_left_s);
  bool OfferGridRoute(og::PathSimplifier& simplifier);
  std::optional<og::PathGeometric> GridRouteAsPath(og::PathSimplifier& simplifier, int stride);
  ob::ScopedStatePtr RouteGoalState(const std::vector<Vector2>& points) const;
  void Simplify(og::PathSimplifier& simplifier, og::PathGeometric* path) const;
  bool Finish();

  const GlobalPlannerParams& params_;
  const CostMap& map_;
  const PlanRequest& request_;
  const std::atomic<bool>* cancel_;
  const Clock::time_point t0_;
  const double budget_s_;
  PlanResult result_;
  Pose2 start_;  // the request's, or the nearest valid pose to it
  Pose2 goal_;   // the request's, or shifted off a blocked footprint
  std::string goal_note_;
  std::vector<double> goal_yaws_;
  OmplProblem problem_;
  std::optional<og::PathGeometric> raw_;   // the first exact solution
  std::optional<og::PathGeometric> best_;  // the best refined path so far
};

// Bounds: finite, and start and goal on the map.
bool PlanRun::CheckRequest() {
  const Pose2& s = request_.start;
  const bool finite = std::isfinite(s.x_m) && std::isfinite(s.y_m) && std::isfinite(s.yaw_rad) &&
                      std::isfinite(goal_.x_m) && std::isfinite(goal_.y_m) &&
                      std::isfinite(goal_.yaw_rad);
  if (!finite) return End(PlanStatus::kOutOfBounds, "start or goal is not finite");
  if (!map_.Contains(s.position()))
    return End(PlanStatus::kOutOfBounds, "start is outside the map");
  if (!map_.Contains(goal_.position())) {
    return End(PlanStatus::kOutOfBounds, "goal is outside the map");
  }
  return true;
}

// A start touching blocking cells: plan from the nearest valid pose close by, if any.
bool PlanRun::RescueStart() {
  if (map_.IsValid(start_)) return true;
  const auto rescued = NearestValidPose(map_, start_, params_.start_rescue_radius_m);
  if (!rescued) return End(PlanStatus::kStartOccupied, "the footprint at the start is blocked");
  result_.start_moved_m = (rescued->position() - start_.position()).norm();
  start_ = *rescued;
  return true;
}

// A goal whose footprint is blocked at every heading: with a shift radius, the nearest valid
// pose close by (a mapping artefact seen from afar need not end the goal).
bool PlanRun::ShiftGoal() {
  bool goal_fits = request_.goal_has_yaw ? map_.IsValid(goal_) : false;
  for (int k = 0; !goal_fits && !request_.goal_has_yaw && k < params_.goal_yaw_samples; ++k) {
    goal_fits = map_.IsValid({goal_.x_m, goal_.y_m, 2.0 * M_PI * k / params_.goal_yaw_samples});
  }
  if (goal_fits || request_.goal_shift_radius_m <= 0.0) return true;
  if (const auto shifted = NearestValidPose(map_, goal_, request_.goal_shift_radius_m)) {
    goal_note_ = BlockingCellText(map_, goal_);
    result_.goal_moved_m = (shifted->position() - goal_.position()).norm();
    goal_ = *shifted;
  }
  return true;
}

// The headings the goal may be reached with: the requested one, or every valid one of
// goal_yaw_samples (the one pointing from the start first).
bool PlanRun::PickGoalHeadings() {
  if (request_.goal_has_yaw && result_.goal_moved_m > 0.0) {
    goal_yaws_.push_back(goal_.yaw_rad);
  } else if (request_.goal_has_yaw) {
    if (map_.IsValid(goal_)) goal_yaws_.push_back(goal_.yaw_rad);
  } else {
    const double toward = std::atan2(goal_.y_m - start_.y_m, goal_.x_m - start_.x_m);
    for (int k = 0; k < params_.goal_yaw_samples; ++k) {
      const double yaw = common::WrapAngle(toward + 2.0 * M_PI * k / params_.goal_yaw_samples);
      if (map_.IsValid({goal_.x_m, goal_.y_m, yaw})) goal_yaws_.push_back(yaw);
    }
  }
  if (goal_yaws_.empty()) {
    return End(PlanStatus::kGoalOccupied,
               "the footprint at the goal is blocked" + BlockingCellText(map_, goal_));
  }
  return true;
}

// "No path" proved on the grid before sampling (sampling planners cannot prove it).
bool PlanRun::ProveConnected() {
  if (Cancelled()) return End(PlanStatus::kCancelled, "cancelled");
  if (!params_.grid_precheck) return true;
  if (!map_.MaybeConnected(start_.position(), goal_.position())) {
    return End(PlanStatus::kNoPath, "the goal is not connected to the start");
  }
  if (params_.unknown_horizon_m > 0.0 && map_.params().unknown_is_traversable &&
      !map_.ConnectedWithinHorizon(start_.position(), goal_.position(), params_.unknown_horizon_m,
                                   params_.unknown_goal_radius_m)) {
    std::ostringstream m;
    m << "the goal is not connected to the start through known cells and unknown cells within "
      << params_.unknown_horizon_m << " m";
    return End(PlanStatus::kNoPath, m.str());
  }
  return true;
}

// Solve within the budget; stop early on cancel or, if asked, at the first exact solution.
bool PlanRun::Solve() {
  og::SimpleSetup& setup = *problem_.setup;
  const double budget = budget_s_;
  if (TimeLeft() <= 0.0) {
    std::ostringstream m;
    m << "no solution within " << budget << " s (the budget ran out before the search)";
    return End(PlanStatus::kTimedOut, m.str());
  }
  ob::PlannerTerminationCondition ptc = ob::timedPlannerTerminationCondition(TimeLeft());
  if (cancel_ != nullptr) ptc = ob::plannerOrTerminationCondition(ptc, CancelCondition());
  if (params_.stop_at_first_solution) {
    ptc = ob::plannerOrTerminationCondition(
        ptc, ob::exactSolnPlannerTerminationCondition(setup.getProblemDefinition()));
  }
  const auto solve_t0 = Clock::now();
  const ob::PlannerStatus status = setup.solve(ptc);
  result_.solve_time_s = SecondsSince(solve_t0);

  if (Cancelled()) return End(PlanStatus::kCancelled, "cancelled");
  if (status == ob::PlannerStatus::APPROXIMATE_SOLUTION ||
      (status == ob::PlannerStatus::EXACT_SOLUTION && !setup.haveExactSolutionPath())) {
    std::ostringstream m;
    m << "only an approximate solution, " << setup.getProblemDefinition()->getSolutionDifference()
      << " m short of the goal";
    return End(PlanStatus::kApproximate, m.str());
  }
  if (status == ob::PlannerStatus::INVALID_START) {
    return End(PlanStatus::kStartOccupied, "OMPL rejected the start");
  }
  if (status == ob::PlannerStatus::INVALID_GOAL) {
    return End(PlanStatus::kGoalOccupied, "OMPL rejected the goal");
  }
  if (status != ob::PlannerStatus::EXACT_SOLUTION) {
    std::ostringstream m;
    m << "no solution within " << budget << " s (" << status.asString() << ")";
    return End(PlanStatus::kTimedOut, m.str());
  }
  result_.solutions = 1;
  raw_ = setup.getSolutionPath();
  std::vector<Pose2> raw_poses;
  for (const ob::State* s : raw_->getStates()) raw_poses.push_back(internal::ToPose(s));
  result_.raw_length_m = internal::PositionLength(raw_poses);
  return true;
}

// Shortcutting passes until they stop helping (or the time cap, or the plan's budget):
// deterministic for a seed when the caps are far away.
void PlanRun::Simplify(og::PathSimplifier& simplifier, og::PathGeometric* path) const {
  const auto t_start = Clock::now();
  // OMPL's shortcutPath checks some shortcuts backwards (from the later point to the earlier
  // one): on a map with one-way cells a pass whose result drives the wrong way is undone.
  const bool directed = map_.one_way_cells() > 0;
  for (int pass = 0; pass < 8 && TimeLeft() > 0.0; ++pass) {
    const double before = path->length();
    simplifier.reduceVertices(*path, 0, 0, 0.33);
    const std::optional<og::PathGeometric> kept =
        directed ? std::optional<og::PathGeometric>(*path) : std::nullopt;
    simplifier.shortcutPath(*path, kShortcutSteps, kShortcutSteps / 4, 0.33, 0.005);
    if (kept && !path->check()) *path = *kept;
    simplifier.collapseCloseVertices(*path);
    if (path->length() > before - 1e-3 || SecondsSince(t_start) > params_.simplify_time_s) break;
  }
}

// The first solution simplified and offered the grid route (or, without one, improved by more
// solutions).
bool PlanRun::Refine() {
  og::PathSimplifier simplifier(problem_.si, problem_.setup->getProblemDefinition()->getGoal(),
                                problem_.objective);
  best_ = *raw_;
  if (params_.simplify_time_s > 0.0) Simplify(simplifier, &*best_);
  // The grid route settles the homotopy class at a fraction of the cost of more sampled
  // solutions; those are planned only when it offers no valid path.
  const bool have_route = OfferGridRoute(simplifier);
  if (Cancelled()) return End(PlanStatus::kCancelled, "cancelled");
  if (!have_route && params_.improvement_rounds > 0 && !Improve(simplifier)) return false;
  result_.budget_exhausted = TimeLeft() <= 0.0;
  return true;
}

// One more exact solution from a cleared planner within `time_left_s`, or nullptr.
std::shared_ptr<og::PathGeometric> PlanRun::SolveAgain(double time_left_s) {
  const ob::ProblemDefinitionPtr& pdef = problem_.setup->getProblemDefinition();
  problem_.planner->clear();
  pdef->clearSolutionPaths();
  ob::PlannerTerminationCondition ptc =
      ob::plannerOrTerminationCondition(ob::timedPlannerTerminationCondition(time_left_s),
                                        ob::exactSolnPlannerTerminationCondition(pdef));
  if (cancel_ != nullptr) ptc = ob::plannerOrTerminationCondition(ptc, CancelCondition());
  if (problem_.planner->solve(ptc) != ob::PlannerStatus::EXACT_SOLUTION ||
      !pdef->hasExactSolution()) {
    return nullptr;
  }
  return std::make_shared<og::PathGeometric>(*pdef->getSolutionPath()->as<og::PathGeometric>());
}

// When the grid route gave nothing: a few more exact solutions within improvement_time_s (and
// the plan's budget), merged with the first by
// PathHybridization; the best of them and of the merged path is kept.
bool PlanRun::Improve(og::PathSimplifier& simplifier) {
  const ob::OptimizationObjectivePtr& objective = problem_.objective;
  og::PathHybridization hybridization(problem_.si, objective);
  hybridization.recordPath(std::make_shared<og::PathGeometric>(*best_), false);
  const auto improve_t0 = Clock::now();
  for (int round = 0; round < params_.improvement_rounds; ++round) {
    const double left = std::min(params_.improvement_time_s - SecondsSince(improve_t0), TimeLeft());
    if (left <= 0.0 || Cancelled()) break;
    const auto path = SolveAgain(left);
    if (path == nullptr) continue;
    if (params_.simplify_time_s > 0.0) Simplify(simplifier, path.get());
    hybridization.recordPath(path, false);
    ++result_.solutions;
    if (objective->isCostBetterThan(path->cost(objective), best_->cost(objective))) {
      best_ = *path;
    }
  }
  if (Cancelled()) return End(PlanStatus::kCancelled, "cancelled");
  if (hybridization.pathCount() > 1 && TimeLeft() > 0.0) {
    hybridization.computeHybridPath();
    if (const auto& hybrid = hybridization.getHybridPath()) {
      og::PathGeometric merged = *hybrid;
      if (params_.simplify_time_s > 0.0) Simplify(simplifier, &merged);
      // The hybridization graph is undirected: on a map with one-way cells check the result.
      if ((map_.one_way_cells() == 0 || merged.check()) &&
          objective->isCostBetterThan(merged.cost(objective), best_->cost(objective))) {
        best_ = merged;
      }
    }
  }
  return true;
}

// The coarse grid route as one more candidate (see GlobalPlannerParams::grid_route_candidate);
// true when it gave a valid path (chosen or not). The coarse route keeps only the footprint's
// inscribed disc off blocking cells; where the padded footprint does not fit along it (a
// passage about as wide as the robot, taken off centre), the full-resolution route, which
// the proximity cost keeps in the middle of such a passage, is tried before giving up.
bool PlanRun::OfferGridRoute(og::PathSimplifier& simplifier) {
  if (!params_.grid_route_candidate) return false;
  const int coarse_stride =
      std::max(1, static_cast<int>(std::lround(params_.grid_route_cell_m / map_.resolution_m())));
  std::vector<int> strides{coarse_stride};
  if (coarse_stride > 1) strides.push_back(1);
  for (const int stride : strides) {
    if (Cancelled() || TimeLeft() <= 0.0) return false;
    const std::optional<og::PathGeometric> route = GridRouteAsPath(simplifier, stride);
    if (!route) continue;
    const ob::OptimizationObjectivePtr& objective = problem_.objective;
    if (objective->isCostBetterThan(route->cost(objective), best_->cost(objective))) {
      best_ = *route;
      result_.grid_route_chosen = true;
    }
    return true;
  }
  return false;
}

// Where the grid route ends: the goal state of the first solution, or, when the request gives no
// heading, the goal position at the heading nearest the route's last leg among those valid there
// (that leg's own first).
ob::ScopedStatePtr PlanRun::RouteGoalState(const std::vector<Vector2>& points) const {
  auto goal = std::make_shared<ob::ScopedState<>>(problem_.space);
  problem_.space->copyState(goal->get(), best_->getState(best_->getStateCount() - 1));
  if (request_.goal_has_yaw || points.size() < 2) return goal;
  const Vector2 leg = points.back() - points[points.size() - 2];
  const double arrival = std::atan2(leg.y(), leg.x());
  std::vector<double> yaws{arrival};
  yaws.insert(yaws.end(), goal_yaws_.begin(), goal_yaws_.end());
  std::stable_sort(yaws.begin(), yaws.end(), [arrival](double a, double b) {
    return std::abs(common::WrapAngle(a - arrival)) < std::abs(common::WrapAngle(b - arrival));
  });
  for (const double yaw : yaws) {
    if (!map_.IsValid({goal_.x_m, goal_.y_m, yaw})) continue;
    auto* s = goal->get()->as<ob::SE2StateSpace::StateType>();
    s->setXY(goal_.x_m, goal_.y_m);
    s->setYaw(internal::OmplYaw(yaw));
    break;
  }
  return goal;
}

// The grid route over blocks of `stride` cells as a simplified, checked OMPL path, or nullopt
// when there is no route or it does not check.
std::optional<og::PathGeometric> PlanRun::GridRouteAsPath(og::PathSimplifier& simplifier,
                                                          int stride) {
  CoarseRouteParams cp;
  cp.stride_cells = stride;
  cp.traversal_cost_weight = params_.traversal_cost_weight;
  cp.clearance_weight = params_.clearance_weight;
  cp.clearance_inflation_m = params_.clearance_inflation_m;
  cp.escape_radius_m = params_.escape_radius_m;
  const GridPath grid_path = CoarseGridRoute(map_, start_.position(), goal_.position(), cp,
                                             [this] { return Cancelled() || TimeLeft() <= 0.0; });
  if (!grid_path.found || grid_path.points_m.size() < 2) return std::nullopt;
  og::PathGeometric route = internal::RouteAsPath(problem_, grid_path.points_m, start_,
                                                  RouteGoalState(grid_path.points_m)->get());
  if (!internal::RepairRoute(problem_, &route)) return std::nullopt;
  // Shortcuts are checked one way only (see Simplify): the repaired route stays the fallback.
  og::PathGeometric simplified = route;
  if (params_.simplify_time_s > 0.0) Simplify(simplifier, &simplified);
  if (simplified.check()) return simplified;
  if (route.check()) return route;
  return std::nullopt;
}

// Interpolate and check again, pose by pose with the robot's own footprint; fall back to the
// planner's own path if needed.
bool PlanRun::Finish() {
  const ob::SpaceInformationPtr& si = problem_.si;
  og::PathGeometric chosen(si);
  bool have = false;
  if (params_.simplify_time_s > 0.0 || params_.improvement_rounds > 0) {
    og::PathGeometric candidate = internal::Interpolate(si, *best_, params_.interpolation_step_m);
    if (internal::PathStillValid(map_, candidate)) {
      chosen = candidate;
      have = true;
      result_.simplified = true;
    }
  }
  if (!have) {
    og::PathGeometric plain = internal::Interpolate(si, *raw_, params_.interpolation_step_m);
    if (!internal::PathStillValid(map_, plain)) {
      return End(PlanStatus::kNoPath, "the planner's path failed re-validation");
    }
    chosen = plain;
  }
  std::vector<Pose2>& poses = result_.poses;
  if (result_.start_moved_m > 0.0) poses.push_back(request_.start);
  for (const ob::State* s : chosen.getStates()) poses.push_back(internal::ToPose(s));
  if (params_.state_space == StateSpaceKind::kSE2) {
    // A wheeled robot drives along the path: headings follow the direction of travel where
    // the footprint fits that way, and one-way cells allow the motions to and from it (OMPL's
    // validated heading is kept elsewhere).
    for (size_t i = 0; i + 1 < poses.size(); ++i) {
      const Vector2 d = poses[i + 1].position() - poses[i].position();
      if (d.norm() < 1e-6) continue;
      const Pose2 along{poses[i].x_m, poses[i].y_m, std::atan2(d.y(), d.x())};
      if (map_.IsValid(along) && (i == 0 || map_.MotionAllowed(poses[i - 1], along)) &&
          map_.MotionAllowed(along, poses[i + 1])) {
        poses[i] = along;
      }
    }
  }
  result_.length_m = internal::PositionLength(poses);
  result_.cost = chosen.cost(problem_.objective).value();
  if (result_.goal_moved_m <= 0.0) return End(PlanStatus::kSuccess, "");
  std::ostringstream m;
  m.setf(std::ios::fixed);
  m.precision(2);
  m << "the footprint at the goal is blocked" << goal_note_ << "; the path ends "
    << result_.goal_moved_m << " m from it, at (" << goal_.x_m << ", " << goal_.y_m << ")";
  return End(PlanStatus::kSuccess, m.str());
}

}  // namespace

StateSpaceKind StateSpaceKindFromName(const std::string& name) {
  if (name == "se2") return StateSpaceKind::kSE2;
  if (name == "dubins") return StateSpaceKind::kDubins;
  if (name == "reeds_shepp") return StateSpaceKind::kReedsShepp;
  CAIRN_THROW_UNLESS(false, "unknown state space '" << name << "' (se2, dubins, reeds_shepp)");
  return StateSpaceKind::kSE2;
}

const char* StateSpaceKindName(StateSpaceKind kind) {
  switch (kind) {
    case StateSpaceKind::kSE2:
      return "se2";
    case StateSpaceKind::kDubins:
      return "dubins";
    case StateSpaceKind::kReedsShepp:
      return "reeds_shepp";
  }
  return "se2";
}

const std::vector<std::string>& KnownPlannerNames() {
  static const std::vector<std::string> names = {"RRTConnect", "RRTstar", "InformedRRTstar",
                                                 "BITstar",    "PRMstar", "RRT"};
  return names;
}

void GlobalPlannerParams::Validate() const {
  bool known = false;
  for (const auto& n : KnownPlannerNames()) known = known || n == planner;
  std::ostringstream names;
  for (const auto& n : KnownPlannerNames()) names << " " << n;
  CAIRN_THROW_UNLESS(known, "unknown planner '" << planner << "'; known:" << names.str());
  CAIRN_THROW_UNLESS(turning_radius_m > 0.0, "turning_radius_m must be positive");
  // Dubins curves are directed (forward only): a second tree grown from the goal, a roadmap's
  // undirected edges or RRT*'s rewiring would reverse curves the robot cannot drive backwards
  // (and RRTConnect's connect loop need not end). The single forward tree of RRT is sound.
  CAIRN_THROW_UNLESS(state_space != StateSpaceKind::kDubins || planner == "RRT",
                     "planner '" << planner
                                 << "' needs a symmetric state space: with dubins use RRT "
                                    "(or use reeds_shepp)");
  CAIRN_THROW_UNLESS(time_budget_s > 0.0, "time_budget_s must be positive");
  CAIRN_THROW_UNLESS(traversal_cost_weight >= 0.0, "traversal_cost_weight must not be negative");
  CAIRN_THROW_UNLESS(clearance_weight >= 0.0, "clearance_weight must not be negative");
  CAIRN_THROW_UNLESS(clearance_inflation_m >= 0.0, "clearance_inflation_m must not be negative");
  CAIRN_THROW_UNLESS(validity_resolution_m > 0.0, "validity_resolution_m must be positive");
  CAIRN_THROW_UNLESS(range_m >= 0.0, "range_m must not be negative");
  CAIRN_THROW_UNLESS(bounds_margin_m >= 0.0, "bounds_margin_m must not be negative");
  CAIRN_THROW_UNLESS(aligned_heading_fraction >= 0.0 && aligned_heading_fraction <= 1.0,
                     "aligned_heading_fraction must lie in [0, 1]");
  CAIRN_THROW_UNLESS(ridge_sample_fraction >= 0.0 && ridge_sample_fraction <= 1.0,
                     "ridge_sample_fraction must lie in [0, 1]");
  CAIRN_THROW_UNLESS(simplify_time_s >= 0.0, "simplify_time_s must not be negative");
  CAIRN_THROW_UNLESS(improvement_rounds >= 0, "improvement_rounds must not be negative");
  CAIRN_THROW_UNLESS(improvement_time_s >= 0.0, "improvement_time_s must not be negative");
  CAIRN_THROW_UNLESS(grid_route_cell_m > 0.0, "grid_route_cell_m must be positive");
  CAIRN_THROW_UNLESS(escape_radius_m >= 0.0, "escape_radius_m must not be negative");
  CAIRN_THROW_UNLESS(interpolation_step_m > 0.0, "interpolation_step_m must be positive");
  CAIRN_THROW_UNLESS(goal_tolerance_m > 0.0, "goal_tolerance_m must be positive");
  CAIRN_THROW_UNLESS(goal_yaw_samples >= 1, "goal_yaw_samples must be at least 1");
  CAIRN_THROW_UNLESS(start_rescue_radius_m >= 0.0, "start_rescue_radius_m must not be negative");
  CAIRN_THROW_UNLESS(unknown_horizon_m >= 0.0, "unknown_horizon_m must not be negative");
  CAIRN_THROW_UNLESS(unknown_goal_radius_m >= 0.0, "unknown_goal_radius_m must not be negative");
  CAIRN_THROW_UNLESS(seed != 0, "seed must not be 0 (OMPL would pick a random one)");
}

GlobalPlanner::GlobalPlanner(GlobalPlannerParams params) : params_(std::move(params)) {
  params_.Validate();
  internal::InstallOmplLogForwarder();
}

PlanResult GlobalPlanner::Plan(const CostMap& map, const PlanRequest& request,
                               const std::atomic<bool>* cancel) const {
  return PlanRun(params_, map, request, cancel).Run();
}

}  // namespace cairn::planner
