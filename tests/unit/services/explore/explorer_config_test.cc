#include "services/explore/explorer_config.h"

#include <string>

#include <gtest/gtest.h>

namespace cairn::explore {
namespace {

ExplorerConfig FromText(const std::string& text) {
  common::YamlMap map = common::YamlMap::FromString(text, "explorer.yaml");
  return LoadExplorerConfig(map);
}

TEST(ExplorerConfigTest, TheShippedFileLoadsWithTheSeedConstants) {
  const ExplorerConfig c =
      LoadExplorerConfigFile(std::string(CAIRN_SOURCE_DIR) + "/config/explore/explorer.yaml");
  EXPECT_EQ(c.mode, ExploreMode::kReactive);
  EXPECT_DOUBLE_EQ(c.reactive.safety_distance_m, 0.65);
  EXPECT_DOUBLE_EQ(c.reactive.reverse_speed_mps, -0.15);
  EXPECT_FALSE(c.reactive.legacy_nan);
  EXPECT_EQ(c.frontier.layer, "occupancy");
}

TEST(ExplorerConfigTest, ModesAndOverridesAreRead) {
  const ExplorerConfig c = FromText(
      "mode: frontier\nduration_s: 60\nfrontier: {potential_scale: 2.0}\n"
      "reactive: {legacy_nan: true}\n");
  EXPECT_EQ(c.mode, ExploreMode::kFrontier);
  EXPECT_DOUBLE_EQ(c.duration_s, 60.0);
  EXPECT_DOUBLE_EQ(c.frontier.frontier.potential_scale, 2.0);
  EXPECT_TRUE(c.reactive.legacy_nan);
  EXPECT_EQ(ExploreModeFromName("stateless"), ExploreMode::kStateless);
  EXPECT_STREQ(ExploreModeName(ExploreMode::kFrontier), "frontier");
}

TEST(ExplorerConfigTest, UnknownKeysBadModesAndBadValuesNameTheProblem) {
  auto error = [](const std::string& text) {
    try {
      FromText(text);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("mode: wander\n").find("unknown exploration mode 'wander'"), std::string::npos);
  EXPECT_NE(error("reactive: {speed: 1}\n").find("speed"), std::string::npos);
  EXPECT_NE(error("duration_s: -1\n").find("duration_s"), std::string::npos);
  EXPECT_NE(error("frontier: {free_threshold_og: 80}\n").find("thresholds"), std::string::npos);
}

}  // namespace
}  // namespace cairn::explore
