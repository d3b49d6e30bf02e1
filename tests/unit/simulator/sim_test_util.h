#pragma once

#include <string>

#include <gtest/gtest.h>

#include "simulator/mujoco_model.h"
#include "simulator/mujoco_sim.h"
#include "simulator/scenario.h"

/// Helpers shared by the simulator unit tests: inline worlds and a fixture that turns MuJoCo
/// warnings into failures.

namespace cairn::sim::testing {

/// The source tree's shipped worlds, robots and profiles.
inline SimPaths TestPaths() { return SimPaths::InTree(CAIRN_SOURCE_DIR); }

/// A 40 x 40 m floor (plane) and nothing else, wrapped around `extra` world-body XML.
inline std::string FlatWorld(const std::string& extra = "") {
  return R"(<mujoco model="flat">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="20 20 0.1" rgba="0.5 0.5 0.5 1"/>
)" + extra +
         R"(
  </worldbody>
</mujoco>)";
}

/// A scenario over inline world text with one robot of `model` at (x, y, yaw).
inline Scenario InlineScenario(const std::string& world_xml, const std::string& robot_id,
                               const std::string& model, double x_m = 0.0, double y_m = 0.0,
                               double yaw_rad = 0.0) {
  Scenario s;
  s.world = "inline";
  s.world_path = "/tmp/inline_world.xml";
  s.world_xml = world_xml;
  s.seed = 7;
  s.spawn_slots = 4;
  if (!robot_id.empty()) {
    SpawnPose spawn;
    spawn.x_m = x_m;
    spawn.y_m = y_m;
    spawn.yaw_rad = yaw_rad;
    s.robots.push_back(MakeRobotSpec(robot_id, model, "", spawn, testing::TestPaths()));
  }
  return s;
}

// Drives `robot` with (v, w) for `duration_s` of sim time, commanding every step.
inline void Drive(MujocoSim& sim, const std::string& robot, double v, double w, double duration_s,
                  SimOutputs* out) {
  const double end = sim.time_s() + duration_s;
  while (sim.time_s() < end) {
    sim.Command(robot, v, w);
    sim.Step(out);
  }
}

/// Fails the test if MuJoCo printed a warning while it ran.
class SimTest : public ::testing::Test {
 protected:
  void SetUp() override {
    InstallMujocoLogHooks();
    warnings_at_start_ = MujocoWarningCount();
  }
  void TearDown() override {
    EXPECT_EQ(MujocoWarningCount(), warnings_at_start_) << "MuJoCo warned during the test";
  }

 private:
  int64_t warnings_at_start_{0};
};

}  // namespace cairn::sim::testing
