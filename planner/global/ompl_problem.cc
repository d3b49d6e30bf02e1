#include "planner/global/ompl_problem.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>

#include <ompl/base/DiscreteMotionValidator.h>
#include <ompl/base/Goal.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/goals/GoalSampleableRegion.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/objectives/StateCostIntegralObjective.h>
#include <ompl/base/spaces/ReedsSheppStateSpace.h>
#include <ompl/geometric/planners/informedtrees/BITstar.h>
#include <ompl/geometric/planners/prm/PRMstar.h>
#include <ompl/geometric/planners/rrt/InformedRRTstar.h>
#include <ompl/geometric/planners/rrt/RRT.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>

#include "common/check.h"
#include "common/log.h"
#include "planner/global/dubins_space.h"

namespace cairn::planner::internal {

using common::Pose2;
using common::Vector2;

namespace {

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

// Near the start and the goal (within the escape radius) the robot's own footprint is checked,
// elsewhere the padded one.
class EscapeZones {
 public:
  EscapeZones(const Vector2& start, const Vector2& goal, double escape_radius_m)
      : start_(start), goal_(goal), radius2_(escape_radius_m * escape_radius_m) {}
  FootprintKind KindAt(const Vector2& p) const {
    return Near(p) ? FootprintKind::kRobot : FootprintKind::kPadded;
  }
  bool Near(const Vector2& p) const {
    return (p - start_).squaredNorm() <= radius2_ || (p - goal_).squaredNorm() <= radius2_;
  }

 private:
  Vector2 start_;
  Vector2 goal_;
  double radius2_;
};

// A state is valid when its position lies on the grid and the padded footprint clears the
// layer; near the start and the goal the robot's own footprint is enough.
class FootprintValidityChecker : public ob::StateValidityChecker {
 public:
  FootprintValidityChecker(const ob::SpaceInformationPtr& si, const CostMap& map,
                           const EscapeZones& zones)
      : ob::StateValidityChecker(si), map_(map), zones_(zones) {}
  bool isValid(const ob::State* state) const override {
    const Pose2 p = ToPose(state);
    if (!map_.Contains(p.position())) return false;
    return map_.IsValid(p, zones_.KindAt(p.position()));
  }

 private:
  const CostMap& map_;
  EscapeZones zones_;
};

// On a map with one-way cells (CostMap::MotionAllowed): OMPL's discrete check of the states
// along a motion, then the direction of travel between consecutive states at the same
// resolution (for Dubins and Reeds-Shepp curves, whose direction turns along the motion; a
// reversing stretch is checked against the heading it drives to). With the padded footprint,
// as the states are, except near the start and the goal: the local planner's trajectories
// stray from the path, and where a footprint grazing a step's edge is refused the way it
// drives, a path with no margin to that edge strands it.
class DirectedMotionValidator : public ob::DiscreteMotionValidator {
 public:
  DirectedMotionValidator(const ob::SpaceInformationPtr& si, const CostMap& map,
                          const EscapeZones& zones)
      : ob::DiscreteMotionValidator(si), map_(map), zones_(zones) {}
  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    return ob::DiscreteMotionValidator::checkMotion(s1, s2) && FirstRefused(s1, s2) < 0;
  }
  bool checkMotion(const ob::State* s1, const ob::State* s2,
                   std::pair<ob::State*, double>& last_valid) const override {
    if (!ob::DiscreteMotionValidator::checkMotion(s1, s2, last_valid)) return false;
    const int refused = FirstRefused(s1, s2);
    if (refused < 0) return true;
    // The motion is good up to the start of the refused segment.
    const double t = static_cast<double>(refused) / Segments(s1, s2);
    if (last_valid.first != nullptr) si_->getStateSpace()->interpolate(s1, s2, t, last_valid.first);
    last_valid.second = t;
    return false;
  }

 private:
  int Segments(const ob::State* s1, const ob::State* s2) const {
    return std::max(1u, si_->getStateSpace()->validSegmentCount(s1, s2));
  }
  // Index of the first segment whose direction the one-way cells refuse, or -1.
  int FirstRefused(const ob::State* s1, const ob::State* s2) const {
    const int n = Segments(s1, s2);
    ob::State* tmp = si_->allocState();
    Pose2 previous = ToPose(s1);
    int refused = -1;
    for (int k = 1; k <= n && refused < 0; ++k) {
      const ob::State* s = s2;
      if (k < n) {
        si_->getStateSpace()->interpolate(s1, s2, static_cast<double>(k) / n, tmp);
        s = tmp;
      }
      const Pose2 pose = ToPose(s);
      const bool near_end = zones_.Near(previous.position()) || zones_.Near(pose.position());
      if (!map_.MotionAllowed(previous, pose,
                              near_end ? FootprintKind::kRobot : FootprintKind::kPadded)) {
        refused = k - 1;
      }
      previous = pose;
    }
    si_->freeState(tmp);
    return refused;
  }

  const CostMap& map_;
  EscapeZones zones_;
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
      // One-way cells (a step's edge) keep paths off as blocking cells do: the local planner
      // may not touch them in the headings they refuse, and a path that grazes one leaves it no
      // room to follow.
      const double d = std::min(map_.SmoothClearanceAt(p), map_.SmoothOneWayClearanceAt(p));
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

// The state space of params.state_space.
std::shared_ptr<ob::SE2StateSpace> MakeSpace(const GlobalPlannerParams& params) {
  switch (params.state_space) {
    case StateSpaceKind::kSE2:
      return std::make_shared<ob::SE2StateSpace>();
    case StateSpaceKind::kDubins:
      return std::make_shared<DubinsSpace>(params.turning_radius_m);
    case StateSpaceKind::kReedsShepp:
      return std::make_shared<ob::ReedsSheppStateSpace>(params.turning_radius_m);
  }
  return std::make_shared<ob::SE2StateSpace>();
}

// The sampled region: the known cells, start and goal, grown by the margin, within the grid's
// axis-aligned extent in the world.
ob::RealVectorBounds SampledBounds(const CostMap& map, const GlobalPlannerParams& params,
                                   const Pose2& start, const Pose2& goal) {
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
    bounds.low[d] = std::max(grid.low[d], bounds.low[d] - params.bounds_margin_m);
    bounds.high[d] = std::min(grid.high[d], bounds.high[d] + params.bounds_margin_m);
  }
  return bounds;
}

// Length plus traversal cost (or length alone when both weights are 0), with the goal region's
// cost-to-go as heuristic; with stop_at_first_solution any exact solution satisfies it.
ob::OptimizationObjectivePtr MakeObjective(const ob::SpaceInformationPtr& si, const CostMap& map,
                                           const GlobalPlannerParams& params) {
  ob::OptimizationObjectivePtr objective;
  if (params.traversal_cost_weight > 0.0 || params.clearance_weight > 0.0) {
    objective = std::make_shared<TraversalCostObjective>(si, map, params);
  } else {
    objective = std::make_shared<ob::PathLengthOptimizationObjective>(si);
  }
  objective->setCostToGoHeuristic(&ob::goalRegionCostToGo);
  if (params.stop_at_first_solution) {
    objective->setCostThreshold(ob::Cost(std::numeric_limits<double>::infinity()));
  }
  return objective;
}

}  // namespace

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

double PositionLength(const std::vector<Pose2>& poses) {
  double length = 0.0;
  for (size_t i = 1; i < poses.size(); ++i) {
    length += (poses[i].position() - poses[i - 1].position()).norm();
  }
  return length;
}

bool PathStillValid(const CostMap& map, og::PathGeometric& path) {
  const std::vector<ob::State*>& states = path.getStates();
  for (size_t i = 0; i < states.size(); ++i) {
    const Pose2 p = ToPose(states[i]);
    if (!map.Contains(p.position()) || !map.IsValid(p)) return false;
    if (i > 0 && !map.MotionAllowed(ToPose(states[i - 1]), p)) return false;
  }
  return true;
}

OmplProblem SetUpProblem(const CostMap& map, const GlobalPlannerParams& params, const Pose2& start,
                         const Pose2& goal, bool goal_has_yaw,
                         const std::vector<double>& goal_yaws) {
  OmplProblem p;
  p.space = MakeSpace(params);
  p.space->setBounds(SampledBounds(map, params, start, goal));
  if (params.aligned_heading_fraction > 0.0 || params.ridge_sample_fraction > 0.0) {
    const double ridge = params.ridge_sample_fraction;
    const double aligned = params.aligned_heading_fraction;
    p.space->setStateSamplerAllocator([&map, ridge, aligned](const ob::StateSpace* s) {
      return std::make_shared<FreeSpaceSE2Sampler>(s, map, ridge, aligned);
    });
  }

  p.setup = std::make_unique<og::SimpleSetup>(p.space);
  og::SimpleSetup& setup = *p.setup;
  p.si = setup.getSpaceInformation();
  const EscapeZones zones(start.position(), goal.position(), params.escape_radius_m);
  setup.setStateValidityChecker(std::make_shared<FootprintValidityChecker>(p.si, map, zones));
  p.si->setStateValidityCheckingResolution(
      std::min(0.5, params.validity_resolution_m / p.space->getMaximumExtent()));
  if (map.one_way_cells() > 0) {
    p.si->setMotionValidator(std::make_shared<DirectedMotionValidator>(p.si, map, zones));
  }

  ob::ScopedState<ob::SE2StateSpace> start_state(p.space);
  start_state->setXY(start.x_m, start.y_m);
  start_state->setYaw(OmplYaw(start.yaw_rad));
  setup.setStartState(start_state);
  if (goal_has_yaw) {
    ob::ScopedState<ob::SE2StateSpace> goal_state(p.space);
    goal_state->setXY(goal.x_m, goal.y_m);
    goal_state->setYaw(OmplYaw(goal.yaw_rad));
    setup.setGoalState(goal_state, params.goal_tolerance_m);
  } else {
    setup.setGoal(
        std::make_shared<PositionGoal>(p.si, goal.position(), goal_yaws, params.goal_tolerance_m));
  }

  p.objective = MakeObjective(p.si, map, params);
  setup.setOptimizationObjective(p.objective);
  p.planner = MakePlanner(params.planner, p.si);
  if (params.range_m > 0.0 && p.planner->params().hasParam("range")) {
    p.planner->params().setParam("range", std::to_string(params.range_m));
  }
  setup.setPlanner(p.planner);
  setup.setup();
  return p;
}

og::PathGeometric Interpolate(const ob::SpaceInformationPtr& si, og::PathGeometric& path,
                              double step_m) {
  og::PathGeometric out(si);
  if (path.getStateCount() == 0) return out;
  out.append(path.getState(0));
  ob::State* tmp = si->allocState();
  for (size_t i = 1; i < path.getStateCount(); ++i) {
    const ob::State* a = path.getState(i - 1);
    const ob::State* b = path.getState(i);
    const int n = std::max(1, static_cast<int>(std::ceil(si->distance(a, b) / step_m)));
    for (int k = 1; k < n; ++k) {
      si->getStateSpace()->interpolate(a, b, static_cast<double>(k) / n, tmp);
      out.append(tmp);
    }
    out.append(b);
  }
  si->freeState(tmp);
  return out;
}

og::PathGeometric RouteAsPath(const OmplProblem& problem, const std::vector<Vector2>& points,
                              const Pose2& start, const ob::State* goal_state) {
  og::PathGeometric route(problem.si);
  ob::ScopedState<ob::SE2StateSpace> s(problem.space);
  const size_t n = points.size();
  // The last point (the goal's cell centre) gives way to the goal state itself: a motion of a
  // few centimetres that must also turn to the goal's heading would turn in place.
  for (size_t i = 0; i + 1 < n || i == 0; ++i) {
    const Vector2& p = points[i];
    double yaw = start.yaw_rad;
    if (i == 0) {
      s->setXY(start.x_m, start.y_m);
    } else {
      const Vector2 d = (i + 1 < n ? points[i + 1] : p) - points[i - 1];
      yaw = std::atan2(d.y(), d.x());
      s->setXY(p.x(), p.y());
    }
    s->setYaw(OmplYaw(yaw));
    route.append(s.get());
  }
  route.append(goal_state);
  return route;
}

namespace {

// Turns `state` in place to the heading nearest its own, among the 16 that
// CostMap::FitsAtSomeHeading tries, where its footprint fits; false (the state unchanged) when
// none does.
bool TurnUntilValid(const ob::SpaceInformation& si, ob::State* state) {
  if (si.isValid(state)) return true;
  auto* s = state->as<ob::SE2StateSpace::StateType>();
  const double yaw0 = s->getYaw();
  constexpr int kHeadings = 16;
  std::array<double, kHeadings> yaws;
  for (int k = 0; k < kHeadings; ++k) yaws[k] = 2.0 * M_PI * k / kHeadings;
  std::sort(yaws.begin(), yaws.end(), [yaw0](double a, double b) {
    return std::abs(common::WrapAngle(a - yaw0)) < std::abs(common::WrapAngle(b - yaw0));
  });
  for (const double yaw : yaws) {
    s->setYaw(OmplYaw(yaw));
    if (si.isValid(state)) return true;
  }
  s->setYaw(yaw0);
  return false;
}

// Appends to `out` the states that bridge the motion from `a` to `b` (not `b` itself): none when
// the motion is valid, else its midpoint turned until it fits, recursively, `depth` levels at
// most. Every state appended is owned by `out`'s path, whatever the outcome.
bool Bridge(const ob::SpaceInformation& si, const ob::State* a, const ob::State* b, int depth,
            std::vector<ob::State*>* out) {
  if (si.checkMotion(a, b)) return true;
  if (depth == 0) return false;
  ob::State* mid = si.allocState();
  si.getStateSpace()->interpolate(a, b, 0.5, mid);
  const bool fits = TurnUntilValid(si, mid);
  if (!fits) {
    si.freeState(mid);
    return false;
  }
  if (!Bridge(si, a, mid, depth - 1, out)) {
    si.freeState(mid);
    return false;
  }
  out->push_back(mid);
  return Bridge(si, mid, b, depth - 1, out);
}

}  // namespace

bool RepairRoute(const OmplProblem& problem, og::PathGeometric* route) {
  const ob::SpaceInformation& si = *problem.si;
  std::vector<ob::State*>& states = route->getStates();
  if (states.size() < 2) return false;
  // Turned where the footprint is blocked at the route's heading; a waypoint where it fits at none
  // of the 16 headings is dropped (the motion past it is bridged below, or the route fails).
  std::vector<ob::State*> kept{states.front()};
  for (size_t i = 1; i + 1 < states.size(); ++i) {
    if (TurnUntilValid(si, states[i])) {
      kept.push_back(states[i]);
    } else {
      si.freeState(states[i]);
    }
  }
  kept.push_back(states.back());
  // Three levels of midpoints: a motion is bridged by up to seven more states.
  constexpr int kBridgeDepth = 3;
  std::vector<ob::State*> repaired{kept.front()};
  bool ok = true;
  for (size_t i = 0; i + 1 < kept.size(); ++i) {
    ok = ok && Bridge(si, kept[i], kept[i + 1], kBridgeDepth, &repaired);
    repaired.push_back(kept[i + 1]);
  }
  states.swap(repaired);  // the path owns every state, bridged or not
  return ok;
}

}  // namespace cairn::planner::internal
