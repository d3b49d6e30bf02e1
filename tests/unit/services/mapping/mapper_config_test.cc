// The mapper's configuration: the shipped files load into the structs, every section's keys
// reach their params, `enabled` lists or removes a layer, and an unknown key or a bad value is
// an error naming the file and line.

#include "services/mapping/mapper_config.h"

#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "common/yaml_reader.h"

namespace cairn::mapping {
namespace {

std::string Source(const std::string& relative) {
  return std::string(CAIRN_SOURCE_DIR) + "/" + relative;
}

MapperConfig FromString(const std::string& text) {
  common::YamlMap root = common::YamlMap::FromString(text, "mapper.yaml");
  return LoadMapperConfig(root);
}

TEST(MapperConfigTest, TheShippedMapperFileLoads) {
  MapperConfig c = LoadMapperConfigFile(Source("config/mapping/mapper.yaml"));
  MapperParams& p = c.params;
  p.robot = "p1";
  EXPECT_EQ(c.profiles, (std::vector<std::string>{"pioneer3at", "rover"}));
  EXPECT_EQ(p.core.layers, (std::vector<std::string>{"terrain", "occupancy", "octomap"}));
  EXPECT_EQ(p.inputs.pose_source, PoseSource::kGroundTruth);
  EXPECT_DOUBLE_EQ(p.core.terrain.publish_period_s, 0.2);
  EXPECT_DOUBLE_EQ(p.core.terrain.map.self_filter_radius_m, 0.5);
  EXPECT_DOUBLE_EQ(p.core.terrain.map.filter.min_variance_m2, 1.0e-7);
  EXPECT_NEAR(p.core.terrain.map.filter.max_spread_slope_rad, 25.0 * M_PI / 180.0, 1e-12);
  EXPECT_EQ(p.core.terrain.map.traversability.min_step_edge_cells, 2);
  EXPECT_DOUBLE_EQ(p.core.terrain.map.obstacles.surface_continuity_m, 0.05);
  EXPECT_DOUBLE_EQ(p.core.occupancy.grid.resolution_m, 0.1);
  EXPECT_DOUBLE_EQ(p.core.band.sensor_height_m, 0.33);
  EXPECT_EQ(p.core.octomap.every_revolutions, 10);
  EXPECT_DOUBLE_EQ(p.core.octomap.tree.resolution_m, 0.1);
  EXPECT_EQ(p.core.dynamic.extent.size_x, 800);  // 40 m at 0.05 m
  p.Validate();
}

TEST(MapperConfigTest, TheShippedApartmentFileLoads) {
  MapperConfig c = LoadMapperConfigFile(Source("config/mapping/apartment.yaml"));
  MapperParams& p = c.params;
  EXPECT_EQ(p.core.layers, (std::vector<std::string>{"terrain", "dynamic"}));
  EXPECT_DOUBLE_EQ(p.core.dynamic.publish_period_s, 0.2);  // occupancy_period_s
  EXPECT_EQ(p.core.dynamic.layers.cost_inc, 8);
  EXPECT_EQ(p.core.dynamic.layers.longterm_cost_dec, 4);
  EXPECT_EQ(p.core.dynamic.static_map_path, "config/maps/apartment.yaml");
  EXPECT_EQ(p.long_term_store, "apartment/long_term");
  EXPECT_DOUBLE_EQ(p.long_term_load_timeout_s, 30.0);
  p.robot = "kobuki";
  p.Validate();
}

TEST(MapperConfigTest, EnabledListsOrRemovesALayer) {
  const MapperConfig c = FromString(
      "occupancy: {enabled: false, preset: seed003, max_scan_tilt_deg: 2.5,\n"
      "            band: {min_height_m: 0.2}}\n"
      "dynamic: {enabled: true, size_x_m: 4.0, size_y_m: 3.0, cost_inc: 6}\n"
      "occupancy_period_s: 0.5\n");
  const MapperCoreParams& core = c.params.core;
  EXPECT_EQ(core.layers, (std::vector<std::string>{"terrain", "octomap", "dynamic"}));
  EXPECT_TRUE(std::isinf(OccupancyParams().protect_occupied_logodds));
  EXPECT_FALSE(std::isinf(core.occupancy.grid.protect_occupied_logodds));  // the seed 003 preset
  EXPECT_TRUE(std::isinf(OccupancyParams().max_scan_tilt_rad));
  EXPECT_NEAR(core.occupancy.grid.max_scan_tilt_rad, 2.5 * M_PI / 180.0, 1e-12);
  EXPECT_DOUBLE_EQ(core.band.min_height_m, 0.2);
  EXPECT_EQ(core.dynamic.extent.size_x, 80);
  EXPECT_EQ(core.dynamic.layers.cost_inc, 6);
  EXPECT_DOUBLE_EQ(core.dynamic.publish_period_s, 0.5);
  EXPECT_DOUBLE_EQ(core.occupancy.publish_period_s, 0.5);
}

void ExpectConfigError(const std::string& text, const std::string& needle) {
  try {
    FromString(text);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const common::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(MapperConfigTest, UnknownKeysAndBadValuesNameTheirLine) {
  ExpectConfigError("map_name: live\nterrain:\n  resolutoin_m: 0.2\n", "resolutoin_m");
  ExpectConfigError("map_name: live\nterrain:\n  resolutoin_m: 0.2\n", "mapper.yaml:3");
  ExpectConfigError("terrain: {filter: {range_noise: 0.01}}\n", "range_noise");
  ExpectConfigError("occupancy: {band: {min_height: 0.2}}\n", "min_height");
  ExpectConfigError("octomap: {every_revolution: 3}\n", "every_revolution");
  ExpectConfigError("dynamic: {cost_incr: 3}\n", "cost_incr");
  ExpectConfigError("pose_source: gps\n", "pose_source");
  ExpectConfigError("occupancy: {preset: fast}\n", "preset");
  ExpectConfigError("lidar_mount: {x: 1}\n", "x");
  ExpectConfigError("sidescan: {enabled: true}\n", "sidescan");
  ExpectConfigError("sonar: {min_peak_hieght: 100}\n", "min_peak_hieght");
}

TEST(MapperConfigTest, ParamsAreValidated) {
  MapperParams p;
  EXPECT_THROW(p.Validate(), std::invalid_argument);  // no robot
  p.robot = "r1";
  p.Validate();
  p.long_term_store = "no-slash";
  EXPECT_THROW(p.Validate(), std::invalid_argument);
  p.long_term_store = "site/map";
  EXPECT_THROW(p.Validate(), std::invalid_argument);  // needs the dynamic layer
  p.core.SetListed(kDynamicLayerName, true);
  p.Validate();
  p.core.octomap.every_revolutions = 0;
  EXPECT_THROW(p.Validate(), std::invalid_argument);
}

TEST(MapperConfigTest, ProfilesByNameOrPath) {
  const std::string dir = Source("config/profiles");
  auto rover = ResolveProfile(dir, "rover");
  ASSERT_TRUE(rover.ok()) << rover.status().ToString();
  EXPECT_EQ(rover->name, "rover");
  EXPECT_TRUE(ResolveProfile(dir, dir + "/kobuki.yaml").ok());
  EXPECT_EQ(ResolveProfile(dir, "warthog").status().code(), common::StatusCode::kNotFound);
  EXPECT_EQ(ResolveProfile(dir, "../etc").status().code(), common::StatusCode::kNotFound);
  EXPECT_EQ(ResolveProfile(dir, "bad name").status().code(), common::StatusCode::kInvalidArgument);
  // Issue 20: a name from the bus is a name in the profiles folder, never a path (the mapper
  // runs as root in the demo: it read any file and echoed its parse error back).
  EXPECT_TRUE(ResolveProfileByName(dir, "rover").ok());
  for (const std::string& bad : {dir + "/kobuki.yaml", std::string("/etc/passwd"),
                                 std::string("../profiles/rover"), std::string("rover.yaml"),
                                 std::string(""), std::string(65, 'a')}) {
    const auto r = ResolveProfileByName(dir, bad);
    EXPECT_EQ(r.status().code(), common::StatusCode::kInvalidArgument) << bad;
    EXPECT_EQ(r.status().message().find("root:"), std::string::npos) << bad;
  }
  EXPECT_EQ(SplitList(" a, b ,,c "), (std::vector<std::string>{"a", "b", "c"}));
}

}  // namespace
}  // namespace cairn::mapping
