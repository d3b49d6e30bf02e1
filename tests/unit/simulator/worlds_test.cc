// The shipped worlds: they load with robots, and their geometry matches what README.md and
// tunnel_lanes.yaml promise (the contract the mapper, navigator and demo tests rely on).

#include <cmath>
#include <string>
#include <tuple>
#include <utility>

#include <gtest/gtest.h>

#include "common/yaml_reader.h"
#include "simulator/mujoco_sim.h"
#include "simulator/places.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::SimTest;

// Height of the surface below (x, y) as the sensors see it, and the geom there.
double SurfaceZ(const MujocoSim& sim, double x, double y, int* geom = nullptr) {
  static const mjtByte kGroups[mjNGROUP] = {1, 1, 1, 0, 0, 0};
  const double p[3] = {x, y, 20.0}, v[3] = {0, 0, -1};
  int g = -1;
  const double d = mj_ray(sim.model(), sim.data(), p, v, kGroups, 1, -1, &g);
  if (geom) *geom = g;
  return d >= 0 ? 20.0 - d : -1e9;
}

Scenario WorldOnly(const std::string& world) {
  const SimPaths paths = testing::TestPaths();
  Scenario s;
  s.world = world;
  s.world_path = paths.WorldPath(world);
  return s;
}

class WorldsTest : public SimTest {};

TEST_F(WorldsTest, EveryShippedWorldHostsEveryRobot) {
  const SimPaths paths = testing::TestPaths();
  for (const std::string& world : paths.ShippedWorlds()) {
    Scenario s = WorldOnly(world);
    SpawnPose at;
    // Free floor in each world (the apartment's living room, the arena's hall, the west side of
    // the room and of the hall; the start areas of outdoor, simple and structured at the origin,
    // unstructured's in its top-right corner: its origin is the canyon's floor by a rim's wall).
    const bool lanes = world == "tunnel" || world == "terraces";
    const bool room = world == "room" || world == "hall";
    const bool corner = world == "unstructured";
    at.x_m = lanes                  ? 4.0
             : world == "apartment" ? 1.5
             : world == "arena"     ? 5.0
             : room                 ? 1.0
             : corner               ? 13.5
                                    : 0.0;
    at.y_m = lanes                  ? 6.0
             : world == "apartment" ? 2.5
             : world == "arena"     ? 4.0
             : room                 ? 2.0
             : corner               ? 15.0
                                    : 0.0;
    int k = 0;
    for (const std::string& model : paths.ShippedRobots()) {
      SpawnPose p = at;
      p.x_m += 1.0 * k++;
      s.robots.push_back(MakeRobotSpec(model + "_1", model, "", p, paths));
    }
    SCOPED_TRACE(world);
    MujocoSim sim(s);
    SimOutputs out;
    while (sim.time_s() < 0.5) sim.Step(&out);
    for (const std::string& id : sim.robot_ids()) {
      // Resting on the floor, upright.
      EXPECT_LT(sim.RobotVelocity(id).norm(), 0.05) << id;
      EXPECT_GT(sim.RobotPose(id).orientation.toRotationMatrix()(2, 2), 0.98) << id;
    }
  }
}

TEST_F(WorldsTest, TunnelLanesMatchTheirContract) {
  Scenario s = WorldOnly("tunnel");
  MujocoSim sim(s);
  common::YamlMap doc =
      common::YamlMap::LoadFile(testing::TestPaths().data_dir + "/worlds/tunnel_lanes.yaml");
  YAML::Node lanes = doc.Raw("lanes");
  ASSERT_EQ(lanes.size(), 10u);
  for (const auto& lane : lanes) {
    const std::string name = lane["name"].as<std::string>();
    SCOPED_TRACE(name);
    const double sx = lane["start"]["x_m"].as<double>(), sy = lane["start"]["y_m"].as<double>();
    const double gx = lane["goal"]["x_m"].as<double>(), gy = lane["goal"]["y_m"].as<double>();
    EXPECT_NEAR(SurfaceZ(sim, sx, sy), 0.0, 1e-9);  // starts on the floor
    EXPECT_NEAR(SurfaceZ(sim, gx, gy), lane["goal_z_m"].as<double>(), 1e-3);
    // Lanes are 4 m apart with walls between them.
    const int k = lane["lane"].as<int>();
    EXPECT_NEAR(sy, 4.0 * k + 2.0, 1e-9);
    EXPECT_GT(SurfaceZ(sim, 12.0, 4.0 * k), 1.4);        // wall on the south side
    EXPECT_GT(SurfaceZ(sim, 12.0, 4.0 * k + 4.0), 1.4);  // and on the north side
  }
  // Feature heights along the lanes (x, y) -> z.
  const double tan5 = std::tan(5.0 * M_PI / 180.0), tan10 = std::tan(10.0 * M_PI / 180.0);
  EXPECT_NEAR(SurfaceZ(sim, 9.5, 2.0), 1.0, 1e-9);           // cube top
  EXPECT_NEAR(SurfaceZ(sim, 9.0, 6.0), 1.0 * tan5, 1e-5);    // 5 deg ramp
  EXPECT_NEAR(SurfaceZ(sim, 9.0, 10.0), 1.0 * tan10, 1e-5);  // 10 deg ramp
  EXPECT_NEAR(SurfaceZ(sim, 10.8, 14.0), 2.0 * tan5 + 0.8 * std::tan(11.0 * M_PI / 180.0), 1e-5);
  EXPECT_NEAR(SurfaceZ(sim, 12.0, 18.0), 0.01, 1e-9);  // 1 cm step
  EXPECT_NEAR(SurfaceZ(sim, 12.0, 22.0), 0.20, 1e-9);  // 20 cm step
  EXPECT_NEAR(SurfaceZ(sim, 12.0, 26.0), 0.20, 1e-9);  // drop platform
  EXPECT_NEAR(SurfaceZ(sim, 14.0, 26.0), 0.0, 1e-9);   // past the drop
  EXPECT_NEAR(SurfaceZ(sim, 10.3, 30.0), -0.3, 1e-9);  // trench bottom
  EXPECT_NEAR(SurfaceZ(sim, 9.9, 30.0), 0.0, 1e-9);    // trench rim
  EXPECT_NEAR(SurfaceZ(sim, 7.5, 33.0), 0.2, 1e-9);    // combined: 20 cm block
  EXPECT_NEAR(SurfaceZ(sim, 7.5, 35.0), 0.0, 1e-9);    // ... and its bypass
  EXPECT_NEAR(SurfaceZ(sim, 8.0, 37.0), 1.0, 1e-9);    // demo cube
  EXPECT_NEAR(SurfaceZ(sim, 20.0, 38.0), 0.21, 1e-9);  // demo platform
  // The 10 deg platform is enclosed: lane walls on both sides reach the end wall.
  EXPECT_GT(SurfaceZ(sim, 23.0, 8.0), 1.4);
  EXPECT_GT(SurfaceZ(sim, 23.0, 12.0), 1.4);
  EXPECT_GT(SurfaceZ(sim, 24.05, 10.0), 1.4);
}

TEST_F(WorldsTest, TerracesLanesMatchTheirContract) {
  Scenario s = WorldOnly("terraces");
  MujocoSim sim(s);
  common::YamlMap doc =
      common::YamlMap::LoadFile(testing::TestPaths().data_dir + "/worlds/terraces_lanes.yaml");
  YAML::Node lanes = doc.Raw("lanes");
  ASSERT_EQ(lanes.size(), 5u);
  for (const auto& lane : lanes) {
    SCOPED_TRACE(lane["name"].as<std::string>());
    const double sx = lane["start"]["x_m"].as<double>(), sy = lane["start"]["y_m"].as<double>();
    const double gx = lane["goal"]["x_m"].as<double>(), gy = lane["goal"]["y_m"].as<double>();
    EXPECT_NEAR(SurfaceZ(sim, sx, sy), 0.0, 1e-9);  // start and goal on the floor
    EXPECT_NEAR(SurfaceZ(sim, gx, gy), 0.0, 1e-9);
    const int k = lane["lane"].as<int>();
    EXPECT_NEAR(sy, 4.0 * k + 2.0, 1e-9);
    EXPECT_GT(SurfaceZ(sim, 12.0, 4.0 * k), 1.4);  // walls on both sides
    EXPECT_GT(SurfaceZ(sim, 12.0, 4.0 * k + 4.0), 1.4);
  }
  const double tan5 = std::tan(5.0 * M_PI / 180.0);
  // Lane 0: a 5 deg ramp to an 8 cm platform that ends in a drop at x = 12.
  EXPECT_NEAR(SurfaceZ(sim, 8.5, 2.0), 0.5 * tan5, 1e-5);
  EXPECT_NEAR(SurfaceZ(sim, 11.9, 2.0), 0.08, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 12.1, 2.0), 0.0, 1e-9);
  // Lane 1: the same with 12 cm.
  EXPECT_NEAR(SurfaceZ(sim, 11.9, 6.0), 0.12, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 12.1, 6.0), 0.0, 1e-9);
  // Lanes 2 and 3: ditches 0.25 m wide and 8 cm deep, 0.6 m wide and 0.25 m deep.
  EXPECT_NEAR(SurfaceZ(sim, 10.1, 10.0), -0.08, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 10.2, 10.0), -0.08, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 9.95, 10.0), 0.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 10.3, 10.0), 0.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 10.3, 14.0), -0.25, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 10.65, 14.0), 0.0, 1e-9);
  // Lane 4: the drop on the south half, a 5 deg ramp down on the north half.
  EXPECT_NEAR(SurfaceZ(sim, 12.1, 17.0), 0.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 12.5, 19.0), 0.08 - 0.5 * tan5, 1e-5);
}

TEST_F(WorldsTest, ApartmentRoomsDoorsAndPlaces) {
  Scenario s = WorldOnly("apartment");
  MujocoSim sim(s);
  EXPECT_EQ(sim.DoorNames(),
            (std::vector<std::string>{"living_room", "kitchen", "bedroom", "bathroom"}));
  for (const char* furniture : {"sofa", "kitchen_table", "chair_1", "chair_2", "glass", "shelf"}) {
    const auto names = sim.ObjectNames();
    EXPECT_NE(std::find(names.begin(), names.end(), furniture), names.end()) << furniture;
  }
  const std::vector<Place> places =
      LoadPlacesFile(testing::TestPaths().data_dir + "/worlds/apartment_places.yaml");
  std::vector<std::string> names;
  for (const Place& p : places) names.push_back(p.name);
  EXPECT_EQ(names, (std::vector<std::string>{"living_room", "kitchen", "corridor", "bedroom",
                                             "bathroom"}));
  for (const Place& p : places) {
    SCOPED_TRACE(p.name);
    ASSERT_GE(p.polygon_m.size(), 3u);
    // The centre of each room is floor inside it.
    common::Vector2 c = common::Vector2::Zero();
    for (const auto& v : p.polygon_m) c += v;
    c /= static_cast<double>(p.polygon_m.size());
    EXPECT_TRUE(p.Contains(c));
    int geom = -1;
    const double z = SurfaceZ(sim, c.x(), c.y(), &geom);
    EXPECT_LT(z, 1.0);  // not a wall
  }
  EXPECT_EQ(PlaceAt(places, {7.0, 1.0}), "kitchen");
  EXPECT_EQ(PlaceAt(places, {1.0, 8.0}), "bedroom");
  EXPECT_EQ(PlaceAt(places, {50.0, 50.0}), "");
}

TEST_F(WorldsTest, ApartmentDoorsStayFullyOpen) {
  // Regression: each leaf touched the end of the wall it is hung on, and the contact pushed
  // every door back to about 30 degrees, too narrow for a Kobuki (generate_worlds.py now
  // excludes leaf-wall contacts).
  MujocoSim sim(WorldOnly("apartment"));
  SimOutputs out;
  while (sim.time_s() < 2.0) sim.Step(&out);
  for (const std::string& door : sim.DoorNames()) {
    const int j = mj_name2id(sim.model(), mjOBJ_JOINT, ("door_" + door).c_str());
    ASSERT_GE(j, 0) << door;
    const double angle_deg = sim.data()->qpos[sim.model()->jnt_qposadr[j]] * 180.0 / M_PI;
    EXPECT_NEAR(std::fabs(angle_deg), 100.0, 5.0) << door;
  }
}

TEST_F(WorldsTest, OutdoorTerrainIsTheGeneratedHeightField) {
  Scenario s = WorldOnly("outdoor");
  MujocoSim sim(s);
  const int terrain = mj_name2id(sim.model(), mjOBJ_GEOM, "terrain");
  ASSERT_GE(terrain, 0);
  // Heights the generator computes for these points (generate_worlds.py, relative to the
  // lowest point): the flat start, two hill tops, the east slope; rows run along +y.
  EXPECT_NEAR(SurfaceZ(sim, 0.0, 0.0), 0.156, 0.005);
  EXPECT_NEAR(SurfaceZ(sim, 12.0, 15.0), 2.230, 0.005);
  EXPECT_NEAR(SurfaceZ(sim, -20.0, 15.0), 0.902, 0.005);
  EXPECT_NEAR(SurfaceZ(sim, 20.0, -12.0), 1.011, 0.005);
  EXPECT_NEAR(SurfaceZ(sim, 26.0, 0.0), 0.892, 0.005);
  // Our height-field rays agree with MuJoCo's on the real terrain.
  for (double x = -25.0; x <= 25.0; x += 2.5) {
    for (double y = -25.0; y <= 25.0; y += 2.5) {
      const double p[3] = {x, y, 30.0}, v[3] = {0.1, -0.05, -1.0 / std::sqrt(1.0125)};
      const double ours = RayHeightField(sim.model(), sim.data(), terrain, p, v);
      const double theirs = mj_rayHfield(sim.model(), sim.data(), terrain, p, v);
      ASSERT_NEAR(ours, theirs, 1e-9) << x << ", " << y;
    }
  }
}

// Height of the terrain geom alone below (x, y) (not what stands on it).
double TerrainZ(const MujocoSim& sim, int terrain, double x, double y) {
  const double p[3] = {x, y, 20.0}, v[3] = {0, 0, -1};
  return 20.0 - mj_rayHfield(sim.model(), sim.data(), terrain, p, v);
}

// Bottom and top of a geom's world-aligned extent (boxes and cylinders standing upright).
std::pair<double, double> GeomZRange(const MujocoSim& sim, const char* name) {
  const int g = mj_name2id(sim.model(), mjOBJ_GEOM, name);
  EXPECT_GE(g, 0) << name;
  if (g < 0) return {0.0, 0.0};
  const double z = sim.data()->geom_xpos[3 * g + 2];
  const double half =
      sim.model()->geom_size[3 * g + (sim.model()->geom_type[g] == mjGEOM_BOX ? 2 : 1)];
  return {z - half, z + half};
}

TEST_F(WorldsTest, SimpleHillHouseAndTree) {
  MujocoSim sim(WorldOnly("simple"));
  const int terrain = mj_name2id(sim.model(), mjOBJ_GEOM, "terrain");
  ASSERT_GE(terrain, 0);
  // The start on the flat crest of the ridge (generate_worlds.py: 1.299 above the lowest point).
  EXPECT_NEAR(SurfaceZ(sim, 0.0, 0.0), 1.299, 0.005);
  for (double a = 0.0; a < 2 * M_PI; a += M_PI / 8) {
    EXPECT_NEAR(SurfaceZ(sim, 2.0 * std::cos(a), 2.0 * std::sin(a)), 1.299, 0.05) << a;
  }
  // The house: a solid box x 2..10, y 2..8 with a 25 deg gable roof, ridge along x at y = 5.
  const double wall_top = 4.1336, tan25 = std::tan(25.0 * M_PI / 180.0);
  EXPECT_NEAR(SurfaceZ(sim, 6.0, 5.0), wall_top + 3.0 * tan25, 0.01);
  EXPECT_NEAR(SurfaceZ(sim, 3.0, 3.0), wall_top + 1.0 * tan25, 0.01);
  EXPECT_NEAR(SurfaceZ(sim, 9.0, 7.5), wall_top + 0.5 * tan25, 0.01);
  EXPECT_LT(SurfaceZ(sim, 1.9, 5.0), 1.4);  // ground just west of the west wall
  EXPECT_LT(SurfaceZ(sim, 6.0, 8.1), 1.4);  // and north of the north wall (no eaves)
  {  // solid: a level ray at mid-height from the west stops at the wall
    static const mjtByte kGroups[mjNGROUP] = {1, 1, 1, 0, 0, 0};
    const double p[3] = {-1.0, 5.0, 2.5}, v[3] = {1, 0, 0};
    int g = -1;
    EXPECT_NEAR(mj_ray(sim.model(), sim.data(), p, v, kGroups, 1, -1, &g), 3.0, 1e-6);
    EXPECT_EQ(g, mj_name2id(sim.model(), mjOBJ_GEOM, "house"));
  }
  // The tree at (-6, -4): crown top 1.5 m above a 2.5 m trunk, less the overlap.
  EXPECT_NEAR(SurfaceZ(sim, -6.0, -4.0), 6.2419, 0.005);
  // House and trunk stand on the terrain: their bottoms are a little below it at every corner.
  const auto house = GeomZRange(sim, "house");
  const auto trunk = GeomZRange(sim, "tree_trunk");
  for (double x : {2.0, 10.0}) {
    for (double y : {2.0, 8.0}) {
      EXPECT_LT(house.first, TerrainZ(sim, terrain, x, y) - 0.1) << x << ", " << y;
      EXPECT_GT(house.first, TerrainZ(sim, terrain, x, y) - 0.6) << x << ", " << y;
    }
  }
  for (double dx : {-0.25, 0.25}) {
    for (double dy : {-0.25, 0.25}) {
      const double ground = TerrainZ(sim, terrain, -6.0 + dx, -4.0 + dy);
      EXPECT_LT(trunk.first, ground - 0.1);
      EXPECT_NEAR(trunk.second, ground + 2.5, 0.1);
    }
  }
  // Anywhere the robot may drive in the work area (x -12..14, y -10..12, outside the house and
  // the tree) the terrain is at most about 8 deg steep.
  const double max_rise = 0.25 * std::tan(8.5 * M_PI / 180.0);
  for (double x = -12.0; x < 14.0; x += 0.25) {
    for (double y = -10.0; y < 12.0; y += 0.25) {
      const double z = TerrainZ(sim, terrain, x, y);
      ASSERT_NEAR(TerrainZ(sim, terrain, x + 0.25, y), z, max_rise) << x << ", " << y;
      ASSERT_NEAR(TerrainZ(sim, terrain, x, y + 0.25), z, max_rise) << x << ", " << y;
    }
  }
}

TEST_F(WorldsTest, StructuredBlockStreetsKerbsCarsAndPassage) {
  MujocoSim sim(WorldOnly("structured"));
  // Free street around the start (nothing within 3.5 m of the origin).
  for (double r : {0.0, 1.0, 2.0, 3.0}) {
    for (double a = 0.0; a < 2 * M_PI; a += M_PI / 8) {
      EXPECT_NEAR(SurfaceZ(sim, r * std::cos(a), r * std::sin(a)), 0.0, 1e-9) << r << " " << a;
    }
  }
  // Buildings: their roofs.
  EXPECT_NEAR(SurfaceZ(sim, -15.75, 9.0), 6.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 1.5, 9.5), 8.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 12.5, 8.5), 5.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, -15.75, -9.5), 4.5, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 1.0, -9.0), 7.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 16.5, -9.0), 6.0, 1e-9);
  // The passage: 2.5 m of ground between building_n (to x 5.5) and building_ne (from x 8).
  for (double x = 5.55; x < 8.0; x += 0.1) EXPECT_NEAR(SurfaceZ(sim, x, 8.0), 0.0, 1e-9) << x;
  EXPECT_NEAR(SurfaceZ(sim, 5.45, 8.0), 8.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 8.05, 8.0), 5.0, 1e-9);
  // Kerbs 0.12 m high along the street edges, with gaps (in front of the passage: x 5..8.5).
  EXPECT_NEAR(SurfaceZ(sim, -2.0, 3.65), 0.12, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 1.5, 3.65), 0.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 6.75, 3.65), 0.0, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 3.0, -3.65), 0.12, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, 9.0, -3.65), 0.0, 1e-9);   // the south-east street's mouth
  EXPECT_NEAR(SurfaceZ(sim, -11.15, 0.0), 0.0, 1e-9);  // the west street crosses
  EXPECT_NEAR(SurfaceZ(sim, -11.15, 6.0), 0.12, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, -11.15, 9.0), 0.0, 1e-9);
  // A parked car: 0.9 m body, 1.4 m cabin.
  EXPECT_NEAR(SurfaceZ(sim, -14.2, 2.4), 1.4, 1e-9);
  EXPECT_NEAR(SurfaceZ(sim, -15.9, 2.4), 0.9, 1e-9);
}

// The rover drives from the start of the exploration worlds: forward along +x, a turn, back.
TEST_F(WorldsTest, RoverDrivesFromTheStartOfSimpleAndStructured) {
  for (const char* world : {"simple", "structured"}) {
    SCOPED_TRACE(world);
    Scenario s = WorldOnly(world);
    SpawnPose at;
    s.robots.push_back(MakeRobotSpec("rover", "rover", "", at, testing::TestPaths()));
    s.robots[0].sensors = SensorSet{};
    MujocoSim sim(s);
    SimOutputs out;
    const double z0 = sim.RobotPose("rover").position_m.z();
    EXPECT_NEAR(z0, SurfaceZ(sim, 0.0, 0.0) + 0.2, 0.03);  // on its 0.2 m wheels
    testing::Drive(sim, "rover", 0.5, 0.0, 10.0, &out);
    const common::Pose3 p = sim.RobotPose("rover");
    EXPECT_GT(p.position_m.x(), 3.0);
    EXPECT_NEAR(p.position_m.y(), 0.0, 0.5);
    EXPECT_NEAR(p.position_m.z(), SurfaceZ(sim, p.position_m.x(), p.position_m.y()) + 0.2, 0.1);
    EXPECT_GT(p.orientation.toRotationMatrix()(2, 2), 0.98);
    testing::Drive(sim, "rover", 0.3, 0.5, 8.0, &out);
    testing::Drive(sim, "rover", 0.5, 0.0, 6.0, &out);
    EXPECT_GT(sim.RobotPose("rover").orientation.toRotationMatrix()(2, 2), 0.98);
    EXPECT_GT((sim.RobotPose("rover").position_m - p.position_m).norm(), 2.0);
  }
}

// The unstructured world's canyon, bridge and basin (simulator/worlds/README.md), and the rover
// driving under the deck along the canyon's floor and over it between the rims.
TEST_F(WorldsTest, UnstructuredCanyonBridgeAndBasinAreDrivenOverAndUnder) {
  MujocoSim sim(WorldOnly("unstructured"));
  int geom = -1;
  EXPECT_NEAR(SurfaceZ(sim, -2.0, 7.5, &geom), 2.2, 1e-6);  // the deck's top
  EXPECT_STREQ(mj_id2name(sim.model(), mjOBJ_GEOM, geom), "bridge_deck");
  EXPECT_NEAR(SurfaceZ(sim, -2.0, 3.0), 0.0, 1e-6);    // the canyon's floor
  EXPECT_NEAR(SurfaceZ(sim, -2.0, 12.0), 0.0, 1e-6);   // north of the bridge
  EXPECT_NEAR(SurfaceZ(sim, -10.0, 13.0), 0.0, 1e-6);  // the basin
  EXPECT_NEAR(SurfaceZ(sim, -2.0, -17.0), 2.2, 0.2);   // the ramp's top, at the rims' level
  EXPECT_NEAR(SurfaceZ(sim, -2.0, 6.1), 3.4, 1e-6);    // a parapet
  // The walls, 1.3 m above the highest ground under them (waves of 0.15 m).
  EXPECT_NEAR(SurfaceZ(sim, 1.15, -5.0), 3.5, 0.35);   // the east rim's
  EXPECT_NEAR(SurfaceZ(sim, -5.15, -5.0), 3.5, 0.35);  // the west rim's
  EXPECT_NEAR(SurfaceZ(sim, -10.0, 9.35), 3.5, 0.35);  // the basin's south one
  for (const auto& [name, x, y, yaw, v, seconds] :
       {std::tuple<const char*, double, double, double, double, double>{"under", -2.0, 2.0,
                                                                        M_PI / 2, 0.5, 18.0},
        {"over", 3.5, 7.5, M_PI, 0.5, 24.0}}) {
    SCOPED_TRACE(name);
    Scenario s = WorldOnly("unstructured");
    SpawnPose at;
    at.x_m = x;
    at.y_m = y;
    at.yaw_rad = yaw;
    s.robots.push_back(MakeRobotSpec("rover", "rover", "", at, testing::TestPaths()));
    s.robots[0].sensors = SensorSet{};
    MujocoSim drive(s);
    SimOutputs out;
    testing::Drive(drive, "rover", v, 0.0, seconds, &out);
    const common::Pose3 p = drive.RobotPose("rover");
    EXPECT_GT(p.orientation.toRotationMatrix()(2, 2), 0.98);
    if (std::string(name) == "under") {
      // Along the floor, under the deck (y 6..9), out north of it.
      EXPECT_GT(p.position_m.y(), 10.0);
      EXPECT_LT(p.position_m.y(), 13.5);
      EXPECT_NEAR(p.position_m.z(), 0.2, 0.1);
    } else {
      // Along the deck, between its parapets, to the west rim.
      EXPECT_LT(p.position_m.x(), -5.5);
      EXPECT_NEAR(p.position_m.z(), 2.2 + 0.2, 0.1);
    }
  }
}

TEST_F(WorldsTest, ArenaHasRoomsAndClutter) {
  Scenario s = WorldOnly("arena");
  MujocoSim sim(s);
  EXPECT_NEAR(SurfaceZ(sim, 6.0, 3.0), 0.0, 1e-9);   // open hall
  EXPECT_NEAR(SurfaceZ(sim, 6.0, 6.07), 1.0, 1e-9);  // the wall between hall and rooms
  EXPECT_NEAR(SurfaceZ(sim, 3.0, 6.07), 0.0, 1e-9);  // its doorway
  EXPECT_NEAR(SurfaceZ(sim, 9.5, 8.5), 0.76, 1e-9);  // the table
  EXPECT_NEAR(SurfaceZ(sim, 1.5, 2.5), 0.4, 1e-9);   // a ball (r 0.2 m)
  EXPECT_NEAR(SurfaceZ(sim, 3.7, 0.7), 0.45, 1e-9);  // the armchair seat
}

}  // namespace
}  // namespace cairn::sim
