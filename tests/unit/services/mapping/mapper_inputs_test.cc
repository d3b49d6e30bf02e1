// MapperInputs: sensor poses per pose_source (ground truth near the data's time, odometry
// composed with a configured or measured mount, IMU attitude), bad points dropped and counted,
// the robot's pose at a revolution's end.

#include "services/mapping/mapper_inputs.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "common/yaml_reader.h"
#include "tests/unit/services/mapping/synthetic_scan.h"

namespace cairn::mapping {
namespace {

using testing::SensorAt;

common::LidarRevolution Revolution(const common::Pose3& reported, int64_t utime, int slices = 2) {
  common::LidarRevolution revolution;
  revolution.revolution = 7;
  revolution.expected_slices = slices;
  for (int s = 0; s < slices; ++s) {
    common::LidarSlice slice;
    slice.utime = utime + s * 10'000;
    slice.max_range_m = 50.0;
    slice.sensor_pose = reported;
    slice.points = {{1.f, 0.f, -0.5f, 0.f, 0}, {2.f, 1.f, -0.5f, 0.f, 1}};
    revolution.slices.push_back(slice);
  }
  return revolution;
}

TEST(MapperInputsTest, GroundTruthKeepsTheReportedPoseNearAPoseSample) {
  MapperInputs inputs({});
  const common::Pose3 reported = SensorAt(1.0, 2.0, 0.5, 0.3);
  RevolutionDrops drops;
  // No pose sample yet: every slice is dropped.
  EXPECT_FALSE(inputs.PrepareRevolution(Revolution(reported, 1'000'000), &drops).has_value());
  EXPECT_EQ(drops.slices_without_pose, 2);
  ASSERT_TRUE(inputs.AddGroundTruth(1'000'000, SensorAt(1.0, 2.0, 0.0, 0.3)));
  common::LidarRevolution revolution = Revolution(reported, 1'000'000);
  revolution.slices[0].points.push_back({NAN, 0.f, 0.f, 0.f, 0});
  revolution.slices[1].points.push_back({60.f, 0.f, 0.f, 0.f, 0});  // beyond the 50 m range
  revolution.slices[1].points.push_back({0.f, std::numeric_limits<float>::infinity(), 0.f, 0.f, 0});
  const auto prepared = inputs.PrepareRevolution(revolution, &drops);
  ASSERT_TRUE(prepared.has_value());
  EXPECT_EQ(drops.bad_points, 3);
  EXPECT_EQ(drops.slices_without_pose, 0);
  EXPECT_FALSE(drops.incomplete);
  ASSERT_EQ(prepared->revolution.slices.size(), 2u);
  EXPECT_EQ(prepared->revolution.slices[0].points.size(), 2u);
  EXPECT_TRUE(prepared->revolution.slices[1].sensor_pose.position_m.isApprox(reported.position_m));
  ASSERT_TRUE(prepared->robot.xy_m.has_value());
  EXPECT_NEAR(prepared->robot.xy_m->x(), 1.0, 1e-9);
  EXPECT_NEAR(*prepared->robot.yaw_rad, 0.3, 1e-9);
  EXPECT_DOUBLE_EQ(prepared->time_s, 1.01);
  // A slice far from every sample is dropped alone; a missing slice is reported.
  common::LidarRevolution late = Revolution(reported, 1'000'000, 3);
  late.slices[2].utime = 9'000'000;
  late.expected_slices = 4;
  const auto partial = inputs.PrepareRevolution(late, &drops);
  ASSERT_TRUE(partial.has_value());
  EXPECT_EQ(partial->revolution.slices.size(), 2u);
  EXPECT_EQ(drops.slices_without_pose, 1);
  EXPECT_TRUE(drops.incomplete);
  EXPECT_TRUE(inputs.TakeNewMounts().empty());  // ground truth measures no mount
}

TEST(MapperInputsTest, OdometryMeasuresTheMountOnceAndComposesIt) {
  MapperInputsParams params;
  params.pose_source = PoseSource::kOdometry;
  params.imu_attitude = false;
  MapperInputs inputs(params);
  ASSERT_TRUE(inputs.AddOdometry(1'000'000, SensorAt(1.0, 0.0, 0.0)));
  ASSERT_TRUE(inputs.AddOdometry(2'000'000, SensorAt(3.0, 0.0, 0.0, M_PI / 2)));
  // The producer reports the lidar 0.2 m ahead of and 0.5 m above the base at the first slice.
  const auto first = inputs.SensorPose("lidar", 1'000'000, SensorAt(1.2, 0.0, 0.5));
  ASSERT_TRUE(first.has_value());
  EXPECT_TRUE(first->position_m.isApprox(common::Vector3(1.2, 0.0, 0.5)));
  const auto mounts = inputs.TakeNewMounts();
  ASSERT_EQ(mounts.size(), 1u);
  EXPECT_EQ(mounts[0].first, "lidar");
  EXPECT_TRUE(mounts[0].second.position_m.isApprox(common::Vector3(0.2, 0.0, 0.5)));
  // Later the reported pose is ignored: odometry (turned 90 deg) composed with the mount.
  const auto later = inputs.SensorPose("lidar", 2'000'000, SensorAt(50.0, 50.0, 9.0));
  ASSERT_TRUE(later.has_value());
  EXPECT_NEAR(later->position_m.x(), 3.0, 1e-9);
  EXPECT_NEAR(later->position_m.y(), 0.2, 1e-9);
  EXPECT_NEAR(later->position_m.z(), 0.5, 1e-9);
  EXPECT_TRUE(inputs.TakeNewMounts().empty());
  EXPECT_FALSE(inputs.SensorPose("lidar", 5'000'000, SensorAt(0, 0, 0)).has_value());
  // A scan without a pose near its time is refused.
  common::LaserScan scan;
  scan.utime = 7'000'000;
  EXPECT_FALSE(inputs.PrepareScan(scan).has_value());
  scan.utime = 1'000'000;
  scan.sensor_pose = SensorAt(1.1, 0.0, 0.1);
  const auto prepared = inputs.PrepareScan(scan);
  ASSERT_TRUE(prepared.has_value());
  EXPECT_TRUE(prepared->sensor_pose.position_m.isApprox(common::Vector3(1.1, 0.0, 0.1)));
}

TEST(MapperInputsTest, AConfiguredMountAndTheImuAttitude) {
  MapperInputsParams params;
  params.pose_source = PoseSource::kOdometry;
  common::Pose3 mount;
  mount.position_m = {0.1, 0.0, 0.33};
  params.lidar_mount = mount;
  MapperInputs inputs(params);
  ASSERT_TRUE(inputs.AddOdometry(1'000'000, SensorAt(2.0, 1.0, 0.0, 0.5)));
  // The IMU: pitched 0.1 rad nose up, its own heading off by 1 rad (only roll and pitch count).
  common::Pose3 imu;
  imu.orientation = Eigen::AngleAxisd(1.5, Eigen::Vector3d::UnitZ()) *
                    Eigen::AngleAxisd(-0.1, Eigen::Vector3d::UnitY());
  ASSERT_TRUE(inputs.AddImu(1'000'000, imu));
  const auto base = inputs.BasePose(1'000'000);
  ASSERT_TRUE(base.has_value());
  EXPECT_NEAR(base->yaw_rad(), 0.5, 1e-9);
  EXPECT_NEAR(base->pitch_rad(), imu.pitch_rad(), 1e-9);
  const auto sensor = inputs.SensorPose("lidar", 1'000'000, SensorAt(0, 0, 0));
  ASSERT_TRUE(sensor.has_value());
  EXPECT_TRUE(sensor->position_m.isApprox(base->position_m + base->orientation * mount.position_m));
  RevolutionDrops drops;
  const auto prepared =
      inputs.PrepareRevolution(Revolution(SensorAt(0, 0, 0), 1'000'000, 1), &drops);
  ASSERT_TRUE(prepared.has_value());
  EXPECT_NEAR(prepared->robot.pitch_rad, imu.pitch_rad(), 1e-9);
}

TEST(MapperInputsTest, AReadingGetsItsPoseLikeAScan) {
  MapperInputs inputs({});
  SensorReading reading;
  reading.stream = "SONAR";
  reading.utime = 1'000'000;
  reading.sensor_pose = SensorAt(1.0, 2.0, 0.2);
  EXPECT_FALSE(inputs.PrepareReading(&reading));  // no ground truth yet
  ASSERT_TRUE(inputs.AddGroundTruth(1'000'000, SensorAt(1.0, 2.0, 0.0)));
  ASSERT_TRUE(inputs.PrepareReading(&reading));
  EXPECT_TRUE(reading.sensor_pose.position_m.isApprox(common::Vector3(1.0, 2.0, 0.2)));
}

TEST(MapperInputsTest, PoseSourcesAndMountsByName) {
  EXPECT_EQ(PoseSourceFromName("odometry"), PoseSource::kOdometry);
  EXPECT_STREQ(PoseSourceName(PoseSource::kGroundTruth), "ground_truth");
  EXPECT_THROW(PoseSourceFromName("gps"), std::invalid_argument);
  common::YamlMap yaml = common::YamlMap::FromString("{z_m: 0.33, yaw_deg: 90}");
  const common::Pose3 mount = LoadMountPose(yaml);
  EXPECT_NEAR(mount.position_m.z(), 0.33, 1e-12);
  EXPECT_NEAR(mount.yaw_rad(), M_PI / 2, 1e-12);
  common::YamlMap bad = common::YamlMap::FromString("{z: 0.33}");
  EXPECT_THROW(LoadMountPose(bad), common::ConfigError);
  MapperInputsParams params;
  params.max_pose_gap_s = 0;
  EXPECT_THROW(MapperInputs{params}, std::invalid_argument);
}

}  // namespace
}  // namespace cairn::mapping
