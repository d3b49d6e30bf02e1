// MapperCore: the configured layers through the seam (a tiny test layer registered from
// outside takes its inputs, in order, and is written like the built-in ones), the obstacle band
// measured from the terrain, layers deferred to their own thread, the dynamic layer's long-term
// restore and reset.

#include "services/mapping/mapper_core.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "services/mapping/mapper_layers.h"
#include "tests/unit/services/mapping/synthetic_scan.h"
#include "tests/unit/services/mapping/terrain_fixtures.h"

namespace cairn::mapping {
namespace {

using testing::SensorAt;
using testing::ShippedProfile;
using testing::SyntheticLidar;
using testing::SyntheticRevolution;

// A tiny layer: counts what it is given, in a 4 x 4 float grid "test/count" (cell (0,0): the
// revolutions, (1,0): the band rays of the last one, (2,0): the scans, (3,0): the last time).
class CountingLayer : public MapperLayer {
 public:
  explicit CountingLayer(uint32_t inputs, LayerSchedule schedule = {})
      : inputs_(inputs), schedule_(schedule) {
    common::GridGeometry g;
    g.resolution_m = 0.5;
    g.size_x = g.size_y = 4;
    grid_ = common::GridMap(g);
    grid_.AddLayer("test/count", 0.f);
  }
  const std::string& name() const override { return name_; }
  uint32_t inputs() const override { return inputs_; }
  LayerSchedule schedule() const override { return schedule_; }
  std::vector<std::string> OwnedLayers() const override { return {"test/count"}; }
  void OnRevolution(const RevolutionInput& input, RevolutionReport*) override {
    grid_.at("test/count")(0, 0) += 1.f;
    log.push_back("revolution " + std::to_string(input.revolution.revolution));
    ++version_;
  }
  void OnObstacleBand(const std::vector<PlanarRay>& rays, RevolutionReport*) override {
    grid_.at("test/count")(1, 0) = static_cast<float>(rays.size());
    log.push_back("band");
    ++version_;
  }
  void OnScan(const common::LaserScan&) override {
    grid_.at("test/count")(2, 0) += 1.f;
    log.push_back("scan");
    ++version_;
  }
  void AdvanceTo(int64_t utime) override {
    grid_.at("test/count")(3, 0) = static_cast<float>(utime * 1e-6);
    log.push_back("time " + std::to_string(utime));
  }
  void Reset() override { grid_.at("test/count").setZero(); }
  std::vector<GridOutput> GridOutputs() const override {
    return {{"test/count", GridEncoding::kFloat, true, true}};
  }
  std::optional<common::GridMap> ExportGrids() const override { return grid_; }
  int64_t version() const override { return version_; }

  std::vector<std::string> log;

 private:
  std::string name_ = "counting";
  uint32_t inputs_;
  LayerSchedule schedule_;
  common::GridMap grid_;
  int64_t version_{0};
};

common::LidarRevolution FlatRevolution(int64_t number, double x, int64_t utime) {
  SyntheticLidar lidar;
  lidar.rings = 8;
  lidar.azimuths = 180;
  lidar.max_range_m = 8.0;
  common::LidarRevolution revolution;
  revolution.revolution = number;
  revolution.expected_slices = 1;
  common::LidarSlice slice = SyntheticRevolution(
      SensorAt(x, 0.0, 0.5), [](double, double) { return 0.0; }, lidar, number);
  slice.utime = utime;
  revolution.slices.push_back(std::move(slice));
  return revolution;
}

RobotContext RobotAt(double x) {
  RobotContext robot;
  robot.xy_m = common::Vector2(x, 0.0);
  return robot;
}

TEST(MapperCoreTest, ATestLayerTakesItsInputsThroughTheSeamInOrder) {
  MapperCoreParams params;
  params.layers = {kTerrainLayerName};
  MapperCore core(params);
  auto owned = std::make_unique<CountingLayer>(kLidarRevolutions | kObstacleBand | kPlanarScans |
                                               kSensorTime);
  CountingLayer* layer = owned.get();
  core.AddLayer(std::move(owned));
  EXPECT_EQ(core.FindLayer("counting"), layer);
  EXPECT_THROW(core.AddLayer(std::make_unique<CountingLayer>(0)), std::invalid_argument);

  // The robot context is where the floor is known (the sensor's blind circle is not).
  const RevolutionReport report =
      core.ProcessRevolution(FlatRevolution(1, 0.0, 2'000'000), RobotAt(2.0), 2.0);
  EXPECT_GT(report.terrain.used, 0);  // the terrain took it first
  common::LaserScan scan;
  scan.utime = 2'100'000;
  core.ProcessScan(scan);
  EXPECT_EQ(layer->log, (std::vector<std::string>{"revolution 1", "band", "time 2000000", "scan",
                                                  "time 2100000"}));
  // The band was measured from the ground the terrain mapped (the flat floor 0.5 m below the
  // sensor; the band's default sensor height, 0.9 m, would put the floor in the band): no point
  // of the floor is an obstacle, every ray is free.
  const auto ground = core.FindLayer(kTerrainLayerName)->GroundHeightUnder({2.0, 0.0});
  ASSERT_TRUE(ground.has_value());
  EXPECT_NEAR(*ground, 0.0, 0.01);
  EXPECT_GT(report.band.free_rays, 0);
  EXPECT_EQ(report.band.hit_rays, 0);
  EXPECT_EQ(core.revolutions(), 1);

  // The layer is written like the built-in ones.
  const std::string dir = ::testing::TempDir() + "/mapper_core_test_outputs";
  ASSERT_TRUE(core.WriteOutputs(dir, "r1", 1).ok());
  std::stringstream yaml;
  yaml << std::ifstream(dir + "/map.yaml").rdbuf();
  EXPECT_NE(yaml.str().find("counting:"), std::string::npos) << yaml.str();
  EXPECT_NE(yaml.str().find("file: test_count.f32"), std::string::npos) << yaml.str();
  EXPECT_EQ(std::filesystem::file_size(dir + "/test_count.f32"), 16 * sizeof(float));

  core.Reset();
  EXPECT_EQ(core.revolutions(), 0);
  EXPECT_EQ(core.terrain()->known_cells(), 0);
  EXPECT_EQ(layer->ExportGrids()->at("test/count")(2, 0), 0.f);
}

TEST(MapperCoreTest, ALayerOnlyGetsTheInputsItTakes) {
  MapperCoreParams params;
  params.layers = {};
  MapperCore core(params);
  auto owned = std::make_unique<CountingLayer>(kPlanarScans);
  CountingLayer* layer = owned.get();
  core.AddLayer(std::move(owned));
  core.ProcessRevolution(FlatRevolution(1, 0.0, 1'000'000), RobotAt(0.0), 1.0);
  common::LaserScan scan;
  scan.utime = 1'100'000;
  core.ProcessScan(scan);
  EXPECT_EQ(layer->log, (std::vector<std::string>{"scan"}));
  EXPECT_EQ(core.terrain(), nullptr);
  EXPECT_EQ(core.occupancy(), nullptr);
}

TEST(MapperCoreTest, ReadingsGoToTheLayersThatTakeTheirStream) {
  class SonarLayer : public CountingLayer {
   public:
    SonarLayer() : CountingLayer(kSensorReadings | kSensorTime) {}
    std::vector<std::string> ReadingStreams() const override { return {"SONAR"}; }
    void OnReading(const SensorReading& reading) override {
      log.push_back("reading " + reading.stream);
    }
  };
  MapperCoreParams params;
  params.layers = {};
  MapperCore core(params);
  auto owned = std::make_unique<SonarLayer>();
  SonarLayer* layer = owned.get();
  core.AddLayer(std::move(owned));
  EXPECT_EQ(core.ReadingStreams(), (std::vector<std::string>{"SONAR"}));
  SensorReading ping;
  ping.stream = "SONAR";
  ping.utime = 3'000'000;
  core.ProcessReading(ping);
  ping.stream = "OTHER";
  ping.utime = 3'100'000;
  core.ProcessReading(ping);
  EXPECT_EQ(layer->log,
            (std::vector<std::string>{"reading SONAR", "time 3000000", "time 3100000"}));
}

TEST(MapperCoreTest, OwnThreadLayersRunInlineOrAreDeferredOnTheirSchedule) {
  MapperCoreParams params;
  params.layers = {};
  LayerSchedule every_second;
  every_second.every_revolutions = 2;
  every_second.own_thread = true;
  MapperCore core(params);
  auto owned = std::make_unique<CountingLayer>(kLidarRevolutions, every_second);
  CountingLayer* layer = owned.get();
  core.AddLayer(std::move(owned));
  // Inline by default, every second revolution.
  for (int k = 1; k <= 4; ++k) {
    const auto report =
        core.ProcessRevolution(FlatRevolution(k, 0.0, k * 100'000), RobotAt(0.0), k * 0.1);
    EXPECT_TRUE(report.deferred.empty());
  }
  EXPECT_EQ(layer->log, (std::vector<std::string>{"revolution 2", "revolution 4"}));
  // Deferred: listed for the caller, not fed.
  core.set_defer_own_thread_layers(true);
  const common::LidarRevolution fifth = FlatRevolution(5, 0.0, 500'000);
  EXPECT_TRUE(core.ProcessRevolution(fifth, RobotAt(0.0), 0.5).deferred.empty());
  const common::LidarRevolution sixth = FlatRevolution(6, 0.0, 600'000);
  const auto report = core.ProcessRevolution(sixth, RobotAt(0.0), 0.6);
  ASSERT_EQ(report.deferred.size(), 1u);
  EXPECT_EQ(report.deferred[0], layer);
  EXPECT_EQ(layer->log.size(), 2u);
  MapperCore::FeedDeferred(report.deferred[0], sixth, RobotAt(0.0), 0.6);
  EXPECT_EQ(layer->log.back(), "revolution 6");
}

TEST(MapperCoreTest, TheLayerListComesFromTheParams) {
  MapperCoreParams params;
  EXPECT_EQ(params.layers, (std::vector<std::string>{"terrain", "occupancy", "octomap"}));
  params.SetListed(kDynamicLayerName, true);
  params.SetListed(kOccupancyLayerName, false);
  params.SetListed(kOccupancyLayerName, true);  // back in its registry place
  EXPECT_EQ(params.layers,
            (std::vector<std::string>{"terrain", "occupancy", "octomap", "dynamic"}));
  params.layers = {"terrain", "no_such_layer"};
  EXPECT_THROW(params.Validate(), std::invalid_argument);
  params.layers = {"terrain", "terrain"};
  EXPECT_THROW(params.Validate(), std::invalid_argument);
  EXPECT_EQ(RegisteredLayers(), (std::vector<std::string>{"terrain", "occupancy", "octomap",
                                                          "dynamic", "explore", "sonar"}));
}

// The dynamic layers on a 4 x 3 m extent.
MapperCoreParams DynamicCoreParams() {
  MapperCoreParams params;
  params.layers = {kTerrainLayerName, kDynamicLayerName};
  params.dynamic.extent.resolution_m = 0.05;
  params.dynamic.extent.size_x = 80;
  params.dynamic.extent.size_y = 60;
  params.dynamic.extent.origin = {-1.0, -1.0, 0.0};
  return params;
}

TEST(MapperCoreTest, RestoresTheLongTermLayerOnlyOnTheSameGrid) {
  MapperCoreParams params = DynamicCoreParams();
  common::GridMap stored(params.dynamic.extent);
  stored.AddLayer(layers::kLongTerm, 0.f)(10, 20) = 98.f;
  params.dynamic.long_term_restore = stored;
  MapperCore restored(params);
  EXPECT_TRUE(restored.long_term_restore_status().ok());
  EXPECT_EQ(restored.dynamic()->LongTermOccupancy({10, 20}), 98);
  // OP_RESET forgets the memory too: back to the static map alone.
  restored.Reset();
  EXPECT_EQ(restored.dynamic()->LongTermOccupancy({10, 20}), -1);

  common::GridGeometry other = params.dynamic.extent;
  other.size_x += 1;
  common::GridMap elsewhere(other);
  elsewhere.AddLayer(layers::kLongTerm, 0.f);
  params.dynamic.long_term_restore = elsewhere;
  MapperCore ignored(params);
  EXPECT_EQ(ignored.long_term_restore_status().code(), common::StatusCode::kInvalidArgument);
  EXPECT_NE(ignored.long_term_restore_status().message().find("another grid"), std::string::npos);
  EXPECT_EQ(ignored.dynamic()->LongTermOccupancy({10, 20}), -1);
}

TEST(MapperCoreTest, TheDynamicLayerStepsOnSensorTimeAndClearingIsANewVersion) {
  MapperCore core(DynamicCoreParams());
  auto* dynamic = dynamic_cast<DynamicMapperLayer*>(core.FindLayer(kDynamicLayerName));
  ASSERT_NE(dynamic, nullptr);
  const int64_t period_us = 200'000;  // 5 Hz
  common::LaserScan scan;
  scan.range_min_m = 0.1;
  scan.range_max_m = 5.0;
  scan.angle_increment_rad = 0.01;
  scan.ranges_m.assign(10, 1.0f);
  scan.utime = 1'000'000;
  core.ProcessScan(scan);  // starts the clock: the first step is one period later
  EXPECT_EQ(core.dynamic()->updates(), 0);
  scan.utime += period_us;
  core.ProcessScan(scan);
  EXPECT_EQ(core.dynamic()->updates(), 1);
  EXPECT_LT(core.dynamic()->ShortTermCost({20, 20}), kCostUnknown);  // the laser marked it
  const int64_t version = dynamic->version();
  dynamic->ClearShortTerm();
  EXPECT_GT(dynamic->version(), version);
  EXPECT_EQ(core.dynamic()->ShortTermCost({20, 20}), kCostUnknown);
}

}  // namespace
}  // namespace cairn::mapping
