#include "simulator/mjcf_compose.h"

#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"
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

}  // namespace
}  // namespace cairn::sim
