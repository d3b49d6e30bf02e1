#include <cmath>

#include <gtest/gtest.h>

#include "simulator/mujoco_sim.h"
#include "simulator/sensors/lidar_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

// Number of lidar points of the last full revolution in a box of the sensor frame.
size_t PointsIn(const SimOutputs& out, double x0, double x1, double y0, double y1, double z0) {
  size_t n = 0;
  const int64_t rev = out.Readings<LidarSensor>().back().revolution - 1;
  for (common::LidarSlice slice : out.Readings<LidarSensor>()) {
    if (slice.revolution != rev) continue;
    common::ExpandRangeImage(&slice);  // the HDL-32E makes range images
    for (const auto& p : slice.points) {
      if (p.x_m > x0 && p.x_m < x1 && p.y_m > y0 && p.y_m < y1 && p.z_m > z0) ++n;
    }
  }
  return n;
}

class ObjectsTest : public SimTest {};

TEST_F(ObjectsTest, SpawnedObjectsAreSeenCollideAndGoAway) {
  Scenario s = InlineScenario(FlatWorld(), "r", "pioneer3at");
  s.robots[0].sensors.Find<LidarSensor>()->range_noise_sigma_m = 0.0;
  MujocoSim sim(s);
  SimOutputs out;
  auto run = [&](double seconds) {
    out.Clear();
    const double end = sim.time_s() + seconds;
    while (sim.time_s() < end) sim.Step(&out);
  };
  run(0.25);
  // Nothing above the floor 2 m ahead of the sensor (x 0.12 on the base).
  EXPECT_EQ(PointsIn(out, 1.5, 2.5, -0.5, 0.5, -0.3), 0u);

  ObjectSpec box;
  box.name = "crate";
  box.size_m = {0.25, 0.4, 0.3};
  box.position_m = {2.37, 0.0, 0.3};
  ASSERT_TRUE(sim.SpawnObject(box).ok());
  run(0.25);
  // Its face at x = 2.12 m, 2.0 m ahead of the sensor.
  EXPECT_GT(PointsIn(out, 1.95, 2.05, -0.4, 0.4, -0.3), 50u);
  EXPECT_EQ(sim.SpawnObject(box).code(), common::StatusCode::kAlreadyExists);

  ASSERT_TRUE(sim.MoveObject("crate", {4.37, 0.0, 0.3}, 0.0).ok());
  run(0.25);
  EXPECT_EQ(PointsIn(out, 1.95, 2.05, -0.4, 0.4, -0.3), 0u);
  EXPECT_GT(PointsIn(out, 3.95, 4.05, -0.4, 0.4, -0.3), 20u);

  // The robot cannot drive through it.
  for (int i = 0; i < 5000; ++i) {
    sim.Command("r", 0.5, 0.0);
    sim.Step(&out);
  }
  out.Clear();
  EXPECT_LT(sim.RobotPose("r").position_m.x(), 4.12 - 0.2);

  ASSERT_TRUE(sim.RemoveObject("crate").ok());
  run(0.25);
  EXPECT_EQ(PointsIn(out, 0.0, 3.0, -0.4, 0.4, -0.3), 0u);
  EXPECT_EQ(sim.RemoveObject("crate").code(), common::StatusCode::kNotFound);
  EXPECT_EQ(sim.MoveObject("crate", {0, 0, 0}, 0).code(), common::StatusCode::kNotFound);
}

TEST_F(ObjectsTest, PoolLimitsShapesAndBadRequests) {
  Scenario s = InlineScenario(FlatWorld(), "", "");
  s.spawn_slots = 3;
  MujocoSim sim(s);
  ObjectSpec o;
  o.position_m = {1, 1, 0.5};
  o.name = "a";
  o.shape = ObjectShape::kCylinder;
  o.size_m = {0.2, 0.5, 0};
  EXPECT_TRUE(sim.SpawnObject(o).ok());
  o.name = "b";
  o.shape = ObjectShape::kSphere;
  o.size_m = {0.3, 0, 0};
  EXPECT_TRUE(sim.SpawnObject(o).ok());
  o.name = "c";
  o.shape = ObjectShape::kBox;
  o.size_m = {0.1, 0.1, 0.1};
  EXPECT_TRUE(sim.SpawnObject(o).ok());
  o.name = "d";
  EXPECT_EQ(sim.SpawnObject(o).code(), common::StatusCode::kResourceExhausted);
  ASSERT_TRUE(sim.RemoveObject("b").ok());
  EXPECT_TRUE(sim.SpawnObject(o).ok());  // the slot is free again
  o.name = "e";
  o.size_m = {std::nan(""), 0.1, 0.1};
  ASSERT_TRUE(sim.RemoveObject("d").ok());
  EXPECT_EQ(sim.SpawnObject(o).code(), common::StatusCode::kInvalidArgument);
  o.size_m = {0.1, 0.1, 0.1};
  o.position_m = {0, std::numeric_limits<double>::infinity(), 0};
  EXPECT_EQ(sim.SpawnObject(o).code(), common::StatusCode::kInvalidArgument);
  o.name = "";
  EXPECT_EQ(sim.SpawnObject(o).code(), common::StatusCode::kInvalidArgument);
  EXPECT_EQ(sim.ObjectNames(), (std::vector<std::string>{"a", "c"}));
  // A sphere's geom really is a sphere of that radius.
  const int g = mj_name2id(sim.model(), mjOBJ_GEOM, "cairn_spawn_0");
  EXPECT_EQ(sim.model()->geom_type[g], mjGEOM_CYLINDER);
}

TEST_F(ObjectsTest, DoorsStartOpenAndCloseOnRequest) {
  const std::string door = R"(
    <body name="leaf" pos="2 0 0">
      <joint name="door_front" type="hinge" axis="0 0 1" limited="true" range="0 90" damping="15"/>
      <geom type="box" size="0.45 0.02 1" pos="0.45 0 1.01" mass="15"/>
    </body>)";
  std::string world = FlatWorld(door);
  world.insert(world.rfind("</mujoco>"),
               R"(<actuator><position name="door_front" joint="door_front" kp="60"/></actuator>)");
  Scenario s = InlineScenario(world, "", "");
  MujocoSim sim(s);
  EXPECT_EQ(sim.DoorNames(), (std::vector<std::string>{"front"}));
  const int j = mj_name2id(sim.model(), mjOBJ_JOINT, "door_front");
  const double* q = sim.data()->qpos + sim.model()->jnt_qposadr[j];
  EXPECT_NEAR(*q, M_PI / 2, 1e-9);  // open at start
  ASSERT_TRUE(sim.SetDoor("front", false).ok());
  SimOutputs out;
  while (sim.time_s() < 4.0) sim.Step(&out);
  EXPECT_NEAR(*q, 0.0, 0.05);
  ASSERT_TRUE(sim.SetDoor("door_front", true).ok());
  while (sim.time_s() < 8.0) sim.Step(&out);
  EXPECT_NEAR(*q, M_PI / 2, 0.05);
  EXPECT_EQ(sim.SetDoor("back", true).code(), common::StatusCode::kNotFound);
  EXPECT_EQ(sim.ListNames(), (std::vector<std::string>{"door:front"}));
}

TEST_F(ObjectsTest, WorldMocapBodiesAreMovableObjects) {
  Scenario s = InlineScenario(
      FlatWorld(
          R"(<body name="sofa" mocap="true" pos="3 0 0"><geom type="box" size="1 0.4 0.4" pos="0 0 0.4"/></body>)"),
      "r", "p3dx");
  MujocoSim sim(s);
  EXPECT_EQ(sim.ObjectNames(), (std::vector<std::string>{"sofa"}));
  ASSERT_TRUE(sim.MoveObject("sofa", {5, 1, 0}, 0.5).ok());
  const int b = mj_name2id(sim.model(), mjOBJ_BODY, "sofa");
  EXPECT_NEAR(sim.data()->xpos[3 * b], 5.0, 1e-9);
  ASSERT_TRUE(sim.RemoveObject("sofa").ok());
  EXPECT_TRUE(sim.ObjectNames().empty());
  EXPECT_EQ(sim.ListNames(), (std::vector<std::string>{"robot:r"}));
}

}  // namespace
}  // namespace cairn::sim
