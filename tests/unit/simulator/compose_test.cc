#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "simulator/mjcf_compose.h"
#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"
#include "simulator/sensors/lidar_sensor.h"
#include "simulator/sensors/odometry_sensor.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

TEST(ComposeTest, PrefixesNamesAndReferences) {
  const std::string fragment =
      R"(<body name="base"><joint name="j"/><site name="s"/></body>
         <velocity name="j" joint="j"/><gyro site="s"/><framequat objtype="site" objname="s"/>)";
  const std::string out = PrefixNames(fragment, "r1");
  EXPECT_NE(out.find(R"(name="r1/base")"), std::string::npos);
  EXPECT_NE(out.find(R"(joint="r1/j")"), std::string::npos);
  EXPECT_NE(out.find(R"(site="r1/s")"), std::string::npos);
  EXPECT_NE(out.find(R"(objname="r1/s")"), std::string::npos);
  EXPECT_NE(out.find(R"(objtype="site")"), std::string::npos);  // not a name
}

TEST(ComposeTest, ExtractsSectionsAndIgnoresComments) {
  bool found = false;
  EXPECT_EQ(
      ExtractSection("<a><!-- <sensor>x</sensor> --><sensor>y</sensor></a>", "sensor", &found),
      "y");
  EXPECT_TRUE(found);
  ExtractSection("<mujoco><sensorx/></mujoco>", "sensor", &found);
  EXPECT_FALSE(found);
  EXPECT_EQ(StripXmlComments("a<!-- x\ny\n -->b"), "a\n\nb");
}

TEST(ComposeTest, RejectsWorldsWithoutWorldbodyAndBadRobotIds) {
  EXPECT_THROW(ComposeScene("<mujoco></mujoco>", "w.xml", {}, 0), std::invalid_argument);
  EXPECT_THROW(ComposeScene("<robot/>", "w.xml", {}, 0), std::invalid_argument);
  const std::string robot = "<mujoco><worldbody><body name=\"b\"/></worldbody></mujoco>";
  EXPECT_THROW(ComposeScene(FlatWorld(), "w.xml", {{"bad id", robot, "r.xml"}}, 0),
               std::invalid_argument);
  try {
    ComposeScene(FlatWorld(), "w.xml", {{"r", "<mujoco/>", "r.xml"}}, 0);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("r.xml"), std::string::npos);
  }
}

class ComposedWorldTest : public SimTest {};

TEST_F(ComposedWorldTest, RobotsGoIntoAnyWorldEvenWithHostileDefaults) {
  // A world whose defaults would disable collisions, with radians and its own actuator.
  const std::string world = R"(<mujoco model="odd">
  <compiler angle="radian"/>
  <default><geom contype="0" conaffinity="0" rgba="0 1 0 1"/></default>
  <worldbody>
    <geom name="floor" type="plane" size="10 10 0.1" contype="1" conaffinity="1"/>
    <body name="flap" pos="3 0 0.5"><joint name="hinge" type="hinge"/><geom type="box" size="0.1 0.1 0.1"/></body>
  </worldbody>
  <actuator><motor joint="hinge"/></actuator>
</mujoco>)";
  Scenario s = InlineScenario(world, "a", "pioneer3at");
  SpawnPose b;
  b.x_m = -2.0;
  s.robots.push_back(MakeRobotSpec("b", "kobuki", "", b, testing::TestPaths()));
  MujocoSim sim(s);
  SimOutputs out;
  // Both robots rest on the floor (their geoms collide) and can drive.
  for (int i = 0; i < 1000; ++i) {
    sim.Command("a", 0.3, 0.0);
    sim.Command("b", 0.3, 0.0);
    sim.Step(&out);
  }
  EXPECT_NEAR(sim.RobotPose("a").position_m.z(), 0.1075, 0.01);
  EXPECT_NEAR(sim.RobotPose("b").position_m.z(), 0.035, 0.01);
  EXPECT_GT(sim.RobotPose("a").position_m.x(), 0.4);
  EXPECT_GT(sim.RobotPose("b").position_m.x(), -1.6);
  // Names are prefixed per robot.
  EXPECT_GE(mj_name2id(sim.model(), mjOBJ_JOINT, "a/wheel_fl"), 0);
  EXPECT_GE(mj_name2id(sim.model(), mjOBJ_JOINT, "b/wheel_left"), 0);
  EXPECT_GE(mj_name2id(sim.model(), mjOBJ_ACTUATOR, "b/wheel_left"), 0);
}

TEST_F(ComposedWorldTest, BrokenMjcfNamesTheFileAndMujocosMessage) {
  Scenario s = InlineScenario(FlatWorld(R"(<geom type="box" size="1 1"/>)"), "", "");
  s.world_path = "/somewhere/broken_world.xml";
  try {
    MujocoSim sim(s);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/somewhere/broken_world.xml"), std::string::npos) << what;
    EXPECT_NE(what.find("size"), std::string::npos) << what;  // MuJoCo's own words
  }
}

TEST_F(ComposedWorldTest, RelativeAssetsResolveNextToTheWorldFile) {
  // A world including another file by a relative name.
  const std::string dir = std::filesystem::temp_directory_path() / "cairn_sim_compose_test";
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/parts.xml") << R"(<mujoco><worldbody>
    <geom name="included_wall" type="box" size="0.1 2 1" pos="2 0 1"/>
  </worldbody></mujoco>)";
  std::ofstream(dir + "/world.xml") << R"(<mujoco><include file="parts.xml"/><worldbody>
    <geom type="plane" size="5 5 0.1"/></worldbody></mujoco>)";
  Scenario s = InlineScenario("", "", "");
  s.world_xml.clear();
  s.world_path = dir + "/world.xml";
  MujocoSim sim(s);
  EXPECT_GE(mj_name2id(sim.model(), mjOBJ_GEOM, "included_wall"), 0);
}

TEST(ScenarioTest, ShippedScenariosLoad) {
  const SimPaths paths = testing::TestPaths();
  const std::string dir = std::string(CAIRN_SOURCE_DIR) + "/config/sim";
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    Scenario s = LoadScenarioFile(entry.path().string(), paths);
    EXPECT_FALSE(s.robots.empty());
    EXPECT_NO_THROW(s.Validate());
    ++count;
  }
  EXPECT_GE(count, 4);
}

TEST(ScenarioTest, UnknownKeysAndBadValuesNameFileAndLine) {
  const SimPaths paths = testing::TestPaths();
  auto load = [&](const std::string& text) {
    common::YamlMap map = common::YamlMap::FromString(text, "test.yaml");
    return LoadScenario(map, paths);
  };
  auto expect_error = [&](const std::string& text, const std::string& fragment) {
    try {
      load(text);
      ADD_FAILURE() << "no error for:\n" << text;
    } catch (const common::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("test.yaml:"), std::string::npos) << e.what();
    }
  };
  expect_error("world: tunnel\nwheels: 4\n", "unknown key 'wheels'");
  expect_error("world: atlantis\n", "unknown world 'atlantis'");
  expect_error("world: tunnel\nrobots:\n  - {id: a, model: tank}\n", "unknown robot model 'tank'");
  expect_error("world: tunnel\nrobots:\n  - {id: a, model: kobuki, profile: ghost}\n",
               "unknown profile 'ghost'");
  expect_error(
      "world: tunnel\nrobots:\n  - id: a\n    model: kobuki\n    sensors:\n      sonar: {}\n",
      "unknown sensor 'sonar'");
  expect_error(
      "world: tunnel\nrobots:\n  - id: a\n    model: kobuki\n    sensors:\n"
      "      planar_laser: {beams: 1}\n",
      "planar_laser.beams");
  expect_error("world: tunnel\nrobots:\n  - {id: a, model: kobuki}\n  - {id: a, model: p3dx}\n",
               "appears twice");
  expect_error("world: tunnel\nphysics: {integrator: implicitfast}\n", "integrator");
}

TEST(ScenarioTest, SensorOverridesStartFromTheModelDefaults) {
  common::YamlMap map = common::YamlMap::FromString(R"(
world: tunnel
seed: 9
robots:
  - id: p
    model: p3dx
    spawn: {x_m: 1.5, y_m: -2.0, yaw_deg: 90}
    sensors:
      planar_laser: {rate_hz: 20.0}
      hdl32e: {slices_per_revolution: 18}
    commands:
      - {at_s: 1.0, duration_s: 2.0, linear_mps: 0.2}
)",
                                                    "inline.yaml");
  const Scenario s = LoadScenario(map, testing::TestPaths());
  ASSERT_EQ(s.robots.size(), 1u);
  const RobotSpec& r = s.robots[0];
  EXPECT_EQ(s.seed, 9u);
  EXPECT_EQ(r.profile.name, "p3dx");
  EXPECT_NEAR(r.spawn.yaw_rad, M_PI / 2, 1e-12);
  ASSERT_TRUE(r.sensors.Has(PlanarLaserSensor::kName));
  EXPECT_EQ(r.sensors.Find<PlanarLaserSensor>()->rate_hz, 20.0);
  EXPECT_EQ(r.sensors.Find<PlanarLaserSensor>()->fov_deg, 240.0);  // the model's default survives
  EXPECT_EQ(r.sensors.Find<PlanarLaserSensor>()->max_range_m, 5.6);
  ASSERT_TRUE(r.sensors.Has(LidarSensor::kName));  // added though the model has none
  EXPECT_EQ(r.sensors.Find<LidarSensor>()->slices_per_revolution, 18);
  EXPECT_FALSE(r.sensors.Has(OdometrySensor::kName));  // not listed: off
  ASSERT_EQ(r.commands.size(), 1u);
  EXPECT_EQ(r.commands[0].linear_mps, 0.2);
}

TEST(ScenarioTest, RobotFlag) {
  const SimPaths paths = testing::TestPaths();
  const RobotSpec r = ParseRobotFlag("scout:kobuki::2.5,-1,90", paths);
  EXPECT_EQ(r.id, "scout");
  EXPECT_EQ(r.profile.name, "kobuki");
  EXPECT_EQ(r.spawn.x_m, 2.5);
  EXPECT_NEAR(r.spawn.yaw_rad, M_PI / 2, 1e-12);
  EXPECT_EQ(ParseRobotFlag("a:pioneer3at:rover", paths).profile.name, "rover");
  EXPECT_THROW(ParseRobotFlag("a", paths), std::invalid_argument);
  EXPECT_THROW(ParseRobotFlag("a:kobuki::1", paths), std::invalid_argument);
  EXPECT_THROW(ParseRobotFlag("a:kobuki::1,nan", paths), std::invalid_argument);
}

TEST(ScenarioTest, ShippedRobotsLoadAndHelpListsWorlds) {
  const SimPaths paths = testing::TestPaths();
  const auto robots = paths.ShippedRobots();
  EXPECT_EQ(robots, (std::vector<std::string>{"kobuki", "p3dx", "pioneer3at"}));
  for (const std::string& name : robots) {
    const RobotModel m = LoadRobotModel(paths, name);
    EXPECT_FALSE(m.description.empty());
    EXPECT_FALSE(m.default_sensors.Names().empty());
  }
  const auto worlds = paths.ShippedWorlds();
  EXPECT_EQ(worlds, (std::vector<std::string>{"apartment", "arena", "outdoor", "tunnel"}));
  for (const std::string& w : worlds) EXPECT_FALSE(paths.WorldSummary(w).empty()) << w;
}

}  // namespace
}  // namespace cairn::sim
