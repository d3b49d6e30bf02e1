// bench_planner: what a navigator's user waits for, and its parts.
//
// 1. One DWA cycle (20 x 20 samples simulated over 1.7 s, five critics, footprint on a 0.05 m
//    cost layer around clutter). Anchor: Nav2 DWB, about 3 ms per cycle (published).
// 2. The whole global plan (planner.plan.*, the headline): GlobalPlanner::Plan as the navigator
//    runs it (its default params: grid pre-check, first solution, simplification, the coarse
//    grid route candidate, improvement rounds without one, re-validation) on a 100 m x 100 m cost
//    layer at 0.1 m with obstacles and a 10 degree ramp band the pioneer3at profile may not climb,
//    derived from an elevation map by the mapper's own traversability code. 100 seeded queries
//    drawn wherever the footprint fits, solvable or not: every one counts, failures included.
//    Baselines in the same run on the same queries: 8-connected grid A* (time) and Theta* on the
//    same grid (any-angle path length).
// 3. Parts (planner.ompl_parts.*, the figures this benchmark used to report): sampling alone
//    (no grid route candidate), only queries grid A* solves with 0.8 m clearance at both ends,
//    the time to the first solution (without the pre-check and simplification) and the length
//    against 8-connected A*.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include "bench/support/figure.h"
#include "common/grid_map.h"
#include "common/layers.h"
#include "common/robot_profile.h"
#include "planner/cost_map.h"
#include "planner/global/global_planner.h"
#include "planner/global/grid_astar.h"
#include "planner/local/dwa_planner.h"
#include "planner/navigator.h"
#include "planner/path.h"
#include "services/mapping/traversability.h"

namespace {

using cairn::bench::Figure;
using cairn::bench::Report;
using cairn::common::GridGeometry;
using cairn::common::GridMap;
using cairn::common::Pose2;
using cairn::common::Vector2;
namespace planner = cairn::planner;
using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t i =
      std::min(v.size() - 1, static_cast<size_t>(std::floor(p * (v.size() - 1) + 0.5)));
  return v[i];
}

cairn::common::RobotProfile Pioneer() {
  return cairn::common::LoadRobotProfileFile(std::string(CAIRN_SOURCE_DIR) +
                                             "/config/profiles/pioneer3at.yaml");
}

void BenchDwa(const cairn::common::RobotProfile& profile) {
  // 30 m x 30 m at 0.05 m, boxes scattered 1-3 m around the robot's corridor.
  GridGeometry g;
  g.resolution_m = 0.05;
  g.size_x = 600;
  g.size_y = 600;
  cairn::common::Layer cost = cairn::common::Layer::Zero(g.size_x, g.size_y);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto box = [&](double x0, double y0, double x1, double y1, float v) {
    for (int iy = std::max(0, int(y0 / g.resolution_m));
         iy < std::min(g.size_y, int(y1 / g.resolution_m)); ++iy) {
      for (int ix = std::max(0, int(x0 / g.resolution_m));
           ix < std::min(g.size_x, int(x1 / g.resolution_m)); ++ix) {
        cost(ix, iy) = v;
      }
    }
  };
  for (int k = 0; k < 120; ++k) {
    const double x = 2.0 + u(rng) * 26.0;
    const double side = u(rng) < 0.5 ? -1.0 : 1.0;
    const double y = 15.0 + side * (1.0 + u(rng) * 2.0);
    const double s = 0.2 + u(rng) * 0.6;
    box(x, y, x + s, y + s, k % 4 == 0 ? 60.0f : 100.0f);
  }
  const planner::CostMap map(g, cost, profile.footprint_m);
  const planner::Path path({{1.0, 15.0, 0.0}, {29.0, 15.0, 0.0}});
  planner::DwaParams params;  // 20 x 20 samples, 1.7 s, 0.1 s steps
  planner::DwaPlanner dwa(planner::VelocityLimits::FromProfile(profile), params);

  std::vector<double> times;
  int valid = 0;
  for (int k = 0; k < 3000; ++k) {
    const Pose2 pose{2.0 + u(rng) * 26.0, 15.0 + (u(rng) - 0.5) * 1.6, (u(rng) - 0.5) * 1.2};
    planner::DwaInput in;
    in.map = &map;
    in.pose = pose;
    in.last_command = {u(rng) * profile.max_vel_x_mps,
                       (u(rng) - 0.5) * 2 * profile.max_vel_theta_radps};
    in.path = &path;
    in.segment_begin = 0;
    in.segment_end = 1;
    in.local_goal = {pose.x_m + 1.2, 15.0};
    const auto t0 = Clock::now();
    const planner::DwaResult r = dwa.Compute(in);
    const auto t1 = Clock::now();
    dwa.Commit(r.command, pose);
    valid += r.found;
    if (k >= 100) times.push_back(Ms(t0, t1));  // after warm-up
  }
  const double median = Percentile(times, 0.5);
  std::printf("DWA: %zu cycles of %d samples, %d found a valid trajectory\n", times.size() + 100,
              params.generator.vx_samples * params.generator.vtheta_samples, valid);
  Report(Figure{"planner.dwa.cycle_median", median, "ms", "Nav2 DWB (published, navigation2#3205)",
                3.0, false, "<= 1 ms", median <= 1.0});
  Report(Figure{"planner.dwa.cycle_p99", Percentile(times, 0.99), "ms",
                "Nav2 DWB (published, navigation2#3205)", 3.0, false, "-", true});
}

// 100 m x 100 m at 0.1 m: flat ground, 1 m blocks, and a band of 10 degree ramps up to a
// plateau and down again across y in [0, 70]: the pioneer3at (8 degrees) must go around its
// north end.
GridMap BenchWorld(uint32_t seed) {
  GridGeometry g;
  g.resolution_m = 0.1;
  g.size_x = 1000;
  g.size_y = 1000;
  GridMap map(g);
  auto& h = map.AddLayer(cairn::layers::kElevation, 0.0f);
  const double slope = std::tan(10.0 * M_PI / 180.0);
  for (int iy = 0; iy < g.size_y; ++iy) {
    for (int ix = 0; ix < g.size_x; ++ix) {
      const Vector2 c = g.CenterOf({ix, iy});
      if (c.y() > 70.0) continue;
      double z = 0.0;
      if (c.x() >= 45.0 && c.x() < 48.0) z = (c.x() - 45.0) * slope;
      if (c.x() >= 48.0 && c.x() < 55.0) z = 3.0 * slope;
      if (c.x() >= 55.0 && c.x() < 58.0) z = (58.0 - c.x()) * slope;
      h(ix, iy) = static_cast<float>(z);
    }
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 150; ++k) {
    const double x = u(rng) * 96.0, y = u(rng) * 96.0, w = 1.0 + u(rng) * 3.0,
                 d = 1.0 + u(rng) * 3.0;
    if (x + w > 43.0 && x < 60.0) continue;  // keep the ramp band clean
    for (int iy = int(y / 0.1); iy < std::min(1000, int((y + d) / 0.1)); ++iy) {
      for (int ix = int(x / 0.1); ix < std::min(1000, int((x + w) / 0.1)); ++ix) h(ix, iy) = 1.0f;
    }
  }
  return map;
}

// The cost layer of the benchmark world for `profile`, with its distance fields and labels.
std::unique_ptr<const planner::CostMap> BenchMap(const cairn::common::RobotProfile& profile) {
  GridMap world = BenchWorld(11);
  const auto d0 = Clock::now();
  cairn::mapping::TraversabilityParams tp;
  tp.blind_zone_half_size_m = 0.0;
  cairn::mapping::ComputeCostLayer(&world, profile, tp);
  const auto d1 = Clock::now();
  const std::string layer = cairn::layers::CostLayer(profile.name);
  planner::CostMapParams cp;  // unknown blocks (there is none)
  auto map = std::make_unique<const planner::CostMap>(world.geometry(), world.at(layer),
                                                      profile.footprint_m, cp);
  (void)map->ComponentOf({1.0, 1.0});  // build the connectivity labels outside the timings
  const auto d2 = Clock::now();
  int ramp_lethal = 0;
  for (double x = 45.5; x < 57.5; x += 0.5) ramp_lethal += map->CostAt({x, 35.0}) >= 100.0f;
  std::printf(
      "world: cost layer derived in %.0f ms, distance fields and labels in %.0f ms; "
      "%d of 24 samples across the ramp band are lethal for %s\n",
      Ms(d0, d1), Ms(d1, d2), ramp_lethal, profile.name.c_str());
  return map;
}

// A pose in x in [x0, x1], y in [3, 67] where the footprint fits (and, with min_clearance_m,
// that far from blocking cells).
Pose2 FreePose(const planner::CostMap& map, std::mt19937* rng, double x0, double x1,
               double min_clearance_m) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  while (true) {
    const Pose2 p{x0 + u(*rng) * (x1 - x0), 3.0 + u(*rng) * 64.0, (u(*rng) - 0.5) * 2 * M_PI};
    if (map.IsValid(p) && map.ClearanceAt(p.position()) > min_clearance_m) return p;
  }
}

struct Timed {
  planner::GridPath path;
  double ms{0.0};
};

Timed TimedGridSearch(const planner::CostMap& map, const Pose2& start, const Pose2& goal,
                      bool any_angle) {
  planner::GridAStarParams params;
  params.any_angle = any_angle;
  const auto t0 = Clock::now();
  Timed out;
  out.path = planner::GridAStar(map, start.position(), goal.position(), params);
  out.ms = Ms(t0, Clock::now());
  return out;
}

// The headline: the whole plan on every query, failures counted.
void BenchPlanTotal(const planner::CostMap& map) {
  const int runs = 100;
  std::mt19937 rng(2027);
  std::vector<double> total_ms, astar_ms, theta_ms, ratio_theta, ratio_astar;
  std::map<std::string, int> reachable_outcomes, unreachable_outcomes;
  int reachable = 0, solved = 0, failures = 0;
  for (int run = 0; run < runs; ++run) {
    const Pose2 start = FreePose(map, &rng, 3.0, 35.0, 0.0);
    const Pose2 goal = FreePose(map, &rng, 65.0, 97.0, 0.0);
    const Timed astar = TimedGridSearch(map, start, goal, false);
    const Timed theta = astar.path.found ? TimedGridSearch(map, start, goal, true) : Timed{};
    planner::GlobalPlannerParams gp;  // the navigator's defaults ...
    gp.seed = 1 + run;
    planner::PlanRequest request{start, goal, false};
    request.goal_shift_radius_m = planner::NavigatorParams{}.occupied_goal_shift_m;  // ... far goal
    const planner::PlanResult r = planner::GlobalPlanner(gp).Plan(map, request);
    total_ms.push_back(r.total_time_s * 1e3);
    astar_ms.push_back(astar.ms);
    const std::string status = planner::PlanStatusName(r.status);
    if (astar.path.found) {
      ++reachable;
      theta_ms.push_back(theta.ms);
      ++reachable_outcomes[status];
      if (r.ok()) {
        ++solved;
        ratio_theta.push_back(r.length_m / theta.path.length_m);
        ratio_astar.push_back(r.length_m / astar.path.length_m);
      } else {
        ++failures;
        std::printf("query %d (reachable): %s (%s)\n", run, status.c_str(), r.message.c_str());
      }
    } else {
      ++unreachable_outcomes[status];
      // No grid path: the right answer is a verdict (no path, or an occupied end), not a budget
      // spent searching.
      if (r.status == planner::PlanStatus::kTimedOut ||
          r.status == planner::PlanStatus::kApproximate) {
        ++failures;
        std::printf("query %d (unreachable): %s (%s)\n", run, status.c_str(), r.message.c_str());
      }
    }
  }
  auto outcomes = [](const std::map<std::string, int>& m) {
    std::string text;
    for (const auto& [name, count] : m) text += " " + name + " " + std::to_string(count);
    return text;
  };
  std::printf("plan: %d queries, %d reachable on the grid:%s; %d unreachable:%s\n", runs, reachable,
              outcomes(reachable_outcomes).c_str(), runs - reachable,
              outcomes(unreachable_outcomes).c_str());
  std::printf(
      "plan: total p50 %.1f ms, p90 %.1f ms, max %.1f ms; grid A* p50 %.1f ms, Theta* p50 %.1f "
      "ms; length vs Theta* p90 %.3f, vs 8-connected A* p50 %.3f\n",
      Percentile(total_ms, 0.5), Percentile(total_ms, 0.9), Percentile(total_ms, 1.0),
      Percentile(astar_ms, 0.5), Percentile(theta_ms, 0.5), Percentile(ratio_theta, 0.9),
      Percentile(ratio_astar, 0.5));
  const double median = Percentile(total_ms, 0.5);
  const double p99 = Percentile(total_ms, 0.99);
  const double rate = reachable > 0 ? 100.0 * solved / reachable : NAN;
  const double ratio = Percentile(ratio_theta, 0.5);
  const std::string a_star = "grid A* 8-connected, same queries (same run)";
  const double astar_median = Percentile(astar_ms, 0.5);
  Report(Figure{"planner.plan.total_median", median, "ms", a_star, astar_median, false,
                "<= 50 ms and <= the grid A*", median <= 50.0 && median <= astar_median});
  Report(Figure{"planner.plan.total_p99", p99, "ms", a_star, Percentile(astar_ms, 0.99), false,
                "<= 200 ms", p99 <= 200.0});
  Report(Figure{"planner.plan.success_rate", rate, "%", "queries grid A* reaches", NAN, true,
                ">= 99 %", rate >= 99.0});
  Report(Figure{"planner.plan.failed_queries", static_cast<double>(failures), "queries", "-", NAN,
                false, "0", failures == 0});
  Report(Figure{"planner.plan.length_ratio_any_angle_median", ratio, "x",
                "Theta* any-angle path length on the same grid (same run)", 1.0, false, "<= 1.05",
                ratio <= 1.05});
}

// The parts this benchmark used to report as its figures: sampling alone, queries the grid A*
// solves with 0.8 m clearance at both ends, the first solution's time and the length against
// 8-connected A*.
void BenchOmplParts(const planner::CostMap& map) {
  std::mt19937 rng(2026);
  std::vector<double> first_ms, total_ms, astar_ms, ratios;
  int success = 0;
  const int runs = 100;
  int skipped = 0;
  for (int run = 0; run < runs; ++run) {
    // A query the grid baseline can solve (a few random goals land in pockets between blocks).
    Pose2 start, goal;
    Timed astar;
    while (true) {
      start = FreePose(map, &rng, 3.0, 35.0, 0.8);
      goal = FreePose(map, &rng, 65.0, 97.0, 0.8);
      astar = TimedGridSearch(map, start, goal, false);
      if (astar.path.found) break;
      ++skipped;
    }
    astar_ms.push_back(astar.ms);
    planner::GlobalPlannerParams gp;  // the navigator's defaults: RRTConnect, 1 s budget ...
    gp.grid_route_candidate = false;  // ... sampling alone, measured against the grid A* baseline
    gp.seed = 1 + run;
    const planner::PlanResult r = planner::GlobalPlanner(gp).Plan(map, {start, goal, false});
    if (r.ok()) {
      ++success;
      first_ms.push_back(r.solve_time_s * 1e3);
      total_ms.push_back(r.total_time_s * 1e3);
      ratios.push_back(r.length_m / astar.path.length_m);
    } else {
      std::printf("run %d: %s (%s)\n", run, planner::PlanStatusName(r.status), r.message.c_str());
    }
  }
  const double first = Percentile(first_ms, 0.5);
  const double rate = 100.0 * success / runs;
  const double ratio = Percentile(ratios, 0.5);
  std::printf(
      "parts (the old figures): sampling alone, %d queries grid A* solves with 0.8 m clearance "
      "(%d draws skipped)\n",
      runs, skipped);
  std::printf(
      "parts: %d/%d exact; first solution p90 %.1f ms; with simplification median %.1f ms; "
      "length ratio to 8-connected A* p90 %.3f, max %.3f\n",
      success, runs, Percentile(first_ms, 0.9), Percentile(total_ms, 0.5), Percentile(ratios, 0.9),
      Percentile(ratios, 1.0));
  const std::string filtered = " (part: A*-solvable queries with 0.8 m clearance, same run)";
  Report(Figure{"planner.ompl_parts.first_solution_median", first, "ms", "grid A*" + filtered,
                Percentile(astar_ms, 0.5), false, "<= 50 ms", first <= 50.0});
  Report(Figure{"planner.ompl_parts.success_rate", rate, "%", "-", NAN, true, ">= 99 %",
                rate >= 99.0});
  Report(Figure{"planner.ompl_parts.length_ratio_8conn_median", ratio, "x",
                "8-connected grid A* path length" + filtered, 1.0, false, "<= 1.05",
                ratio <= 1.05});
  Report(Figure{"planner.ompl_parts.plan_total_median", Percentile(total_ms, 0.5), "ms",
                "grid A*" + filtered, Percentile(astar_ms, 0.5), false, "-", true});
}

}  // namespace

int main() {
  const cairn::bench::StealNote steal_note;
  const auto profile = Pioneer();
  BenchDwa(profile);
  const auto map = BenchMap(profile);
  BenchPlanTotal(*map);
  BenchOmplParts(*map);
  return 0;
}
