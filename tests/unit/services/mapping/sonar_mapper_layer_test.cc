#include "services/mapping/sonar_mapper_layer.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "services/mapping/mapper_layers.h"

// The sonar layer on hand-made pings: what a ping clears and marks, seen through the layer's
// exported grids.

namespace cairn::mapping {
namespace {

// A ping from the head at (x, y) looking along `yaw_rad`, 50 bins of 1 m.
SonarReading Ping(std::vector<uint8_t> bins, double x = 0.0, double y = 0.0, double yaw_rad = 0.0) {
  SonarReading r;
  r.stream = "SONAR";
  r.sensor_pose.position_m = {x, y, -5.0};
  r.sensor_pose.orientation =
      common::Quaternion(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()));
  r.range_max_m = 50.0;
  r.bins = std::move(bins);
  return r;
}

// Test 3's flat seabed 2 m down: bins 5.. falling from 81, under the 110 threshold.
std::vector<uint8_t> Seabed() {
  std::vector<uint8_t> b(50, 0);
  const int v[] = {81, 75, 65, 58, 52, 47, 43, 39, 36, 33};
  for (int k = 0; k < 10; ++k) b[5 + k] = static_cast<uint8_t>(v[k]);
  for (int k = 15; k < 49; ++k) b[k] = 30;
  return b;
}

// Test 4's wall 10 m ahead: the seabed up to it, 247 at bin 10, nothing behind.
std::vector<uint8_t> Wall() {
  std::vector<uint8_t> b(50, 0);
  const int v[] = {81, 75, 65, 58, 54};
  for (int k = 0; k < 5; ++k) b[5 + k] = static_cast<uint8_t>(v[k]);
  b[10] = 247;
  return b;
}

float At(const common::GridMap& map, const char* layer, double x, double y) {
  return map.ValueAt(layer, {x, y}).value_or(NAN);
}

// Test 17 in one ping: the seabed's echoes never make an obstacle, and the beam clears to its
// range.
TEST(SonarMapperLayerTest, Seed004Test17TheSeabedAddsNoObstacleAndTheBeamClearsToRange) {
  SonarMapperLayer layer{SonarMapperLayerParams{}};
  EXPECT_FALSE(layer.ExportGrids().has_value());
  layer.OnReading(Ping(Seabed()));
  EXPECT_EQ(layer.last_obstacles(), 0);
  const auto map = layer.ExportGrids();
  ASSERT_TRUE(map.has_value());
  for (double x = 1.0; x < 49.0; x += 1.0) {
    EXPECT_LT(At(*map, kSonarLogOdds, x, 0.0), 0.f) << "x " << x;
  }
  int occupied = 0;
  const common::Layer& l = map->at(kSonarLogOdds);
  for (int i = 0; i < l.size(); ++i) occupied += l.data()[i] > 0.f;
  EXPECT_EQ(occupied, 0);
}

// A wall's peak: free up to it, occupied at bin 10's near edge, unknown behind. The beam's
// heading is the head's (here 90 deg: the robot's yaw and the pan together).
TEST(SonarMapperLayerTest, AWallsPeakIsAnObstacleWithFreeWaterBeforeIt) {
  SonarMapperLayer layer{SonarMapperLayerParams{}};
  layer.OnReading(Ping(Wall(), 3.0, 4.0, M_PI / 2));
  EXPECT_EQ(layer.last_obstacles(), 1);
  const auto map = layer.ExportGrids();
  ASSERT_TRUE(map.has_value());
  EXPECT_GT(At(*map, kSonarLogOdds, 3.05, 14.05), 0.f);
  EXPECT_LT(At(*map, kSonarLogOdds, 3.05, 9.0), 0.f);
  EXPECT_TRUE(std::isnan(At(*map, kSonarLogOdds, 3.05, 20.0)));
  EXPECT_GT(At(*map, kSonarOccupancy, 3.05, 14.05), 50.f);
  // Seen again and again it stays; a reset forgets it.
  for (int i = 0; i < 5; ++i) layer.OnReading(Ping(Wall(), 3.0, 4.0, M_PI / 2));
  EXPECT_EQ(layer.obstacles(), 6);
  layer.Reset();
  EXPECT_FALSE(layer.ExportGrids().has_value());
}

// Two peaks: the nearer one stops the clearing, the farther one is marked too.
TEST(SonarMapperLayerTest, ThePeaksBeyondTheFirstAreMarkedWithoutClearing) {
  std::vector<uint8_t> b(50, 0);
  b[5] = 80;
  b[8] = 200;
  b[9] = 60;
  b[20] = 230;
  b[21] = 40;
  std::vector<int> found;
  const auto rays = SonarPingRays(Ping(b), SonarPeakParams{}, &found);
  EXPECT_EQ(found, (std::vector<int>{8, 20}));
  ASSERT_EQ(rays.size(), 2u);
  EXPECT_TRUE(rays[0].hit);
  EXPECT_NEAR(rays[0].origin_m.x(), 0.0, 1e-12);
  EXPECT_NEAR(rays[0].end_m.x(), 8.0, 1e-12);
  EXPECT_TRUE(rays[1].hit);
  EXPECT_NEAR(rays[1].origin_m.x(), 20.0, 1e-12);  // a mark, no clearing
  EXPECT_NEAR(rays[1].end_m.x(), 20.0, 1e-12);
  SonarMapperLayer layer{SonarMapperLayerParams{}};
  layer.OnReading(Ping(b));
  const auto map = layer.ExportGrids();
  ASSERT_TRUE(map.has_value());
  EXPECT_GT(At(*map, kSonarLogOdds, 20.1, 0.1), 0.f);
  EXPECT_TRUE(std::isnan(At(*map, kSonarLogOdds, 14.0, 0.1))) << "cleared behind the first peak";
}

// With a beam width, a peak marks the arc the beam covers at its range (3 deg at 10 m: 0.52 m,
// a point a cell of 0.25 m either side of the axis), not one point; the clearing stays on the
// axis.
TEST(SonarMapperLayerTest, ABeamWidthMarksThePeaksArc) {
  std::vector<int> found;
  const auto point = SonarPingRays(Ping(Wall()), SonarPeakParams{}, &found);
  ASSERT_EQ(point.size(), 1u);
  const double width_rad = 3.0 * M_PI / 180.0;
  const auto arc = SonarPingRays(Ping(Wall()), SonarPeakParams{}, &found, width_rad, 0.25);
  ASSERT_EQ(arc.size(), 1u + 2u * 1u);  // floor(0.5 * 0.0524 * 10 / 0.25) = 1 a side
  for (size_t i = 1; i < arc.size(); ++i) {
    EXPECT_TRUE(arc[i].hit);
    EXPECT_EQ(arc[i].origin_m, arc[i].end_m);  // marks only
    EXPECT_NEAR(arc[i].end_m.norm(), 10.0, 1e-9);
    EXPECT_LE(std::abs(std::atan2(arc[i].end_m.y(), arc[i].end_m.x())), 0.5 * width_rad);
  }
  SonarMapperLayerParams params;
  params.beam_width_deg = 3.0;
  SonarMapperLayer layer{params};
  layer.OnReading(Ping(Wall()));
  const auto map = layer.ExportGrids();
  ASSERT_TRUE(map.has_value());
  for (const PlanarRay& mark : arc) {
    EXPECT_GT(At(*map, kSonarLogOdds, mark.end_m.x(), mark.end_m.y()), 0.f);
  }
  EXPECT_GT(std::abs(arc[1].end_m.y()), 0.2);
}

// The vehicle's own water: a disc round the hull's centre, behind the head along the hull (the
// head's heading less its pan): its unobserved cells read free after every ping; an observed
// obstacle inside it stays.
TEST(SonarMapperLayerTest, TheVehiclesOwnWaterIsClearedRoundItsCentre) {
  SonarMapperLayerParams params;
  params.vehicle_centre_behind_head_m = 0.7;
  params.vehicle_clear_radius_m = 0.9;
  SonarMapperLayer layer{params};
  // The hull faces +x; the head at (0.7, 0) looks 30 deg left.
  SonarReading ping = Ping(Wall(), 0.7, 0.0, 30.0 * M_PI / 180.0);
  ping.pan_rad = 30.0 * M_PI / 180.0;
  layer.OnReading(ping);
  const auto map = layer.ExportGrids();
  ASSERT_TRUE(map.has_value());
  for (const common::Vector2& p : {common::Vector2(-0.7, 0.0), common::Vector2(0.0, -0.8),
                                   common::Vector2(0.0, 0.8), common::Vector2(0.6, -0.5)}) {
    EXPECT_LT(At(*map, kSonarLogOdds, p.x(), p.y()), 0.f) << p.transpose();
  }
  EXPECT_TRUE(std::isnan(At(*map, kSonarLogOdds, -1.2, 0.0)));  // beyond the disc, behind
  // A rock seen 0.6 m beside the hull is not cleared by it.
  SonarMapperLayer beside{params};
  beside.OnReading(Ping(Wall(), 0.0, -9.4, M_PI / 2));  // a peak at (0, 0.6): 10 m north of it
  SonarReading again = Ping(Seabed(), 0.7, 0.0, 0.0);
  for (int i = 0; i < 5; ++i) beside.OnReading(again);
  const auto seen = beside.ExportGrids();
  ASSERT_TRUE(seen.has_value());
  EXPECT_GT(At(*seen, kSonarLogOdds, 0.0, 0.6), 0.f) << "the rock beside the hull was cleared";
  params.vehicle_clear_radius_m = -1.0;
  EXPECT_THROW(params.Validate(), std::invalid_argument);
}

// Each ping's detection waits for the service to publish it: the peaks' bins and world points,
// or a clear beam; at most kMaxPendingDetections, the oldest dropped and counted.
TEST(SonarMapperLayerTest, EachPingsDetectionIsKeptForPublishing) {
  SonarMapperLayer layer{SonarMapperLayerParams{}};
  SonarReading wall = Ping(Wall(), 3.0, 4.0, M_PI / 2);
  wall.utime = 42;
  layer.OnReading(wall);
  layer.OnReading(Ping(Seabed()));
  const std::vector<SonarDetection> d = layer.TakeDetections();
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].utime, 42);
  EXPECT_EQ(d[0].bins, (std::vector<int>{10}));
  ASSERT_EQ(d[0].points.size(), 1u);
  EXPECT_NEAR(d[0].points[0].x(), 3.0, 1e-9);
  EXPECT_NEAR(d[0].points[0].y(), 14.0, 1e-9);
  EXPECT_NEAR(d[0].beam_yaw_rad, M_PI / 2, 1e-9);
  EXPECT_TRUE(d[1].bins.empty());
  EXPECT_TRUE(layer.TakeDetections().empty());
  for (size_t i = 0; i < SonarMapperLayer::kMaxPendingDetections + 5; ++i) {
    layer.OnReading(Ping(Seabed()));
  }
  EXPECT_EQ(layer.TakeDetections().size(), SonarMapperLayer::kMaxPendingDetections);
  EXPECT_EQ(layer.dropped_detections(), 5);
}

TEST(SonarMapperLayerTest, RegisteredAsSonarAndReadFromItsSection) {
  MapperCoreParams core;
  EXPECT_FALSE(core.Has(kSonarLayerName));
  core.SetListed(kSonarLayerName, true);
  EXPECT_NO_THROW(core.Validate());
  auto layer = MakeMapperLayer(kSonarLayerName, core);
  EXPECT_EQ(layer->ReadingStreams(), std::vector<std::string>{"SONAR"});
  common::YamlMap section = common::YamlMap::FromString(
      "min_peak_height: 120\nverify_shadow: true\nresolution_m: 0.5\n", "mapper.yaml");
  const SonarMapperLayerParams p = LoadSonarMapperLayerParams(section);
  EXPECT_EQ(p.peaks.min_peak_height, 120);
  EXPECT_TRUE(p.peaks.verify_shadow);
  EXPECT_EQ(p.grid.resolution_m, 0.5);
  EXPECT_EQ(p.grid.size_x_cells, SonarMapperLayerParams::DefaultGrid().size_x_cells);
  common::YamlMap bad = common::YamlMap::FromString("min_peak_hieght: 120\n", "mapper.yaml");
  EXPECT_THROW(LoadSonarMapperLayerParams(bad), common::ConfigError);
}

}  // namespace
}  // namespace cairn::mapping
