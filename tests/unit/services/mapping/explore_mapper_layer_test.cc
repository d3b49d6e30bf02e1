#include "services/mapping/explore_mapper_layer.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "common/yaml_reader.h"
#include "services/explore/info_map.h"
#include "services/explore/nbv_mission.h"
#include "services/mapping/mapper_layers.h"

namespace cairn::mapping {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr char kNav[] = "explore/navigability";

// A folder per test: ctest runs the tests of this file side by side.
std::string TempPath(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(CAIRN_BINARY_DIR) / "test-tmp" /
                                    "explore_mapper_layer_test" /
                                    ::testing::UnitTest::GetInstance()->current_test_info()->name();
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

// An explorer configuration with small sweeps: 2 deg pan steps over 180 deg (90 lines), beams
// 1 deg apart, a 20 x 20 m work area round the origin.
std::string ExplorerConfigFile() {
  const std::string path = TempPath("explorer_nbv.yaml");
  std::ofstream(path) << "mode: nbv\n"
                         "nbv:\n"
                         "  work_area: \"-10,-10 10,-10 10,10 -10,10\"\n"
                         "  pan_step_deg: 2.0\n"
                         "  pan_range_deg: 180.0\n"
                         "  tilt_step_deg: 1.0\n"
                         "  scanner_height_m: 1.0\n";
  return path;
}

ExploreMapperLayerParams Params() {
  ExploreMapperLayerParams p;
  p.explorer_config = ExplorerConfigFile();
  ReadExplorerConfig(&p);
  return p;
}

// The turret's line at pan step `k` over flat ground (z 0), the scanner 1 m up at (x, 0): the
// simulator's frame (the line's x axis up, its y axis the horizontal pan direction), beams from
// -135 to 135 deg, returns within 7 m (6.9 m across the ground).
TurretLineReading Line(int k, double x = 0.0, double t0_s = 10.0) {
  const double pan = k * 2.0 * kDeg;
  const double c = std::cos(pan), s = std::sin(pan);
  Eigen::Matrix3d r;
  r << 0.0, c, -s, 0.0, s, c, 1.0, 0.0, 0.0;
  TurretLineReading reading;
  reading.stream = "TURRET_SCAN";
  reading.utime = static_cast<int64_t>((t0_s + 0.02 * k) * 1e6);
  common::LaserScan& line = reading.line;
  line.utime = reading.utime;
  line.sensor_pose.position_m = Eigen::Vector3d(x, 0.0, 1.0);
  line.sensor_pose.orientation = common::Quaternion(r);
  line.angle_min_rad = -135 * kDeg;
  line.angle_increment_rad = 1 * kDeg;
  line.range_min_m = 0.05;
  line.range_max_m = 30.0;
  for (int b = 0; b <= 270; ++b) {
    const double a = line.angle_min_rad + b * line.angle_increment_rad;
    const double down = -std::cos(a);  // the beam's downward component
    const double range = down > 0.0 ? 1.0 / down : INFINITY;
    line.ranges_m.push_back(range < 7.0 ? static_cast<float>(range) : INFINITY);
  }
  reading.sensor_pose = line.sensor_pose;
  reading.pan_rad = pan;
  return reading;
}

void Sweep(ExploreMapperLayer* layer, int from, int to, double x = 0.0, double t0_s = 10.0) {
  for (int k = from; k < to; ++k) layer->OnReading(Line(k, x, t0_s));
}

TEST(ExploreMapperLayerTest, ASweepOverFlatGroundMakesTheCellsRoundTheScannerSafe) {
  ExploreMapperLayer layer(Params());
  EXPECT_FALSE(layer.ExportGrids().has_value()) << "nothing to show before a sweep";
  const int64_t before = layer.version();
  // Joined mid-sweep: those lines wait for the next pan 0.
  Sweep(&layer, 40, 90, 0.0, 5.0);
  EXPECT_EQ(layer.scans(), 0);
  Sweep(&layer, 0, 90);
  EXPECT_EQ(layer.scans(), 1);
  EXPECT_NE(layer.version(), before);
  const auto grids = layer.ExportGrids();
  ASSERT_TRUE(grids.has_value());
  for (const std::string& name : layer.OwnedLayers()) EXPECT_TRUE(grids->HasLayer(name)) << name;
  bool published_nav = false;
  for (const GridOutput& g : layer.GridOutputs()) published_nav |= g.name == kNav && g.published;
  EXPECT_TRUE(published_nav);
  // Ground 2..5 m away is safe; beyond 7 m nothing came back.
  for (const double d : {2.0, 3.5, 5.0}) {
    for (const double bearing_deg : {45.0, 90.0, 135.0}) {
      const common::Vector2 at(d * std::cos(bearing_deg * kDeg), d * std::sin(bearing_deg * kDeg));
      const auto cnc = grids->ValueAt(kNav, at);
      ASSERT_TRUE(cnc.has_value()) << at.transpose();
      EXPECT_GT(*cnc, 0.7f) << at.transpose();
    }
  }
  EXPECT_FALSE(grids->ValueAt(kNav, {0.0, 8.5}).has_value()) << "beyond the returns";
}

TEST(ExploreMapperLayerTest, ABrokenSweepIsDroppedAndTheNextPanZeroStartsAnother) {
  ExploreMapperLayer layer(Params());
  Sweep(&layer, 0, 30);             // the sweep stops at line 30 ...
  Sweep(&layer, 0, 90, 0.0, 20.0);  // ... and the next one starts at pan 0
  EXPECT_EQ(layer.scans(), 1);
  EXPECT_EQ(layer.broken_sweeps(), 1);
  // One log line each: the sweep that broke, the one that went on the map.
  const std::vector<std::string> events = layer.TakeEvents();
  ASSERT_EQ(events.size(), 2u);
  EXPECT_NE(events[0].find("sweep dropped"), std::string::npos) << events[0];
  EXPECT_NE(events[1].find("sweep 1 at (0.0, 0.0)"), std::string::npos) << events[1];
  EXPECT_TRUE(layer.TakeEvents().empty());
  // A sweep during which the scanner moved is dropped.
  Sweep(&layer, 0, 45, 3.0, 30.0);
  Sweep(&layer, 45, 90, 3.5, 30.0);
  EXPECT_EQ(layer.scans(), 1);
  layer.Reset();
  EXPECT_EQ(layer.scans(), 0);
  EXPECT_FALSE(layer.ExportGrids().has_value());
}

// The layer and cairn-explorer's mission make the same map from the same sweeps: the explorer
// decides on the map the mapper publishes and stores.
TEST(ExploreMapperLayerTest, TheSameSweepsGiveTheExplorersMap) {
  const ExploreMapperLayerParams params = Params();
  ExploreMapperLayer layer(params);
  explore::NbvMission mission(params.mission);
  mission.Start(10.0);
  for (int k = 0; k < 90; ++k) {
    const TurretLineReading line = Line(k);
    layer.OnReading(line);
    mission.OnTurretLine(line.line, line.pan_rad, line.utime * 1e-6);
  }
  ASSERT_EQ(mission.scans(), 1);
  ASSERT_EQ(layer.scans(), 1);
  const auto grids = layer.ExportGrids();
  ASSERT_TRUE(grids.has_value());
  EXPECT_TRUE(*grids == mission.info_map().ToGridMap());
}

TEST(ExploreMapperLayerTest, ListedWithoutAnExplorerConfigurationItSaysWhatIsMissing) {
  ExploreMapperLayerParams p;
  try {
    p.Validate();
    FAIL() << "no explorer configuration accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("explore.explorer_config"), std::string::npos) << e.what();
  }
  p.explorer_config = TempPath("no_such_explorer.yaml");
  EXPECT_ANY_THROW(ReadExplorerConfig(&p));
  // A work area that crosses itself is refused with the layer's key in the message.
  p.explorer_config = ExplorerConfigFile();
  p.work_area = "0,0 4,4 4,0 0,4";
  try {
    ReadExplorerConfig(&p);
    FAIL() << "a self-intersecting work area accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("explore.explorer_config"), std::string::npos) << e.what();
  }
}

TEST(ExploreMapperLayerTest, RegisteredAsExploreAndOffUnlessListed) {
  MapperCoreParams core;
  EXPECT_FALSE(core.Has(kExploreLayerName));
  core.explore = Params();
  core.SetListed(kExploreLayerName, true);
  EXPECT_NO_THROW(core.Validate());
  auto layer = MakeMapperLayer(kExploreLayerName, core);
  ASSERT_NE(layer, nullptr);
  EXPECT_EQ(layer->name(), "explore");
  EXPECT_EQ(layer->ReadingStreams(), std::vector<std::string>{"TURRET_SCAN"});
  EXPECT_EQ(layer->inputs(), static_cast<uint32_t>(kSensorReadings));
}

}  // namespace
}  // namespace cairn::mapping
