#include "planner/global/global_planner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>

#include <ompl/base/Goal.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/goals/GoalSampleableRegion.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/objectives/StateCostIntegralObjective.h>
#include <ompl/base/spaces/DubinsStateSpace.h>
#include <ompl/base/spaces/ReedsSheppStateSpace.h>
#include <ompl/base/spaces/SE2StateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/PathHybridization.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/informedtrees/BITstar.h>
#include <ompl/geometric/planners/prm/PRMstar.h>
#include <ompl/geometric/planners/rrt/InformedRRTstar.h>
#include <ompl/geometric/planners/rrt/RRT.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include "common/check.h"
#include "common/log.h"
#include "planner/global/dubins_space.h"
#include "planner/global/grid_astar.h"

namespace cairn::planner {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using common::Pose2;
using common::Vector2;

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

// OMPL's console output goes to the product log; the note OMPL prints when the seed is set
// again for the next plan is expected and dropped.
class OmplLogForwarder : public ompl::msg::OutputHandler {
 public:
  void log(const std::string& text, ompl::msg::LogLevel level, const char* /*filename*/,
           int /*line*/) override {
    if (text.find("Random number generation already started") != std::string::npos) return;
    if (level >= ompl::msg::LOG_ERROR) {
      CAIRN_LOG_ERROR("ompl: %s", text.c_str());
    } else if (level >= ompl::msg::LOG_WARN) {
      CAIRN_LOG_WARN("ompl: %s", text.c_str());
    } else {
      CAIRN_LOG_DEBUG("ompl: %s", text.c_str());
    }
  }
};

void InstallOmplLogForwarder() {
  static std::once_flag once;
  std::call_once(once, [] {
    static OmplLogForwarder forwarder;
    ompl::msg::useOutputHandler(&forwarder);
    ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  });
}

// OMPL's SO(2) range is [-pi, pi); WrapAngle returns (-pi, pi].
double OmplYaw(double yaw_rad) {
  const double y = common::WrapAngle(yaw_rad);
  return y >= M_PI ? -M_PI : y;
}

Pose2 ToPose(const ob::State* state) {
  const auto* s = state->as<ob::SE2StateSpace::StateType>();
  return {s->getX(), s->getY(), s->getYaw()};
}

// A state is valid when its position lies on the grid and the padded footprint clears the
// layer; near the start and the goal the robot's own footprint is enough.
class FootprintValidityChecker : public ob::StateValidityChecker {
 public:
  FootprintValidityChecker(const ob::SpaceInformationPtr& si, const CostMap& map,
                           const Vector2& start, const Vector2& goal, double escape_radius_m)
      : ob::StateValidityChecker(si),
        map_(map),
        start_(start),
        goal_(goal),
        escape2_(escape_radius_m * escape_radius_m) {}
  bool isValid(const ob::State* state) const override {
    const Pose2 p = ToPose(state);
    if (!map_.Contains(p.position())) return false;
    const bool near_end = (p.position() - start_).squaredNorm() <= escape2_ ||
                          (p.position() - goal_).squaredNorm() <= escape2_;
    return map_.IsValid(p, near_end ? FootprintKind::kRobot : FootprintKind::kPadded);
  }

 private:
  const CostMap& map_;
  Vector2 start_;
  Vector2 goal_;
  double escape2_;
};

// SE(2) samples for narrow passages. A share of the positions comes from the ridge cells of
// the distance field (the middle of corridors and doors, MAPRM's medial-axis idea), and a share
// of the headings follows the free space: perpendicular to the gradient of the distance to the
// nearest blocking cell, either way round, with a little noise. The rest is uniform. A narrow
// passage admits only states near its middle with headings close to its direction; uniform
// samples would rarely land there.
class FreeSpaceSE2Sampler : public ob::StateSampler {
 public:
  FreeSpaceSE2Sampler(const ob::StateSpace* space, const CostMap& map, double ridge_fraction,
                      double aligned_fraction)
      : ob::StateSampler(space),
        map_(map),
        ridge_fraction_(ridge_fraction),
        aligned_fraction_(aligned_fraction),
        fallback_(space->allocDefaultStateSampler()) {
    // Ridge cells inside the sampled bounds.
    const auto& b = space_->as<ob::SE2StateSpace>()->getBounds();
    const auto& g = map.geometry();
    for (const int32_t i : map.RidgeCells()) {
      const Vector2 c =
          g.CenterOf({static_cast<int>(i % g.size_x), static_cast<int>(i / g.size_x)});
      if (c.x() >= b.low[0] && c.x() <= b.high[0] && c.y() >= b.low[1] && c.y() <= b.high[1]) {
        ridges_.push_back(c);
      }
    }
  }
  void sampleUniform(ob::State* state) override {
    auto* s = state->as<ob::SE2StateSpace::StateType>();
    const auto& b = space_->as<ob::SE2StateSpace>()->getBounds();
    double x, y;
    if (!ridges_.empty() && rng_.uniform01() < ridge_fraction_) {
      const Vector2& c = ridges_[rng_.uniformInt(0, static_cast<int>(ridges_.size()) - 1)];
      const double h = 0.5 * map_.resolution_m();
      x = std::clamp(c.x() + rng_.uniformReal(-h, h), b.low[0], b.high[0]);
      y = std::clamp(c.y() + rng_.uniformReal(-h, h), b.low[1], b.high[1]);
    } else {
      x = rng_.uniformReal(b.low[0], b.high[0]);
      y = rng_.uniformReal(b.low[1], b.high[1]);
    }
    double yaw = rng_.uniformReal(-M_PI, M_PI);
    if (rng_.uniform01() < aligned_fraction_) {
      const double h = map_.resolution_m();
      const double gx = map_.SmoothClearanceAt({x + h, y}) - map_.SmoothClearanceAt({x - h, y});
      const double gy = map_.SmoothClearanceAt({x, y + h}) - map_.SmoothClearanceAt({x, y - h});
      if (std::isfinite(gx) && std::isfinite(gy) && std::hypot(gx, gy) > 1e-6) {
        yaw = std::atan2(gy, gx) + M_PI / 2 + (rng_.uniformBool() ? 0.0 : M_PI) +
              rng_.gaussian(0.0, 0.15);
      }
    }
    s->setXY(x, y);
    s->setYaw(OmplYaw(yaw));
  }
  void sampleUniformNear(ob::State* state, const ob::State* near, double distance) override {
    fallback_->sampleUniformNear(state, near, distance);
  }
  void sampleGaussian(ob::State* state, const ob::State* mean, double std_dev) override {
    fallback_->sampleGaussian(state, mean, std_dev);
  }

 private:
  const CostMap& map_;
  double ridge_fraction_;
  double aligned_fraction_;
  ob::StateSamplerPtr fallback_;
  std::vector<Vector2> ridges_;
};

// Length plus traversal cost: the integral of 1 + w · cost / 100 + w_c · proximity along the
// motion, by the trapezoid rule over samples about one cost cell apart (OMPL's own integration
// would sample at the much finer validity resolution). Proximity (0..1) grows as the distance to
// the nearest blocking cell falls below the inscribed radius plus the clearance inflation: the
// cost layer carries no inflation, and without it shortcut paths would hug corners.
class TraversalCostObjective : public ob::StateCostIntegralObjective {
 public:
  TraversalCostObjective(const ob::SpaceInformationPtr& si, const CostMap& map,
                         const GlobalPlannerParams& params)
      : ob::StateCostIntegralObjective(si, true),
        map_(map),
        weight_(params.traversal_cost_weight / 100.0),
        clearance_weight_(params.clearance_weight),
        inflation_m_(params.clearance_inflation_m),
        inscribed_m_(map.footprint().inscribed_radius_m()),
        step_m_(std::max(map.resolution_m(), 0.1)) {
    description_ = "length plus traversal cost";
  }
  double CostAt(const Vector2& p) const {
    double c = 1.0 + weight_ * map_.TraversalCostAt(p);
    if (clearance_weight_ > 0.0 && inflation_m_ > 0.0) {
      const double d = map_.SmoothClearanceAt(p);
      if (std::isfinite(d)) {
        c += clearance_weight_ * std::clamp(1.0 - (d - inscribed_m_) / inflation_m_, 0.0, 1.0);
      }
    }
    return c;
  }
  ob::Cost stateCost(const ob::State* s) const override {
    return ob::Cost(CostAt(ToPose(s).position()));
  }
  ob::Cost motionCost(const ob::State* s1, const ob::State* s2) const override {
    const double d = si_->distance(s1, s2);
    const Vector2 a = ToPose(s1).position();
    const Vector2 b = ToPose(s2).position();
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step_m_)));
    double sum = 0.0;
    double prev = CostAt(a);
    for (int k = 1; k <= n; ++k) {
      const double c = CostAt(a + (b - a) * (double(k) / n));
      sum += 0.5 * (prev + c);
      prev = c;
    }
    return ob::Cost(d * sum / n);
  }
  // Every state costs at least 1 per unit distance, so distance is an admissible heuristic.
  ob::Cost motionCostHeuristic(const ob::State* s1, const ob::State* s2) const override {
    return ob::Cost(si_->distance(s1, s2));
  }

 private:
  const CostMap& map_;
  double weight_;
  double clearance_weight_;
  double inflation_m_;
  double inscribed_m_;
  double step_m_;
};

// A goal position with any heading: sampled over the headings whose footprint is valid.
class PositionGoal : public ob::GoalSampleableRegion {
 public:
  PositionGoal(const ob::SpaceInformationPtr& si, const Vector2& goal, std::vector<double> yaws,
               double tolerance_m)
      : ob::GoalSampleableRegion(si), goal_(goal), yaws_(std::move(yaws)) {
    setThreshold(tolerance_m);
  }
  double distanceGoal(const ob::State* st) const override {
    return (ToPose(st).position() - goal_).norm();
  }
  void sampleGoal(ob::State* st) const override {
    auto* s = st->as<ob::SE2StateSpace::StateType>();
    s->setXY(goal_.x(), goal_.y());
    s->setYaw(OmplYaw(yaws_[next_++ % yaws_.size()]));
  }
  unsigned int maxSampleCount() const override { return static_cast<unsigned>(yaws_.size()); }

 private:
  Vector2 goal_;
  std::vector<double> yaws_;
  mutable size_t next_{0};
};

ob::PlannerPtr MakePlanner(const std::string& name, const ob::SpaceInformationPtr& si) {
  if (name == "RRTConnect") return std::make_shared<og::RRTConnect>(si);
  if (name == "RRT") return std::make_shared<og::RRT>(si);
  if (name == "RRTstar") return std::make_shared<og::RRTstar>(si);
  if (name == "InformedRRTstar") return std::make_shared<og::InformedRRTstar>(si);
  if (name == "BITstar")
    return std::make_shared<og::BITstar>(si, "kBITstar");  // k-nearest by default
  if (name == "PRMstar") return std::make_shared<og::PRMstar>(si);
  CAIRN_DEMAND(false);  // names are validated in GlobalPlannerParams::Validate
  return nullptr;
}

double PositionLength(const std::vector<Pose2>& poses) {
  double length = 0.0;
  for (size_t i = 1; i < poses.size(); ++i) {
    length += (poses[i].position() - poses[i - 1].position()).norm();
  }
  return length;
}

// Every pose of an interpolated path with the robot's own footprint (the padding used while
// planning covers the space between these poses).
bool PathStillValid(const CostMap& map, og::PathGeometric& path) {
  for (const ob::State* s : path.getStates()) {
    const Pose2 p = ToPose(s);
    if (!map.Contains(p.position()) || !map.IsValid(p)) return false;
  }
  return true;
}

// The valid pose nearest to `start` within `radius_m` (rings of positions, the start's heading
// first), or nullopt.
std::optional<Pose2> RescueStart(const CostMap& map, const Pose2& start, double radius_m) {
  const double step = std::max(0.05, 0.5 * map.resolution_m());
  for (double r = step; r <= radius_m + 1e-9; r += step) {
    const int n = std::max(8, static_cast<int>(std::ceil(2.0 * M_PI * r / step)));
    for (int yaw_try = 0; yaw_try < 9; ++yaw_try) {
      const double yaw =
          start.yaw_rad +
          (yaw_try == 0 ? 0.0 : (yaw_try % 2 ? 1 : -1) * M_PI / 4 * ((yaw_try + 1) / 2));
      for (int k = 0; k < n; ++k) {
        const double a = 2.0 * M_PI * k / n;
        const Pose2 p{start.x_m + r * std::cos(a), start.y_m + r * std::sin(a),
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
  InstallOmplLogForwarder();
}

PlanResult GlobalPlanner::Plan(const CostMap& map, const PlanRequest& request,
                               const std::atomic<bool>* cancel) const {
  const auto t0 = Clock::now();
  PlanResult result;
  auto finish = [&](PlanStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    result.total_time_s = SecondsSince(t0);
    return result;
  };
  auto cancelled = [&] { return cancel != nullptr && cancel->load(); };
  Pose2 goal = request.goal;

  // Cheap outcomes first: bounds, occupied start or goal, cancellation, grid connectivity.
  const bool finite = std::isfinite(request.start.x_m) && std::isfinite(request.start.y_m) &&
                      std::isfinite(request.start.yaw_rad) && std::isfinite(goal.x_m) &&
                      std::isfinite(goal.y_m) && std::isfinite(goal.yaw_rad);
  if (!finite) return finish(PlanStatus::kOutOfBounds, "start or goal is not finite");
  if (!map.Contains(request.start.position())) {
    return finish(PlanStatus::kOutOfBounds, "start is outside the map");
  }
  if (!map.Contains(goal.position()))
    return finish(PlanStatus::kOutOfBounds, "goal is outside the map");
  // A start touching blocking cells: plan from the nearest valid pose close by, if any.
  Pose2 start = request.start;
  if (!map.IsValid(start)) {
    const auto rescued = RescueStart(map, start, params_.start_rescue_radius_m);
    if (!rescued)
      return finish(PlanStatus::kStartOccupied, "the footprint at the start is blocked");
    result.start_moved_m = (rescued->position() - start.position()).norm();
    start = *rescued;
  }
  // A goal whose footprint is blocked at every heading: with a shift radius, the nearest valid
  // pose close by (a mapping artefact seen from afar need not end the goal).
  bool goal_fits = request.goal_has_yaw ? map.IsValid(goal) : false;
  for (int k = 0; !goal_fits && !request.goal_has_yaw && k < params_.goal_yaw_samples; ++k) {
    goal_fits = map.IsValid({goal.x_m, goal.y_m, 2.0 * M_PI * k / params_.goal_yaw_samples});
  }
  std::string goal_note;
  if (!goal_fits && request.goal_shift_radius_m > 0.0) {
    if (const auto shifted = RescueStart(map, goal, request.goal_shift_radius_m)) {
      goal_note = BlockingCellText(map, goal);
      result.goal_moved_m = (shifted->position() - goal.position()).norm();
      goal = *shifted;
    }
  }
  std::vector<double> goal_yaws;
  if (request.goal_has_yaw && result.goal_moved_m > 0.0) {
    goal_yaws.push_back(goal.yaw_rad);
  } else if (request.goal_has_yaw) {
    if (map.IsValid(goal)) goal_yaws.push_back(goal.yaw_rad);
  } else {
    // Try the heading that points from the start first, then evenly spaced ones.
    const double toward = std::atan2(goal.y_m - start.y_m, goal.x_m - start.x_m);
    for (int k = 0; k < params_.goal_yaw_samples; ++k) {
      const double yaw = common::WrapAngle(toward + 2.0 * M_PI * k / params_.goal_yaw_samples);
      if (map.IsValid({goal.x_m, goal.y_m, yaw})) goal_yaws.push_back(yaw);
    }
  }
  if (goal_yaws.empty()) {
    return finish(PlanStatus::kGoalOccupied,
                  "the footprint at the goal is blocked" + BlockingCellText(map, goal));
  }
  if (cancelled()) return finish(PlanStatus::kCancelled, "cancelled");
  if (params_.grid_precheck && !map.MaybeConnected(start.position(), goal.position())) {
    return finish(PlanStatus::kNoPath, "the goal is not connected to the start");
  }
  if (params_.grid_precheck && params_.unknown_horizon_m > 0.0 &&
      map.params().unknown_is_traversable &&
      !map.ConnectedWithinHorizon(start.position(), goal.position(), params_.unknown_horizon_m,
                                  params_.unknown_goal_radius_m)) {
    std::ostringstream m;
    m << "the goal is not connected to the start through known cells and unknown cells within "
      << params_.unknown_horizon_m << " m";
    return finish(PlanStatus::kNoPath, m.str());
  }

  std::lock_guard<std::mutex> lock(PlanMutex());
  ompl::RNG::setSeed(params_.seed);

  // State space bounded by the grid's axis-aligned extent in the world.
  std::shared_ptr<ob::SE2StateSpace> space;
  switch (params_.state_space) {
    case StateSpaceKind::kSE2:
      space = std::make_shared<ob::SE2StateSpace>();
      break;
    case StateSpaceKind::kDubins:
      space = std::make_shared<DubinsSpace>(params_.turning_radius_m);
      break;
    case StateSpaceKind::kReedsShepp:
      space = std::make_shared<ob::ReedsSheppStateSpace>(params_.turning_radius_m);
      break;
  }
  const auto& g = map.geometry();
  ob::RealVectorBounds bounds(2);
  bounds.setLow(std::numeric_limits<double>::infinity());
  bounds.setHigh(-std::numeric_limits<double>::infinity());
  auto include = [&](const Vector2& w) {
    for (int d = 0; d < 2; ++d) {
      bounds.low[d] = std::min(bounds.low[d], w[d]);
      bounds.high[d] = std::max(bounds.high[d], w[d]);
    }
  };
  // The grid's extent in the world (its corners, for a rotated grid).
  ob::RealVectorBounds grid = bounds;
  for (const Vector2& corner :
       {Vector2(0, 0), Vector2(g.length_x_m(), 0), Vector2(0, g.length_y_m()),
        Vector2(g.length_x_m(), g.length_y_m())}) {
    const Vector2 w = g.origin.Transform(corner);
    for (int d = 0; d < 2; ++d) {
      grid.low[d] = std::min(grid.low[d], w[d]);
      grid.high[d] = std::max(grid.high[d], w[d]);
    }
  }
  // Sampled region: known cells, start and goal, grown by the margin, within the grid.
  include(start.position());
  include(goal.position());
  if (const auto known = map.known_cells()) {
    const double res = g.resolution_m;
    for (const Vector2& corner :
         {Vector2(known->first.ix * res, known->first.iy * res),
          Vector2((known->second.ix + 1) * res, known->first.iy * res),
          Vector2(known->first.ix * res, (known->second.iy + 1) * res),
          Vector2((known->second.ix + 1) * res, (known->second.iy + 1) * res)}) {
      include(g.origin.Transform(corner));
    }
  }
  for (int d = 0; d < 2; ++d) {
    bounds.low[d] = std::max(grid.low[d], bounds.low[d] - params_.bounds_margin_m);
    bounds.high[d] = std::min(grid.high[d], bounds.high[d] + params_.bounds_margin_m);
  }
  space->setBounds(bounds);
  if (params_.aligned_heading_fraction > 0.0 || params_.ridge_sample_fraction > 0.0) {
    const double ridge = params_.ridge_sample_fraction;
    const double aligned = params_.aligned_heading_fraction;
    space->setStateSamplerAllocator([&map, ridge, aligned](const ob::StateSpace* s) {
      return std::make_shared<FreeSpaceSE2Sampler>(s, map, ridge, aligned);
    });
  }

  og::SimpleSetup setup(space);
  const ob::SpaceInformationPtr si = setup.getSpaceInformation();
  setup.setStateValidityChecker(std::make_shared<FootprintValidityChecker>(
      si, map, start.position(), goal.position(), params_.escape_radius_m));
  si->setStateValidityCheckingResolution(
      std::min(0.5, params_.validity_resolution_m / space->getMaximumExtent()));

  ob::ScopedState<ob::SE2StateSpace> start_state(space);
  start_state->setXY(start.x_m, start.y_m);
  start_state->setYaw(OmplYaw(start.yaw_rad));
  setup.setStartState(start_state);
  if (request.goal_has_yaw) {
    ob::ScopedState<ob::SE2StateSpace> goal_state(space);
    goal_state->setXY(goal.x_m, goal.y_m);
    goal_state->setYaw(OmplYaw(goal.yaw_rad));
    setup.setGoalState(goal_state, params_.goal_tolerance_m);
  } else {
    setup.setGoal(
        std::make_shared<PositionGoal>(si, goal.position(), goal_yaws, params_.goal_tolerance_m));
  }

  ob::OptimizationObjectivePtr objective;
  if (params_.traversal_cost_weight > 0.0 || params_.clearance_weight > 0.0) {
    objective = std::make_shared<TraversalCostObjective>(si, map, params_);
  } else {
    objective = std::make_shared<ob::PathLengthOptimizationObjective>(si);
  }
  objective->setCostToGoHeuristic(&ob::goalRegionCostToGo);
  if (params_.stop_at_first_solution) {
    objective->setCostThreshold(ob::Cost(std::numeric_limits<double>::infinity()));
  }
  setup.setOptimizationObjective(objective);

  ob::PlannerPtr planner = MakePlanner(params_.planner, si);
  if (params_.range_m > 0.0 && planner->params().hasParam("range")) {
    planner->params().setParam("range", std::to_string(params_.range_m));
  }
  setup.setPlanner(planner);
  setup.setup();

  // Solve within the budget; stop early on cancel or, if asked, at the first exact solution.
  const double budget = request.time_budget_s > 0.0 ? request.time_budget_s : params_.time_budget_s;
  ob::PlannerTerminationCondition ptc = ob::timedPlannerTerminationCondition(budget);
  if (cancel != nullptr) {
    ptc = ob::plannerOrTerminationCondition(
        ptc, ob::PlannerTerminationCondition([cancel] { return cancel->load(); }));
  }
  if (params_.stop_at_first_solution) {
    ptc = ob::plannerOrTerminationCondition(
        ptc, ob::exactSolnPlannerTerminationCondition(setup.getProblemDefinition()));
  }
  const auto solve_t0 = Clock::now();
  const ob::PlannerStatus status = setup.solve(ptc);
  result.solve_time_s = SecondsSince(solve_t0);

  if (cancelled()) return finish(PlanStatus::kCancelled, "cancelled");
  if (status == ob::PlannerStatus::APPROXIMATE_SOLUTION ||
      (status == ob::PlannerStatus::EXACT_SOLUTION && !setup.haveExactSolutionPath())) {
    std::ostringstream m;
    m << "only an approximate solution, " << setup.getProblemDefinition()->getSolutionDifference()
      << " m short of the goal";
    return finish(PlanStatus::kApproximate, m.str());
  }
  if (status == ob::PlannerStatus::INVALID_START) {
    return finish(PlanStatus::kStartOccupied, "OMPL rejected the start");
  }
  if (status == ob::PlannerStatus::INVALID_GOAL) {
    return finish(PlanStatus::kGoalOccupied, "OMPL rejected the goal");
  }
  if (status != ob::PlannerStatus::EXACT_SOLUTION) {
    std::ostringstream m;
    m << "no solution within " << budget << " s (" << status.asString() << ")";
    return finish(PlanStatus::kTimedOut, m.str());
  }

  result.solutions = 1;
  og::PathGeometric raw = setup.getSolutionPath();
  std::vector<Pose2> raw_poses;
  for (const ob::State* s : raw.getStates()) raw_poses.push_back(ToPose(s));
  result.raw_length_m = PositionLength(raw_poses);

  // Shortcutting passes until they stop helping (or the time cap): deterministic for a seed.
  og::PathSimplifier simplifier(si, setup.getProblemDefinition()->getGoal(), objective);
  auto simplify = [&](og::PathGeometric* path) {
    const auto t_start = Clock::now();
    for (int pass = 0; pass < 8; ++pass) {
      const double before = path->length();
      simplifier.reduceVertices(*path, 0, 0, 0.33);
      simplifier.shortcutPath(*path, kShortcutSteps, kShortcutSteps / 4, 0.33, 0.005);
      simplifier.collapseCloseVertices(*path);
      if (path->length() > before - 1e-3 || SecondsSince(t_start) > params_.simplify_time_s) break;
    }
  };

  // A few more exact solutions, merged with the first by PathHybridization.
  og::PathGeometric best = raw;
  if (params_.simplify_time_s > 0.0) simplify(&best);
  if (params_.improvement_rounds > 0) {
    og::PathHybridization hybridization(si, objective);
    hybridization.recordPath(std::make_shared<og::PathGeometric>(best), false);
    const auto improve_t0 = Clock::now();
    for (int round = 0; round < params_.improvement_rounds; ++round) {
      const double left = params_.improvement_time_s - SecondsSince(improve_t0);
      if (left <= 0.0 || cancelled()) break;
      planner->clear();
      setup.getProblemDefinition()->clearSolutionPaths();
      ob::PlannerTerminationCondition round_ptc = ob::plannerOrTerminationCondition(
          ob::timedPlannerTerminationCondition(left),
          ob::exactSolnPlannerTerminationCondition(setup.getProblemDefinition()));
      if (cancel != nullptr) {
        round_ptc = ob::plannerOrTerminationCondition(
            round_ptc, ob::PlannerTerminationCondition([cancel] { return cancel->load(); }));
      }
      if (planner->solve(round_ptc) != ob::PlannerStatus::EXACT_SOLUTION ||
          !setup.getProblemDefinition()->hasExactSolution()) {
        continue;
      }
      auto path = std::make_shared<og::PathGeometric>(
          *setup.getProblemDefinition()->getSolutionPath()->as<og::PathGeometric>());
      if (params_.simplify_time_s > 0.0) simplify(path.get());
      hybridization.recordPath(path, false);
      ++result.solutions;
      if (objective->isCostBetterThan(path->cost(objective), best.cost(objective))) best = *path;
    }
    if (cancelled()) return finish(PlanStatus::kCancelled, "cancelled");
    if (hybridization.pathCount() > 1) {
      hybridization.computeHybridPath();
      if (const auto& hybrid = hybridization.getHybridPath()) {
        og::PathGeometric merged = *hybrid;
        if (params_.simplify_time_s > 0.0) simplify(&merged);
        if (objective->isCostBetterThan(merged.cost(objective), best.cost(objective))) {
          best = merged;
        }
      }
    }
  }

  // The grid route as one more candidate (see GlobalPlannerParams::grid_route_candidate).
  if (params_.grid_route_candidate && !cancelled()) {
    GridAStarParams gp;
    gp.traversal_cost_weight = params_.traversal_cost_weight;
    gp.clearance_weight = params_.clearance_weight;
    gp.clearance_inflation_m = params_.clearance_inflation_m;
    const GridPath grid_path = GridAStar(map, start.position(), goal.position(), gp);
    if (grid_path.found && grid_path.points_m.size() >= 2) {
      og::PathGeometric route(si);
      ob::ScopedState<ob::SE2StateSpace> s(space);
      const size_t n = grid_path.points_m.size();
      for (size_t i = 0; i < n; ++i) {
        const Vector2& p = grid_path.points_m[i];
        double yaw = start.yaw_rad;
        if (i == 0) {
          s->setXY(start.x_m, start.y_m);
        } else {
          const Vector2 d = (i + 1 < n ? grid_path.points_m[i + 1] : p) - grid_path.points_m[i - 1];
          yaw = std::atan2(d.y(), d.x());
          s->setXY(p.x(), p.y());
        }
        s->setYaw(OmplYaw(yaw));
        route.append(s.get());
      }
      // End on a goal state the planner accepts (the goal position with an allowed heading).
      const ob::State* last = best.getState(best.getStateCount() - 1);
      route.append(last);
      if (params_.simplify_time_s > 0.0) simplify(&route);
      if (route.check() &&
          objective->isCostBetterThan(route.cost(objective), best.cost(objective))) {
        best = route;
        result.grid_route_chosen = true;
      }
    }
  }

  // Interpolate and check again; fall back to the planner's own path if needed. States are
  // spread evenly along every motion by OMPL's metric (position plus weighted heading, or arc
  // length for Dubins and Reeds-Shepp), never shorter than the position step.
  auto interpolate = [&](og::PathGeometric& path) {
    og::PathGeometric out(si);
    if (path.getStateCount() == 0) return out;
    out.append(path.getState(0));
    ob::State* tmp = si->allocState();
    for (size_t i = 1; i < path.getStateCount(); ++i) {
      const ob::State* a = path.getState(i - 1);
      const ob::State* b = path.getState(i);
      const int n = std::max(
          1, static_cast<int>(std::ceil(si->distance(a, b) / params_.interpolation_step_m)));
      for (int k = 1; k < n; ++k) {
        si->getStateSpace()->interpolate(a, b, static_cast<double>(k) / n, tmp);
        out.append(tmp);
      }
      out.append(b);
    }
    si->freeState(tmp);
    return out;
  };
  og::PathGeometric chosen(si);
  bool have = false;
  if (params_.simplify_time_s > 0.0 || params_.improvement_rounds > 0) {
    og::PathGeometric candidate = interpolate(best);
    if (PathStillValid(map, candidate)) {
      chosen = candidate;
      have = true;
      result.simplified = true;
    }
  }
  if (!have) {
    og::PathGeometric plain = interpolate(raw);
    if (!PathStillValid(map, plain)) {
      return finish(PlanStatus::kNoPath, "the planner's path failed re-validation");
    }
    chosen = plain;
  }
  if (result.start_moved_m > 0.0) result.poses.push_back(request.start);
  for (const ob::State* s : chosen.getStates()) result.poses.push_back(ToPose(s));
  if (params_.state_space == StateSpaceKind::kSE2) {
    // A wheeled robot drives along the path: headings follow the direction of travel where
    // the footprint fits that way (OMPL's validated heading is kept elsewhere).
    for (size_t i = 0; i + 1 < result.poses.size(); ++i) {
      const Vector2 d = result.poses[i + 1].position() - result.poses[i].position();
      if (d.norm() < 1e-6) continue;
      const Pose2 along{result.poses[i].x_m, result.poses[i].y_m, std::atan2(d.y(), d.x())};
      if (map.IsValid(along)) result.poses[i] = along;
    }
  }
  result.length_m = PositionLength(result.poses);
  result.cost = chosen.cost(objective).value();
  if (result.goal_moved_m > 0.0) {
    std::ostringstream m;
    m.setf(std::ios::fixed);
    m.precision(2);
    m << "the footprint at the goal is blocked" << goal_note << "; the path ends "
      << result.goal_moved_m << " m from it, at (" << goal.x_m << ", " << goal.y_m << ")";
    return finish(PlanStatus::kSuccess, m.str());
  }
  return finish(PlanStatus::kSuccess, "");
}

}  // namespace cairn::planner
