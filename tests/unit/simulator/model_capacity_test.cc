#include "simulator/model_capacity.h"

#include <set>
#include <string>

#include <gtest/gtest.h>

#include "simulator/mjcf_compose.h"
#include "simulator/mujoco_model.h"
#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"
#include "simulator/sensors/lidar_sensor.h"
#include "simulator/sensors/odometry_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::SimTest;
using testing::TestPaths;

// `robots` Pioneer 3-ATs in the tunnel, one per lane, driving along it.
Scenario TunnelFleet(int robots) {
  const SimPaths paths = TestPaths();
  Scenario s;
  s.world = "tunnel";
  s.world_path = paths.WorldPath("tunnel");
  s.seed = 1;
  for (int i = 0; i < robots; ++i) {
    SpawnPose spawn;
    spawn.x_m = 4.0;
    spawn.y_m = 2.0 + 4.0 * i;
    RobotSpec robot = MakeRobotSpec("p" + std::to_string(i), "pioneer3at", "", spawn, paths);
    robot.commands = {{0.0, 100.0, 0.5, 0.0}};
    s.robots.push_back(robot);
  }
  return s;
}

class ModelCapacityTest : public SimTest {};

TEST_F(ModelCapacityTest, EightPioneersInTheTunnelComposeCreateDataAndStep) {
  // Formerly "could not create mjData": 2600 contacts and 15600 rows made MuJoCo 2.2 ask for
  // 15600^2 efc_AR cells and a stack of 5 x 15680^2 numbers.
  MujocoSim sim(TunnelFleet(8));
  const mjModel* m = sim.model();
  ASSERT_NE(sim.data(), nullptr);
  // Sized for what the scene holds: 8 x (4 wheels x 4 partners x 1 contact + a chassis box x
  // 4 partners x 8 contacts), 4 rows each (condim 3, pyramidal).
  EXPECT_EQ(m->nconmax, 8 * (4 * 4 * 1 + 4 * 8));
  EXPECT_EQ(m->njmax, 4 * m->nconmax);
  EXPECT_EQ(m->nstack, MujocoStackHeuristic(m, m->njmax));
  // efc_AR is njmax^2 doubles: under 100 MB now.
  EXPECT_LT(8.0 * m->njmax * m->njmax, 100e6);

  // Every robot drives and every robot's lidar and odometry report.
  SimOutputs out;
  while (sim.time_s() < 2.0) sim.Step(&out);
  std::set<std::string> lidar_robots, odometry_robots;
  for (const auto& slice : out.Readings<LidarSensor>()) lidar_robots.insert(slice.robot);
  for (const auto& odom : out.Readings<OdometrySensor>()) odometry_robots.insert(odom.robot);
  EXPECT_EQ(lidar_robots.size(), 8u);
  EXPECT_EQ(odometry_robots.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    const std::string id = "p" + std::to_string(i);
    EXPECT_GT(sim.RobotPose(id).position_m.x(), 4.2) << id << " did not drive";
  }
  // The contacts of the run fit (the buffers never filled: SimTest checks MuJoCo's warnings).
  EXPECT_LE(sim.data()->maxuse_con, m->nconmax);
  EXPECT_LE(sim.data()->maxuse_efc, m->njmax);
  EXPECT_EQ(sim.stats().unstable_steps, 0);
}

TEST_F(ModelCapacityTest, GrowsLinearlyWithTheRobots) {
  MujocoSim one(TunnelFleet(1));
  MujocoSim two(TunnelFleet(2));
  MujocoSim four(TunnelFleet(4));
  // One robot stays at MuJoCo's defaults (its 48 contacts are below 100), more grow by 48 each.
  EXPECT_EQ(one.model()->nconmax, 100);
  EXPECT_EQ(one.model()->njmax, 500);
  EXPECT_EQ(two.model()->nconmax, 100);
  EXPECT_EQ(four.model()->nconmax, 4 * 48);
  EXPECT_EQ(four.model()->njmax, 4 * 4 * 48);
}

TEST_F(ModelCapacityTest, ComposedTextRecordsTheSizesTheModelWasGiven) {
  MujocoSim sim(TunnelFleet(3));
  const SizeAttributes set = SizeAttributesOf(sim.composed_xml());
  EXPECT_TRUE(set.nconmax && set.njmax && set.nstack);
  // (Its compiler sees the robots at the origin, on top of each other: placeholder warnings.)
  const MjModelPtr again = LoadModelFromText(sim.composed_xml(), TestPaths().WorldPath("tunnel"),
                                             /*placeholder_buffers=*/true);
  EXPECT_EQ(again->nconmax, sim.model()->nconmax);
  EXPECT_EQ(again->njmax, sim.model()->njmax);
  EXPECT_EQ(again->nstack, sim.model()->nstack);
}

TEST_F(ModelCapacityTest, AWorldsOwnSizesAreKept) {
  const std::string world = R"(<mujoco model="sized">
  <size njmax="777" nuserdata="2"/>
  <worldbody><geom name="floor" type="plane" size="10 10 0.1"/></worldbody>
</mujoco>)";
  Scenario s = testing::InlineScenario(world, "a", "pioneer3at");
  MujocoSim sim(s);
  EXPECT_EQ(sim.model()->njmax, 777);
  EXPECT_EQ(sim.model()->nuserdata, 2);
  EXPECT_EQ(sim.model()->nconmax, 100);
  EXPECT_EQ(sim.model()->nstack, MujocoStackHeuristic(sim.model(), 777));
}

TEST(ModelCapacityTextTest, WritesOnlyWhatTheTextDoesNotSet) {
  ModelCapacity sizes;
  sizes.nconmax = 11;
  sizes.njmax = 22;
  sizes.nstack = 33;
  const std::string bare = "<mujoco model=\"m\">\n  <worldbody/>\n</mujoco>";
  const std::string added = WithSizes(bare, sizes, SizeAttributesOf(bare));
  EXPECT_NE(added.find(R"(<size nconmax="11" njmax="22" nstack="33"/>)"), std::string::npos);

  const std::string own =
      "<mujoco>\n  <size  njmax = \"5\" nkey=\"1\"/>\n  <worldbody/>\n</mujoco>";
  const SizeAttributes set = SizeAttributesOf(own);
  EXPECT_FALSE(set.nconmax);
  EXPECT_TRUE(set.njmax);
  EXPECT_FALSE(set.nstack);
  const std::string merged = WithSizes(own, sizes, set);
  EXPECT_NE(merged.find(R"(<size nconmax="11" nstack="33"  njmax = "5" nkey="1"/>)"),
            std::string::npos)
      << merged;
  // Negative values are left to MuJoCo.
  sizes.nstack = -1;
  EXPECT_EQ(WithSizes(bare, sizes, {}).find("nstack"), std::string::npos);
  // <sizes> is not <size>.
  EXPECT_FALSE(SizeAttributesOf("<mujoco><sizes njmax=\"3\"/></mujoco>").any());
}

TEST_F(ModelCapacityTest, HeightFieldContactsFollowTheCellsUnderAWheel) {
  // A 10 x 10 m field of 51 x 51 samples (0.2 m cells) under a sphere of radius 0.1075: its
  // bounding square spans 3 x 3 cells at most, 2 prisms each.
  const std::string world = R"(<mujoco model="field">
  <asset><hfield name="h" nrow="51" ncol="51" size="5 5 0.5 0.1"/></asset>
  <worldbody>
    <geom name="ground" type="hfield" hfield="h"/>
    <body name="ball" pos="0 0 1"><freejoint/><geom type="sphere" size="0.1075"/></body>
  </worldbody>
</mujoco>)";
  const MjModelPtr m = LoadModelFromText(world, "/tmp/field.xml");
  const ModelCapacity c = ContactCapacity(m.get(), kParkedGeomGroup);
  EXPECT_EQ(c.nconmax, 100);  // 18 contacts: MuJoCo's minimum
  EXPECT_EQ(c.njmax, 500);

  // Many balls: 18 contacts and 72 rows each (the field is their only partner).
  std::string many = R"(<mujoco model="field">
  <asset><hfield name="h" nrow="51" ncol="51" size="5 5 0.5 0.1"/></asset>
  <worldbody>
    <geom name="ground" type="hfield" hfield="h"/>)";
  for (int i = 0; i < 20; ++i) {
    many += "<body pos=\"" + std::to_string(i * 0.4 - 4) +
            " 0 1\"><freejoint/><geom type=\"sphere\" size=\"0.1075\" contype=\"1\" "
            "conaffinity=\"2\"/></body>";
  }
  many += "</worldbody></mujoco>";
  const MjModelPtr m20 = LoadModelFromText(many, "/tmp/field.xml");
  const ModelCapacity c20 = ContactCapacity(m20.get(), kParkedGeomGroup);
  EXPECT_EQ(c20.nconmax, 20 * 18);
  EXPECT_EQ(c20.njmax, 20 * 18 * 4);
}

}  // namespace
}  // namespace cairn::sim
