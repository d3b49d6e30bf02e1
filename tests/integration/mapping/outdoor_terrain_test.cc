// Natural terrain judged as terrain (issue 17): the real cairn::sim core drives a Pioneer 3-AT
// over the outdoor world's hills (MuJoCo ray casting, the simulated HDL-32E with its range
// noise) and feeds the real terrain map of config/mapping/mapper.yaml in-process. The
// Pioneer's cost layer and the obstacle registry are then compared with the truth, read from
// the world itself by casting vertical rays (the height field and every geom standing on it):
// - cells lethal where the ground is within the profile's limits and no geom stands within a
//   cell are under 1 % of the mapped cells;
// - every rock, wall, tree and building the map saw is lethal;
// - the registry lists each real object once and no feature on smooth ground.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "common/layers.h"
#include "common/robot_profile.h"
#include "services/mapping/mapper_config.h"
#include "services/mapping/mapper_inputs.h"
#include "services/mapping/terrain_map.h"
#include "services/mapping/traversability.h"
#include "services/runtime/revolution_assembler.h"
#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"
#include "simulator/sensors/ground_truth_sensor.h"
#include "simulator/sensors/lidar_sensor.h"
#include "simulator/sensors/odometry_sensor.h"
#include "simulator/sensors/planar_laser_sensor.h"

namespace cairn::testing {
namespace {

constexpr double kPi = 3.14159265358979323846;

// One drive: spawn pose, then a constant speed along the spawn heading for a while.
struct Drive {
  double x_m, y_m, yaw_rad, speed_mps, duration_s;
};

// The truth of one map cell, from vertical rays into the world.
struct CellTruth {
  double z_m{NAN};  // top surface at the cell centre (terrain or a geom)
  int object{-1};   // index of the object (rock, wall, ...) standing in the cell, or -1
};

struct WorldObject {
  std::string name;            // rock_3, tree_1, house (its five walls), shed, garden_wall
  std::vector<int64_t> cells;  // mapped cells of its footprint
};

struct Evaluation;

class OutdoorTerrainTest : public ::testing::Test {
 public:
  void SetUp() override {
    const std::string root = CAIRN_SOURCE_DIR;
    config_ = mapping::LoadMapperConfigFile(root + "/config/mapping/mapper.yaml");
    profile_ = common::LoadRobotProfileFile(root + "/config/profiles/pioneer3at.yaml");
  }

  // Drives and maps in `world`; leaves the map in map_ and the simulator in sim_.
  void DriveAndMap(const std::vector<Drive>& drives, const std::string& world = "outdoor") {
    const sim::SimPaths paths = sim::SimPaths::InTree(CAIRN_SOURCE_DIR);
    map_ = std::make_unique<mapping::TerrainMap>(config_.params.core.terrain.map);
    map_->AddProfile(profile_);
    for (const Drive& d : drives) {
      sim::Scenario scenario;
      scenario.world = world;
      scenario.world_path = paths.WorldPath(world);
      scenario.seed = 17;
      sim::RobotSpec robot = sim::MakeRobotSpec("p1", "pioneer3at", "",
                                                {d.x_m, d.y_m, d.yaw_rad, std::nullopt}, paths);
      robot.commands.push_back({0.5, d.duration_s, d.speed_mps, 0.0});
      robot.sensors.Remove(sim::PlanarLaserSensor::kName);
      robot.sensors.Remove(sim::OdometrySensor::kName);
      scenario.robots.push_back(robot);
      sim_ = std::make_unique<sim::MujocoSim>(scenario);
      mapping::MapperInputs inputs(config_.params.inputs);
      runtime::RevolutionAssembler assembler;
      sim::SimOutputs out;
      while (sim_->time_s() < d.duration_s + 1.5) {
        out.Clear();
        sim_->Step(&out);
        for (auto& pose : out.Mutable<sim::GroundTruthReading>(sim::GroundTruthSensor::kName)) {
          inputs.AddGroundTruth(pose.utime, pose.pose);
        }
        for (auto& slice : out.Mutable<common::LidarSlice>(sim::LidarSensor::kName)) {
          const int64_t arrival_us = slice.utime;  // sim time: the test's only clock
          // The points of the sensor's range image, as FromLcm makes them off the bus.
          common::ExpandRangeImage(&slice);
          for (auto& revolution : assembler.OnSlice(std::move(slice), arrival_us)) {
            mapping::RevolutionDrops drops;
            auto prepared = inputs.PrepareRevolution(std::move(revolution), &drops);
            if (!prepared) continue;
            map_->Integrate(prepared->revolution, prepared->time_s);
            map_->UpdateDerived(prepared->robot);
            last_robot_ = prepared->robot;
          }
        }
      }
    }
    grid_ = map_->Export({layers::kElevation, layers::kElevationVariance, layers::kGroundBound,
                          layers::kSlope, layers::kRoughness, layers::kDitchDepth,
                          layers::CostLayer(profile_.name)});
  }

  // The top surface under (x, y) and the world geom there (-1: none; robots are skipped).
  std::pair<double, int> CastDown(double x, double y) const {
    const mjModel* m = sim_->model();
    const mjData* d = sim_->data();
    mjtNum pnt[3] = {x, y, 30.0};
    const mjtNum vec[3] = {0, 0, -1};
    for (int k = 0; k < 8; ++k) {
      int geom = -1;
      const mjtNum dist = mj_ray(m, d, pnt, vec, nullptr, 1, -1, &geom);
      if (geom < 0 || dist < 0) return {NAN, -1};
      const double z = pnt[2] - dist;
      if (m->geom_bodyid[geom] == 0) return {z, geom};
      pnt[2] = z - 1e-4;  // a robot's part: look beneath it
    }
    return {NAN, -1};
  }

  // Truth for every cell of grid_, sub-sampled 4 x 4 for the objects.
  void ComputeTruth() {
    const mjModel* m = sim_->model();
    const common::GridMap& g = *grid_;
    const int sx = g.size_x(), sy = g.size_y();
    const double res = g.resolution_m();
    truth_.assign(static_cast<size_t>(sx) * sy, CellTruth{});
    std::map<std::string, int> index;
    for (int y = 0; y < sy; ++y) {
      for (int x = 0; x < sx; ++x) {
        const common::Vector2 c = g.geometry().CenterOf({x, y});
        CellTruth& t = truth_[x + static_cast<int64_t>(y) * sx];
        t.z_m = CastDown(c.x(), c.y()).first;
        for (int i = 0; i < 4 && t.object < 0; ++i) {
          for (int j = 0; j < 4 && t.object < 0; ++j) {
            const int geom =
                CastDown(c.x() + (i - 1.5) * res / 4, c.y() + (j - 1.5) * res / 4).second;
            if (geom < 0) continue;
            std::string name =
                mj_id2name(m, mjOBJ_GEOM, geom) ? mj_id2name(m, mjOBJ_GEOM, geom) : "";
            if (name == "terrain" || name.empty()) continue;
            if (name.rfind("house", 0) == 0) name = "house";
            auto it = index.find(name);
            if (it == index.end()) {
              it = index.emplace(name, static_cast<int>(objects_.size())).first;
              objects_.push_back({name, {}});
            }
            t.object = it->second;
          }
        }
      }
    }
  }

  mapping::MapperConfig config_;
  common::RobotProfile profile_;
  std::unique_ptr<sim::MujocoSim> sim_;
  std::unique_ptr<mapping::TerrainMap> map_;
  std::optional<common::GridMap> grid_;
  std::vector<CellTruth> truth_;
  std::vector<WorldObject> objects_;
  mapping::RobotContext last_robot_;

  Evaluation Evaluate() const;
};

// What the map says against the truth.
struct Evaluation {
  int64_t mapped{0};
  int64_t drivable{0};      // mapped cells within the profile's limits, no object near
  int64_t false_lethal{0};  // ... marked lethal
  std::map<std::string, int64_t> false_by_rule;
  std::vector<std::string> false_samples;      // the first few, with their rule
  std::vector<std::string> object_failures;    // objects seen but not lethal
  std::vector<std::string> registry_failures;  // features on smooth ground, objects listed twice
  std::string registry_text;
};

// Why the cost layer made a cell lethal (the rules of ComputeCostLayer, in its order).
std::string LethalRule(const common::GridMap& g, const common::RobotProfile& p, int x, int y) {
  const auto& h = g.at(layers::kElevation);
  const auto& bound = g.at(layers::kGroundBound);
  if (std::isnan(h(x, y))) return "unknown cell (ditch)";
  if (!std::isnan(g.at(layers::kDitchDepth)(x, y))) return "ditch";
  const double max_slope = std::min(p.max_slope_up_rad, p.max_slope_down_rad);
  if (g.at(layers::kSlope)(x, y) >= max_slope) return "slope";
  if (g.at(layers::kRoughness)(x, y) > p.max_roughness_m) return "roughness";
  const int d[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (const auto& o : d) {
    const float hn = h(x + o[0], y + o[1]);
    if (std::isnan(hn)) {
      if (std::isfinite(bound(x + o[0], y + o[1]))) return "unseen drop";
      continue;
    }
    if (hn - h(x, y) > p.max_step_up_m || h(x, y) - hn > p.max_step_down_m) return "step";
  }
  return "other";
}

double Distance2(const common::Vector2& a, const common::Vector2& b) {
  return (a - b).squaredNorm();
}

Evaluation Evaluate(const common::GridMap& g, const std::vector<CellTruth>& truth,
                    const std::vector<WorldObject>& objects_in, const common::RobotProfile& p,
                    const common::ObstacleRegistry& registry) {
  Evaluation e;
  const int sx = g.size_x(), sy = g.size_y();
  const double res = g.resolution_m();
  const auto& cost = g.at(layers::CostLayer(p.name));
  const double max_slope = std::min(p.max_slope_up_rad, p.max_slope_down_rad);
  auto T = [&](int x, int y) -> const CellTruth& {
    return truth[x + static_cast<int64_t>(y) * sx];
  };
  std::vector<WorldObject> objects = objects_in;
  for (int y = 2; y < sy - 2; ++y) {
    for (int x = 2; x < sx - 2; ++x) {
      if (std::isnan(cost(x, y))) continue;
      ++e.mapped;
      const CellTruth& t = T(x, y);
      if (t.object >= 0) objects[t.object].cells.push_back(x + static_cast<int64_t>(y) * sx);
      // Cells within two of an object are not judged: the plane fit of the slope reaches one
      // cell out, and the cell next to a face holds some of its returns.
      bool near_object = false;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) near_object |= T(x + dx, y + dy).object >= 0;
      if (near_object || std::isnan(t.z_m)) continue;
      // The true slope as the map defines it: the plane fitted to the 3 x 3 cells around.
      double gx = 0, gy = 0;
      for (int d = -1; d <= 1; ++d) {
        gx += T(x + 1, y + d).z_m - T(x - 1, y + d).z_m;
        gy += T(x + d, y + 1).z_m - T(x + d, y - 1).z_m;
      }
      gx /= 6 * res;
      gy /= 6 * res;
      const double slope = std::atan(std::hypot(gx, gy));
      double up = 0, down = 0;
      for (const auto& n : {T(x + 1, y), T(x - 1, y), T(x, y + 1), T(x, y - 1)}) {
        up = std::max(up, n.z_m - t.z_m);
        down = std::max(down, t.z_m - n.z_m);
      }
      if (!(slope < max_slope && up <= p.max_step_up_m && down <= p.max_step_down_m)) continue;
      ++e.drivable;
      if (cost(x, y) >= layers::kCostLethal) {
        ++e.false_lethal;
        const std::string rule = LethalRule(g, p, x, y);
        ++e.false_by_rule[rule];
        if (e.false_samples.size() < 15) {
          const common::Vector2 c = g.geometry().CenterOf({x, y});
          char buf[160];
          std::snprintf(buf, sizeof(buf), "(%.1f, %.1f) %s: true slope %.1f deg, map %.1f deg",
                        c.x(), c.y(), rule.c_str(), slope * 180 / kPi,
                        g.at(layers::kSlope)(x, y) * 180 / kPi);
          e.false_samples.push_back(buf);
        }
      }
    }
  }
  // Every object seen is lethal. Seen means with mapped ground
  // beside it: the top of a rock behind a crest, its ground never seen, is a patch of ground
  // floating in the unknown for any map.
  auto ground_beside = [&](const WorldObject& o) {
    for (int64_t i : o.cells) {
      const int x = static_cast<int>(i % sx), y = static_cast<int>(i / sx);
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (T(x + dx, y + dy).object < 0 && !std::isnan(cost(x + dx, y + dy))) return true;
    }
    return false;
  };
  // Lethal: 90 % of the mapped cells of its footprint are lethal or beside a lethal cell (a cell
  // holding a sliver of a wall reads the ground beside it; the robot's footprint never reaches
  // it).
  auto lethal_near = [&](int64_t i) {
    const int x = static_cast<int>(i % sx), y = static_cast<int>(i / sx);
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (cost(x + dx, y + dy) >= layers::kCostLethal) return true;
    return false;
  };
  for (const WorldObject& o : objects) {
    if (o.cells.size() < 2 || !ground_beside(o)) continue;
    int covered = 0;
    for (int64_t i : o.cells) covered += lethal_near(i);
    if (covered < 0.9 * o.cells.size()) {  // slivers at a corner, seen past its edge
      std::ostringstream s;
      s << o.name << ": " << covered << " of " << o.cells.size()
        << " mapped cells lethal or beside a lethal cell";
      e.object_failures.push_back(s.str());
    }
  }
  // The registry: every feature on an object (its outline within 0.5 m of the object's mapped
  // footprint), each object with enough lethal cells listed, and listed once.
  std::vector<int> listed(objects.size(), 0);
  std::ostringstream text;
  for (const auto& ob : registry.obstacles) {
    text << common::ObstacleKindName(ob.kind) << " at (" << ob.centroid_m.x() << ", "
         << ob.centroid_m.y() << ") cells " << ob.num_cells << " height " << ob.height_m
         << " slope " << ob.slope_rad * 180 / kPi << "\n";
    std::set<int> on;
    for (size_t k = 0; k < objects.size(); ++k) {
      for (int64_t i : objects[k].cells) {
        const common::Vector2 c =
            g.geometry().CenterOf({static_cast<int>(i % sx), static_cast<int>(i / sx)});
        bool near = Distance2(c, ob.centroid_m) < 0.5 * 0.5;
        for (const auto& v : ob.outline_m) near |= Distance2(c, v) < 0.5 * 0.5;
        if (near) on.insert(static_cast<int>(k));
      }
    }
    if (on.empty()) {
      std::ostringstream s;
      s << "a " << common::ObstacleKindName(ob.kind) << " on no object at (" << ob.centroid_m.x()
        << ", " << ob.centroid_m.y() << "), " << ob.num_cells << " cells";
      e.registry_failures.push_back(s.str());
    }
    for (int k : on) ++listed[k];
  }
  for (size_t k = 0; k < objects.size(); ++k) {
    int lethal = 0;
    for (int64_t i : objects[k].cells) lethal += cost.data()[i] >= layers::kCostLethal;
    // Unlisted counts only for an object seen as one: its top alone, floating in the unknown,
    // is a patch of steep ground for any map (as for the cost layer above).
    if (listed[k] > 1 || (listed[k] == 0 && lethal >= 4 && ground_beside(objects[k]))) {
      std::ostringstream s;
      s << objects[k].name << " listed " << listed[k] << " times (" << lethal << " lethal cells)";
      e.registry_failures.push_back(s.str());
    }
  }
  e.registry_text = text.str();
  return e;
}

Evaluation OutdoorTerrainTest::Evaluate() const {
  return cairn::testing::Evaluate(*grid_, truth_, objects_, profile_, map_->BuildRegistry());
}

std::string Describe(const Evaluation& e) {
  std::ostringstream s;
  s << e.mapped << " mapped cells, " << e.drivable << " drivable, " << e.false_lethal
    << " of them lethal (" << 100.0 * e.false_lethal / std::max<int64_t>(1, e.mapped)
    << " % of the mapped cells); by rule:";
  for (const auto& [rule, n] : e.false_by_rule) s << " " << rule << " " << n << ";";
  for (const auto& f : e.false_samples) s << "\n  " << f;
  s << "\nobjects not lethal:";
  for (const auto& f : e.object_failures) s << " " << f << ";";
  s << "\nregistry problems:";
  for (const auto& f : e.registry_failures) s << " " << f << ";";
  s << "\nregistry:\n" << e.registry_text;
  return s.str();
}

// The README's demo: from the start towards the default goal (8, -2), past rock_5; the map
// reaches 15-20 m over the hills around.
Evaluation DemoRoute(OutdoorTerrainTest* t) {
  t->DriveAndMap({{0.0, 0.0, std::atan2(-2.0, 8.0), 0.4, 20.0}});
  t->ComputeTruth();
  return t->Evaluate();
}

// Few false lethal cells on drivable ground, and every object seen lethal.
void ExpectCostLayerMatchesTheTruth(const Evaluation& e) {
  SCOPED_TRACE(Describe(e));
  std::printf("%s\n", Describe(e).c_str());
  ASSERT_GT(e.mapped, 10000);
  EXPECT_LT(e.false_lethal, 0.01 * e.mapped);
  EXPECT_TRUE(e.object_failures.empty());
}

TEST_F(OutdoorTerrainTest, TheDemoRoutesCostLayerMatchesTheTruth) {
  ExpectCostLayerMatchesTheTruth(DemoRoute(this));
}

// Northwards towards (3, 9), between the shed and the garden wall (the goal itself stands on
// 8-10 deg ground: lethal for the Pioneer, rightly).
TEST_F(OutdoorTerrainTest, TheRouteNorthCostLayerMatchesTheTruth) {
  DriveAndMap({{0.0, 0.0, std::atan2(9.0, 3.0), 0.4, 22.0}});
  ComputeTruth();
  ExpectCostLayerMatchesTheTruth(Evaluate());
}

// Northwards towards (3, 9), past rock_10 (a small rock seen from 9 m as two cells of its
// face, listed as it stands 12 cm high: obstacles.min_small_feature_height_m) and the shadow
// at the foot of rock_5 (no ditch: a ditch has two walls).
TEST_F(OutdoorTerrainTest, TheRouteNorthsRegistryListsEachObjectOnce) {
  DriveAndMap({{0.0, 0.0, std::atan2(9.0, 3.0), 0.4, 22.0}});
  ComputeTruth();
  const Evaluation e = Evaluate();
  SCOPED_TRACE(Describe(e));
  EXPECT_TRUE(e.registry_failures.empty());
}

// The registry of the same drive lists every object once (the house's walls joined across its
// doorway, each rock with its lower faces) and no feature on smooth ground. A 4-cell, 6 cm
// "step" on the hillside behind the shed at (7.75, 9.25) was the last false one: cells seen
// once, in the first revolution, along the level ring's contour (1.32 m, the lidar's height)
// before any normal existed, kept the heights of where their points lay and stood as a terrace
// against the cells above (TerrainMap::RecommitUnsettled).
TEST_F(OutdoorTerrainTest, TheDemoRoutesRegistryListsEachObjectOnce) {
  const Evaluation e = DemoRoute(this);
  SCOPED_TRACE(Describe(e));
  EXPECT_TRUE(e.registry_failures.empty());
}

// One feature, one entry, in the terraces world (issue 17): driven up lane 0's 5 deg ramp, over
// its platform and off its 8 cm drop, the map's registry lists the ramp, platform and drop as one
// terrace whose parts are the ramp and the 8 cm face (its full drop, not the mixed cells at its
// foot), one-way for the Pioneer 3-AT: eastwards only.
TEST_F(OutdoorTerrainTest, TheTerracesLaneZeroIsOneTerraceOneWayEast) {
  DriveAndMap({{4.0, 2.0, 0.0, 0.4, 28.0}}, "terraces");
  const common::ObstacleRegistry registry = map_->BuildRegistry();
  std::ostringstream listed;
  const common::Obstacle* terrace = nullptr;
  int others = 0;
  for (const auto& o : registry.obstacles) {
    if (o.kind == common::ObstacleKind::kWallOrObject || o.centroid_m.x() < 7.5 ||
        o.centroid_m.x() > 13.5 || o.centroid_m.y() < 0.3 || o.centroid_m.y() > 3.7) {
      continue;
    }
    listed << "\n"
           << common::ObstacleKindName(o.kind) << " at (" << o.centroid_m.x() << ", "
           << o.centroid_m.y() << ") height " << o.height_m << " slope " << o.slope_rad;
    for (const auto& p : o.parts) {
      listed << "\n  " << common::ObstacleKindName(p.kind) << " at (" << p.centroid_m.x() << ", "
             << p.centroid_m.y() << ") height " << p.height_m << " onto heading "
             << p.heading_in_rad * 180 / kPi;
    }
    if (o.kind == common::ObstacleKind::kTerrace && terrace == nullptr) {
      terrace = &o;
    } else {
      ++others;
    }
  }
  SCOPED_TRACE(listed.str());
  ASSERT_NE(terrace, nullptr);
  EXPECT_EQ(others, 0);
  const common::ObstaclePart* face = nullptr;
  const common::ObstaclePart* ramp = nullptr;
  for (const auto& p : terrace->parts) {
    (p.kind == common::ObstacleKind::kRamp ? ramp : face) = &p;
  }
  ASSERT_NE(ramp, nullptr);
  ASSERT_NE(face, nullptr);
  EXPECT_NEAR(face->height_m, 0.08, 0.02);
  const common::ObstacleVerdict* v = terrace->VerdictFor(profile_.name);
  ASSERT_NE(v, nullptr);
  EXPECT_TRUE(common::IsOneWay(*v)) << v->reason;
}

}  // namespace
}  // namespace cairn::testing
