#include "services/explore/turret_scan.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "scan_test_scenes.h"
#include <Eigen/Geometry>

namespace cairn::explore {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Small scans: 10 deg pan steps over 180 deg (18 lines), 7 beams 45 deg apart from -135 deg.
TurretScanParams Params() {
  TurretScanParams p;
  p.pan_step_rad = 10 * kDeg;
  p.pan_range_rad = 180 * kDeg;
  p.tilt_step_rad = 45 * kDeg;
  p.timeout_s = 30.0;
  return p;
}

// The turret's scanning plane at `pan_rad` (the simulator's convention: the line's x axis is
// the turret's up axis, its y axis the horizontal pan direction) at `position`.
common::LaserScan Line(double pan_rad, const Eigen::Vector3d& position = {2.0, 3.0, 1.0},
                       float range_m = 2.0f, int beams = 7) {
  const Eigen::Matrix3d r = scan_testing::TurretLineFrame(pan_rad);
  common::LaserScan line;
  line.sensor_pose.position_m = position;
  line.sensor_pose.orientation = common::Quaternion(r);
  line.angle_min_rad = -135 * kDeg;
  line.angle_increment_rad = 45 * kDeg;
  line.range_min_m = 0.05;
  line.range_max_m = 50.0;
  line.ranges_m.assign(beams, range_m);
  return line;
}

std::optional<OrderedScan> Sweep(TurretScanAssembler* a, int from_step, int to_step, double t0,
                                 const Eigen::Vector3d& position = {2.0, 3.0, 1.0}) {
  std::optional<OrderedScan> out;
  for (int k = from_step; k < to_step; ++k) {
    out = a->Add(Line(k * 10 * kDeg, position), k * 10 * kDeg, t0 + 0.02 * k);
    if (out) return out;
  }
  return out;
}

TEST(TurretScanTest, AFullSweepFromPanZeroBecomesAnOrderedScan) {
  TurretScanAssembler a(Params());
  EXPECT_FALSE(a.Add(Line(0.0), 0.0, 0.0)) << "nothing before a request";
  a.Request(1.0);
  // Lines before the next pan-0 line are skipped.
  EXPECT_FALSE(Sweep(&a, 12, 18, 1.0));
  EXPECT_EQ(a.state(), TurretScanAssembler::State::kWaitingForStart);
  const std::optional<OrderedScan> scan = Sweep(&a, 0, 18, 2.0);
  ASSERT_TRUE(scan);
  EXPECT_EQ(a.state(), TurretScanAssembler::State::kDone);
  EXPECT_EQ(scan->num_lines, 18);
  EXPECT_EQ(scan->beams_per_line, 7);
  EXPECT_NO_THROW(scan->Validate());
  EXPECT_FLOAT_EQ(scan->robot_base_z_m, 0.0f);  // scanner 1 m above the ground
  EXPECT_TRUE(scan->sensor_origin_m.isApprox(Eigen::Vector3f(2, 3, 1)));
  // Beam 3 (angle 0) points up in every line; beam 5 (+90 deg) horizontally along the pan.
  const Eigen::Vector3f up = scan->points_m[4 * 7 + 3];
  EXPECT_TRUE(up.isApprox(Eigen::Vector3f(2, 3, 3), 1e-5)) << up.transpose();
  const Eigen::Vector3f side = scan->points_m[9 * 7 + 5];  // pan 90 deg: along +y
  EXPECT_TRUE(side.isApprox(Eigen::Vector3f(2, 5, 1), 1e-5)) << side.transpose();
}

TEST(TurretScanTest, MoreMissingLinesThanAllowedStartTheSweepOverAndSaySo) {
  TurretScanAssembler a(Params());  // at most 3 missing lines in a row
  a.Request(0.0);
  EXPECT_FALSE(Sweep(&a, 0, 5, 0.0));
  std::string event;
  EXPECT_FALSE(a.Add(Line(9 * 10 * kDeg), 9 * 10 * kDeg, 0.2, &event));
  EXPECT_NE(event.find("line 5 missing"), std::string::npos) << event;
  EXPECT_EQ(a.restarts(), 1);
  EXPECT_TRUE(Sweep(&a, 0, 18, 1.0));
  // A line going back starts over too.
  a.Request(2.0);
  EXPECT_FALSE(Sweep(&a, 0, 5, 2.0));
  event.clear();
  EXPECT_FALSE(a.Add(Line(3 * 10 * kDeg), 3 * 10 * kDeg, 2.2, &event));
  EXPECT_NE(event.find("line 5 missing (got 3)"), std::string::npos) << event;
}

TEST(TurretScanTest, AFewLinesLostOnTheBusLeaveLinesWithNoReturn) {
  TurretScanAssembler a(Params());
  a.Request(0.0);
  EXPECT_FALSE(Sweep(&a, 0, 5, 0.0));
  std::string event;
  EXPECT_FALSE(a.Add(Line(7 * 10 * kDeg), 7 * 10 * kDeg, 0.2, &event));  // 5 and 6 lost
  EXPECT_TRUE(event.empty()) << event;
  EXPECT_EQ(a.missing_lines(), 2);
  const std::optional<OrderedScan> scan = Sweep(&a, 8, 18, 0.3);
  ASSERT_TRUE(scan.has_value());
  EXPECT_EQ(a.restarts(), 0);
  EXPECT_EQ(scan->num_lines, 18);
  for (int line : {5, 6}) {
    for (int b = 0; b < 7; ++b) EXPECT_FALSE(scan->points_m[line * 7 + b].allFinite());
  }
  EXPECT_TRUE(scan->points_m[7 * 7 + 3].allFinite());
}

TEST(TurretScanTest, TheRobotMustStandStill) {
  TurretScanAssembler a(Params());
  a.Request(0.0);
  EXPECT_FALSE(Sweep(&a, 0, 6, 0.0));
  std::string event;
  EXPECT_FALSE(a.Add(Line(6 * 10 * kDeg, {2.2, 3.0, 1.0}), 6 * 10 * kDeg, 0.2, &event));
  EXPECT_NE(event.find("moved"), std::string::npos) << event;
  EXPECT_EQ(a.state(), TurretScanAssembler::State::kWaitingForStart);
}

TEST(TurretScanTest, OversizedOrMismatchedLinesAreRefusedWithoutGrowing) {
  TurretScanParams p = Params();
  p.max_beams = 16;
  TurretScanAssembler a(p);
  a.Request(0.0);
  // A line claiming a million beams is dropped before anything is allocated for it.
  common::LaserScan huge = Line(0.0);
  huge.ranges_m.assign(1'000'000, 2.0f);
  EXPECT_FALSE(a.Add(huge, 0.0, 0.0));
  EXPECT_EQ(a.state(), TurretScanAssembler::State::kWaitingForStart);
  EXPECT_FALSE(Sweep(&a, 0, 3, 0.0));
  std::string event;
  EXPECT_FALSE(a.Add(Line(30 * kDeg, {2.0, 3.0, 1.0}, 2.0f, 9), 30 * kDeg, 0.1, &event));
  EXPECT_NE(event.find("beam layout"), std::string::npos) << event;
  EXPECT_FALSE(a.Add(Line(NAN), NAN, 0.2));
}

TEST(TurretScanTest, ARequestThatIsNeverServedTimesOut) {
  TurretScanAssembler a(Params());
  a.Request(0.0);
  std::string event;
  EXPECT_FALSE(a.CheckTimeout(29.0, &event));
  EXPECT_TRUE(a.CheckTimeout(31.0, &event));
  EXPECT_NE(event.find("timed out"), std::string::npos) << event;
  EXPECT_EQ(a.state(), TurretScanAssembler::State::kTimedOut);
  EXPECT_FALSE(a.CheckTimeout(40.0));
  TurretScanParams bad = Params();
  bad.pan_step_rad = 0.0;
  EXPECT_THROW(TurretScanAssembler{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace cairn::explore
