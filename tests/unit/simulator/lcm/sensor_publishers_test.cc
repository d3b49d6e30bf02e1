#include "simulator/lcm/sensor_publishers.h"

#include <cstring>
#include <map>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "cairn/lcmt_imu.hpp"
#include "cairn/lcmt_laser_scan.hpp"
#include "cairn/lcmt_lidar_ranges.hpp"
#include "cairn/lcmt_odometry.hpp"
#include "cairn/lcmt_point_cloud_slice.hpp"
#include "cairn/lcmt_pose.hpp"
#include "cairn/lcmt_sonar_ping.hpp"

#include "common/channels.h"
#include "common/point_cloud.h"
#include "services/runtime/conversions.h"
#include "simulator/lcm/sim_service.h"
#include "simulator/sensor_registry.h"
#include "simulator/sensors/ground_truth_sensor.h"
#include "simulator/sensors/imu_sensor.h"
#include "simulator/sensors/lidar_sensor.h"
#include "simulator/sensors/odometry_sensor.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "simulator/sensors/sonar_sensor.h"
#include "simulator/sensors/turret_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::InlineScenario;

std::unique_ptr<runtime::Node> MemqNode() {
  runtime::NodeOptions options;
  options.process_name = "sensor_publishers_test";
  options.lcm_url = "memq://";
  options.install_signal_handlers = false;
  return std::make_unique<runtime::Node>(options);
}

// Publishes `out` through the built-in publishers and returns the last message on `channel`.
template <typename Msg>
Msg PublishAndReceive(const SimOutputs& out, const std::string& channel) {
  auto node = MemqNode();
  Msg received{};
  int count = 0;
  node->Subscribe<Msg>(channel, [&](const Msg& m) {
    received = m;
    ++count;
  });
  for (const auto& group : out.groups()) {
    const SensorPublisher* publisher = BuiltinSensorPublishers().Find(group->sensor());
    EXPECT_NE(publisher, nullptr) << group->sensor();
    if (publisher != nullptr) publisher->publish(*node, *group);
  }
  while (node->lcm().handleTimeout(0) > 0) {
  }
  EXPECT_EQ(count, 1) << channel;
  return received;
}

TEST(SensorPublishersTest, EveryBuiltinSensorHasOneOnItsChannel) {
  const std::map<std::string, std::string> streams = {{"hdl32e", channels::kLidarRanges},
                                                      {"planar_laser", channels::kScan},
                                                      {"turret", channels::kTurretScan},
                                                      {"odometry", channels::kOdom},
                                                      {"imu", channels::kImu},
                                                      {"ground_truth", channels::kPose},
                                                      {"sonar", channels::kSonar}};
  for (const auto& [name, stream] : streams) {
    const SensorPublisher* p = BuiltinSensorPublishers().Find(name);
    ASSERT_NE(p, nullptr) << name;
    EXPECT_EQ(p->stream, stream);
  }
  // Every core sensor kind, those added later too, has exactly one, and --help's description
  // names its channel.
  for (const auto& [name, description] : BuiltinSensors().Catalogue()) {
    const SensorPublisher* p = BuiltinSensorPublishers().Find(name);
    ASSERT_NE(p, nullptr) << name;
    EXPECT_NE(description.find(std::string("<robot>.") + p->stream), std::string::npos) << name;
  }
  EXPECT_EQ(BuiltinSensorPublishers().publishers().size(), BuiltinSensors().kinds().size());
}

TEST(SensorPublishersTest, LidarSlicesAndScans) {
  SimOutputs out;
  common::LidarSlice slice;
  slice.utime = 5000;
  slice.robot = "r";
  slice.slice_index = 3;
  slice.slice_count = 20;
  slice.points.push_back({1.f, 2.f, 3.f, 40.f, 7});
  out.Add(LidarSensor::kName, slice);
  const auto lidar = PublishAndReceive<cairn::lcmt_point_cloud_slice>(out, "r.LIDAR");
  EXPECT_EQ(lidar.utime, 5000);
  EXPECT_EQ(lidar.slice_index, 3);
  EXPECT_EQ(lidar.robot, "r");
  EXPECT_EQ(lidar.num_points, 1);
  // With a grid and a range resolution, the same slice goes out as ranges, on LIDAR_RANGES.
  SimOutputs gridded;
  slice.grid.ring_elevation_rad.assign(8, 0.f);
  slice.grid.columns = 4;
  slice.grid.azimuth_step_rad = 0.01;
  slice.grid.range_resolution_m = 0.002;
  slice.points[0].column = 2;
  gridded.Add(LidarSensor::kName, slice);
  const auto ranges = PublishAndReceive<cairn::lcmt_lidar_ranges>(gridded, "r.LIDAR_RANGES");
  EXPECT_EQ(ranges.utime, 5000);
  EXPECT_EQ(ranges.slice_index, 3);
  EXPECT_EQ(ranges.num_rays, 32);
  ASSERT_EQ(ranges.ranges.size(), 32u);
  // The point (1, 2, 3) m is 3.742 m away: 1871 steps of 2 mm, at column 2, ring 7.
  EXPECT_EQ(ranges.ranges[2 * 8 + 7], 1871);
  EXPECT_EQ(ranges.intensity[2 * 8 + 7], 40);

  SimOutputs scans;
  common::LaserScan scan;
  scan.utime = 7000;
  scan.robot = "k";
  scan.ranges_m = {1.f, 2.f};
  scan.intensities = {0.f, 0.f};
  scans.Add(PlanarLaserSensor::kName, scan);
  const auto msg = PublishAndReceive<cairn::lcmt_laser_scan>(scans, "k.SCAN");
  EXPECT_EQ(msg.utime, 7000);
  EXPECT_EQ(msg.ranges_m, (std::vector<float>{1.f, 2.f}));
}

TEST(SensorPublishersTest, FastPointCloudSliceEncodesTheSameBytesAsLcm) {
  for (int n : {0, 1, 7, 2880}) {
    common::LidarSlice slice;
    slice.utime = 123456789;
    slice.robot = "robot-7";
    slice.revolution = 42;
    slice.slice_index = 5;
    slice.slice_count = 20;
    slice.azimuth_start_rad = -0.3;
    slice.azimuth_end_rad = 0.01;
    slice.max_range_m = 70.0;
    slice.sensor_pose.position_m = common::Vector3(-0.25, 1.25, 2.75);
    slice.sensor_pose.orientation = common::Quaternion(0.5, -0.5, 0.5, 0.5);
    for (int i = 0; i < n; ++i) {
      common::LidarPoint p;
      p.x_m = 0.001f * static_cast<float>(i) - 3.0f;
      p.y_m = -1e-7f * static_cast<float>(i * i);
      p.z_m = i % 3 == 0 ? -0.0f : 12345.678f / static_cast<float>(i + 1);
      p.intensity = static_cast<float>(i % 256);
      p.ring = static_cast<int16_t>(i % 32 - 5);
      slice.points.push_back(p);
    }
    // LCM's own encoding of the message runtime::ToLcm makes.
    const cairn::lcmt_point_cloud_slice m = runtime::ToLcm(slice);
    const int size = m.getEncodedSize();
    std::vector<uint8_t> expected(static_cast<size_t>(size) + 3, 0xAB);
    std::vector<uint8_t> fast(static_cast<size_t>(size) + 3, 0xAB);
    ASSERT_EQ(m.encode(expected.data(), 3, size), size);
    const FastPointCloudSlice wrapped(slice);
    ASSERT_EQ(wrapped.getEncodedSize(), size);
    ASSERT_EQ(wrapped.encode(fast.data(), 3, size), size) << n << " points";
    EXPECT_EQ(fast, expected) << n << " points";
    // Too little room, or a negative offset: refused like LCM's own.
    EXPECT_EQ(wrapped.encode(fast.data(), 0, size - 1), -1);
    EXPECT_EQ(wrapped.encode(fast.data(), -1, size), -1);
  }
}

TEST(SensorPublishersTest, FastLidarRangesEncodesTheSameBytesAsLcm) {
  for (int columns : {1, 7, 90}) {
    common::LidarSlice slice;
    slice.utime = 987654321;
    slice.robot = "robot-3";
    slice.revolution = 11;
    slice.slice_index = 19;
    slice.slice_count = 20;
    slice.azimuth_start_rad = 5.9;
    slice.max_range_m = 70.0;
    slice.sensor_pose.position_m = common::Vector3(3.5, -1.25, 0.75);
    slice.sensor_pose.orientation = common::Quaternion(0.5, 0.5, -0.5, 0.5);
    for (int r = 0; r < 32; ++r) slice.grid.ring_elevation_rad.push_back(-0.5f + 0.02f * r);
    slice.grid.azimuth_step_rad = 2.0 * M_PI / 1800.0;
    slice.grid.columns = columns;
    slice.grid.range_resolution_m = 0.002;
    for (int c = 0; c < columns; ++c) {
      for (int r = 0; r < 32; ++r) {
        if ((c + r) % 5 == 0) continue;  // no return
        common::LidarPoint p;
        p.x_m = 0.37f * static_cast<float>(r + 1) - 0.01f * static_cast<float>(c);
        p.y_m = r % 3 == 0 ? NAN : -0.5f;           // a point without a range: no return either
        p.z_m = 200.f * static_cast<float>(c % 2);  // beyond 16 bits of 2 mm steps
        p.intensity = static_cast<float>((c * 32 + r) % 300) - 20.f;  // clamped to 0..255
        p.ring = static_cast<int16_t>(r);
        p.column = static_cast<uint16_t>(c);
        slice.points.push_back(p);
      }
    }
    // LCM's own encoding of the message runtime::ToLcmRanges makes.
    const cairn::lcmt_lidar_ranges m = runtime::ToLcmRanges(slice);
    const int size = m.getEncodedSize();
    std::vector<uint8_t> expected(static_cast<size_t>(size) + 3, 0xAB);
    std::vector<uint8_t> fast(static_cast<size_t>(size) + 3, 0xAB);
    ASSERT_EQ(m.encode(expected.data(), 3, size), size);
    const FastLidarRanges wrapped(slice);
    ASSERT_EQ(wrapped.getEncodedSize(), size);
    ASSERT_EQ(wrapped.encode(fast.data(), 3, size), size) << columns << " columns";
    EXPECT_EQ(fast, expected) << columns << " columns";
    EXPECT_EQ(wrapped.encode(fast.data(), 0, size - 1), -1);
    EXPECT_EQ(wrapped.encode(fast.data(), -1, size), -1);
    // The same rays as a range image (what the HDL-32E makes): the same bytes, each range
    // as it is, and decoded, the image's points.
    common::LidarSlice image = slice;
    image.points.clear();
    image.range_steps.resize(m.ranges.size());
    std::memcpy(image.range_steps.data(), m.ranges.data(), m.ranges.size() * sizeof(int16_t));
    image.range_intensity = m.intensity;
    ASSERT_TRUE(common::HasRangeImage(image));
    std::vector<uint8_t> from_image(static_cast<size_t>(size) + 3, 0xAB);
    ASSERT_EQ(FastLidarRanges(image).encode(from_image.data(), 3, size), size);
    EXPECT_EQ(from_image, expected) << columns << " columns";
    cairn::lcmt_lidar_ranges decoded;
    ASSERT_EQ(decoded.decode(from_image.data(), 3, size), size);
    auto back = runtime::FromLcm(decoded);
    ASSERT_TRUE(back.ok()) << back.status().message();
    common::LidarSlice expanded = image;
    common::ExpandRangeImage(&expanded);
    ASSERT_GT(expanded.points.size(), 0u);
    ASSERT_EQ(back->points.size(), expanded.points.size());
    for (size_t k = 0; k < expanded.points.size(); ++k) {
      ASSERT_EQ(back->points[k].x_m, expanded.points[k].x_m) << k;
      ASSERT_EQ(back->points[k].z_m, expanded.points[k].z_m) << k;
      ASSERT_EQ(back->points[k].column, expanded.points[k].column) << k;
    }
    // As points on LIDAR, an image goes out expanded; the fast points encoder refuses it.
    EXPECT_EQ(runtime::ToLcm(image).num_points, static_cast<int32_t>(expanded.points.size()));
    const FastPointCloudSlice image_as_points(image);
    std::vector<uint8_t> points_buffer(static_cast<size_t>(image_as_points.getEncodedSize()));
    EXPECT_EQ(
        image_as_points.encode(points_buffer.data(), 0, static_cast<int>(points_buffer.size())),
        -1);
    // A point off the grid, or no grid at all: refused.
    common::LidarSlice off = slice;
    off.points.back().column = static_cast<uint16_t>(columns);
    EXPECT_EQ(FastLidarRanges(off).encode(fast.data(), 3, size), -1);
    off.grid = {};
    EXPECT_EQ(FastLidarRanges(off).getEncodedSize(), -1);
  }
}

TEST(SensorPublishersTest, TurretLineCarriesPanPeriodAndFrame) {
  SimOutputs out;
  TurretLine line;
  line.scan.utime = 20000;
  line.scan.robot = "r";
  line.scan.ranges_m = {4.f};
  line.scan.intensities = {10.f};
  line.pan_rad = 0.25;
  line.line_period_s = 0.02;
  out.Add(TurretSensor::kName, line);
  const auto m = PublishAndReceive<cairn::lcmt_laser_scan>(out, "r.TURRET_SCAN");
  EXPECT_EQ(m.frame, "turret");
  EXPECT_EQ(m.turret_angle_rad, 0.25);
  EXPECT_EQ(m.scan_time_s, 0.02f);
  EXPECT_EQ(m.utime, 20000);
}

TEST(SensorPublishersTest, SonarPingCarriesItsBeamOfBinsAndTheHeadsPose) {
  SimOutputs out;
  SonarPing ping;
  ping.utime = 66667;
  ping.robot = "auv";
  ping.sensor_pose.position_m = {1.0, 2.0, -3.0};
  ping.pan_rad = -0.5;
  ping.range_max_m = 50.0;
  ping.sound_speed_mps = 1500.0;
  ping.bins = {0, 81, 255, 0};
  out.Add(SonarSensor::kName, ping);
  const auto m = PublishAndReceive<cairn::lcmt_sonar_ping>(out, "auv.SONAR");
  EXPECT_EQ(m.frame, "sonar");
  EXPECT_EQ(m.utime, 66667);
  EXPECT_EQ(m.pan_rad, -0.5);
  EXPECT_EQ(m.num_bins, 4);
  EXPECT_EQ(m.intensities, (std::vector<uint8_t>{0, 81, 255, 0}));
  EXPECT_EQ(m.sensor_position_m[2], -3.0);
  EXPECT_EQ(m.range_max_m, 50.0);
}

TEST(SensorPublishersTest, OdometryImuAndGroundTruth) {
  SimOutputs out;
  OdometryReading odom;
  odom.utime = 1;
  odom.robot = "r";
  odom.pose.position_m = {1.0, 2.0, 0.1};
  odom.linear_velocity_mps = {0.5, 0.0, 0.0};
  out.Add(OdometrySensor::kName, odom);
  ImuReading imu;
  imu.utime = 2;
  imu.robot = "r";
  imu.orientation = common::Quaternion(0.0, 1.0, 0.0, 0.0);
  imu.linear_acceleration_mps2 = {0.0, 0.0, 9.81};
  imu.angular_velocity_variance = 4e-6;
  out.Add(ImuSensor::kName, imu);
  GroundTruthReading truth;
  truth.utime = 3;
  truth.robot = "r";
  truth.pose.position_m = {4.0, 5.0, 6.0};
  truth.angular_velocity_radps = {0.0, 0.0, 0.3};
  out.Add(GroundTruthSensor::kName, truth);

  const auto o = PublishAndReceive<cairn::lcmt_odometry>(out, "r.ODOM");
  EXPECT_EQ(o.frame, "odom");
  EXPECT_EQ(o.child_frame, "base_link");
  EXPECT_EQ(o.position_m[1], 2.0);
  EXPECT_EQ(o.linear_velocity_mps[0], 0.5);
  EXPECT_EQ(o.pose_covariance[0], 0.0);
  const auto i = PublishAndReceive<cairn::lcmt_imu>(out, "r.IMU");
  EXPECT_EQ(i.frame, "imu");
  EXPECT_EQ(i.orientation_wxyz[1], 1.0);
  EXPECT_EQ(i.linear_acceleration_mps2[2], 9.81);
  EXPECT_EQ(i.angular_velocity_variance, 4e-6);
  const auto p = PublishAndReceive<cairn::lcmt_pose>(out, "r.POSE");
  EXPECT_EQ(p.utime, 3);
  EXPECT_EQ(p.position_m[2], 6.0);
  EXPECT_EQ(p.angular_velocity_radps[2], 0.3);
}

// --- the seam on the LCM side: a sensor and its publisher written here -------------------------

struct BeaconParams {
  double rate_hz{10.0};
  void Validate() const {}
};
BeaconParams LoadBeaconParams(common::YamlMap& map, const BeaconParams& defaults) {
  BeaconParams p = defaults;
  map.Get("rate_hz", &p.rate_hz);
  FinishSensorParams(map, p);
  return p;
}
struct BeaconReading {
  int64_t utime{0};
  std::string robot;
};

class BeaconSensor final : public SimSensor {
 public:
  static constexpr char kName[] = "beacon";
  static constexpr char kDescription[] = "a robot's id, 10 times a second (a test sensor)";
  using Params = BeaconParams;
  using Reading = BeaconReading;
  static constexpr auto kLoadParams = &LoadBeaconParams;

  BeaconSensor(const BeaconParams& params, const SensorContext& context) : robot_(context.robot) {
    schedule_.rate_hz = params.rate_hz;
  }
  bool Due(double now_s) const override { return schedule_.Due(now_s); }
  void Produce(const SensorFrame& frame, SimOutputs* out) override {
    schedule_.Advance(frame.now_s);
    out->Add(kName, BeaconReading{frame.utime, robot_});
  }

 private:
  std::string robot_;
  SensorSchedule schedule_;
};

cairn::lcmt_pose BeaconToLcm(const BeaconReading& r) {
  cairn::lcmt_pose m{};
  m.utime = r.utime;
  m.robot = r.robot;
  m.frame = "beacon";
  return m;
}

TEST(SensorPublishersSeamTest, ANewSensorWithItsPublisherIsOnTheBus) {
  InstallMujocoLogHooks();
  Scenario s = InlineScenario(FlatWorld(), "r", "p3dx");
  s.robots[0].sensors.Set<BeaconSensor>();
  MujocoSim sim(s);
  auto node = MemqNode();
  SensorPublishers publishers = BuiltinSensorPublishers();
  publishers.Add(MakeSensorPublisher(BeaconSensor::kName, "BEACON", &BeaconToLcm));
  SimService dut(*node, sim, SimServiceParams{}, publishers);
  std::vector<cairn::lcmt_pose> beacons;
  int64_t scans = 0;
  node->Subscribe<cairn::lcmt_pose>("r.BEACON",
                                    [&](const cairn::lcmt_pose& m) { beacons.push_back(m); });
  node->SubscribeRaw("r.SCAN", [&](const std::string&, const void*, int, int64_t) { ++scans; });
  dut.StepAndPublish(500);  // 1 s
  dut.HandlePending();
  ASSERT_EQ(beacons.size(), 10u);
  EXPECT_EQ(beacons.back().utime, 1000000);
  EXPECT_EQ(beacons.back().frame, "beacon");
  EXPECT_EQ(scans, 10);  // the built-in sensors beside it are unchanged
  // Two publishers for one sensor are refused.
  EXPECT_THROW(publishers.Add(MakeSensorPublisher(BeaconSensor::kName, "X", &BeaconToLcm)),
               std::invalid_argument);
}

TEST(SensorPublishersSeamTest, ASensorWithoutPublisherStopsTheServiceAtStart) {
  InstallMujocoLogHooks();
  Scenario s = InlineScenario(FlatWorld(), "r", "p3dx");
  s.robots[0].sensors.Set<BeaconSensor>();
  MujocoSim sim(s);
  auto node = MemqNode();
  try {
    SimService dut(*node, sim, SimServiceParams{});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sensor 'beacon' has no LCM publisher"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace cairn::sim
