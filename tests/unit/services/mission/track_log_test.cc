// Planned against driven X(t), Y(t): a row per period of sim time, the plan's nearest point,
// and the CSV as written.

#include "services/mission/track_log.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

namespace cairn::mission {
namespace {

TEST(TrackLogTest, ARowPerPeriodWithThePlansNearestPoint) {
  TrackLog log(0.5);
  log.OnTruth(1'000'000, {0.0, 0.0});  // before any plan or odometry
  ASSERT_TRUE(log.OnPath({{0.0, 1.0}, {10.0, 1.0}}).ok());
  log.OnOdometry({0.1, 0.05});
  log.OnTruth(1'200'000, {0.2, 0.0});  // within the period: no row
  log.OnTruth(1'500'000, {3.0, 0.2});
  // A path with a NaN is refused; the plan before it stays.
  EXPECT_FALSE(log.OnPath({{0.0, 0.0}, {std::nan(""), 1.0}}).ok());
  log.OnTruth(2'000'000, {4.0, 0.4});
  ASSERT_EQ(log.samples().size(), 3u);
  EXPECT_FALSE(log.samples()[0].planned_m.has_value());
  EXPECT_FALSE(log.samples()[0].odom_m.has_value());
  EXPECT_DOUBLE_EQ(log.samples()[1].t_s, 0.5);
  ASSERT_TRUE(log.samples()[1].planned_m.has_value());
  EXPECT_TRUE(log.samples()[1].planned_m->isApprox(common::Vector2(3.0, 1.0)));
  EXPECT_TRUE(log.samples()[1].odom_m->isApprox(common::Vector2(0.1, 0.05)));
  EXPECT_TRUE(log.samples()[2].planned_m->isApprox(common::Vector2(4.0, 1.0)));
}

TEST(TrackLogTest, NearestOnPathProjectsOntoSegmentsAndClampsAtTheEnds) {
  const std::vector<common::Vector2> path = {{0, 0}, {2, 0}, {2, 2}};
  EXPECT_TRUE(NearestOnPath(path, {1.0, -1.0}).isApprox(common::Vector2(1.0, 0.0)));
  EXPECT_TRUE(NearestOnPath(path, {3.0, 1.5}).isApprox(common::Vector2(2.0, 1.5)));
  EXPECT_TRUE(NearestOnPath(path, {-1.0, -1.0}).isApprox(common::Vector2(0.0, 0.0)));
  EXPECT_TRUE(NearestOnPath({{5, 5}}, {0.0, 0.0}).isApprox(common::Vector2(5.0, 5.0)));
}

TEST(TrackLogTest, TheCsvHasTheHeaderAndEmptyFieldsWhereNothingWasKnown) {
  TrackLog log(0.1, 2);
  log.OnTruth(0, {1.0, 2.0});
  ASSERT_TRUE(log.OnPath({{0.0, 0.0}, {0.0, 4.0}}).ok());
  log.OnTruth(100'000, {1.0, 3.0});
  log.OnTruth(200'000, {1.0, 3.5});  // over max_samples: counted
  EXPECT_EQ(log.dropped(), 1);
  const std::string path = ::testing::TempDir() + "/track_log_test.csv";
  ASSERT_TRUE(log.WriteCsv(path).ok());
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(),
            "t_s,odom_x_m,odom_y_m,truth_x_m,truth_y_m,planned_x_m,planned_y_m\n"
            "0.00,,,1.000,2.000,,\n"
            "0.10,,,1.000,3.000,0.000,3.000\n");
  EXPECT_FALSE(log.WriteCsv("/nonexistent-dir/x.csv").ok());
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace cairn::mission
