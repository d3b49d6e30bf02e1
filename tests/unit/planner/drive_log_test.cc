#include "planner/drive_log.h"

#include <gtest/gtest.h>

namespace cairn::planner {
namespace {

DwaResult Cycle(double v, double w, bool found, std::vector<int64_t> rejections) {
  DwaResult r;
  r.found = found;
  r.command = {v, w};
  r.samples = 400;
  r.rejections = std::move(rejections);
  r.best_values = {0.25, 1.5};
  return r;
}

TEST(DriveLogTest, TellsWhatTheDrivingDidSinceTheTimerRestarted) {
  DriveLog dut;
  dut.CountTurn();
  dut.Record(Cycle(0.1, 0.2, true, {10, 300}), {4.0, 5.0});
  dut.Record(Cycle(0.3, -0.4, false, {30, 100}), {4.5, 5.0});
  EXPECT_EQ(dut.turning(), 1);
  EXPECT_EQ(dut.dwa_cycles(), 2);
  EXPECT_EQ(dut.invalid_cycles(), 1);
  EXPECT_EQ(dut.rejections(), (std::vector<int64_t>{40, 400}));
  const std::string text =
      dut.Describe(0.05, {"speed", "clearance"}, common::Pose2{1, 2, 0.5}, 3.25);
  EXPECT_EQ(text,
            " (moved 0.05 m; 1 cycles turning toward the path, 2 DWA cycles at a mean 0.20 m/s, "
            "0.30 rad/s, 1 without a valid sample; rejected per cycle: clearance 200.00/400, "
            "speed 20.00/400; last choice (0.30, -0.40) scored speed 0.25, clearance 1.50; at "
            "(1.00, 2.00, 0.50), carrot (4.50, 5.00), 3.25 m of path left)");
  // Without a pose the place is left out; after Clear nothing is left.
  dut.Clear();
  EXPECT_EQ(dut.Describe(0.0, {}, std::nullopt, 0.0),
            " (moved 0.00 m; 0 cycles turning toward the path, 0 DWA cycles)");
}

TEST(DriveLogTest, NamesTheBestForwardSampleWhenTheChoiceWasAnother) {
  DriveLog dut;
  DwaResult r = Cycle(0.0, 0.3, true, {0, 0});
  r.has_best_forward = true;
  r.best_forward = {0.2, 0.0};
  r.best_forward_values = {0.5, 2.5};
  dut.Record(r, {1.0, 1.0});
  const std::string text = dut.Describe(0.0, {"speed", "clearance"}, std::nullopt, 0.0);
  EXPECT_NE(text.find("; best forward (0.20, 0.00) scored speed 0.50, clearance 2.50"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("rejected per cycle"), std::string::npos) << text;
}

}  // namespace
}  // namespace cairn::planner
