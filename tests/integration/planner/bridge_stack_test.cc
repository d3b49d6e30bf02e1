// The bridge closed loop: cairn-sim in seed 002's unstructured world with the rover (the
// simulator's 1.1 m body with its lidar), cairn-mapper and cairn-navigator under cairn-launch.
// The deck (x -6.5..2.5, y 6..9, its top level with the rims, 1.9 m clear above the canyon
// floor, 1.2 m parapets) is driven over from the east rim, and under along the canyon floor:
// under a deck higher than the robot plus a margin the floor stays navigable, and on the deck
// the canyon 2.2 m below is no obstacle.
// The geometry: simulator/worlds/generate_worlds.py, unstructured().

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/integration/planner/navigator_stack_fixture.h"

namespace cairn::planner {
namespace {

using namespace testing_stack;  // NOLINT: the fixture and its helpers

// The stretch of the canyon the deck spans, inside its parapets and walls.
constexpr double kUnderX0 = -3.5, kUnderX1 = -0.5, kUnderY0 = 6.5, kUnderY1 = 8.5;

class BridgeStackTest : public NavigatorStackTest {
 protected:
  BridgeStackTest() : NavigatorStackTest("unstructured") {
    UseBody("rover");
    UseProfile("rover", "rover", {});
  }

  // Drives from (x, y, yaw) to the goal and returns the ground-truth poses, empty on failure.
  std::vector<cairn::lcmt_pose> Drive(double x, double y, double yaw_deg, double goal_x,
                                      double goal_y) {
    StartStack(x, y, yaw_deg);
    if (HasFatalFailure()) return {};
    EXPECT_TRUE(WaitFor([&] { return CostVersion() >= 3; }, 30.0, [&] { bus_.Pump(20); }));
    SendGoal(25, goal_x, goal_y);
    EXPECT_TRUE(WaitState(kStateReached, 120.0)) << StatusText();
    if (HasFailure()) return {};
    auto poses = Poses();
    EXPECT_FALSE(poses.empty());
    if (poses.empty()) return {};
    const auto& last = poses.back();
    EXPECT_LT(std::hypot(last.position_m[0] - goal_x, last.position_m[1] - goal_y), 0.6);
    return poses;
  }

  static bool UnderTheDeck(const cairn::lcmt_pose& p) {
    return p.position_m[0] > kUnderX0 && p.position_m[0] < kUnderX1 && p.position_m[1] > kUnderY0 &&
           p.position_m[1] < kUnderY1;
  }
};

// From the canyon floor south of the bridge to its north end, under the deck: the deck 1.9 m
// above is not an obstacle in the rover's cost layer, and the robot stays on the floor.
TEST_F(BridgeStackTest, DrivesUnderTheDeckAlongTheCanyonFloor) {
  const auto poses = Drive(-2.0, 1.0, 90.0, -2.0, 12.0);
  ASSERT_FALSE(poses.empty());
  const double floor_z = poses.front().position_m[2];
  int under = 0;
  for (const auto& p : poses) {
    if (!UnderTheDeck(p)) continue;
    ++under;
    ASSERT_NEAR(p.position_m[2], floor_z, 0.15)
        << "left the canyon floor under the deck at y " << p.position_m[1];
  }
  EXPECT_GT(under, 0) << "never passed under the deck";
}

// From the east rim across the deck to the west rim: the robot crosses at the deck's height,
// never touches a parapet, and the canyon under the deck does not stop it.
TEST_F(BridgeStackTest, DrivesOverTheDeckBetweenTheParapets) {
  const auto poses = Drive(4.0, 7.5, 180.0, -8.0, 7.5);
  ASSERT_FALSE(poses.empty());
  const double rim_z = poses.front().position_m[2];
  const auto parapet_south = Box(-5.5, 6.0, 1.5, 6.2);
  const auto parapet_north = Box(-5.5, 8.8, 1.5, 9.0);
  int over = 0;
  for (const auto& p : poses) {
    ASSERT_GT(p.position_m[2], rim_z - 0.3)
        << "fell below the deck at x " << p.position_m[0] << ", y " << p.position_m[1];
    const auto footprint = FootprintAt(ToPose2(p));
    ASSERT_FALSE(ConvexOverlap(footprint, parapet_south, 0.0))
        << "touched the south parapet at x " << p.position_m[0];
    ASSERT_FALSE(ConvexOverlap(footprint, parapet_north, 0.0))
        << "touched the north parapet at x " << p.position_m[0];
    if (UnderTheDeck(p)) ++over;  // over the canyon, on the deck
  }
  EXPECT_GT(over, 0) << "never crossed the canyon";
}

}  // namespace
}  // namespace cairn::planner
