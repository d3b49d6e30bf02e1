#include "planner/navigator_config.h"

#include <string>

#include <gtest/gtest.h>

#include "planner/local/critic_registry.h"

namespace cairn::planner {
namespace {

std::string ConfigError(const std::string& yaml) {
  try {
    common::YamlMap root = common::YamlMap::FromString(yaml, "nav.yaml");
    LoadNavigatorConfig(root);
  } catch (const common::ConfigError& e) {
    return std::string(e.what());
  }
  return std::string();
}

TEST(NavigatorConfigTest, LoadsTheShippedFileAndRefusesUnknownKeys) {
  const NavigatorConfig c =
      LoadNavigatorConfigFile(std::string(CAIRN_SOURCE_DIR) + "/config/navigator/navigator.yaml");
  EXPECT_EQ(c.global_planner.planner, "RRTConnect");
  EXPECT_EQ(c.local_planner.generator.vx_samples, 20);
  EXPECT_DOUBLE_EQ(c.navigator.control_period_s, 0.05);
  EXPECT_DOUBLE_EQ(c.local_planner.generator.control_period_s, 0.05);
  EXPECT_EQ(c.navigator.recovery.sequence.size(), 5u);
  const auto error = ConfigError;
  EXPECT_NE(error("local_planner:\n  critics:\n    - {name: speed, scale: 1, speedd: 1}\n")
                .find("nav.yaml:3"),
            std::string::npos);
  EXPECT_NE(error("global_planner:\n  planner: RRTfast\n").find("RRTfast"), std::string::npos);
  EXPECT_NE(error("global_planner:\n  state_space: se3\n").find("nav.yaml:2"), std::string::npos);
  EXPECT_NE(error("recovery:\n  sequence: [rotate, dance]\n").find("dance"), std::string::npos);
  EXPECT_NE(error("pose_source: gps\n").find("nav.yaml:1"), std::string::npos);
  EXPECT_NE(error("control_rate_hz: -1\n").find("control_rate_hz"), std::string::npos);
  EXPECT_EQ(error("navigator:\n  xy_goal_tolerance_m: 0.3\n"), "");
  // The critics' keys moved into the critic list: the old flat keys are unknown now.
  EXPECT_NE(error("local_planner:\n  clearance_inflation_m: 0.2\n").find("nav.yaml:2"),
            std::string::npos);
}

TEST(NavigatorConfigTest, TheShippedCriticListIsTheDefaultOne) {
  const NavigatorConfig shipped =
      LoadNavigatorConfigFile(std::string(CAIRN_SOURCE_DIR) + "/config/navigator/navigator.yaml");
  const auto& critics = shipped.local_planner.critics;
  const std::vector<CriticConfig> defaults = DefaultCritics();
  ASSERT_EQ(critics.size(), defaults.size());
  for (size_t i = 0; i < critics.size(); ++i) {
    EXPECT_EQ(critics[i].name, defaults[i].name) << i;
    EXPECT_DOUBLE_EQ(critics[i].scale, defaults[i].scale) << i;
  }
  // The file spells out each critic's defaults.
  EXPECT_DOUBLE_EQ(shipped.local_planner.FindCritic("clearance")->params.at("inflation_m"), 0.3);
  EXPECT_DOUBLE_EQ(shipped.local_planner.FindCritic("clearance")->params.at("admissible_braking"),
                   1.0);
  EXPECT_DOUBLE_EQ(
      shipped.local_planner.FindCritic("path_align")->params.at("forward_point_distance_m"), 0.325);
  // Without the key the defaults hold.
  common::YamlMap empty = common::YamlMap::FromString("{}", "empty.yaml");
  EXPECT_EQ(LoadNavigatorConfig(empty).local_planner.critics, defaults);
  // The apartment narrows the clearance critic only.
  const NavigatorConfig apartment =
      LoadNavigatorConfigFile(std::string(CAIRN_SOURCE_DIR) + "/config/navigator/apartment.yaml");
  ASSERT_EQ(apartment.local_planner.critics.size(), defaults.size());
  EXPECT_DOUBLE_EQ(apartment.local_planner.FindCritic("clearance")->params.at("inflation_m"), 0.15);
}

TEST(NavigatorConfigTest, CriticListsAreCheckedAtTheirLine) {
  const std::string order =
      "local_planner:\n"
      "  critics:\n"
      "    - {name: clearance, scale: 2.0, inflation_m: 0.2, admissible_braking: false}\n"
      "    - {name: speed, scale: 0.5}\n";
  common::YamlMap root = common::YamlMap::FromString(order, "nav.yaml");
  const NavigatorConfig c = LoadNavigatorConfig(root);
  ASSERT_EQ(c.local_planner.critics.size(), 2u);
  EXPECT_EQ(c.local_planner.critics[0].name, "clearance");
  EXPECT_DOUBLE_EQ(c.local_planner.critics[0].scale, 2.0);
  EXPECT_DOUBLE_EQ(c.local_planner.critics[0].params.at("admissible_braking"), 0.0);
  EXPECT_EQ(c.local_planner.critics[1].name, "speed");
  const std::string unknown = ConfigError(
      "local_planner:\n  critics:\n    - {name: speed, scale: 1}\n    - {name: sonar, scale: 1}\n");
  EXPECT_NE(unknown.find("nav.yaml:4"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("unknown critic 'sonar'"), std::string::npos) << unknown;
  EXPECT_NE(ConfigError("local_planner:\n  critics:\n    - {name: speed}\n").find("scale"),
            std::string::npos);
  EXPECT_NE(ConfigError("local_planner:\n  critics: {speed: 1}\n").find("nav.yaml:2"),
            std::string::npos);
  EXPECT_NE(ConfigError("local_planner:\n  critics:\n    - {name: clearance, scale: 1, "
                        "inflation_m: wide}\n")
                .find("inflation_m"),
            std::string::npos);
  // Issue 20 (found by fuzz_yaml_loaders): a null key escaped as yaml-cpp's InvalidNode.
  EXPECT_NE(ConfigError("local_planner:\n  critics:\n    - {name: clearance, scale: 1, ~: 2}\n")
                .find("must be a number"),
            std::string::npos);
  EXPECT_NE(ConfigError("local_planner:\n  critics:\n    - {name: speed, scale: 1}\n"
                        "    - {name: speed, scale: 2}\n")
                .find("listed twice"),
            std::string::npos);
  EXPECT_NE(ConfigError("local_planner:\n  critics: []\n").find("at least one critic"),
            std::string::npos);
}

TEST(NavigatorMapConfigTest, DefaultIsTheProfileCostLayer) {
  common::YamlMap root = common::YamlMap::FromString("control_rate_hz: 20\n", "nav.yaml");
  const NavigatorConfig c = LoadNavigatorConfig(root);
  EXPECT_EQ(c.map.encoding, MapEncoding::kCost);
  EXPECT_EQ(c.map.LayerFor("kobuki"), "cost/kobuki");
  // The directed companion of the cost layer is read by default; not with occupancy or off.
  EXPECT_EQ(c.map.DirectedLayerFor("kobuki"), "directed/kobuki");
  common::YamlMap off = common::YamlMap::FromString(
      "map:\n  directed: false\ncost_map:\n  one_way_cost: 70\n", "nav.yaml");
  const NavigatorConfig no = LoadNavigatorConfig(off);
  EXPECT_EQ(no.map.DirectedLayerFor("kobuki"), "");
  EXPECT_FLOAT_EQ(no.cost_map.one_way_cost, 70.f);
  MapLayerConfig occupancy;
  occupancy.encoding = MapEncoding::kOccupancy;
  EXPECT_EQ(occupancy.DirectedLayerFor("kobuki"), "");
  MapLayerConfig named;
  named.layer = "cost/robauco";
  EXPECT_EQ(named.DirectedLayerFor("kobuki"), "directed/robauco");
}

TEST(NavigatorMapConfigTest, OccupancySectionAndErrors) {
  common::YamlMap root = common::YamlMap::FromString(
      "map:\n  encoding: occupancy\n  occupied_threshold_og: 30\n  free_threshold_og: 10\n",
      "nav.yaml");
  const NavigatorConfig c = LoadNavigatorConfig(root);
  EXPECT_EQ(c.map.encoding, MapEncoding::kOccupancy);
  EXPECT_EQ(c.map.LayerFor("kobuki"), "final");  // the dynamic map server's composed layer
  EXPECT_FLOAT_EQ(c.map.occupancy.occupied_threshold_og, 30.f);
  EXPECT_FLOAT_EQ(c.map.occupancy.free_threshold_og, 10.f);
  const auto error = ConfigError;
  EXPECT_NE(error("map:\n  encoding: pgm\n").find("nav.yaml:2"), std::string::npos);
  EXPECT_NE(error("map:\n  occupied_thresh: 0.65\n").find("nav.yaml:2"), std::string::npos);
  EXPECT_NE(error("map:\n  encoding: occupancy\n  free_threshold_og: 80\n").find("free_threshold"),
            std::string::npos);
}

TEST(NavigatorMapConfigTest, LoadsTheShippedApartmentFile) {
  const NavigatorConfig c =
      LoadNavigatorConfigFile(std::string(CAIRN_SOURCE_DIR) + "/config/navigator/apartment.yaml");
  EXPECT_EQ(c.map.encoding, MapEncoding::kOccupancy);
  EXPECT_EQ(c.map.LayerFor("kobuki"), "final");
  EXPECT_LT(c.map.occupancy.free_threshold_og, c.map.occupancy.occupied_threshold_og);
  EXPECT_FALSE(c.cost_map.unknown_is_traversable);
}

// The AUV's configuration (seed 004): the sonar layer, unknown water blocking, explore first and
// approach through known water, the 2 m goal tolerance, commands through the velocity bridge.
TEST(NavigatorMapConfigTest, LoadsTheShippedUnderwaterFile) {
  const NavigatorConfig c =
      LoadNavigatorConfigFile(std::string(CAIRN_SOURCE_DIR) + "/config/navigator/underwater.yaml");
  EXPECT_EQ(c.command_output, CommandOutput::kBodyVelocity);
  EXPECT_EQ(c.control_clock, ControlClock::kPose);
  EXPECT_EQ(NavigatorConfig{}.control_clock, ControlClock::kWall);
  EXPECT_NE(ConfigError("control_clock: sim\n").find("control clock"), std::string::npos);
  EXPECT_EQ(c.map.encoding, MapEncoding::kOccupancy);
  EXPECT_EQ(c.map.LayerFor("sparus2_msis"), "sonar/occupancy");
  EXPECT_FALSE(c.cost_map.unknown_is_traversable);
  EXPECT_GT(c.cost_map.footprint_padding_m, 0.0);
  EXPECT_EQ(c.navigator.xy_goal_tolerance_m, 2.0);
  EXPECT_GT(c.navigator.wait_for_map_s, 0.0);
  EXPECT_TRUE(c.navigator.approach_through_known);
  EXPECT_NE(ConfigError("command_output: twist\n").find("command output"), std::string::npos);
  EXPECT_NE(ConfigError("navigator: {wait_for_map_s: -1}\n").find("wait_for_map_s"),
            std::string::npos);
  EXPECT_NE(ConfigError("cost_map: {footprint_padding_m: -0.1}\n").find("footprint_padding_m"),
            std::string::npos);
}

}  // namespace
}  // namespace cairn::planner
