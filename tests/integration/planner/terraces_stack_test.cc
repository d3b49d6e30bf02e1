// Directed terrain closed loop: cairn-sim in the terraces world (one Pioneer 3-AT: step up 3 cm,
// step down 10 cm, ditches up to 0.10 m), cairn-mapper and cairn-navigator under cairn-launch.
// Lanes, starts and goals: simulator/worlds/terraces_lanes.yaml. The verdicts depend on the
// direction of travel: an 8 cm drop may be driven down, never up.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/integration/planner/navigator_stack_fixture.h"

namespace cairn::planner {
namespace {

using namespace testing_stack;  // NOLINT: the fixture and its helpers

class TerracesStackTest : public NavigatorStackTest {
 protected:
  TerracesStackTest() : NavigatorStackTest("terraces") {}

  // The footprint never touched the lane walls at y = 4k and 4k + 4 (0.2 m thick).
  void ExpectClearOfTheWalls(int lane) {
    const double y0 = 4.0 * lane, y1 = y0 + 4.0;
    for (const auto& p : Poses()) {
      const auto fp = FootprintAt(ToPose2(p));
      ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, y0 - 0.1, 24.0, y0 + 0.1), 0.0))
          << "touched the south wall at x " << p.position_m[0];
      ASSERT_FALSE(ConvexOverlap(fp, Box(3.0, y1 - 0.1, 24.0, y1 + 0.1), 0.0))
          << "touched the north wall at x " << p.position_m[0];
    }
  }

  // Lane 2: the 0.25 m ditch that stops the pioneer3at; the rover bridges 0.30 m. On 0.1 m
  // cells: at the shipped 0.2 m no cell of a 0.25 m slot holds its bottom alone.
  void DriveTheRoverOverTheNarrowDitch() {
    UseTerrainResolution(0.1);
    UseBody("rover");
    UseProfile("rover", "rover", {});
    StartStack(4.0, 10.0, 0.0, HorizonNavigatorConfig());
    ASSERT_TRUE(WaitFor([&] { return CostVersion() >= 5; }, 30.0, [&] { bus_.Pump(20); }));
    SendGoal(18, 15.0, 10.0);
    ASSERT_TRUE(WaitState(kStateReached, 150.0)) << StatusText();
    const auto poses = Poses();  // a copy: a reference into the temporary would dangle
    ASSERT_FALSE(poses.empty());
    const auto& last = poses.back();
    EXPECT_LT(std::hypot(last.position_m[0] - 15.0, last.position_m[1] - 10.0), 0.5);
    ExpectClearOfTheWalls(2);
  }

  // The mapper's registry names the ditch across `lane` at x in [x0, x1] as one ditch, its
  // width within a cell (0.1 m) and its depth within 2 cm of the world's.
  void ExpectDitchInTheRegistry(int lane, double x0, double x1, double depth_m) {
    const double y0 = 4.0 * lane, y1 = y0 + 4.0;
    std::optional<cairn::lcmt_obstacle> ditch;
    int ditches = 0;
    const bool found = WaitFor(
        [&] {
          const auto r =
              bus_.Last<cairn::lcmt_obstacle_registry>(ch::ForRobot(kRobot, ch::kMapObstacles));
          if (!r) return false;
          ditches = 0;
          for (const auto& o : r->obstacles) {
            if (o.kind != cairn::lcmt_obstacle::KIND_DITCH ||
                !testing::CentroidIn(o, x0 - 0.5, x1 + 0.5, y0, y1)) {
              continue;
            }
            ++ditches;
            ditch = o;
          }
          return ditches == 1 && std::abs(ditch->width_m - (x1 - x0)) <= 0.1 &&
                 std::abs(ditch->depth_m - depth_m) <= 0.02;
        },
        20.0, [&] { bus_.Pump(20); });
    ASSERT_EQ(ditches, 1) << StatusText();
    EXPECT_TRUE(found) << StatusText();
    EXPECT_NEAR(ditch->width_m, x1 - x0, 0.1);
    EXPECT_NEAR(ditch->depth_m, depth_m, 0.02);
  }

  // The registry lists the ramp, platform and far end of `lane` (x 7.5..13.5) as one entry, a
  // terrace with a ramp among its parts, and nothing else there but the lane walls. Returns it.
  std::optional<cairn::lcmt_obstacle> TerraceInTheRegistry(int lane) {
    const double y0 = 4.0 * lane, y1 = y0 + 4.0;
    std::optional<cairn::lcmt_obstacle> terrace;
    std::string listed;
    WaitFor(
        [&] {
          const auto r =
              bus_.Last<cairn::lcmt_obstacle_registry>(ch::ForRobot(kRobot, ch::kMapObstacles));
          if (!r) return false;
          terrace.reset();
          int others = 0;
          listed.clear();
          for (const auto& o : r->obstacles) {
            if (o.kind == cairn::lcmt_obstacle::KIND_WALL_OR_OBJECT ||
                !testing::CentroidIn(o, 7.5, 13.5, y0 + 0.3, y1 - 0.3)) {
              continue;
            }
            listed += " " + std::to_string(o.id) + ":kind" + std::to_string(o.kind) + "@(" +
                      std::to_string(o.centroid_m[0]) + "," + std::to_string(o.centroid_m[1]) + ")";
            if (o.kind == cairn::lcmt_obstacle::KIND_TERRACE && !terrace) {
              terrace = o;
            } else {
              ++others;
            }
          }
          if (!terrace || others > 0) return false;
          for (const auto& p : terrace->parts) {
            if (p.kind == cairn::lcmt_obstacle::KIND_RAMP) return true;
          }
          return false;
        },
        20.0, [&] { bus_.Pump(20); });
    EXPECT_TRUE(terrace.has_value()) << "listed in lane " << lane << ":" << listed;
    return terrace;
  }
};

// A terrace and its parts, one line each, for failure messages.
std::string DescribeTerrace(const cairn::lcmt_obstacle& t, const std::string& profile) {
  std::ostringstream out;
  auto verdict = [&](const std::vector<cairn::lcmt_obstacle_verdict>& vs) {
    for (const auto& v : vs) {
      if (v.profile == profile) return (v.crossable ? std::string("crossable") : v.reason);
    }
    return std::string("?");
  };
  out << "terrace " << t.id << " at (" << t.centroid_m[0] << ", " << t.centroid_m[1]
      << "): " << verdict(t.verdicts);
  for (const auto& p : t.parts) {
    out << "\n  part kind " << int(p.kind) << " at (" << p.centroid_m[0] << ", " << p.centroid_m[1]
        << ") height " << p.height_m << " m slope " << p.slope_rad << " rad, " << p.num_cells
        << " cells, onto heading " << p.heading_in_rad * 180 / M_PI
        << " deg: " << verdict(p.verdicts);
  }
  return out.str();
}

// The heading in a one-way verdict's "crossable heading H deg only", or NaN.
double OneWayHeadingDeg(const std::string& reason) {
  const std::string key = "crossable heading ";
  const size_t at = reason.find(key);
  return at == std::string::npos ? std::nan("") : std::atof(reason.c_str() + at + key.size());
}

// From the platform the floor below the drop lies in the edge's lidar shadow: the rim reads as an
// unseen drop, and the navigator (map.look_at_unseen_drops) plans over it to look. The floor
// cell at the face's foot stays unknown; with no ray below the floor there it is judged as the
// 8 cm step down from the rim to the floor beyond (planner/README.md, "Unseen drops").
TEST_F(TerracesStackTest, DrivesUpTheRampAndOffTheEightCentimetreDrop) {
  // Lane 0: a 5 deg ramp up to an 8 cm platform that ends in an 8 cm drop at x = 12, wall to
  // wall. Down the drop is the only way to the goal, and 8 cm is within the 10 cm step down.
  // The 12 m horizon keeps the robot from looking for another way through the unexplored lanes.
  StartStack(4.0, 2.0, 0.0, HorizonNavigatorConfig());
  ASSERT_TRUE(WaitFor([&] { return CostVersion() >= 5; }, 30.0, [&] { bus_.Pump(20); }));
  SendGoal(11, 15.0, 2.0);
  ASSERT_TRUE(WaitState(kStateReached, 150.0)) << StatusText();
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  const double start_z = poses.front().position_m[2];
  double top_z = start_z;
  for (const auto& p : poses) top_z = std::max(top_z, p.position_m[2]);
  EXPECT_GT(top_z - start_z, 0.06) << "it never drove over the platform";
  const auto& last = poses.back();
  EXPECT_LT(std::hypot(last.position_m[0] - 15.0, last.position_m[1] - 2.0), 0.5);
  EXPECT_NEAR(last.position_m[2] - start_z, 0.0, 0.02) << "not back on the floor";
  ExpectClearOfTheWalls(0);
  // One feature, one entry: the ramp, the platform and the drop are one terrace, and its verdict
  // is what the robot just did: crossable eastwards only, up the ramp and off the drop.
  const auto terrace = TerraceInTheRegistry(0);
  ASSERT_TRUE(terrace.has_value());
  const auto* v = testing::Verdict(*terrace, profile_);
  ASSERT_NE(v, nullptr);
  EXPECT_FALSE(v->crossable) << DescribeTerrace(*terrace, profile_);
  EXPECT_NE(v->reason.find("; one-way: "), std::string::npos)
      << DescribeTerrace(*terrace, profile_);
  const double heading = OneWayHeadingDeg(v->reason);
  EXPECT_LE(std::min(heading, 360.0 - heading), 20.0) << DescribeTerrace(*terrace, profile_);
}

TEST_F(TerracesStackTest, NeverClimbsTheEightCentimetreDropFromBelow) {
  // Lane 0 the other way: from the floor past the drop back to the start. Climbing 8 cm exceeds
  // the 3 cm step up, and the lane walls leave no other way: no path, and the footprint never
  // reaches the platform (x 8.9..12).
  ExpectNoPathNeverEntering(15.0, 2.0, 12, 4.0, Box(8.9, 0.1, 12.0, 3.9), 110.0, true, 180.0);
}

TEST_F(TerracesStackTest, NeverDrivesOffTheTwelveCentimetreDrop) {
  // Lane 1: the same terrace with a 12 cm drop (over the 10 cm step down). The robot may climb
  // the ramp to look, but never crosses the edge at x = 12.
  ExpectNoPathNeverEntering(4.0, 6.0, 13, 15.0, Box(12.0, 4.1, 24.0, 7.9), 150.0, false);
}

TEST_F(TerracesStackTest, NeverClimbsTheTwelveCentimetreDropFromBelow) {
  ExpectNoPathNeverEntering(15.0, 6.0, 14, 4.0, Box(9.4, 4.1, 12.0, 7.9), 110.0, true, 180.0);
}

TEST_F(TerracesStackTest, ClimbsTheRampBesideTheOneWayDropInsteadOfTheDrop) {
  // Lane 4 from the far end: at x = 12 the platform drops 8 cm on the south half (y < 18) and
  // falls along a 5 deg ramp on the north half. The robot must go round to the ramp.
  StartStack(15.0, 18.0, 180.0, HorizonNavigatorConfig());
  ASSERT_TRUE(WaitFor([&] { return CostVersion() >= 5; }, 30.0, [&] { bus_.Pump(20); }));
  SendGoal(15, 4.0, 18.0);
  ASSERT_TRUE(WaitState(kStateReached, 150.0)) << StatusText();
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  const auto& last = poses.back();
  EXPECT_LT(std::hypot(last.position_m[0] - 4.0, last.position_m[1] - 18.0), 0.5);
  // The drop's face: the footprint never straddled it.
  const auto face = Box(11.95, 16.1, 12.05, 17.95);
  for (const auto& p : poses) {
    ASSERT_FALSE(ConvexOverlap(FootprintAt(ToPose2(p)), face, 0.0))
        << "climbed the drop at x " << p.position_m[0] << ", y " << p.position_m[1];
  }
  ExpectClearOfTheWalls(4);
  // One entry for the whole: crossable (over its two ramps), its drop one-way.
  const auto terrace = TerraceInTheRegistry(4);
  ASSERT_TRUE(terrace.has_value());
  const auto* v = testing::Verdict(*terrace, profile_);
  ASSERT_NE(v, nullptr);
  EXPECT_TRUE(v->crossable) << DescribeTerrace(*terrace, profile_);
  int ramps = 0;
  for (const auto& p : terrace->parts) ramps += p.kind == cairn::lcmt_obstacle::KIND_RAMP;
  EXPECT_EQ(ramps, 2) << DescribeTerrace(*terrace, profile_);
}

TEST_F(TerracesStackTest, NeverEntersADitchWiderThanItsProfileAllows) {
  // Lane 3: a 0.6 m wide, 0.25 m deep ditch at x 10.0..10.6, wall to wall; the rover's profile
  // bridges 0.30 m (it crosses the 0.25 m ditch of lane 2, below).
  UseBody("rover");
  UseProfile("rover", "rover", {});
  ExpectNoPathNeverEntering(4.0, 14.0, 16, 15.0, Box(10.0, 12.1, 10.6, 15.9), 110.0, true);
}

// The rover's lidar (0.62 m up) sees the trench's bottom from 0.9..1.3 m short of its near rim,
// on the way to a goal 0.8 m short of it. The registry lists it once, 0.6 m wide and 0.25 m deep
// (the seen-floor ditch of obstacles.seen_ditch_max_width_m). With the Pioneer 3-AT's lidar
// (0.33 m up) the bottom is never seen from outside the trench.
TEST_F(TerracesStackTest, TheRegistryNamesTheWideDitchWithItsWidthAndDepth) {
  UseBody("rover");
  UseProfile("rover", "rover", {});
  StartStack(4.0, 14.0, 0.0, HorizonNavigatorConfig());
  ASSERT_TRUE(WaitFor([&] { return CostVersion() >= 5; }, 30.0, [&] { bus_.Pump(20); }));
  SendGoal(19, 9.2, 14.0);
  ASSERT_TRUE(WaitState(kStateReached, 120.0)) << StatusText();
  ExpectDitchInTheRegistry(3, 10.0, 10.6, 0.25);
}

// The simulated Pioneer 3-AT's chassis clears the floor by 7.5 cm, so it cannot mount the 8 cm
// face whatever its profile allows: this runs the rover's body (0.15 m clearance, lidar on a
// 0.62 m mast, which from the floor sees over the platform onto the ramp behind it) with the
// rover's profile allowed 12 cm steps up. The floor cell at the face's foot mixes face and floor
// returns and stays unknown; the rover bridges one cell (0.30 m ditches), so the crossing is the
// step from the floor to the platform beyond it.
TEST_F(TerracesStackTest, AProfileThatStepsUpTwelveCentimetresClimbsTheEightCentimetreDrop) {
  // Lane 0 from the floor past the drop: the drop is now the way back.
  UseBody("rover");
  UseProfile("climber", "rover", {{"max_step_up_m", "0.12"}});
  StartStack(15.0, 2.0, 180.0, HorizonNavigatorConfig());
  ASSERT_TRUE(WaitFor([&] { return CostVersion() >= 5; }, 30.0, [&] { bus_.Pump(20); }));
  SendGoal(17, 4.0, 2.0);
  ASSERT_TRUE(WaitState(kStateReached, 150.0)) << StatusText();
  const auto poses = Poses();
  ASSERT_FALSE(poses.empty());
  const double start_z = poses.front().position_m[2];
  double top_z = start_z;
  for (const auto& p : poses) top_z = std::max(top_z, p.position_m[2]);
  EXPECT_GT(top_z - start_z, 0.06) << "it never climbed onto the platform";
  const auto& last = poses.back();
  EXPECT_LT(std::hypot(last.position_m[0] - 4.0, last.position_m[1] - 2.0), 0.5);
  ExpectClearOfTheWalls(0);
}

TEST_F(TerracesStackTest, TheRoverBridgesADitchNarrowerThanItsProfileAllows) {
  DriveTheRoverOverTheNarrowDitch();
}

// After the rover drove over it, the registry lists the narrow ditch once with its width and
// depth. The slot is sized for the sensor: its bottom shows only to rays steeper than
// atan(depth / width), and the lidar's lowest ring is 30.67 deg down, so a 0.15 m wide, 0.1 m
// deep slot never shows it. This one (0.25 m, 8 cm) shows it to the rings below 17.7 deg, and
// on 0.1 m cells one cell (x 10.1..10.2) holds bottom returns alone; on the shipped 0.2 m cells
// none does (the bottom cell mixes rim and bottom returns and the gap reads 0.4 m wide).
TEST_F(TerracesStackTest, TheRegistryNamesTheNarrowDitchOnceWithItsWidthAndDepth) {
  DriveTheRoverOverTheNarrowDitch();
  ExpectDitchInTheRegistry(2, 10.0, 10.25, 0.08);
}

}  // namespace
}  // namespace cairn::planner
