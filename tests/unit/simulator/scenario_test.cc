#include "simulator/scenario.h"

#include <cmath>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "simulator/sensors/lidar_sensor.h"
#include "simulator/sensors/odometry_sensor.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

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
      "world: tunnel\nrobots:\n  - id: a\n    model: kobuki\n    sensors:\n      sidescan: {}\n",
      "unknown sensor 'sidescan'");
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
  EXPECT_EQ(robots, (std::vector<std::string>{"kobuki", "p3dx", "pioneer3at", "rover", "sparus2"}));
  for (const std::string& name : robots) {
    const RobotModel m = LoadRobotModel(paths, name);
    EXPECT_FALSE(m.description.empty());
    EXPECT_FALSE(m.default_sensors.Names().empty());
  }
  const auto worlds = paths.ShippedWorlds();
  EXPECT_EQ(worlds, (std::vector<std::string>{"apartment", "arena", "breakwater", "cave", "floor",
                                              "hall", "outdoor", "rocks", "room", "simple",
                                              "structured", "terraces", "tunnel", "unstructured"}));
  for (const std::string& w : worlds) EXPECT_FALSE(paths.WorldSummary(w).empty()) << w;
}

TEST(ScenarioTest, FlagScenariosAndTheFoldersArePassedIn) {
  const SimPaths paths = SimPaths::InTree("/srv/cairn");
  EXPECT_EQ(paths.data_dir, "/srv/cairn/simulator");
  EXPECT_EQ(paths.config_dir, "/srv/cairn/config");
  EXPECT_THROW(paths.WorldPath("tunnel"), std::invalid_argument);  // nothing shipped there
  const Scenario s = MakeScenario("tunnel", {"a:kobuki", "b:p3dx::2,0,90"}, testing::TestPaths());
  EXPECT_EQ(s.world, "tunnel");
  ASSERT_EQ(s.robots.size(), 2u);
  EXPECT_EQ(s.robots[1].spawn.x_m, 2.0);
  EXPECT_NO_THROW(s.Validate());
  EXPECT_THROW(MakeScenario("atlantis", {}, testing::TestPaths()), std::invalid_argument);
}

TEST(ScenarioTest, PhysicsParams) {
  common::YamlMap map =
      common::YamlMap::FromString("timestep_s: 0.001\nintegrator: rk4\n", "physics.yaml");
  const PhysicsParams p = LoadPhysicsParams(map);
  EXPECT_EQ(p.timestep_s, 0.001);
  EXPECT_EQ(p.integrator, "rk4");
  common::YamlMap unknown = common::YamlMap::FromString("step_s: 0.001\n", "physics.yaml");
  EXPECT_THROW(LoadPhysicsParams(unknown), common::ConfigError);
  PhysicsParams bad;
  bad.integrator = "verlet";
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::sim
