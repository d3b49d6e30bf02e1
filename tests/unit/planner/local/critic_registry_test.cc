#include "planner/local/critic_registry.h"

#include <string>

#include <gtest/gtest.h>

#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using testing::PioneerFootprint;
using testing::TestLayer;

std::string ErrorOf(const CriticConfig& config, const CriticRegistry& registry = BuiltinCritics()) {
  try {
    registry.Check(config);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(CriticRegistryTest, TheShippedCriticsAndTheDefaultList) {
  EXPECT_EQ(
      BuiltinCritics().names(),
      (std::vector<std::string>{"clearance", "goal_dist", "oscillation", "path_align", "speed"}));
  // Today's order (cheap critics first, clearance last) and weights.
  const std::vector<CriticConfig> expected = {{"speed", 0.4, {}},
                                              {"oscillation", 0.2, {}},
                                              {"goal_dist", 1.5, {}},
                                              {"path_align", 1.0, {}},
                                              {"clearance", 1.0, {}}};
  EXPECT_EQ(DefaultCritics(), expected);
  for (const CriticConfig& c : DefaultCritics()) {
    const auto critic = BuiltinCritics().Make(c, CriticSetup{});
    ASSERT_NE(critic, nullptr);
    EXPECT_EQ(critic->name(), c.name);
    EXPECT_DOUBLE_EQ(critic->scale(), c.scale);
  }
}

TEST(CriticRegistryTest, UnknownCriticsKeysAndBadValuesAreRefusedByName) {
  EXPECT_NE(ErrorOf({"clearence", 1.0, {}}).find("unknown critic 'clearence'"), std::string::npos);
  EXPECT_NE(ErrorOf({"clearence", 1.0, {}}).find("known: clearance goal_dist"), std::string::npos);
  const std::string key = ErrorOf({"clearance", 1.0, {{"inflation", 0.2}}});
  EXPECT_NE(key.find("unknown key 'inflation'"), std::string::npos) << key;
  EXPECT_NE(key.find("'clearance'"), std::string::npos) << key;
  EXPECT_NE(ErrorOf({"speed", 1.0, {{"max_vel_x_mps", 1.0}}}).find("max_vel_x_mps"),
            std::string::npos);
  EXPECT_NE(ErrorOf({"clearance", 1.0, {{"admissible_braking", 2.0}}}).find("true or false"),
            std::string::npos);
  EXPECT_NE(ErrorOf({"clearance", 1.0, {{"inflation_m", -0.1}}}).find("clearance.inflation_m"),
            std::string::npos);
  EXPECT_NE(ErrorOf({"path_align", 1.0, {{"forward_point_distance_m", NAN}}}).find("finite"),
            std::string::npos);
  EXPECT_NE(ErrorOf({"oscillation", 1.0, {{"reset_dist_m", 0.0}}}).find("reset_dist_m"),
            std::string::npos);
  EXPECT_NE(ErrorOf({"goal_dist", -1.0, {}}).find("scale"), std::string::npos);
  EXPECT_EQ(ErrorOf({"clearance", 0.5, {{"inflation_m", 0.15}, {"admissible_braking", 0.0}}}), "");
}

TEST(CriticRegistryTest, ACriticsOwnKeysReachIt) {
  // A wall 1 m ahead of a robot driving at 0.5 m/s: blocked beyond its braking distance. By
  // default such a trajectory is kept at a penalty; with admissible_braking off it is rejected.
  TestLayer layer(100, 60, 0.1);
  layer.Rect(6.0, 0.0, 6.5, 6.0, 100.0f);
  const auto map = layer.Build(PioneerFootprint());
  CriticSetup setup;
  const TrajectoryGenerator gen(setup.limits, setup.generator);
  Trajectory t;
  gen.Simulate({5.2, 3.0, 0.0}, {0.5, 0.0}, &t);
  CriticContext context;
  context.map = map.get();
  context.pose = {5.2, 3.0, 0.0};
  auto lenient = BuiltinCritics().Make({"clearance", 1.0, {}}, setup);
  auto strict = BuiltinCritics().Make({"clearance", 1.0, {{"admissible_braking", 0.0}}}, setup);
  lenient->Prepare(context);
  strict->Prepare(context);
  EXPECT_TRUE(lenient->Evaluate(t).valid);
  EXPECT_FALSE(strict->Evaluate(t).valid);
  // The setup's limits reach the critics that use them: the speed critic's top speed.
  setup.limits.max_vel_x_mps = 1.0;
  auto speed = BuiltinCritics().Make({"speed", 1.0, {}}, setup);
  gen.Simulate({0.0, 0.0, 0.0}, {0.5, 0.0}, &t);
  EXPECT_DOUBLE_EQ(speed->Evaluate(t).value, 0.5);
}

TEST(CriticRegistryTest, NamesAreRegisteredOnce) {
  CriticRegistry registry;
  const CriticFactory factory = [](const CriticConfig& c, const CriticSetup&) {
    CriticParamReader(c).Finish();
    return std::make_unique<GoalDistCritic>(c.scale);
  };
  registry.Add("goal_dist", factory);
  EXPECT_TRUE(registry.Has("goal_dist"));
  EXPECT_FALSE(registry.Has("speed"));
  EXPECT_THROW(registry.Add("goal_dist", factory), std::invalid_argument);
  EXPECT_THROW(registry.Add("", factory), std::invalid_argument);
  EXPECT_THROW(registry.Add("speed", nullptr), std::invalid_argument);
  EXPECT_NE(ErrorOf({"speed", 1.0, {}}, registry).find("unknown critic 'speed'"),
            std::string::npos);
}

TEST(CriticParamReaderTest, ReadsNumbersAndBooleansAndCatchesLeftovers) {
  const CriticConfig config{"x", 1.0, {{"a_m", 2.5}, {"on", 1.0}, {"off", 0.0}, {"extra", 3.0}}};
  CriticParamReader reader(config);
  double a = 0.0;
  bool on = false, off = true;
  double absent = 7.0;
  EXPECT_TRUE(reader.Get("a_m", &a));
  EXPECT_TRUE(reader.Get("on", &on));
  EXPECT_TRUE(reader.Get("off", &off));
  EXPECT_FALSE(reader.Get("absent", &absent));
  EXPECT_DOUBLE_EQ(a, 2.5);
  EXPECT_TRUE(on);
  EXPECT_FALSE(off);
  EXPECT_DOUBLE_EQ(absent, 7.0);
  EXPECT_THROW(reader.Finish(), std::invalid_argument);
  double extra = 0.0;
  reader.Get("extra", &extra);
  EXPECT_NO_THROW(reader.Finish());
}

}  // namespace
}  // namespace cairn::planner
